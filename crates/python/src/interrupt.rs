//! Running engine work off the GIL, interruptible by Ctrl-C, with panics caught.
//!
//! The work runs on a thread of its own while this thread, holding the GIL only briefly, waits
//! for it in 50 ms steps and calls `Python::check_signals` in between: Ctrl-C raises
//! `KeyboardInterrupt` there, which sets the cancel flag the render loop polls between passes,
//! waits for the work to stop, and re-raises. Other Python threads run meanwhile.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// Runs `work(cancel)` on a worker thread (see the module docs).
pub fn run<T: Send>(py: Python<'_>, work: impl FnOnce(&AtomicBool) -> T + Send) -> PyResult<T> {
    let cancel = AtomicBool::new(false);
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel();
        let cancel = &cancel;
        s.spawn(move || {
            let out = catch_unwind(AssertUnwindSafe(|| work(cancel)));
            let _ = tx.send(out);
        });
        let mut interrupt = None;
        let mut rx = rx;
        let out = loop {
            // The receiver is moved in and out: it may cross threads but not be shared.
            let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
            rx = back;
            match got {
                Ok(out) => break out,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if interrupt.is_none() {
                        if let Err(e) = py.check_signals() {
                            cancel.store(true, Ordering::SeqCst);
                            interrupt = Some(e);
                        }
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "internal error: the render thread ended without a result",
                    ))
                }
            }
        };
        if let Some(e) = interrupt {
            return Err(e);
        }
        out.map_err(|panic| {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            PyRuntimeError::new_err(format!("internal error in haze (a bug; please report it): {what}"))
        })
    })
}

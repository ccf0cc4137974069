//! What the `haze` binary's integration tests share: the binary, paths in the repository and
//! in a temporary folder, and the check of a clean failure. Each test file is its own crate and
//! takes this module with `mod common;`, using a part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const HAZE: &str = env!("CARGO_BIN_EXE_haze");

/// A path relative to the repository's root.
pub fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").join(rel)
}

/// The test data shipped in the repository (`tests/data`, e.g. `validation/scenes/...`).
pub fn data(rel: &str) -> PathBuf {
    repo("tests/data").join(rel)
}

/// A folder of its own for one test, `name`, inside this test process's temporary folder. Under
/// the target directory (`CARGO_TARGET_TMPDIR`), not the system's temporary folder, which the
/// test runs would otherwise fill with one folder per process; `cargo clean` removes them.
pub fn tmp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("haze-cli-tests-{}", std::process::id()))
        .join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A file `name` in this test process's temporary folder.
pub fn tmp(name: &str) -> PathBuf {
    tmp_dir("").join(name)
}

/// A path as the `&str` an argument list takes.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("test paths are UTF-8")
}

pub fn haze(args: &[&str]) -> Output {
    Command::new(HAZE).args(args).output().expect("haze runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit code 1 with an `error:` line (a panic would exit with 101 and print "panicked");
/// returns the message.
pub fn assert_clean_failure(o: &Output, context: &str) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{context}: exit {:?}\n{err}", o.status.code());
    assert!(err.starts_with("error: "), "{context}: {err}");
    assert!(!err.contains("panicked"), "{context}: {err}");
    err
}

/// A clean failure (as [`assert_clean_failure`]) whose message contains `want`.
pub fn assert_fails_with(o: &Output, want: &str) {
    let err = assert_clean_failure(o, want);
    assert!(err.contains(want), "`{err}` lacks `{want}`");
}

/// A success; returns the standard output.
pub fn assert_success(o: &Output, what: &str) -> String {
    assert!(o.status.success(), "{what} failed:\n{}", stderr(o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

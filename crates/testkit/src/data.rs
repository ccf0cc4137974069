//! Where the tests find their data: the validation scenes shipped in the repository
//! (`tests/data/validation/`) and the third-party peer scenes, which are never copied into the
//! repository (their licences do not clearly allow it) and are looked for in `$HAZE_PEERS_DIR`,
//! then in `../shared/peers` beside the repository (where CI has them). `scripts/fetch-peers.sh`
//! downloads them for anyone with network access.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Once;

/// The environment variable naming a directory that holds the peer scenes.
pub const PEERS_ENV: &str = "HAZE_PEERS_DIR";

/// The repository's root directory (tests run from the source tree).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A file of the validation data shipped in the repository, e.g. `validation("scenes/hg-box.xml")`.
pub fn validation(rel: &str) -> PathBuf {
    repo_root().join("tests/data/validation").join(rel)
}

/// A validation scene by name, e.g. `validation_scene("hg-box")`.
pub fn validation_scene(name: &str) -> PathBuf {
    validation(&format!("scenes/{name}.xml"))
}

/// The directory of the peer scenes: `$HAZE_PEERS_DIR` if set (it must then exist), else
/// `../shared/peers` beside the repository if it exists, else `None`.
pub fn peers_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os(PEERS_ENV).filter(|d| !d.is_empty()) {
        let dir = PathBuf::from(dir);
        assert!(dir.is_dir(), "${PEERS_ENV} = {} is not a directory", dir.display());
        return Some(dir);
    }
    let beside = repo_root().join("../shared/peers");
    beside.is_dir().then_some(beside)
}

static SKIP_LINE: Once = Once::new();

/// True for the first test binary of this `cargo test` run that asks (see [`peers_or_skip`]).
fn first_in_this_run() -> bool {
    #[cfg(unix)]
    {
        let marker =
            std::env::temp_dir().join(format!("haze-peers-skipped-{}", std::os::unix::process::parent_id()));
        std::fs::OpenOptions::new().write(true).create_new(true).open(marker).is_ok()
    }
    #[cfg(not(unix))]
    true
}

/// The peer directory, or `None` after printing the line saying what is skipped and how to get
/// the data: once per `cargo test` run, whichever test binaries need the peers (a marker file
/// named after the parent process, cargo, that the test binaries share; on other platforms
/// once per test binary). Tests of peer scenes start with
/// `let Some(peers) = haze_testkit::data::peers_or_skip() else { return };`.
pub fn peers_or_skip() -> Option<PathBuf> {
    let dir = peers_dir();
    if dir.is_none() {
        // Straight to stderr: the test harness captures `eprintln!` of passing tests.
        SKIP_LINE.call_once(|| {
            if !first_in_this_run() {
                return;
            }
            let _ = writeln!(
                std::io::stderr(),
                "skipped: peer scenes (Mitsuba 3 media render tests, tof-cbox-volumetric, \
                 mi3-phase-trampoline-teapot) not found in ${PEERS_ENV} or ../shared/peers; \
                 run scripts/fetch-peers.sh"
            );
        });
    }
    dir
}

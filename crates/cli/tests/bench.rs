//! `haze bench` finds its default scenes among the files shipped with haze (beside the
//! executable or in the current directory), not at a path compiled into the binary.

use std::path::PathBuf;
use std::process::Command;

const HAZE: &str = env!("CARGO_BIN_EXE_haze");

/// Runs `haze bench --integrator none` (which fails after locating the default scenes) with
/// `exe` from an empty directory and returns its stderr.
fn bench_from_empty_dir(exe: &PathBuf, tag: &str) -> String {
    let dir = std::env::temp_dir().join(format!("haze-bench-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(exe).args(["bench", "--integrator", "none"]).current_dir(&dir).output().unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(!out.status.success());
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn default_scenes_are_found_beside_the_executable() {
    // target/<profile>/haze in the clone: the validation scenes are two directories up.
    let err = bench_from_empty_dir(&PathBuf::from(HAZE), "clone");
    assert!(err.contains("measures volpath or vrl, not 'none'"), "{err}");
}

#[test]
fn missing_default_scenes_are_a_clear_error() {
    // A copy of the binary outside the clone (an installed `haze`) with no data beside it.
    let dir = std::env::temp_dir().join(format!("haze-bench-bin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("haze");
    std::fs::copy(HAZE, &exe).unwrap();
    let err = bench_from_empty_dir(&exe, "installed");
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(err.contains("default scene tests/data/validation/scenes/hg-box.xml was not found"), "{err}");
    assert!(err.contains("give the scene files as arguments"), "{err}");
}

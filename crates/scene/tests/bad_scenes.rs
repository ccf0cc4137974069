//! The bad-input corpus: every `tests/bad-scenes/NAME.xml` at the repository root must fail to
//! load with a message that starts with the file's path and contains every line of
//! `NAME.expected` (the element, key words and `:LINE:`).

use haze_scene::{load_file, LoadOptions};
use std::path::Path;

const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/bad-scenes");

#[test]
fn every_bad_scene_fails_with_the_expected_message() {
    let mut entries: Vec<_> = std::fs::read_dir(CORPUS)
        .expect("tests/bad-scenes exists")
        .map(|e| e.expect("readable directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    entries.sort();
    assert!(entries.len() >= 24, "only {} bad scenes", entries.len());

    let mut failures = Vec::new();
    for xml in &entries {
        let expected_path = xml.with_extension("expected");
        let expected = std::fs::read_to_string(&expected_path)
            .unwrap_or_else(|e| panic!("{}: {e}", expected_path.display()));
        let message = match load_file(xml, &LoadOptions::default()) {
            Ok(_) => {
                failures.push(format!("{}: loaded without an error", xml.display()));
                continue;
            }
            Err(e) => e.to_string(),
        };
        if message.contains('\n') {
            failures.push(format!("{message}\n    is not one line"));
        }
        if !message.starts_with(&xml.display().to_string()) {
            failures.push(format!("{message}\n    does not start with the file path"));
        }
        for want in expected.lines().filter(|l| !l.is_empty()) {
            if !message.contains(want) {
                failures.push(format!("{message}\n    lacks `{want}`"));
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Each scene has its expected-message file, so that the command-line test can reuse the
/// corpus as it is.
#[test]
fn every_bad_scene_has_an_expected_file() {
    for e in std::fs::read_dir(CORPUS).expect("tests/bad-scenes exists") {
        let p = e.expect("readable directory entry").path();
        if p.extension().is_some_and(|x| x == "xml") {
            assert!(Path::new(&p.with_extension("expected")).exists(), "{}", p.display());
        }
    }
}

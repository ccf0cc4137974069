//! Front-end settings that used to panic (issue 16): a time budget too large for a `Duration`
//! (or too small for any pass) is an error of the engine's option table, for every front end.

use haze_engine::options::{resolve, Spelling};
use haze_engine::MethodKind;
use haze_scene::{load_str, LoadOptions};
use std::path::Path;

#[test]
fn huge_time_budget_is_an_error_not_a_panic() {
    let e =
        resolve(MethodKind::VolPath, &[("time", "1e20")], Spelling::Flag).expect_err("an error").to_string();
    assert!(e.contains("--time is more than a year"), "{e}");
    let e =
        resolve(MethodKind::Vrl, &[("time", "1e-300")], Spelling::Keyword).expect_err("an error").to_string();
    assert!(e.contains("time is too small a budget"), "{e}");
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"/></scene>"#;
    let scene = load_str(xml, Path::new("t.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    let ok = resolve(MethodKind::VolPath, &[("time", "2")], Spelling::Flag).unwrap();
    assert_eq!(
        ok.render_settings(MethodKind::VolPath, &scene).time_limit,
        Some(std::time::Duration::from_secs(2))
    );
}

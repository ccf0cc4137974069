//! Front-end settings that used to panic (issue 16): a time budget too large for a `Duration`.

use haze_engine::methods::render_settings;
use haze_scene::{load_str, LoadOptions};
use std::path::Path;

#[test]
fn huge_time_budget_is_an_error_not_a_panic() {
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"/></scene>"#;
    let scene = load_str(xml, Path::new("t.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    let e = render_settings(&scene, None, Some(1e20), 0, 1, false).expect_err("an error").to_string();
    assert!(e.contains("too large"), "{e}");
    let ok = render_settings(&scene, None, Some(2.0), 0, 1, false).unwrap();
    assert_eq!(ok.time_limit, Some(std::time::Duration::from_secs(2)));
}

//! Hostile input the loader must refuse quickly and clearly, or load (issue 16): cases too big
//! to commit are generated here. The small ones are in the bad-scene corpus
//! (`tests/bad-scenes/`, checked by `bad_scenes.rs`).

use haze_scene::{load_file, load_str, LoadError, LoadOptions, Scene};
use std::path::Path;
use std::time::{Duration, Instant};

const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/bad-scenes");

const FILM: &str = r#"<sensor type="perspective"><film type="hdrfilm">
    <integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>"#;

fn load(xml: &str) -> Result<Scene, LoadError> {
    load_str(xml, Path::new("hostile.xml"), Path::new("."), &LoadOptions::default())
}

fn error(xml: &str) -> String {
    match load(xml) {
        Ok(_) => panic!("the scene loaded, but an error was expected"),
        Err(e) => e.to_string(),
    }
}

/// `gen_deep_nesting.py`: 100,000 nested elements aborted the process with a stack overflow.
#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let n = 100_000;
    let xml = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<shape type=\"sphere\">".repeat(n),
        "</shape>".repeat(n)
    );
    let e = error(&xml);
    assert!(e.contains("nest too deeply (the limit is 64 levels)"), "{e}");
}

/// `gen_many_elements.py`: loading took time quadratic in the number of elements (16 s for
/// 100,000 `<default>`s, over a minute on one line); the line/column lookup is now logarithmic.
#[test]
fn many_elements_load_in_linear_time() {
    for sep in ["\n", ""] {
        let body: String =
            (0..100_000).map(|i| format!("<default name=\"d{i}\" value=\"1\"/>{sep}")).collect();
        let xml = format!("<scene version=\"3.0.0\">\n{body}{FILM}\n</scene>\n");
        let start = Instant::now();
        load(&xml).unwrap();
        assert!(start.elapsed() < Duration::from_secs(5), "{:?}", start.elapsed());
    }
    // Positions stay right on a long line and after many lines.
    let body: String = (0..1000).map(|i| format!("<default name=\"d{i}\" value=\"1\"/>")).collect();
    let xml = format!("<scene version=\"3.0.0\">\n{body}\n\n<shape type=\"nope\"/>\n</scene>");
    let e = load(&xml).err().unwrap();
    assert_eq!((e.line, e.column), (4, 1), "{e}");
}

/// A 50 MB attribute value was echoed whole in the message.
#[test]
fn long_values_are_shortened_in_messages() {
    let value = "x".repeat(50 << 20);
    let e = error(&format!("<scene version=\"3.0.0\">{FILM}<shape type=\"sphere\"><float name=\"radius\" value=\"{value}\"/></shape></scene>"));
    assert!(e.len() < 1000, "{} bytes", e.len());
    assert!(e.contains("cannot parse") && e.contains(&format!("{} bytes in all", value.len() + 2)), "{e}");
    // Many short words too.
    let value = "1 ".repeat(1 << 20);
    let e = error(&format!("<scene version=\"3.0.0\">{FILM}<shape type=\"sphere\"><point name=\"center\" value=\"{value}\"/></shape></scene>"));
    assert!(e.len() < 2000, "{} bytes", e.len());
}

/// `include_depth_17_misleading.xml`: a chain of 21 files, each including the next, is not a
/// cycle; the message says the depth limit was reached.
#[test]
fn include_depth_limit_says_so() {
    let path = Path::new(CORPUS).join("include_chain/depth-17.xml");
    let e = load_file(&path, &LoadOptions::default()).err().expect("an error").to_string();
    assert!(e.contains("include depth limit (16) reached"), "{e}");
    assert!(!e.contains("recursively"), "{e}");
    assert!(e.contains("c15.xml:1:"), "{e}");
}

/// `rotate_huge_axis_misleading.xml`: an axis of length 1e20 is a fine axis (its squared
/// length overflowed, and the message said the axis was zero).
#[test]
fn huge_and_tiny_rotation_axes_rotate() {
    let rotated = |axis: &str| {
        let xml = format!(
            r#"<scene version="3.0.0"><sensor type="perspective">
            <transform name="to_world"><rotate {axis} angle="90"/></transform></sensor></scene>"#
        );
        load(&xml).unwrap().camera.to_world
    };
    let reference = rotated(r#"x="1""#);
    for axis in [r#"x="1e20""#, r#"x="1e-30""#, r#"x="3e38""#] {
        assert!(rotated(axis).abs_diff_eq(reference, 1e-6), "{axis}");
    }
    let e = error(
        r#"<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><rotate x="0" angle="9"/></transform></sensor></scene>"#,
    );
    assert!(e.contains("the rotation axis is zero"), "{e}");
    let e = error(
        r#"<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><rotate x="inf" angle="9"/></transform></sensor></scene>"#,
    );
    assert!(e.contains("'x' must be a finite number"), "{e}");
}

/// Values that made every sample NaN are refused where they are read.
#[test]
fn values_that_overflow_are_refused() {
    let cases = [
        (
            r#"<medium type="homogeneous" id="m"><float name="sigma_t" value="3.4e38"/></medium>"#,
            "'sigma_t' (times 'scale') must be at most",
        ),
        (
            r#"<medium type="homogeneous" id="m"><float name="sigma_t" value="1e19"/><float name="scale" value="1e19"/></medium>"#,
            "'sigma_t' (times 'scale') must be at most",
        ),
        (
            r#"<emitter type="point"><rgb name="intensity" value="3.4e38"/></emitter>"#,
            "'intensity' must be at most",
        ),
        (
            r#"<emitter type="constant"><rgb name="radiance" value="1e30"/></emitter>"#,
            "'radiance' must be at most",
        ),
        (
            r#"<shape type="sphere"><bsdf type="dielectric"><float name="int_ior" value="1e30"/></bsdf></shape>"#,
            "'int_ior' must lie in",
        ),
        (
            r#"<shape type="sphere"><bsdf type="plastic"><float name="ext_ior" value="1e-30"/></bsdf></shape>"#,
            "'ext_ior' must lie in",
        ),
        (
            r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha" value="1e30"/></bsdf></shape>"#,
            "'alpha' must be at most",
        ),
        (r#"<shape type="sphere"><float name="radius" value="1e30"/></shape>"#, "haze takes geometry within"),
        (
            r#"<shape type="rectangle"><transform name="to_world"><translate x="1e20"/></transform></shape>"#,
            "haze takes geometry within",
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="1e-30"/></transform></shape>"#,
            "too small for f32 ray tracing",
        ),
        (r#"<shape type="cube"><transform name="to_world"><scale z="0"/></transform></shape>"#, "singular"),
        (
            r#"<emitter type="spot"><transform name="to_world"><scale value="0"/></transform></emitter>"#,
            "singular",
        ),
        (
            r#"<emitter type="spot"><transform name="to_world"><scale x="1" y="1" z="0"/></transform></emitter>"#,
            "singular",
        ),
        (
            r#"<shape type="sphere"><transform name="to_world"><lookat origin="-3e38, 0, 0" target="3e38, 0, 0" up="0, 1, 0"/></transform></shape>"#,
            "too far apart",
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 nan"/></transform></shape>"#,
            "not finite",
        ),
    ];
    for (body, want) in cases {
        let e = error(&format!("<scene version=\"3.0.0\">{FILM}{body}</scene>"));
        assert!(e.contains(want), "{body}\n  gave: {e}\n  wanted: {want}");
    }
}

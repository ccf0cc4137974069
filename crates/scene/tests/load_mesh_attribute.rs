//! Mitsuba 3's `mesh_attribute` texture: PLY properties grouped into attributes as Mitsuba 3.9.1
//! groups them, looked up at a hit with its triangle and barycentrics, and every way a scene can
//! ask for an attribute it cannot have, each an error naming the file, line and element.

use glam::{Vec2, Vec3};
use haze_core::{Ray, Rgb};
use haze_scene::texture::TexPoint;
use haze_scene::{load_str, Bsdf, LoadError, LoadOptions, Scene, Texture};
use std::path::PathBuf;

const SENSOR: &str = r#"<sensor type="perspective"/>"#;

/// A directory of its own for each test (tests run in parallel).
fn dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("haze-mesh-attribute-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An ASCII PLY file: vertex properties after `x y z`, then faces (index lists) with their
/// properties.
fn ply(dir: &std::path::Path, name: &str, vprops: &[&str], verts: &[&str], fprops: &[&str], faces: &[&str]) {
    let mut s = format!("ply\nformat ascii 1.0\nelement vertex {}\n", verts.len());
    for p in ["float x", "float y", "float z"].iter().chain(vprops) {
        s += &format!("property {p}\n");
    }
    s += &format!("element face {}\nproperty list uchar int vertex_indices\n", faces.len());
    for p in fprops {
        s += &format!("property {p}\n");
    }
    s += "end_header\n";
    for l in verts.iter().chain(faces) {
        s += l;
        s += "\n";
    }
    std::fs::write(dir.join(name), s).unwrap();
}

fn load_in(dir: &std::path::Path, body: &str) -> Result<Scene, LoadError> {
    let xml = format!("<scene version=\"3.0.0\">\n{SENSOR}\n{body}\n</scene>");
    load_str(&xml, &dir.join("s.xml"), dir, &LoadOptions::default())
}

fn err_in(dir: &std::path::Path, body: &str) -> String {
    match load_in(dir, body) {
        Ok(_) => panic!("expected an error for {body}"),
        Err(e) => e.to_string(),
    }
}

fn diffuse_texture(s: &Scene, shape: usize) -> Texture {
    match &s.shapes[shape].bsdf {
        Bsdf::Diffuse { reflectance } => reflectance.clone(),
        b => panic!("diffuse expected, got {b:?}"),
    }
}

/// The triangle (0,0,2) (1,0,2) (0,1,2) with red, green and blue vertices: a ray through
/// (0.25, 0.5) hits it with barycentrics (b1, b2) = (0.25, 0.5), where the interpolated colour
/// is (0.25 red + 0.25 green + 0.5 blue) times the scale. Distinct corners, so a wrong vertex
/// order or swapped barycentrics changes the value.
#[test]
fn vertex_colour_is_interpolated_at_the_hit() {
    let d = dir("vertex");
    ply(
        &d,
        "tri.ply",
        &["float r", "float g", "float b"],
        &["0 0 2 1 0 0", "1 0 2 0 1 0", "0 1 2 0 0 1"],
        &[],
        &["3 0 1 2"],
    );
    let s = load_in(
        &d,
        r#"<shape type="ply"><string name="filename" value="tri.ply"/>
             <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
               <string name="name" value="vertex_color"/><float name="scale" value="0.8"/>
             </texture></bsdf></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let h = s.intersect(&Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z)).expect("the ray hits the triangle");
    assert!((h.bary - Vec2::new(0.25, 0.5)).length() < 1e-5, "{:?}", h.bary);
    let got = diffuse_texture(&s, 0).eval(h.tex());
    let want = Rgb::new(0.25, 0.25, 0.5) * 0.8;
    assert!((got - want).map(f32::abs).max_component() < 1e-5, "{got:?} != {want:?}");
    // The BSDF reads it: diffuse f = rho / pi cos.
    let f = s.shapes[0].bsdf.eval(Vec3::Z, Vec3::Z, h.tex());
    assert!((f - want * std::f32::consts::FRAC_1_PI).map(f32::abs).max_component() < 1e-5, "{f:?}");
    // By uv alone (no triangle) the texture has nothing to read.
    assert_eq!(diffuse_texture(&s, 0).eval(h.uv), Rgb::ZERO);
}

/// A face attribute is constant over its face; a quad face (two triangles) gives both its row.
#[test]
fn face_attribute_is_per_face_and_follows_polygons() {
    let d = dir("face");
    ply(
        &d,
        "quad.ply",
        &[],
        &["0 0 2", "1 0 2", "1 1 2", "0 1 2", "2 0 2"],
        &["float weight_0"],
        &["4 0 1 2 3 0.25", "3 1 4 2 0.75"],
    );
    let s = load_in(
        &d,
        r#"<texture type="mesh_attribute" id="w"><string name="name" value="face_weight"/></texture>
           <bsdf type="blendbsdf" id="b"><ref name="weight" id="w"/>
             <bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>
           <shape type="ply"><string name="filename" value="quad.ply"/><ref id="b"/></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let Bsdf::Blend(b) = &s.shapes[0].bsdf else { panic!("blendbsdf expected") };
    for (x, y, want) in [(0.2, 0.1, 0.25), (0.2, 0.9, 0.25), (0.9, 0.5, 0.25), (1.5, 0.2, 0.75)] {
        let h = s.intersect(&Ray::new(Vec3::new(x, y, 0.0), Vec3::Z)).expect("hit");
        assert!((b.weight(h.tex()) - want).abs() < 1e-6, "at ({x}, {y}): {}", b.weight(h.tex()));
    }
}

/// PLY properties become attributes under Mitsuba 3.9.1's names and with its values (measured
/// with Mitsuba 3.9.1's `Mesh.attribute_buffer` on the same files).
#[test]
fn ply_properties_are_named_and_read_as_mitsuba_reads_them() {
    let d = dir("names");
    ply(
        &d,
        "names.ply",
        &[
            "uchar red",
            "uchar green",
            "uchar blue",
            "float c_r",
            "float c_g",
            "float c_b",
            "short s_0",
            "char k_x",
        ],
        &["0 0 2 128 255 0 0.1 0.2 0.3 100 100", "1 0 2 0 0 0 0 0 0 32767 127", "0 1 2 0 0 0 0 0 0 0 0"],
        &[],
        &["3 0 1 2"],
    );
    let at_vertex0 = TexPoint { uv: Vec2::ZERO, prim: 0, bary: Vec2::ZERO };
    let value = |name: &str| {
        let body = format!(
            r#"<shape type="ply"><string name="filename" value="names.ply"/>
                 <bsdf type="roughconductor"><texture type="mesh_attribute" name="specular_reflectance">
                   <string name="name" value="{name}"/></texture></bsdf></shape>"#
        );
        match load_in(&d, &body) {
            Ok(s) => match &s.shapes[0].bsdf {
                Bsdf::Conductor(c) => c.specular_reflectance.eval(at_vertex0),
                b => panic!("{b:?}"),
            },
            Err(e) => panic!("{name}: {e}"),
        }
    };
    assert_eq!(value("vertex_c_color"), Rgb::new(0.1, 0.2, 0.3), "{{name}}_r g b: '_color' appended");
    // `short` and `char`: divided by the type's largest value, then decoded from sRGB.
    assert!((value("vertex_s")[0] - 0.000_236_211).abs() < 1e-8, "{:?}", value("vertex_s"));
    assert!((value("vertex_k")[0] - 0.582_693_5).abs() < 1e-6, "{:?}", value("vertex_k"));
    // A `uchar` colour stays as it is (128, not 128/255): out of [0, 1] for a reflectance.
    let e = err_in(
        &d,
        r#"<shape type="ply"><string name="filename" value="names.ply"/>
             <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
               <string name="name" value="vertex_color"/></texture></bsdf></shape>"#,
    );
    assert!(e.contains("'reflectance' must lie in [0, 1] in every channel"), "{e}");
    let e = err_in(
        &d,
        r#"<shape type="ply"><string name="filename" value="names.ply"/>
             <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
               <string name="name" value="vertex_color"/><float name="scale" value="0.005"/></texture></bsdf></shape>"#,
    );
    assert!(e.contains("'reflectance' must lie in [0, 1]"), "255 * 0.005 > 1: {e}");
    // The control: scaled into [0, 1] (255 * 0.0039 < 1), the same attribute loads.
    load_in(
        &d,
        r#"<shape type="ply"><string name="filename" value="names.ply"/>
             <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
               <string name="name" value="vertex_color"/><float name="scale" value="0.0039"/></texture></bsdf></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
}

/// Each way of naming an attribute the shape cannot give is an error naming the texture's
/// file, line and element, with what was wrong.
#[test]
fn missing_attributes_are_errors_naming_the_texture() {
    let d = dir("errors");
    ply(&d, "plain.ply", &[], &["0 0 0", "1 0 0", "0 1 0"], &[], &["3 0 1 2"]);
    ply(
        &d,
        "rgba.ply",
        &["float r", "float g", "float b", "float a", "float t_0"],
        &["0 0 0 1 1 1 1 0", "1 0 0 1 1 1 1 0", "0 1 0 1 1 1 1 0"],
        &[],
        &["3 0 1 2"],
    );
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let tex = |name: &str| {
        format!(
            r#"<bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
                 <string name="name" value="{name}"/></texture></bsdf>"#
        )
    };
    let shape = |file: &str, name: &str| {
        format!(
            r#"<shape type="{}"><string name="filename" value="{file}"/>{}</shape>"#,
            &file[file.len() - 3..],
            tex(name)
        )
    };
    let cases: Vec<(String, &str)> = vec![
        (
            r#"<shape type="sphere"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"/></bsdf></shape>"#.into(),
            "s.xml:3:43: <texture type=\"mesh_attribute\" name=\"reflectance\">: a mesh_attribute needs 'name'",
        ),
        (shape("plain.ply", "color"), "a mesh attribute's name starts with \"vertex_\" or \"face_\", not 'color'"),
        (
            format!(r#"<shape type="sphere">{}</shape>"#, tex("vertex_color")),
            "mesh_attribute 'vertex_color' reads an attribute of a mesh, and <shape type=\"sphere\"> at line 3 is not a mesh (a ply file)",
        ),
        (
            shape("plain.ply", "vertex_color"),
            "<shape type=\"ply\"> at line 3 has no mesh attribute 'vertex_color' (its file has no other vertex or face properties)",
        ),
        (
            shape("rgba.ply", "face_t"),
            "<shape type=\"ply\"> at line 3 has no mesh attribute 'face_t' (it has vertex_color, vertex_t)",
        ),
        (
            shape("tri.obj", "vertex_color"),
            "has no mesh attribute 'vertex_color' (haze reads attributes from PLY files only, and this is a 'obj' mesh)",
        ),
        (
            shape("rgba.ply", "vertex_color"),
            "mesh attribute 'vertex_color' of <shape type=\"ply\"> at line 3 has 4 channels; mesh_attribute reads 1 or 3",
        ),
        (
            r#"<emitter type="spot"><texture type="mesh_attribute" name="texture"><string name="name" value="vertex_color"/></texture></emitter>"#.into(),
            "mesh_attribute 'vertex_color' reads the mesh whose BSDF holds it; here it is not in a shape's BSDF",
        ),
    ];
    for (body, want) in cases {
        let e = err_in(&d, &body);
        assert!(e.contains(want), "{body}\n  gave: {e}\n  want: {want}");
        // The texture's element, or its `name` parameter's.
        let at_texture = e.contains("s.xml:3:") && e.contains("<texture type=\"mesh_attribute\"");
        assert!(at_texture || e.contains("s.xml:4:18: <string name=\"name\">"), "where: {e}");
    }
    // The same texture in a top-level declaration only is checked, not bound: it loads.
    load_in(&d, r#"<texture type="mesh_attribute" id="t"><string name="name" value="vertex_color"/></texture><shape type="ply"><string name="filename" value="plain.ply"/></shape>"#)
        .unwrap_or_else(|e| panic!("{e}"));
    // The 1-channel attribute of the same file binds (the control for the 4-channel error).
    load_in(&d, &shape("rgba.ply", "vertex_t")).unwrap_or_else(|e| panic!("{e}"));
}

//! Loading the BSDF and texture plugins: Mitsuba 3 defaults, named IORs, textures nested and
//! referenced, `twosided`, and the BSDFs of Mitsuba 3's media test scenes.

use glam::Vec2;
use haze_core::Rgb;
use haze_scene::bsdf::MicrofacetType;
use haze_scene::{load_str, Bsdf, LoadError, LoadOptions, Scene, Texture};
use std::path::Path;

fn load_result(body: &str) -> Result<Scene, LoadError> {
    let xml = format!("<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n{body}\n</scene>");
    load_str(&xml, Path::new("inline.xml"), Path::new("."), &LoadOptions::default())
}

fn bsdf_of(body: &str) -> Bsdf {
    let s = load_result(&format!("<shape type=\"sphere\">{body}</shape>")).unwrap_or_else(|e| panic!("{e}"));
    s.shapes[0].bsdf.clone()
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-5
}

#[test]
fn dielectric_family_defaults_and_named_iors() {
    let Bsdf::ThinDielectric { eta } = bsdf_of(
        r#"<bsdf type="thindielectric"><string name="int_ior" value="water"/>
           <string name="ext_ior" value="air"/></bsdf>"#,
    ) else {
        panic!("thindielectric expected")
    };
    // The peer README: "water"/"air" give eta = 1.33263.
    assert!(close(eta, 1.33263), "{eta}");

    let Bsdf::RoughDielectric(r) = bsdf_of(
        r#"<bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.3"/></bsdf>"#,
    ) else {
        panic!("roughdielectric expected")
    };
    assert!(close(r.eta, 1.29964), "{}", r.eta);
    assert_eq!(
        {
            let d = r.distr.fixed().unwrap();
            (d.ty, d.alpha_u, d.sample_visible)
        },
        (MicrofacetType::Beckmann, 0.3, true)
    );

    let Bsdf::RoughDielectric(r) = bsdf_of(
        r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
           <boolean name="sample_visible" value="false"/></bsdf>"#,
    ) else {
        panic!("roughdielectric expected")
    };
    assert_eq!(
        {
            let d = r.distr.fixed().unwrap();
            (d.ty, d.alpha_u, d.sample_visible)
        },
        (MicrofacetType::Ggx, 0.1, false)
    );
    assert!(close(r.eta, 1.5046 / 1.000277));
}

#[test]
fn plastic_family_defaults() {
    let Bsdf::Plastic(p) = bsdf_of(r#"<bsdf type="plastic"/>"#) else { panic!("plastic expected") };
    // polypropylene in air: Mitsuba reports eta = 1.48959.
    assert!(close(p.eta, 1.48959), "{}", p.eta);
    assert_eq!(p.diffuse_reflectance, Texture::Constant(Rgb::splat(0.5)));
    assert!(!p.nonlinear);
    assert!(close(p.specular_sampling_weight, 1.0 / 1.5));

    let Bsdf::RoughPlastic(p) = bsdf_of(
        r#"<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.2, 0.7, 0.7"/>
           <boolean name="nonlinear" value="true"/></bsdf>"#,
    ) else {
        panic!("roughplastic expected")
    };
    assert_eq!((p.distr.ty, p.distr.alpha_u), (MicrofacetType::Beckmann, 0.1));
    assert!(p.nonlinear && close(p.eta, 1.48959));
    assert_eq!(p.diffuse_reflectance, Texture::Constant(Rgb::new(0.2, 0.7, 0.7)));
}

#[test]
fn textures_nested_and_referenced() {
    let b = bsdf_of(
        r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
             <rgb name="color0" value="0.2"/><rgb name="color1" value="0.4"/>
             <transform name="to_uv"><matrix value="16 0 0 0 0 16 0 0 0 0 16 0 0 0 0 1"/></transform>
           </texture></bsdf>"#,
    );
    let Bsdf::Diffuse { reflectance } = b else { panic!("diffuse expected") };
    assert_eq!(reflectance.eval(Vec2::new(0.25 / 16.0, 0.25 / 16.0)), Rgb::splat(0.2));
    assert_eq!(reflectance.eval(Vec2::new(0.75 / 16.0, 0.25 / 16.0)), Rgb::splat(0.4));

    let s = load_result(
        r#"<texture type="checkerboard" id="checks"/>
           <shape type="sphere"><bsdf type="plastic"><ref name="diffuse_reflectance" id="checks"/></bsdf></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let Bsdf::Plastic(p) = &s.shapes[0].bsdf else { panic!("plastic expected") };
    assert!(matches!(p.diffuse_reflectance, Texture::Checkerboard { color0, color1, .. }
        if color0 == Rgb::splat(0.4) && color1 == Rgb::splat(0.2)));
    // Sampling weight from the texture's mean, 0.3.
    assert!(close(p.specular_sampling_weight, 1.0 / 1.3));
}

/// A shape without a `<bsdf>` reflects as a grey `diffuse` (0.5), but an emitting one is black, as
/// in Mitsuba 3: a bare area light reflects nothing. A given BSDF is kept on an emitter.
#[test]
fn default_bsdf_is_black_on_emitters() {
    let diffuse = |r: f32| Bsdf::Diffuse { reflectance: Rgb::splat(r).into() };
    assert_eq!(bsdf_of(""), diffuse(0.5));
    assert_eq!(bsdf_of(r#"<emitter type="area"/>"#), diffuse(0.0));
    assert_eq!(
        bsdf_of(r#"<emitter type="area"/><bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf>"#),
        diffuse(0.3)
    );
    let s = load_result(
        r#"<bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.6"/></bsdf>
           <shape type="rectangle"><ref id="grey"/><emitter type="area"/></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes[0].bsdf, diffuse(0.6));
}

#[test]
fn twosided_wraps_one_bsdf() {
    let s = load_result(
        r#"<bsdf type="twosided" id="wall"><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf>
           <shape type="sphere"><ref id="wall"/></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.shapes[0].bsdf,
        Bsdf::TwoSided(Box::new(Bsdf::Diffuse { reflectance: Rgb::splat(0.7).into() }))
    );
}

#[test]
fn bad_bsdf_and_texture_parameters() {
    let err = |body: &str| match load_result(&format!("<shape type=\"sphere\">{body}</shape>")) {
        Ok(_) => panic!("{body}: loaded"),
        Err(e) => e.to_string(),
    };
    let e = err(r#"<bsdf type="roughdielectric"><float name="alpha" value="-0.1"/></bsdf>"#);
    assert!(e.contains("'alpha' must be > 0, got -0.1"), "{e}");
    let e = err(r#"<bsdf type="twosided"/>"#);
    assert!(e.contains("needs one nested or referenced <bsdf>"), "{e}");
    let e = err(r#"<bsdf type="twosided"><bsdf type="diffuse"/><bsdf type="null"/></bsdf>"#);
    assert!(e.contains("different BSDF on each side"), "{e}");
    let e = err(r#"<bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"/></bsdf>"#);
    assert!(e.contains("a mesh_attribute needs 'name'"), "{e}");
    let e = err(
        r#"<bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/></texture></bsdf>"#,
    );
    assert!(e.contains("<shape type=\"sphere\"> at line 3 is not a mesh"), "{e}");
    let e = err(r#"<bsdf type="diffuse"><texture type="noise" name="reflectance"/></bsdf>"#);
    assert!(
        e.contains(
            "unsupported texture type 'noise' (supported: rawconstant, checkerboard, bitmap, mesh_attribute)"
        ),
        "{e}"
    );
    let e = err(
        r#"<bsdf type="principled"><float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf>"#,
    );
    assert!(e.contains("give either 'eta' or 'specular', not both"), "{e}");
    let e = err(r#"<bsdf type="principledthin"><float name="diff_trans" value="2.5"/></bsdf>"#);
    assert!(e.contains("'diff_trans' must lie in [0, 2]"), "{e}");
    let e = err(r#"<bsdf type="diffuse"><texture type="rawconstant" name="reflectance"/></bsdf>"#);
    assert!(e.contains("a rawconstant needs 'value'"), "{e}");
    let e = err(
        r#"<bsdf type="diffuse"><texture type="rawconstant" name="reflectance"><string name="value" value="a"/></texture></bsdf>"#,
    );
    assert!(e.contains("is a <float> or a <vector>"), "{e}");
    let e = err(
        r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"><rgb name="color0" value="2"/></texture></bsdf>"#,
    );
    assert!(e.contains("'reflectance' must lie in [0, 1]"), "{e}");
    let e =
        err(r#"<bsdf type="dielectric"><texture type="checkerboard" name="specular_reflectance"/></bsdf>"#);
    assert!(e.contains("does not take a texture 'specular_reflectance'"), "{e}");
    let e = err(r#"<bsdf type="plastic"><rgb name="specular_reflectance" value="0.5"/></bsdf>"#);
    assert!(e.contains("unsupported: 'specular_reflectance' other than 1"), "{e}");
}

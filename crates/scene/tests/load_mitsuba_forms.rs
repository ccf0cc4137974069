//! Forms that public Mitsuba 3 scenes use (issue 38): sensor parameters haze accepts and
//! ignores as Mitsuba 3 does, integrators haze does not have (kept for an override), objects
//! declared at the top level and referenced.

use haze_scene::{load_str, LoadError, LoadOptions, Scene};
use std::path::Path;

const SENSOR: &str = r#"<sensor type="perspective"/>"#;

fn load_xml(body: &str) -> Result<Scene, LoadError> {
    let xml = format!("<scene version=\"3.0.0\">\n{body}\n</scene>");
    load_str(&xml, Path::new("inline.xml"), Path::new("."), &LoadOptions::default())
}

fn load(body: &str) -> Scene {
    load_xml(body).unwrap_or_else(|e| panic!("{e}"))
}

fn error(body: &str) -> LoadError {
    match load_xml(body) {
        Ok(_) => panic!("the scene loaded, but an error was expected"),
        Err(e) => e,
    }
}

/// Mitsuba 3 reads `focus_distance` in every projective camera and ignores it for a pinhole;
/// `aperture_radius` belongs to `thinlens` only.
#[test]
fn perspective_focus_distance_is_accepted_and_aperture_radius_is_not() {
    let with = load(
        r#"<sensor type="perspective"><float name="fov" value="40"/><float name="focus_distance" value="3.5"/></sensor>"#,
    );
    let without = load(r#"<sensor type="perspective"><float name="fov" value="40"/></sensor>"#);
    assert_eq!(with.camera.fov_x_deg, without.camera.fov_x_deg);
    assert_eq!(with.camera.far_clip, without.camera.far_clip);
    let e = error(r#"<sensor type="perspective"><float name="focus_distance" value="nan"/></sensor>"#);
    assert!(e.message.contains("'focus_distance' must be a finite number"), "{e}");
    let e = error(r#"<sensor type="perspective"><float name="aperture_radius" value="0.1"/></sensor>"#);
    assert!(e.message.contains("unused parameter 'aperture_radius'"), "{e}");
    assert_eq!(e.line, 2);
}

/// An integrator type haze does not have loads; the scene keeps the error a render with its
/// own integrator gives (file, line, element) and the settings an override honours.
#[test]
fn unsupported_integrators_load_with_their_error_and_settings() {
    let s = load(&format!(
        r#"{SENSOR}<integrator type="direct"><integer name="emitter_samples" value="4"/></integrator>"#
    ));
    let e = s.integrator.unsupported.as_deref().expect("direct is unsupported");
    assert!(e.starts_with("inline.xml:2:"), "{e}");
    assert!(
        e.contains("<integrator type=\"direct\">") && e.contains("unsupported integrator type 'direct'"),
        "{e}"
    );
    assert_eq!((s.integrator.name.as_str(), s.integrator.max_depth), ("direct", 2), "direct is one bounce");
    assert_eq!(s.integrator.declared_at.as_deref(), Some("inline.xml:2"));

    let s = load(&format!(
        r#"{SENSOR}<integrator type="ptracer"><integer name="max_depth" value="7"/><integer name="rr_depth" value="9"/>
           <boolean name="hide_emitters" value="true"/><integer name="samples_per_pass" value="3"/></integrator>"#
    ));
    assert!(s.integrator.unsupported.is_some());
    assert_eq!((s.integrator.max_depth, s.integrator.rr_depth, s.integrator.hide_emitters), (7, 9, true));

    // A wrapper of one nested integrator takes that one's settings.
    let s = load(&format!(
        r#"{SENSOR}<integrator type="aov"><string name="aovs" value="dd.y:depth"/>
             <integrator type="path"><integer name="max_depth" value="3"/></integrator></integrator>"#
    ));
    assert_eq!((s.integrator.name.as_str(), s.integrator.max_depth), ("aov", 3));
    assert!(s.integrator.unsupported.as_deref().is_some_and(|e| e.contains("'aov'")));
    let s = load(&format!(r#"{SENSOR}<integrator type="stokes"><integrator type="direct"/></integrator>"#));
    assert_eq!((s.integrator.name.as_str(), s.integrator.max_depth), ("stokes", 2));

    // A supported one has no error and its place; no <integrator> has neither.
    let s = load(&format!(
        r#"{SENSOR}<integrator type="path"><integer name="max_depth" value="4"/></integrator>"#
    ));
    assert_eq!((s.integrator.unsupported.as_deref(), s.integrator.max_depth), (None, 4));
    assert_eq!(s.integrator.declared_at.as_deref(), Some("inline.xml:2"));
    assert_eq!(load(SENSOR).integrator, haze_scene::IntegratorSpec::default());

    // The settings an override keeps are still checked.
    let e = error(&format!(
        r#"{SENSOR}<integrator type="ptracer"><integer name="max_depth" value="-3"/></integrator>"#
    ));
    assert!(e.message.contains("'max_depth' must be -1 (unlimited) or >= 0, got -3"), "{e}");
    assert_eq!(e.element, "<integer name=\"max_depth\">");
    // So is a supported integrator's every parameter.
    let e = error(&format!(
        r#"{SENSOR}<integrator type="volpath"><integer name="samples" value="3"/></integrator>"#
    ));
    assert!(e.message.contains("unused parameter 'samples'"), "{e}");
    // `moment` around an unsupported integrator is that one.
    let s = load(&format!(r#"{SENSOR}<integrator type="moment"><integrator type="ptracer"/></integrator>"#));
    assert!(s
        .integrator
        .unsupported
        .as_deref()
        .is_some_and(|e| e.contains("'ptracer'") && e.contains(":2:")));
}

/// Mitsuba 3's Cornell box (`scenes/cbox/cbox-rgb.xml`) and its sampler scenes declare an area
/// emitter, a sampler, a film and BSDFs at the top level with ids and refer to them.
#[test]
fn top_level_objects_with_ids_are_referenced() {
    let s = load(
        r#"<sampler type="independent" id="spp9"><integer name="sample_count" value="9"/></sampler>
        <film type="hdrfilm" id="film"><integer name="width" value="20"/><integer name="height" value="10"/>
            <rfilter type="box"/></film>
        <sensor type="perspective"><ref id="spp9"/><ref id="film"/></sensor>
        <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7"/></bsdf>
        <emitter type="area" id="light"><rgb name="radiance" value="3, 2, 1"/></emitter>
        <shape type="rectangle"><ref id="white"/><ref id="light"/></shape>
        <shape type="sphere"><ref id="light"/></shape>"#,
    );
    assert_eq!((s.spp, s.camera.width, s.camera.height), (9, 20, 10));
    assert_eq!(s.emitters.len(), 2, "each shape that refers to the area emitter emits");
    for (i, e) in s.emitters.iter().enumerate() {
        assert!(
            matches!(e, haze_scene::Emitter::Area { shape, radiance } if *shape == i as u32 && *radiance == haze_core::Rgb::new(3.0, 2.0, 1.0).into()),
            "{e:?}"
        );
    }
    // A top-level area emitter without an id, or a sampler without one, refers to nothing.
    let e = error(&format!(r#"{SENSOR}<emitter type="area"/>"#));
    assert!(e.message.contains("must be nested inside the <shape>"), "{e}");
    let e = error(&format!(r#"{SENSOR}<sampler type="independent"/>"#));
    assert!(
        e.message.contains("must be nested inside <sensor> (or declared with an id and referenced)"),
        "{e}"
    );
    // A referenced definition is checked where it is used; the error points into it.
    let e = error(
        r#"<sampler type="independent" id="s"><integer name="sample_count" value="0"/></sampler>
        <sensor type="perspective"><ref id="s"/></sensor>"#,
    );
    assert_eq!((e.line, e.element.as_str()), (2, "<integer name=\"sample_count\">"));
    assert!(e.message.contains("'sample_count' must be > 0"), "{e}");
    let e =
        error(&format!(r#"{SENSOR}<emitter type="area" id="l"><rgb name="radiance" value="-1"/></emitter>"#));
    assert!(e.message.contains("'radiance' must not be negative"), "{e}");
    // Dangling references name the file and line of the <ref>.
    let e = error(&format!("{SENSOR}\n<shape type=\"sphere\"><ref id=\"nowhere\"/></shape>"));
    assert_eq!((e.file.to_str(), e.line), (Some("inline.xml"), 3));
    assert!(e.message.contains("dangling reference: no object has id 'nowhere'"), "{e}");
    // Only area emitters attach to shapes.
    let e = error(&format!(
        r#"{SENSOR}<emitter type="point" id="p"/><shape type="sphere"><ref id="p"/></shape>"#
    ));
    assert!(e.message.contains("only an area emitter can be attached to a shape"), "{e}");
}

fn bsdf_of(bsdf: &str) -> Result<haze_scene::Bsdf, LoadError> {
    load_xml(&format!("{SENSOR}<shape type=\"sphere\">{bsdf}</shape>")).map(|mut s| s.shapes.remove(0).bsdf)
}

/// A conductor's `eta` and `k` given as wavelength lists are not clamped like reflectances:
/// Mitsuba 3.9.1 (`scalar_rgb`, `mi.traverse`) gives these RGB values for them.
#[test]
fn conductor_spectra_are_unbounded() {
    let Ok(haze_scene::Bsdf::Conductor(c)) = bsdf_of(
        r#"<bsdf type="conductor"><spectrum name="eta" value="300:1.8, 400:1.65, 500:0.9, 600:0.2, 700:0.16, 800:0.18"/>
        <spectrum name="k" value="300:1.92, 400:1.95, 500:1.95, 600:2.97, 700:3.8, 800:5.12"/></bsdf>"#,
    ) else {
        panic!("a conductor")
    };
    for (got, want) in [(c.eta, [0.0452341, 0.585709, 1.33692]), (c.k, [3.38869, 2.34904, 1.87516])] {
        for i in 0..3 {
            assert!((got[i] - want[i]).abs() < 2e-3 * want[i].max(0.1), "{got:?} vs Mitsuba {want:?}");
        }
    }
}

#[test]
fn conductors_take_mitsuba_names_or_eta_and_k() {
    use haze_scene::bsdf::{conductor_ior, Conductor, MicrofacetType};
    let Ok(haze_scene::Bsdf::Conductor(c)) =
        bsdf_of(r#"<bsdf type="conductor"><string name="material" value="Au"/></bsdf>"#)
    else {
        panic!("a conductor")
    };
    assert_eq!((c.eta, c.k), conductor_ior("Au").unwrap());
    assert!(c.distr.is_none());
    let Ok(haze_scene::Bsdf::Conductor(c)) = bsdf_of(r#"<bsdf type="conductor"/>"#) else {
        panic!("a conductor")
    };
    assert_eq!((c.eta, c.k), (haze_core::Rgb::ZERO, haze_core::Rgb::ONE), "Mitsuba's default: material none");
    let Ok(haze_scene::Bsdf::Conductor(c)) = bsdf_of(
        r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha_u" value="0.3"/>
           <float name="alpha_v" value="0.3"/><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/>
           <rgb name="specular_reflectance" value="0.5"/></bsdf>"#,
    ) else {
        panic!("a rough conductor")
    };
    let Conductor { eta, distr: Some(d), specular_reflectance, .. } = *c else { panic!("rough") };
    let d = *d.fixed().expect("numbers: a fixed roughness");
    assert_eq!((d.ty, d.alpha_u, d.alpha_v, d.sample_visible), (MicrofacetType::Ggx, 0.3, 0.3, true));
    assert_eq!(eta, haze_core::Rgb::new(0.2, 0.9, 1.1));
    assert_eq!(specular_reflectance, haze_core::Rgb::splat(0.5).into());
    // Anisotropic and textured roughness (Mitsuba 3's roughconductor, roughdielectric and
    // pplastic take `alpha`, `alpha_u`, `alpha_v` as numbers or textures).
    let Ok(haze_scene::Bsdf::Conductor(c)) = bsdf_of(
        r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/>
           <string name="material" value="Al"/></bsdf>"#,
    ) else {
        panic!("an anisotropic rough conductor")
    };
    let d = *c.distr.as_ref().and_then(|d| d.fixed()).expect("fixed");
    assert_eq!((d.ty, d.alpha_u, d.alpha_v), (MicrofacetType::Beckmann, 0.05, 0.3));
    for (ty, alphas) in [
        (
            "roughdielectric",
            r#"<texture type="checkerboard" name="alpha"><float name="color0" value="0"/></texture>"#,
        ),
        (
            "roughconductor",
            r#"<texture type="checkerboard" name="alpha_u"/><texture type="checkerboard" name="alpha_v"><float name="color0" value="0.3"/></texture>"#,
        ),
        ("pplastic", r#"<texture type="checkerboard" name="alpha_u"/><float name="alpha_v" value="0.2"/>"#),
    ] {
        let xml = format!(r#"<bsdf type="{ty}">{alphas}</bsdf>"#);
        let b = bsdf_of(&xml).unwrap_or_else(|e| panic!("{xml}: {e}"));
        let textured = match &b {
            haze_scene::Bsdf::RoughDielectric(r) => r.distr.fixed().is_none(),
            haze_scene::Bsdf::Conductor(c) => c.distr.as_ref().is_some_and(|d| d.fixed().is_none()),
            haze_scene::Bsdf::PPlastic(p) => p.distr.fixed().is_none(),
            _ => false,
        };
        assert!(textured, "{xml}: {b:?}");
        assert_eq!(b.is_anisotropic(), ty != "roughdielectric", "{xml}");
    }
    for (xml, want) in [
        (
            r#"<bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf>"#,
            "unknown conductor 'Unobtainium'",
        ),
        (
            r#"<bsdf type="conductor"><string name="material" value="Au"/><float name="eta" value="1"/></bsdf>"#,
            "either 'eta' and 'k' or 'material'",
        ),
        (r#"<bsdf type="conductor"><float name="k" value="-1"/></bsdf>"#, "'k' must lie in [0, 100]"),
        (
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="-0.2"/></bsdf>"#,
            "'alpha_v' must be > 0, got -0.2",
        ),
        (
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.2"/></bsdf>"#,
            "give either 'alpha' or 'alpha_u' and 'alpha_v', not both",
        ),
        (
            r#"<bsdf type="roughdielectric"><texture type="checkerboard" name="alpha"><float name="color1" value="-1"/></texture></bsdf>"#,
            "'alpha' must lie in [0, 100]",
        ),
        (
            r#"<bsdf type="roughplastic"><texture type="checkerboard" name="alpha"/></bsdf>"#,
            "does not take a texture 'alpha'",
        ),
        (
            r#"<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/></bsdf>"#,
            "unused parameter 'alpha_u'",
        ),
        (
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/></bsdf>"#,
            "'alpha_u' needs 'alpha_v' too",
        ),
        (r#"<bsdf type="roughconductor"><float name="alpha" value="0"/></bsdf>"#, "'alpha' must be > 0"),
        (r#"<bsdf type="conductor"><float name="alpha" value="0.1"/></bsdf>"#, "unused parameter 'alpha'"),
        (
            r#"<bsdf type="conductor"><rgb name="specular_reflectance" value="2"/></bsdf>"#,
            "'specular_reflectance' must lie in [0, 1]",
        ),
    ] {
        let e = bsdf_of(xml).err().unwrap_or_else(|| panic!("{xml} loaded"));
        assert!(e.message.contains(want), "{xml}: {e}");
        assert_eq!(e.line, 2, "{e}");
    }
}

/// A `bitmap` texture wherever a texture is taken, shared between references, with its
/// parameters checked and a missing file an error naming the element.
#[test]
fn bitmap_textures_load_png_and_check_their_parameters() {
    let dir = std::env::temp_dir().join(format!("haze-load-bitmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    image::RgbImage::from_fn(4, 2, |x, y| image::Rgb([(60 * x) as u8, (100 * y) as u8, 255]))
        .save(dir.join("tex.png"))
        .unwrap();
    let load_in = |body: &str| {
        let xml = format!("<scene version=\"3.0.0\">\n{SENSOR}{body}\n</scene>");
        load_str(&xml, &dir.join("s.xml"), &dir, &LoadOptions::default())
    };
    let s = load_in(
        r#"<texture type="bitmap" id="t"><string name="filename" value="tex.png"/><string name="filter_type" value="nearest"/>
             <string name="wrap_mode" value="clamp"/><boolean name="raw" value="true"/></texture>
           <shape type="sphere"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>
           <shape type="sphere"><bsdf type="roughconductor"><ref name="specular_reflectance" id="t"/></bsdf></shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let haze_scene::Bsdf::Diffuse { reflectance: haze_scene::Texture::Bitmap(a) } = &s.shapes[0].bsdf else {
        panic!("a bitmap")
    };
    let haze_scene::Bsdf::Conductor(c) = &s.shapes[1].bsdf else { panic!("a conductor") };
    let haze_scene::Texture::Bitmap(b) = &c.specular_reflectance else { panic!("a bitmap") };
    assert!(std::sync::Arc::ptr_eq(a, b), "one image for both references");
    let v = a.eval(glam::Vec2::new(0.9, 0.9));
    assert!(
        (v[0] - 180.0 / 255.0).abs() < 1e-6 && (v[1] - 100.0 / 255.0).abs() < 1e-6,
        "raw: the stored values, {v:?}"
    );
    for (xml, want) in [
        (r#"<string name="filename" value="missing.png"/>"#, "cannot read"),
        (
            r#"<string name="filename" value="tex.png"/><string name="wrap_mode" value="wrap"/>"#,
            "unknown wrap_mode 'wrap'",
        ),
        (
            r#"<string name="filename" value="tex.png"/><string name="filter_type" value="trilinear"/>"#,
            "unknown filter_type",
        ),
        (r#""#, "missing parameter 'filename'"),
    ] {
        let e = load_in(&format!(r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">{xml}</texture></bsdf></shape>"#))
            .err()
            .unwrap_or_else(|| panic!("{xml} loaded"));
        assert!(e.message.contains(want), "{xml}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `instance` places copies of a `shapegroup`'s shapes, each instance's `to_world` after the
/// shape's own; the group alone renders nothing.
#[test]
fn instances_place_copies_of_their_shapegroup() {
    let s = load(&format!(
        r#"{SENSOR}
        <shape type="shapegroup" id="g">
            <shape type="sphere"><float name="radius" value="0.5"/><transform name="to_world"><translate x="1"/></transform>
                <bsdf type="conductor"/></shape>
            <shape type="rectangle"/>
        </shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><scale value="2"/></transform></shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><translate y="5"/></transform></shape>"#
    ));
    assert_eq!(s.shapes.len(), 4);
    let centres: Vec<(glam::Vec3, f32)> = s
        .shapes
        .iter()
        .filter_map(|sh| match sh.geometry {
            haze_scene::Geometry::Sphere { center, radius, .. } => Some((center, radius)),
            _ => None,
        })
        .collect();
    assert_eq!(centres, vec![(glam::Vec3::new(2.0, 0.0, 0.0), 1.0), (glam::Vec3::new(1.0, 5.0, 0.0), 0.5)]);
    assert!(matches!(s.shapes[0].bsdf, haze_scene::Bsdf::Conductor(_)));
    assert!(s.shapes[2].name.contains("instance"), "{}", s.shapes[2].name);
    assert!(load(&format!(r#"{SENSOR}<shape type="shapegroup" id="g"><shape type="cube"/></shape>"#))
        .shapes
        .is_empty());
    for (xml, want) in [
        (
            r#"<shape type="shapegroup" id="g"><shape type="sphere"><emitter type="area"/></shape></shape>
            <shape type="instance"><ref id="g"/></shape>"#,
            "cannot emit",
        ),
        (r#"<shape type="instance"/>"#, "needs a <ref> to a shapegroup"),
        (
            r#"<shape type="sphere" id="s"/><shape type="instance"><ref id="s"/></shape>"#,
            "not a 'sphere' shape",
        ),
        (r#"<shape type="shapegroup" id="g"><shape type="shapegroup"/></shape>"#, "do not nest"),
        (
            r#"<shape type="shapegroup" id="g"><shape type="sphere"/></shape>
            <shape type="instance"><ref id="g"/><transform name="to_world"><scale x="2"/></transform></shape>"#,
            "may only rotate, translate and scale uniformly",
        ),
    ] {
        let e = error(&format!("{SENSOR}{xml}"));
        assert!(e.message.contains(want), "{xml}: {e}");
    }
}

/// `cylinder`: the open tube around `p0 p1`, tessellated finely: vertices on the surface,
/// outward normals and winding, and the area `2 pi r h` to the tessellation's accuracy.
#[test]
fn cylinders_are_open_tubes_around_their_axis() {
    let s = load(&format!(
        r#"{SENSOR}<shape type="cylinder"><point name="p0" value="1, 0, 0"/><point name="p1" x="1" y="0" z="2"/>
           <float name="radius" value="0.5"/></shape>"#
    ));
    let haze_scene::Geometry::Mesh(m) = &s.shapes[0].geometry else { panic!("a mesh") };
    let axis = |p: glam::Vec3| glam::Vec3::new(p.x - 1.0, p.y, 0.0);
    for p in &m.positions {
        assert!((axis(*p).length() - 0.5).abs() < 1e-5 && (-1e-6..=2.0 + 1e-6).contains(&p.z), "{p}");
    }
    let mut area = 0.0f64;
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        area += 0.5 * n.length() as f64;
        assert!(n.dot(axis((a + b + c) / 3.0)) > 0.0, "outward winding");
    }
    let want = 2.0 * std::f64::consts::PI * 0.5 * 2.0;
    assert!((area - want).abs() < 1e-4 * want, "{area} vs {want}");
    for (p, n) in m.positions.iter().zip(m.normals.as_ref().unwrap()) {
        assert!((*n - axis(*p) / 0.5).length() < 1e-4, "radial normals");
    }
    let e = error(&format!(r#"{SENSOR}<shape type="cylinder"><point name="p1" value="0, 0, 0"/></shape>"#));
    assert!(e.message.contains("'p0' and 'p1' must differ"), "{e}");
    let e = error(&format!(r#"{SENSOR}<shape type="cylinder"><float name="radius" value="0"/></shape>"#));
    assert!(e.message.contains("'radius' must be > 0"), "{e}");
}

/// A cylinder's `uv` is Mitsuba 3's (`u = phi / 2 pi` from the axis frame's `x`, `v` from `p0` to
/// `p1`): rays and the `uv` Mitsuba 3.9.1 (`scalar_rgb`, `ray_intersect`) reports for them, on
/// three cylinders under a rotation and a translation, one with its axis along `-z` (the other
/// branch of the frame) and one with its axis along `x` (`n.z = 0`). The tolerance covers the
/// tessellation and the rays' rounding to 4-6 digits.
#[test]
fn cylinder_uv_is_mitsubas() {
    /// A ray (origin, direction) and the uv Mitsuba reports at its hit.
    type Probe = ([f32; 3], [f32; 3], [f32; 2]);
    /// `p0`, `p1`, `radius` and four probes.
    type Case = ([f32; 3], [f32; 3], f32, [Probe; 4]);
    let cases: [Case; 3] = [
        (
            [0.3, -0.2, 0.5],
            [1.1, 0.7, -0.4],
            0.6,
            [
                ([1.1361, 1.445, -0.4033], [-0.172605, -0.844559, 0.50688], [0.31365, 0.18219]),
                ([1.3718, 5.6109, -1.2755], [-0.075818, -0.926396, 0.36884], [0.66680, 0.89617]),
                ([1.5529, -3.4719, 0.5763], [-0.06407, 0.997927, -0.006098], [0.15930, 0.36431]),
                ([-6.4737, -4.9082, -6.6736], [0.648281, 0.411107, 0.640877], [0.30807, 0.33744]),
            ],
        ),
        (
            [0.0, 0.0, 0.0],
            [0.0, 0.0, -1.0],
            1.0,
            [
                ([-4.6502, 0.3046, 6.0023], [0.634792, -0.006689, -0.772654], [0.54214, 0.49617]),
                ([-2.3159, 8.0017, 3.616], [0.251722, -0.910464, -0.328164], [0.62842, 0.40837]),
                ([-0.5051, 2.7316, 0.3009], [0.383442, -0.923215, 0.025436], [0.76261, 0.70634]),
                ([1.0626, -1.8532, 1.0761], [-0.550389, 0.790909, -0.26746], [0.23759, 0.20156]),
            ],
        ),
        (
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            0.5,
            [
                ([4.9611, 4.5809, -4.7941], [-0.512287, -0.586237, 0.627606], [0.96466, 0.34968]),
                ([-0.4867, -0.3891, 5.5281], [0.371508, 0.05249, -0.926945], [0.54463, 0.31634]),
                ([0.3652, 6.0941, -1.2121], [0.144747, -0.952859, 0.266662], [0.18782, 0.47110]),
                ([0.5769, -4.4563, 0.4539], [0.135084, 0.98958, 0.049831], [0.74743, 0.35386]),
            ],
        ),
    ];
    for (p0, p1, radius, probes) in cases {
        let [a, b, c] = p0;
        let [d, e, f] = p1;
        let s = load(&format!(
            r#"{SENSOR}<shape type="cylinder"><point name="p0" value="{a}, {b}, {c}"/>
               <point name="p1" value="{d}, {e}, {f}"/><float name="radius" value="{radius}"/>
               <transform name="to_world"><rotate y="1" angle="30"/><translate x="0.5" z="1"/></transform></shape>"#
        ));
        for (o, dir, want) in probes {
            let ray = haze_core::Ray::new(glam::Vec3::from(o), glam::Vec3::from(dir).normalize());
            let hit = s.intersect(&ray).unwrap_or_else(|| panic!("{p0:?} {p1:?}: {o:?} misses"));
            let du = (hit.uv.x - want[0]).abs();
            let du = du.min(1.0 - du);
            assert!(
                du < 2e-3 && (hit.uv.y - want[1]).abs() < 2e-3,
                "{p0:?} {p1:?}: uv {} vs Mitsuba's {want:?}",
                hit.uv
            );
        }
    }
}

#[test]
fn masks_wrap_one_bsdf_with_an_opacity() {
    let Ok(haze_scene::Bsdf::Mask(m)) = bsdf_of(
        r#"<bsdf type="mask"><float name="opacity" value="0.25"/><bsdf type="roughconductor"/></bsdf>"#,
    ) else {
        panic!("a mask")
    };
    assert_eq!(m.alpha(glam::Vec2::ZERO.into()), 0.25);
    assert!(matches!(*m.nested, haze_scene::Bsdf::Conductor(_)));
    let Ok(haze_scene::Bsdf::Mask(m)) = bsdf_of(r#"<bsdf type="mask"><bsdf type="diffuse"/></bsdf>"#) else {
        panic!("a mask")
    };
    assert_eq!(m.alpha(glam::Vec2::ZERO.into()), 0.5, "Mitsuba's default opacity");
    for (xml, want) in [
        (r#"<bsdf type="mask"/>"#, "a mask needs one nested or referenced <bsdf>"),
        (
            r#"<bsdf type="mask"><float name="opacity" value="1.5"/><bsdf type="diffuse"/></bsdf>"#,
            "'opacity' must lie in [0, 1]",
        ),
    ] {
        let e = bsdf_of(xml).err().unwrap_or_else(|| panic!("{xml} loaded"));
        assert!(e.message.contains(want), "{xml}: {e}");
    }
}

#[test]
fn pplastic_reads_mitsuba_parameters() {
    let Ok(haze_scene::Bsdf::PPlastic(b)) = bsdf_of(
        r#"<bsdf type="pplastic"><rgb name="diffuse_reflectance" value="0.05, 0.03, 0.1"/><float name="alpha" value="0.06"/></bsdf>"#,
    ) else {
        panic!("a pplastic")
    };
    let d = *b.distr.fixed().expect("fixed");
    assert_eq!((d.alpha_u, d.ty), (0.06, haze_scene::bsdf::MicrofacetType::Beckmann));
    assert!((b.eta - 1.49 / 1.000277).abs() < 1e-6, "polypropylene in air");
    let Ok(haze_scene::Bsdf::PPlastic(b)) =
        bsdf_of(r#"<bsdf type="pplastic"><float name="eta" value="1.3"/></bsdf>"#)
    else {
        panic!("a pplastic")
    };
    assert_eq!(b.eta, 1.3);
    let e = bsdf_of(
        r#"<bsdf type="pplastic"><float name="eta" value="1.3"/><float name="int_ior" value="1.5"/></bsdf>"#,
    )
    .expect_err("an error");
    assert!(e.message.contains("either 'eta' or 'int_ior'"), "{e}");
}

/// Mitsuba 3's samplers: their types, parameters and defaults, and the sample counts rounded as
/// Mitsuba 3.9.1 rounds them (and renders them).
#[test]
fn samplers_load_with_mitsuba_names_defaults_and_rounding() {
    use haze_core::SamplerKind;
    let sampler = |body: &str| load(&format!(r#"<sensor type="perspective">{body}</sensor>"#));
    let s = sampler(r#"<sampler type="stratified"><integer name="sample_count" value="10"/></sampler>"#);
    assert_eq!(
        (s.sampler.kind, s.spp, s.sampler.sample_count(), s.sampler.jitter),
        (SamplerKind::Stratified, 16, 16, true)
    );
    let s = sampler(
        r#"<sampler type="multijitter"><integer name="sample_count" value="10"/><boolean name="jitter" value="false"/></sampler>"#,
    );
    assert_eq!((s.sampler.kind, s.spp, s.sampler.jitter), (SamplerKind::Multijitter, 12, false));
    let s = sampler(
        r#"<sampler type="orthogonal"><integer name="sample_count" value="30"/><integer name="strength" value="2"/><integer name="seed" value="3"/></sampler>"#,
    );
    assert_eq!((s.sampler.kind, s.spp), (SamplerKind::Orthogonal, 49));
    let s = sampler(r#"<sampler type="ldsampler"/>"#);
    assert_eq!((s.sampler.kind, s.spp), (SamplerKind::LdSampler, 4));
    let s = sampler(r#"<sampler type="ldsampler"><integer name="sample_count" value="17"/></sampler>"#);
    assert_eq!(s.spp, 64);
    // No sampler: independent, 4 samples.
    let s = load(SENSOR);
    assert_eq!((s.sampler.kind, s.spp), (SamplerKind::Independent, 4));

    let e = error(
        r#"<sensor type="perspective"><sampler type="orthogonal"><integer name="strength" value="3"/></sampler></sensor>"#,
    );
    assert!(e.message.contains("orthogonal 'strength' 3 is not supported"), "{e}");
    // Mitsuba 3's ldsampler has no jitter (Mitsuba 3 reports it unreferenced too).
    let e = error(
        r#"<sensor type="perspective"><sampler type="ldsampler"><boolean name="jitter" value="false"/></sampler></sensor>"#,
    );
    assert!(e.message.contains("jitter"), "{e}");
    // Mitsuba 3.9 has no `sobol` sampler.
    let e = error(r#"<sensor type="perspective"><sampler type="sobol"/></sensor>"#);
    assert!(e.message.contains("sobol"), "{e}");
    let e = error(
        r#"<sensor type="perspective"><sampler type="stratified"><integer name="sample_count" value="-4"/></sampler></sensor>"#,
    );
    assert!(e.message.contains("'sample_count' must be > 0"), "{e}");
}

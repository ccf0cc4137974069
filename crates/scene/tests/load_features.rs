//! Loader behaviour on small inline scenes: Mitsuba 3 defaults, references, substitution,
//! includes and the translation of each plugin.

use glam::Vec3;
use haze_core::{Phase, Rgb};
use haze_scene::{load_file, load_str, Bsdf, Emitter, Geometry, LoadError, LoadOptions, Scene};
use std::path::{Path, PathBuf};

const SENSOR: &str = r#"<sensor type="perspective"/>"#;

fn load_with(body: &str, options: &LoadOptions) -> Result<Scene, LoadError> {
    let xml = format!("<scene version=\"3.0.0\">\n{body}\n</scene>");
    load_str(&xml, Path::new("inline.xml"), Path::new("."), options)
}

fn load(body: &str) -> Scene {
    load_with(body, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn expect_error(r: Result<Scene, LoadError>) -> LoadError {
    match r {
        Ok(_) => panic!("the scene loaded, but an error was expected"),
        Err(e) => e,
    }
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn mitsuba_defaults() {
    let s = load(&format!("{SENSOR}<shape type=\"sphere\"/>"));
    assert_eq!((s.camera.width, s.camera.height, s.spp), (768, 576, 4));
    assert_eq!((s.camera.near_clip, s.camera.far_clip), (0.01, 10000.0));
    assert_eq!(s.integrator, haze_scene::IntegratorSpec::default());
    // 50mm lens on the diagonal, film 4:3: tan(x/2) = tan(diag/2) * 4/5.
    let diag_half = (43.266_67f32 / 100.0).atan();
    let x = 2.0 * (diag_half.tan() * 0.8).atan().to_degrees();
    assert!((s.camera.fov_x_deg - x).abs() < 1e-3, "{}", s.camera.fov_x_deg);
    let sphere = &s.shapes[0];
    assert_eq!(sphere.bsdf, Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() });
    assert!(matches!(sphere.geometry, Geometry::Sphere { radius, center, flip_normals: false }
        if radius == 1.0 && center == Vec3::ZERO));
}

#[test]
fn references_may_point_forward_and_share_one_medium() {
    let s = load(&format!(
        r#"{SENSOR}
        <shape type="cube"><ref name="interior" id="fog"/><ref id="glass"/></shape>
        <shape type="sphere"><ref name="exterior" id="fog"/></shape>
        <medium type="homogeneous" id="fog"><float name="sigma_t" value="3"/></medium>
        <bsdf type="dielectric" id="glass">
            <string name="int_ior" value="water"/><float name="ext_ior" value="1"/>
        </bsdf>"#
    ));
    assert_eq!(s.media.len(), 1);
    assert_eq!(s.media[0].name, "fog");
    assert_eq!(s.media[0].as_homogeneous().unwrap().albedo, Rgb::splat(0.75));
    assert_eq!(s.media[0].phase, Phase::Isotropic);
    assert_eq!((s.shapes[0].interior, s.shapes[1].exterior), (Some(0), Some(0)));
    assert_eq!(s.shapes[0].bsdf, Bsdf::Dielectric { eta: 1.333 });
}

#[test]
fn nested_media_scale_and_float_spectra() {
    let s = load(
        r#"<sensor type="perspective">
            <medium type="homogeneous"><float name="sigma_t" value="0.5"/></medium>
        </sensor>
        <shape type="sphere">
            <medium type="homogeneous" name="interior">
                <rgb name="sigma_t" value="1, 2, 3"/>
                <float name="scale" value="2"/>
                <spectrum name="albedo" value="0.5"/>
                <phase type="hg"/>
                <boolean name="sample_emitters" value="true"/>
            </medium>
        </shape>"#,
    );
    assert_eq!(s.media.len(), 2);
    assert_eq!(s.camera.medium, Some(0));
    assert_eq!(s.media[0].as_homogeneous().unwrap().sigma_t, Rgb::splat(0.5));
    assert_eq!(s.media[1].as_homogeneous().unwrap().sigma_t, Rgb::new(2.0, 4.0, 6.0));
    assert_eq!(s.media[1].as_homogeneous().unwrap().albedo, Rgb::splat(0.5));
    assert_eq!(s.media[1].phase, Phase::HenyeyGreenstein { g: 0.8 });
    assert_eq!(s.shapes[0].interior, Some(1));
}

#[test]
fn defines_override_defaults() {
    let body = String::from(
        r#"<default name="spp" value="16"/><default name="r" value="2"/>
        <sensor type="perspective">
            <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        </sensor>
        <shape type="sphere"><float name="radius" value="$r"/></shape>"#,
    );
    assert_eq!(load(&body).spp, 16);
    let options = LoadOptions { defines: vec![("spp".into(), "3".into())] };
    let s = load_with(&body, &options).unwrap();
    assert_eq!(s.spp, 3);
    assert!(matches!(s.shapes[0].geometry, Geometry::Sphere { radius, .. } if radius == 2.0));
}

#[test]
fn sphere_to_world_and_disk() {
    let s = load(&format!(
        r#"{SENSOR}
        <shape type="sphere">
            <point name="center" x="1" y="0" z="0"/>
            <float name="radius" value="0.5"/>
            <boolean name="flip_normals" value="true"/>
            <transform name="to_world">
                <rotate z="1" angle="90"/><scale value="2"/><translate y="1"/>
            </transform>
        </shape>
        <shape type="disk"><transform name="to_world"><scale x="2"/></transform></shape>"#
    ));
    let Geometry::Sphere { center, radius, flip_normals } = s.shapes[0].geometry else { panic!("sphere") };
    // (1,0,0) -> rotate -> (0,1,0) -> scale -> (0,2,0) -> translate -> (0,3,0).
    assert!(close(center, Vec3::new(0.0, 3.0, 0.0)), "{center}");
    assert_eq!((radius, flip_normals), (1.0, true));
    let Geometry::Disk { to_world, .. } = s.shapes[1].geometry else { panic!("disk") };
    assert!(close(to_world.transform_point3(Vec3::X), Vec3::new(2.0, 0.0, 0.0)));
}

#[test]
fn emitters() {
    let s = load(&format!(
        r#"{SENSOR}
        <emitter type="point">
            <transform name="to_world"><translate x="1" y="2" z="3"/></transform>
            <float name="intensity" value="5"/>
        </emitter>
        <emitter type="spot"><rgb name="intensity" value="1, 2, 3"/></emitter>
        <emitter type="spot"><float name="cutoff_angle" value="40"/><float name="beam_width" value="10"/></emitter>
        <emitter type="constant"><spectrum name="radiance" value="0.25"/></emitter>
        <shape type="rectangle"><emitter type="area"/></shape>"#
    ));
    assert_eq!(
        s.emitters[0],
        Emitter::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Rgb::splat(5.0) }
    );
    let Emitter::Spot { intensity, cutoff_angle, beam_width, .. } = s.emitters[1] else { panic!("spot") };
    assert_eq!(intensity, Rgb::new(1.0, 2.0, 3.0));
    assert!((cutoff_angle - 20f32.to_radians()).abs() < 1e-6);
    assert!((beam_width - 15f32.to_radians()).abs() < 1e-6);
    let Emitter::Spot { cutoff_angle, beam_width, .. } = s.emitters[2] else { panic!("spot") };
    assert!((cutoff_angle - 40f32.to_radians()).abs() < 1e-6);
    assert!((beam_width - 10f32.to_radians()).abs() < 1e-6);
    assert_eq!(s.emitters[3], Emitter::Constant { radiance: Rgb::splat(0.25) });
    assert_eq!(s.emitters[4], Emitter::Area { shape: 0, radiance: Rgb::ONE.into() });
    assert_eq!(s.shapes[0].emitter, Some(4));
}

/// Mitsuba 3's `directional`: the travel direction from `direction` (normalised) or from
/// `to_world`'s local +z, +z by default; `irradiance` 1 by default.
#[test]
fn directional_emitter() {
    let s = load(&format!(
        r#"{SENSOR}
        <emitter type="directional">
            <vector name="direction" x="0" y="-2" z="0"/>
            <rgb name="irradiance" value="3, 2, 1"/>
        </emitter>
        <emitter type="directional">
            <transform name="to_world"><rotate x="1" angle="90"/></transform>
        </emitter>
        <emitter type="directional"/>"#
    ));
    let Emitter::Directional { d, irradiance } = s.emitters[0] else { panic!("directional") };
    assert!(close(d, Vec3::new(0.0, -1.0, 0.0)), "{d}");
    assert_eq!(irradiance, Rgb::new(3.0, 2.0, 1.0));
    // A rotation by 90 degrees about +x takes +z to -y.
    let Emitter::Directional { d, irradiance } = s.emitters[1] else { panic!("directional") };
    assert!(close(d, Vec3::new(0.0, -1.0, 0.0)), "{d}");
    assert_eq!(irradiance, Rgb::ONE);
    assert_eq!(s.emitters[2], Emitter::Directional { d: Vec3::Z, irradiance: Rgb::ONE });
    assert!(s.emitters.iter().all(|e| e.is_delta() && e.is_infinite() && !e.is_environment()));
}

#[test]
fn integrators_and_sensor_options() {
    let s = load(
        r#"<integrator type="vrl_lightcuts">
            <integer name="max_depth" value="3"/><boolean name="hide_emitters" value="true"/>
        </integrator>
        <sensor type="perspective">
            <float name="fov" value="30"/><string name="fov_axis" value="y"/>
            <float name="near_clip" value="0.5"/><float name="far_clip" value="50"/>
            <film type="hdrfilm">
                <integer name="width" value="200"/><integer name="height" value="100"/>
                <string name="pixel_format" value="rgba"/>
                <string name="component_format" value="float16"/>
                <boolean name="banner" value="false"/>
                <rfilter type="box"/>
            </film>
            <sampler type="independent">
                <integer name="sample_count" value="7"/><integer name="seed" value="3"/>
            </sampler>
        </sensor>"#,
    );
    assert_eq!(s.integrator.name, "vrl_lightcuts");
    assert_eq!((s.integrator.max_depth, s.integrator.rr_depth), (3, 5));
    assert!(s.integrator.hide_emitters);
    assert_eq!(s.spp, 7);
    let x = 2.0 * ((15f32).to_radians().tan() * 2.0).atan().to_degrees();
    assert!((s.camera.fov_x_deg - x).abs() < 1e-3);
    assert_eq!((s.camera.near_clip, s.camera.far_clip), (0.5, 50.0));
}

/// `banner` (Mitsuba 0.x) is read and ignored, as Mitsuba 3's hdrfilm does; it must still be
/// a boolean.
#[test]
fn film_banner_is_a_boolean_and_ignored() {
    let with = |v: &str| format!(r#"<sensor type="perspective"><film type="hdrfilm">{v}</film></sensor>"#);
    let s = load(&with(r#"<boolean name="banner" value="true"/>"#));
    assert_eq!((s.camera.width, s.camera.height), (768, 576));
    let e = expect_error(load_with(&with(r#"<string name="banner" value="yes"/>"#), &LoadOptions::default()));
    assert!(e.message.contains("wrong type for parameter 'banner': expected <boolean>"), "{e}");
    assert_eq!(e.line, 2, "{e}");
}

#[test]
fn includes_and_search_paths() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("xml-includes");
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::write(
        dir.join("parts/camera.xml"),
        r#"<scene version="3.0.0">
            <default name="res" value="20"/>
            <sensor type="perspective">
                <film type="hdrfilm"><integer name="width" value="$res"/></film>
            </sensor>
        </scene>"#,
    )
    .unwrap();
    std::fs::write(dir.join("parts/white.xml"), r#"<bsdf type="diffuse"/>"#).unwrap();
    std::fs::write(
        dir.join("main.xml"),
        r#"<scene version="3.0.0">
            <include filename="parts/camera.xml"/>
            <shape type="sphere"><include filename="parts/white.xml"/></shape>
        </scene>"#,
    )
    .unwrap();
    let s = load_file(&dir.join("main.xml"), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.camera.width, 20);
    assert_eq!(s.shapes[0].bsdf, Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() });

    // A file including itself.
    std::fs::write(dir.join("loop.xml"), r#"<scene version="3.0.0"><include filename="loop.xml"/></scene>"#)
        .unwrap();
    let e = expect_error(load_file(&dir.join("loop.xml"), &LoadOptions::default()));
    assert!(e.message.contains("recursively"), "{e}");
}

#[test]
fn spectra_as_wavelength_lists_and_filters() {
    let s = load(
        r#"<sensor type="perspective"><film type="hdrfilm"><rfilter type="tent"/></film></sensor>
        <shape type="sphere"><emitter type="area">
            <spectrum name="radiance" value="400:0, 500:0.3, 600:0.8, 700:1.1"/></emitter></shape>
        <emitter type="constant"><spectrum name="radiance" value="0.25"/></emitter>"#,
    );
    let Emitter::Area { radiance: haze_scene::texture::Texture::Constant(radiance), .. } = s.emitters[0]
    else {
        panic!("area emitter expected")
    };
    // Mitsuba 3's rgb variants give this triple for the same spectrum (peer README).
    let expected = [1.12687, 0.488194, 0.0880343];
    for (got, want) in radiance.0.iter().zip(expected) {
        assert!((got - want).abs() < 1e-4, "{radiance}");
    }
    assert_eq!(s.emitters[1], Emitter::Constant { radiance: Rgb::splat(0.25) });
    assert_eq!(s.camera.filter, haze_scene::camera::PixelFilter::Tent { radius: 1.0 });
    // No <rfilter>: Mitsuba 3's gaussian.
    let d = load(&format!("{SENSOR}<shape type=\"sphere\"/>"));
    assert_eq!(d.camera.filter, haze_scene::camera::PixelFilter::Gaussian { stddev: 0.5 });
}

#[test]
fn mesh_files_with_normals_and_flipped_tex_coords() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("xml-meshes");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("quad.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n\
         o a\nf 1/1/1 2/2/1 3/3/1 4/4/1\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n\
         property double z\nproperty float nx\nproperty float ny\nproperty float nz\n\
         property float s\nproperty float t\nelement face 1\nproperty list uchar uint vertex_index\n\
         end_header\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n",
    )
    .unwrap();
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"/>
        <shape type="obj"><string name="filename" value="quad.obj"/>
            <transform name="to_world"><scale x="2" y="1" z="1"/></transform></shape>
        <shape type="ply"><string name="filename" value="tri.ply"/>
            <transform name="to_world"><scale x="1" y="1" z="-3"/></transform></shape>
        <shape type="obj"><string name="filename" value="quad.obj"/>
            <boolean name="face_normals" value="true"/>
            <boolean name="flip_tex_coords" value="false"/></shape>
    </scene>"#;
    let s =
        load_str(xml, Path::new("m.xml"), &dir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let mesh = |i: usize| match &s.shapes[i].geometry {
        Geometry::Mesh(m) => m.clone(),
        _ => panic!("mesh"),
    };
    let quad = mesh(0);
    assert_eq!((quad.positions.len(), quad.indices.len()), (4, 2));
    assert!(quad.positions.iter().any(|p| close(*p, Vec3::new(2.0, 1.0, 0.0))));
    assert!(quad.normals.unwrap().iter().all(|n| close(*n, Vec3::Z)));
    // OBJ texture coordinates are flipped vertically by default, as in Mitsuba 3.
    assert!(quad.uvs.unwrap().iter().any(|uv| uv.y == 1.0 - 0.0));
    let tri = mesh(1);
    // Normals transform with the inverse transpose: z scaled by -3 -> normal -z.
    assert!(tri.normals.unwrap().iter().all(|n| close(*n, Vec3::NEG_Z)));
    assert_eq!(tri.uvs.unwrap()[2], glam::Vec2::new(0.0, 1.0));
    let plain = mesh(2);
    assert!(plain.normals.is_none());
    assert!(plain.uvs.unwrap().iter().any(|uv| uv.x == 0.0 && uv.y == 0.0));
}

/// `load_file_with_sources` lists the main file, its includes and its mesh files, each once
/// (a mesh used twice is listed once): what a worker on another machine needs.
#[test]
fn sources_list_every_file_read() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("xml-sources");
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::write(dir.join("parts/quad.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        dir.join("parts/camera.xml"),
        r#"<scene version="3.0.0"><sensor type="perspective"/></scene>"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("main.xml"),
        r#"<scene version="3.0.0">
            <include filename="parts/camera.xml"/>
            <shape type="obj"><string name="filename" value="parts/quad.obj"/></shape>
            <shape type="obj"><string name="filename" value="parts/quad.obj"/></shape>
        </scene>"#,
    )
    .unwrap();
    let main = dir.join("main.xml");
    let (s, files) =
        haze_scene::load_file_with_sources(&main, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 2);
    assert_eq!(files, vec![main.clone(), dir.join("parts/camera.xml"), dir.join("parts/quad.obj")]);
}

/// `projector` (Mitsuba 3's names and defaults) and its errors, each naming the parameter.
#[test]
fn projector_parameters_and_errors() {
    use haze_scene::emitter::Emitter;
    let with =
        |body: &str| format!("<sensor type=\"perspective\"/>\n<emitter type=\"projector\">{body}</emitter>");
    let s = load(&with(r#"<float name="fov" value="90"/><float name="scale" value="2"/>"#));
    let Emitter::Projector(p) = &s.emitters[0] else { panic!("a projector") };
    assert!((p.tan_x - 1.0).abs() < 1e-6 && (p.tan_y - 1.0).abs() < 1e-6 && p.scale == 2.0);
    assert_eq!(p.irradiance, Rgb::ONE.into());
    for (body, want) in [
        (r#"<float name="scale" value="-1"/>"#, "'scale' must be >= 0, got -1"),
        (r#"<float name="fov" value="180"/>"#, "'fov' must be in (0, 180) degrees"),
        (r#"<rgb name="irradiance" value="-1"/>"#, "'irradiance' must lie in [0,"),
        (
            r#"<transform name="to_world"><scale value="0"/></transform>"#,
            "the projector's to_world is singular",
        ),
        (r#"<float name="cutoff_angle" value="20"/>"#, "unused parameter 'cutoff_angle'"),
    ] {
        let e = expect_error(load_with(&with(body), &LoadOptions::default()));
        assert!(e.message.contains(want), "{body}: {e}");
        assert_eq!(e.line, 3, "{body}: {e}");
    }
}

/// An `area` emitter's `radiance` as a texture (nested or `<ref>`), and its errors, each naming
/// the parameter and its line; a texture stays refused where an emitter takes none.
#[test]
fn textured_area_radiance_and_errors() {
    use haze_scene::texture::Texture;
    let with = |body: &str| {
        format!(
            "<sensor type=\"perspective\"/>\n<texture type=\"checkerboard\" id=\"c\"/>\n<shape type=\"rectangle\"><emitter type=\"area\">\n{body}</emitter></shape>"
        )
    };
    let radiance = |s: &Scene| match &s.emitters[0] {
        Emitter::Area { radiance, .. } => radiance.clone(),
        e => panic!("an area emitter, not {e:?}"),
    };
    let s = load(&with(
        r#"<texture type="checkerboard" name="radiance"><rgb name="color0" value="5, 4, 3"/></texture>"#,
    ));
    let Texture::Checkerboard { color0, .. } = radiance(&s) else { panic!("a checkerboard") };
    assert_eq!(color0, Rgb::new(5.0, 4.0, 3.0), "emitted radiance is not limited to [0, 1]");
    assert!(matches!(
        radiance(&load(&with(r#"<ref name="radiance" id="c"/>"#))),
        Texture::Checkerboard { .. }
    ));
    assert_eq!(radiance(&load(&with(r#"<rgb name="radiance" value="2"/>"#))), Rgb::splat(2.0).into());
    assert_eq!(radiance(&load(&with(""))), Rgb::ONE.into());
    for (body, want, line) in [
        (
            r#"<texture type="checkerboard" name="radiance"><rgb name="color1" value="-1"/></texture>"#,
            "'radiance' must lie in [0,",
            4, // the emitter's line: the texture's values are checked where it is used
        ),
        (r#"<rgb name="radiance" value="-1"/>"#, "'radiance' must not be negative", 5),
        (
            r#"<rgb name="radiance" value="1"/><texture type="checkerboard" name="radiance"/>"#,
            "'radiance' is given more than once",
            5,
        ),
        (
            r#"<texture type="checkerboard" name="irradiance"/>"#,
            "<emitter type=\"area\"> does not take a texture 'irradiance' (texture parameters: radiance)",
            5,
        ),
    ] {
        let e = expect_error(load_with(&with(body), &LoadOptions::default()));
        assert!(e.message.contains(want), "{body}: {e}");
        assert_eq!(e.line, line, "{body}: {e}");
    }
    // Emitters without a texture parameter keep refusing one, naming the emitter.
    for (emitter, param) in [("constant", "radiance"), ("point", "intensity"), ("directional", "irradiance")]
    {
        let xml = format!(
            "<sensor type=\"perspective\"/>\n<emitter type=\"{emitter}\">\n<texture type=\"checkerboard\" name=\"{param}\"/></emitter>"
        );
        let e = expect_error(load_with(&xml, &LoadOptions::default()));
        let want = format!("<emitter type=\"{emitter}\"> does not take a nested <texture>");
        assert!(e.message.contains(&want), "{emitter}: {e}");
        assert_eq!(e.line, 4, "{emitter}: {e}");
    }
}

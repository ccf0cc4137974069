//! The peer scenes load as their READMEs describe them (files by others: includes from a
//! subdirectory, `<path>`, `$integrator` from an included `<default>`, PLY and OBJ meshes).

use super::peers;
use glam::Vec3;
use haze_core::Rgb;
use haze_scene::{load_file, load_str, Bsdf, Emitter, Geometry, LoadOptions, Scene, Texture};
use std::path::Path;

const MEDIA_TESTS: &str = "mitsuba3-media-tests/tests/scenes/participating_media";

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

fn close_f(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-5
}

/// A Mitsuba 3 test scene (includes from a subdirectory, `<path>`, `$integrator` from an
/// included `<default>`): everything up to its `envmap` is understood.
#[test]
fn mitsuba_test_scene_loads_with_envmap_and_moment() {
    let Some(path) = peers(&format!("{MEDIA_TESTS}/test_homo_spectral_sigmat_volpathmis.xml")) else {
        return;
    };
    let s = load_file(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    // `moment` wraps `$integrator` = volpathmis with the base file's max_depth.
    assert_eq!(
        (s.integrator.name.as_str(), s.integrator.max_depth, s.integrator.rr_depth),
        ("volpathmis", 6, 5)
    );
    assert!(matches!(s.emitters[0], Emitter::EnvMap(_)), "{:?}", s.emitters.len());
    assert_eq!(s.camera.filter, haze_scene::camera::PixelFilter::Box);
    assert!((s.camera.fov_x_deg - 34.0221).abs() < 1e-3);
}

/// The BSDFs of Mitsuba 3's media test scenes that use the new plugins load as the peer
/// README describes them (ball and pedestal first, in file order).
#[test]
fn mitsuba_media_test_scene_bsdfs() {
    let Some(dir) = peers(MEDIA_TESTS) else { return };
    let load = |name: &str| load_file(&dir.join(name), &LoadOptions::default());
    let s = load("test_surf_area_light_volpath.xml").unwrap_or_else(|e| panic!("{e}"));
    let kinds: Vec<&Bsdf> = s.shapes.iter().map(|sh| &sh.bsdf).collect();
    assert!(kinds.iter().any(|b| matches!(b, Bsdf::Plastic(p) if p.diffuse_reflectance == Texture::Constant(Rgb::new(0.5, 0.3, 0.2)))));
    assert!(kinds.iter().any(|b| matches!(b, Bsdf::RoughPlastic(_))));
    assert!(kinds.iter().any(|b| matches!(b, Bsdf::Diffuse { reflectance: Texture::Checkerboard { .. } })));
    for name in [
        "test_homo_area_light_volpath.xml",
        "test_homo_emitter_inside_medium_volpath.xml",
        "test_homo_obj_inside_medium_volpath.xml",
        "test_homo_roughdielectric_spot_volpath.xml",
    ] {
        let s = load(name).unwrap_or_else(|e| panic!("{e}"));
        let has = |f: &dyn Fn(&Bsdf) -> bool| s.shapes.iter().any(|sh| f(&sh.bsdf));
        match name {
            "test_homo_roughdielectric_spot_volpath.xml" => {
                assert!(has(
                    &|b| matches!(b, Bsdf::RoughDielectric(r) if close_f(r.eta, 1.29964) && r.distr.fixed().is_some_and(|d| d.alpha_u == 0.3))
                ))
            }
            _ => {
                assert!(
                    has(&|b| matches!(b, Bsdf::ThinDielectric { eta } if close_f(*eta, 1.33263))),
                    "{name}"
                )
            }
        }
    }
}

/// An inline scene with one mesh shape whose file name is relative to the peers directory.
fn mesh_scene(peers_dir: &Path, shape: &str) -> Result<Scene, haze_scene::LoadError> {
    let xml = format!(
        r#"<scene version="3.0.0">
            <sensor type="perspective"/>
            {shape}
        </scene>"#
    );
    load_str(&xml, Path::new("inline.xml"), peers_dir, &LoadOptions::default())
}

#[test]
fn teapot_ply() {
    let Some(dir) = peers("") else { return };
    let s = mesh_scene(
        &dir,
        r#"<shape type="ply">
             <string name="filename"
                     value="mi3-phase-trampoline-teapot/resources/data/common/meshes/teapot.ply"/>
             <transform name="to_world"><translate x="10"/></transform>
           </shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let Geometry::Mesh(m) = &s.shapes[0].geometry else { panic!("ply is a mesh") };
    assert_eq!(m.positions.len(), 1177);
    assert_eq!(m.indices.len(), 2256);
    // First vertex of the file is (1.38137, 0, 2.45469), moved by the translation.
    assert!(close(m.positions[0], Vec3::new(11.38137, 0.0, 2.45469)));
    assert_eq!(s.shapes[0].bsdf, Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() });
}

#[test]
fn sphere_obj() {
    let Some(dir) = peers("") else { return };
    let s = mesh_scene(
        &dir,
        r#"<shape type="obj">
             <string name="filename"
                     value="mitsuba3-media-tests/tests/scenes/participating_media/meshes/sphere_tiny.obj"/>
             <transform name="to_world"><scale value="2"/></transform>
           </shape>"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let Geometry::Mesh(m) = &s.shapes[0].geometry else { panic!("obj is a mesh") };
    assert_eq!(m.indices.len(), 3072);
    // The file's bounding box, scaled by 2.
    let lo = m.positions.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
    let hi = m.positions.iter().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
    assert!(close(lo, 2.0 * Vec3::new(-0.757253, -0.861576, -0.757253)));
    assert!(close(hi, 2.0 * Vec3::new(0.757253, 0.65293, 0.757253)));
    assert!(m.uvs.is_some());
    if let Some(n) = &m.normals {
        assert_eq!(n.len(), m.positions.len());
        assert!(n.iter().all(|n| (n.length() - 1.0).abs() < 1e-4 || *n == Vec3::ZERO));
    }
}

/// A Mitsuba 3 test scene written by others: volpathmis, constant emitter, PLY with a nested
/// interior medium.
#[test]
fn peer_teapot_scene() {
    let Some(path) = peers("mi3-phase-trampoline-teapot/small.xml") else { return };
    let s = load_file(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.integrator.name, "volpathmis");
    assert_eq!(s.emitters, vec![Emitter::Constant { radiance: Rgb::ONE }]);
    assert_eq!(s.shapes[0].interior, Some(0));
    assert_eq!(s.media[0].as_homogeneous().unwrap().albedo, Rgb::new(0.99, 0.4, 0.4));
    assert_eq!((s.camera.width, s.camera.height, s.spp), (32, 32, 8));
}

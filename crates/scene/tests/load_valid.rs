//! The validation scenes (`tests/data/validation`) load with the expected contents. The peer
//! scenes' loading tests (real PLY and OBJ files by others) are in `crates/render/tests/peers/`.

use glam::Vec3;
use haze_core::{Phase, Rgb};
use haze_scene::{load_file, Bsdf, Emitter, Geometry, LoadOptions, Scene};
use haze_testkit::data::validation_scene;

fn load(name: &str) -> Scene {
    load_file(&validation_scene(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn hg_box() {
    let s = load("hg-box");
    assert_eq!(s.integrator.name, "volpath");
    assert_eq!((s.integrator.max_depth, s.integrator.rr_depth), (200, 100));
    assert_eq!(s.spp, 64);
    assert_eq!((s.camera.width, s.camera.height), (128, 96));
    assert_eq!(s.camera.fov_x_deg, 40.0);
    assert_eq!(s.camera.medium, None);
    assert!(close(s.camera.position(), Vec3::new(3.0, 2.0, 4.0)));

    assert_eq!(s.media.len(), 1);
    let m = &s.media[0];
    assert_eq!(m.name, "haze");
    let h = m.as_homogeneous().expect("a homogeneous medium");
    assert_eq!(h.sigma_t, Rgb::splat(2.0));
    assert_eq!(h.albedo, Rgb::new(0.9, 0.8, 0.7));
    assert_eq!(m.phase, Phase::HenyeyGreenstein { g: 0.5 });

    assert_eq!(s.shapes.len(), 2);
    let cube = &s.shapes[0];
    assert!(matches!(&cube.geometry, Geometry::Mesh(m) if m.indices.len() == 12));
    assert_eq!(cube.bsdf, Bsdf::Null);
    assert_eq!((cube.interior, cube.exterior, cube.emitter), (Some(0), None, None));
    let floor = &s.shapes[1];
    assert_eq!(floor.bsdf, Bsdf::Diffuse { reflectance: Rgb::ZERO.into() });
    // The floor is the rectangle scaled by 4 and rotated -90 deg about x: y = 0, normal +y.
    let Geometry::Mesh(f) = &floor.geometry else { panic!("rectangle is a mesh") };
    assert!(f.positions.iter().all(|p| p.y.abs() < 1e-5 && p.x.abs() <= 4.0 + 1e-5));
    assert!(close(f.face_normal(0), Vec3::Y));

    assert_eq!(
        s.emitters,
        vec![Emitter::Point { position: Vec3::new(-1.2, 2.4, 0.6), intensity: Rgb::splat(40.0) }]
    );
}

#[test]
fn foggy_room() {
    let s = load("foggy-room");
    assert_eq!(s.media.len(), 1);
    assert_eq!(s.media[0].as_homogeneous().unwrap().sigma_t, Rgb::splat(0.8));
    assert_eq!(s.media[0].as_homogeneous().unwrap().albedo, Rgb::splat(0.95));
    assert_eq!(s.media[0].phase, Phase::Isotropic);
    assert_eq!(s.camera.medium, Some(0));
    assert_eq!(s.camera.fov_x_deg, 60.0);

    assert_eq!(s.shapes.len(), 2);
    assert_eq!(s.shapes[0].interior, Some(0));
    let light = &s.shapes[1];
    assert_eq!((light.exterior, light.emitter), (Some(0), Some(0)));
    assert_eq!(s.emitters, vec![Emitter::Area { shape: 1, radiance: Rgb::splat(40.0).into() }]);
    // The light faces down (rotated +90 deg about x), just below the ceiling.
    let Geometry::Mesh(m) = &light.geometry else { panic!("rectangle is a mesh") };
    assert!(close(m.face_normal(0), Vec3::NEG_Y));
    assert!(m.positions.iter().all(|p| (p.y - 2.45).abs() < 1e-5));
}

//! The validation scenes and real mesh files load with the expected contents.

use glam::Vec3;
use haze_core::{Phase, Rgb};
use haze_scene::{load_file, load_str, Bsdf, Emitter, Geometry, LoadOptions, Scene};
use std::path::{Path, PathBuf};

const SHARED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared");

fn shared(rel: &str) -> PathBuf {
    Path::new(SHARED).join(rel)
}

fn load(rel: &str) -> Scene {
    let path = shared(rel);
    load_file(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn hg_box() {
    let s = load("validation/scenes/hg-box.xml");
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
    assert_eq!(m.sigma_t, Rgb::splat(2.0));
    assert_eq!(m.albedo, Rgb::new(0.9, 0.8, 0.7));
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
    let s = load("validation/scenes/foggy-room.xml");
    assert_eq!(s.media.len(), 1);
    assert_eq!(s.media[0].sigma_t, Rgb::splat(0.8));
    assert_eq!(s.media[0].albedo, Rgb::splat(0.95));
    assert_eq!(s.media[0].phase, Phase::Isotropic);
    assert_eq!(s.camera.medium, Some(0));
    assert_eq!(s.camera.fov_x_deg, 60.0);

    assert_eq!(s.shapes.len(), 2);
    assert_eq!(s.shapes[0].interior, Some(0));
    let light = &s.shapes[1];
    assert_eq!((light.exterior, light.emitter), (Some(0), Some(0)));
    assert_eq!(s.emitters, vec![Emitter::Area { shape: 1, radiance: Rgb::splat(40.0) }]);
    // The light faces down (rotated +90 deg about x), just below the ceiling.
    let Geometry::Mesh(m) = &light.geometry else { panic!("rectangle is a mesh") };
    assert!(close(m.face_normal(0), Vec3::NEG_Y));
    assert!(m.positions.iter().all(|p| (p.y - 2.45).abs() < 1e-5));
}

fn mesh_scene(shape: &str) -> Result<Scene, haze_scene::LoadError> {
    let xml = format!(
        r#"<scene version="3.0.0">
            <sensor type="perspective"/>
            {shape}
        </scene>"#
    );
    load_str(&xml, Path::new("inline.xml"), Path::new(SHARED), &LoadOptions::default())
}

#[test]
fn teapot_ply() {
    let s = mesh_scene(
        r#"<shape type="ply">
             <string name="filename"
                     value="peers/mi3-phase-trampoline-teapot/resources/data/common/meshes/teapot.ply"/>
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
    let s = mesh_scene(
        r#"<shape type="obj">
             <string name="filename"
                     value="peers/mitsuba3-media-tests/tests/scenes/participating_media/meshes/sphere_tiny.obj"/>
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
    let s = load("peers/mi3-phase-trampoline-teapot/small.xml");
    assert_eq!(s.integrator.name, "volpathmis");
    assert_eq!(s.emitters, vec![Emitter::Constant { radiance: Rgb::ONE }]);
    assert_eq!(s.shapes[0].interior, Some(0));
    assert_eq!(s.media[0].albedo, Rgb::new(0.99, 0.4, 0.4));
    assert_eq!((s.camera.width, s.camera.height, s.spp), (32, 32, 8));
}

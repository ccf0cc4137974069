//! The path walker (`haze_render::walker`) on a tiny scene built in code: a cube `[-1, 1]^3`
//! behind a `null` boundary holding a homogeneous medium, under an environment.

use glam::{Mat4, Vec3};
use haze_core::{Phase, Ray, Rgb, Sampler};
use haze_render::walker::Walker;
use haze_scene::shape::cube_mesh;
use haze_scene::{Bsdf, Camera, Emitter, Flight, Geometry, IntegratorSpec, Medium, Scene, Shape};

fn slab(sigma_t: Rgb) -> Scene {
    let camera = Camera::pinhole(Mat4::IDENTITY, 30.0, (4, 4));
    let shape = Shape {
        name: "slab".into(),
        geometry: Geometry::Mesh(cube_mesh(&Mat4::IDENTITY, false)),
        bsdf: Bsdf::Null,
        interior: Some(0),
        exterior: None,
        emitter: None,
    };
    Scene::new(
        None,
        camera,
        1,
        IntegratorSpec::default(),
        vec![shape],
        vec![Medium::homogeneous("m".into(), sigma_t, Rgb::ONE, Phase::Isotropic)],
        vec![Emitter::Constant { radiance: Rgb::ONE }],
    )
}

/// Legs through the medium: the walker enters the cube at its null face (medium 0 beyond),
/// crosses it with Beer-Lambert transmittance `exp(-sigma_t L)`, `L` the cube's width 2, leaves it (no medium) and
/// escapes; every step counts one vertex.
#[test]
fn legs_cross_null_boundaries_with_beer_lambert() {
    let sigma_t = Rgb::new(0.25, 1.0, 2.0);
    let scene = slab(sigma_t);
    let mut s = Sampler::new(1, 0, 0);
    let mut w = Walker::new(Ray::new(Vec3::new(0.2, 0.1, -5.0), Vec3::Z), None);
    let mut beta = Rgb::ONE;
    let mut media = Vec::new();
    let mut inside = 0.0;
    while w.next_vertex() {
        let leg = w.trace_leg(&scene);
        beta *= w.transmittance(&scene, leg.t_surface, &mut s);
        if w.medium.is_some() {
            inside += leg.t_surface;
        }
        let Some(h) = leg.hit.map(|h| scene.interaction(&h)) else { break };
        assert!(w.cross_if_null(&scene, &h), "the cube's faces are null");
        media.push(w.medium);
    }
    assert_eq!(media, vec![Some(0), None]);
    // The cube's width, within the ray offsets at the crossings (`offset_origin`).
    assert!((inside - 2.0).abs() < 1e-3, "{inside}");
    let want = sigma_t.exp_neg(inside);
    for c in 0..3 {
        assert!((beta[c] - want[c]).abs() < 1e-6 * want[c], "channel {c}: {} vs {}", beta[c], want[c]);
    }
}

/// Free flights: from the cube's centre along +z with grey `sigma_t = 1`, a leg scatters before
/// the face at distance 1 with probability `1 - exp(-1)` (within 4 binomial standard errors of
/// 20,000 legs), at a distance inside the cube; the others pass with weight 1 and reach the
/// face.
#[test]
fn sampled_legs_scatter_with_the_free_flight_probability() {
    let scene = slab(Rgb::ONE);
    let mut s = Sampler::new(5, 0, 0);
    let n = 20_000;
    let mut scattered = 0;
    for _ in 0..n {
        let mut w = Walker::new(Ray::new(Vec3::ZERO, Vec3::Z), Some(0));
        let (leg, flight) = w.sample_leg(&scene, 0, &mut s, |_| {});
        match flight.expect("in a medium") {
            Flight::Scatter { t, .. } => {
                assert!(t > 0.0 && t < 1.0, "t {t}");
                scattered += 1;
            }
            Flight::Pass { weight, .. } => {
                assert!((weight - Rgb::ONE).max_component().abs() < 1e-6, "{weight:?}");
                assert!((leg.t_surface - 1.0).abs() < 1e-5, "{}", leg.t_surface);
            }
        }
    }
    let p = 1.0 - (-1.0f64).exp();
    let got = scattered as f64 / n as f64;
    let se = (p * (1.0 - p) / n as f64).sqrt();
    assert!((got - p).abs() < 4.0 * se, "{got} vs {p}");
}

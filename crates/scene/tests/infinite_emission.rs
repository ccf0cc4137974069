//! Light paths from emitters at infinity (`docs/theory.md` §13, (T38)): the flux that light
//! tracing delivers onto a sphere inside the scene equals the analytic value `pi a^2 Int L dw`
//! (constant, envmap) or `pi a^2 E` (directional), per emitter and through the power-weighted
//! emitter choice, within a z-test; a flux off by 10% (a control) fails the same test.

use glam::{Mat4, Vec2, Vec3};
use haze_core::{Ray, Rgb, Sampler, PI};
use haze_scene::shape::analytic::intersect_sphere;
use haze_scene::{load_str, EnvMap, IntegratorSpec, LoadOptions, Scene};
use std::path::Path;
use std::sync::Arc;

/// The target sphere (inside the scene) and a second one that widens the bounding sphere.
const TARGET: (Vec3, f32) = (Vec3::new(0.4, 0.2, -0.3), 0.6);

fn scene(emitters: Vec<haze_scene::Emitter>) -> Scene {
    let xml = r#"<scene version="3.0.0">
        <sensor type="perspective"/>
        <shape type="sphere"><point name="center" x="0.4" y="0.2" z="-0.3"/><float name="radius" value="0.6"/></shape>
        <shape type="sphere"><point name="center" x="-2" y="1" z="1.5"/><float name="radius" value="0.3"/></shape>
    </scene>"#;
    let s = load_str(xml, Path::new("spheres.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    Scene::new(
        None,
        s.camera.clone(),
        1,
        IntegratorSpec::default(),
        s.shapes.clone(),
        s.media.clone(),
        emitters,
    )
}

/// A 16 x 9 map: a dim gradient sky with a bright 2 x 1 pixel sun, rotated off the axes.
fn envmap() -> EnvMap {
    let (w, h) = (16usize, 9usize);
    let mut rgb = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let sun = (x == 5 || x == 6) && y == 2;
            let c =
                if sun { [40.0, 35.0, 30.0] } else { [0.1 + 0.05 * y as f32, 0.2, 0.3 + 0.02 * x as f32] };
            rgb.extend_from_slice(&c);
        }
    }
    EnvMap::new(w, h, &rgb, 1.0, Mat4::from_rotation_y(0.7) * Mat4::from_rotation_x(0.3)).unwrap()
}

/// `Int L dw` of the map by the midpoint rule on a fine (theta, phi) grid.
fn envmap_integral(map: &EnvMap) -> [f64; 3] {
    let (nt, np) = (1200, 2400);
    let mut sum = [0.0f64; 3];
    for i in 0..nt {
        let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::PI;
        let dw = (std::f64::consts::PI / nt as f64) * (2.0 * std::f64::consts::PI / np as f64) * theta.sin();
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                theta.cos() as f32,
                (theta.sin() * phi.sin()) as f32,
            );
            let l = map.eval(d);
            for c in 0..3 {
                sum[c] += l[c] as f64 * dw;
            }
        }
    }
    sum
}

/// Mean and standard error, per channel, of the flux the samples deliver onto the target.
fn flux_on_target(
    n: usize,
    seed: u64,
    mut sample: impl FnMut(Vec2, Vec2, f32) -> Option<(Vec3, Vec3, Rgb)>,
) -> [(f64, f64); 3] {
    let mut s = Sampler::from_seed(seed);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        let (u_sel, u_pos, u_dir) = (s.next_1d(), s.next_2d(), s.next_2d());
        let Some((o, d, w)) = sample(u_pos, u_dir, u_sel) else { continue };
        assert!(w.is_finite() && w.min_component() >= 0.0, "weight {w:?}");
        if intersect_sphere(&Ray::new(o, d), TARGET.0, TARGET.1).is_some() {
            for c in 0..3 {
                sum[c] += w[c] as f64;
                sum2[c] += (w[c] as f64).powi(2);
            }
        }
    }
    std::array::from_fn(|c| {
        let mean = sum[c] / n as f64;
        (mean, ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt())
    })
}

fn z_scores(got: [(f64, f64); 3], want: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| (got[c].0 - want[c]) / got[c].1.max(1e-12 * want[c]))
}

#[test]
fn light_paths_from_infinity_deliver_the_analytic_flux() {
    use haze_scene::Emitter;
    let map = envmap();
    let integral = envmap_integral(&map);
    let sky = Rgb::new(0.2, 0.3, 0.4);
    let sun = Rgb::new(2.0, 1.5, 0.8);
    let emitters = vec![
        Emitter::Constant { radiance: sky },
        Emitter::Directional { d: Vec3::new(0.3, -1.0, 0.2).normalize(), irradiance: sun },
        Emitter::EnvMap(Arc::new(map)),
    ];
    let sc = scene(emitters);
    let cross = PI as f64 * (TARGET.1 as f64).powi(2);
    let want: [[f64; 3]; 3] = [
        std::array::from_fn(|c| cross * 4.0 * std::f64::consts::PI * sky[c] as f64),
        std::array::from_fn(|c| cross * sun[c] as f64),
        std::array::from_fn(|c| cross * integral[c]),
    ];
    let n = 300_000;
    for (k, want) in want.iter().enumerate() {
        let got =
            flux_on_target(n, 7 + k as u64, |u_pos, u_dir, _| sc.sample_infinite_emission(k, u_pos, u_dir));
        let z = z_scores(got, *want);
        assert!(z.iter().all(|z| z.abs() < 4.5), "emitter {k}: {got:?} vs {want:?} (z {z:?})");
        // Control: the same test rejects a flux 10% off.
        let off = flux_on_target(n, 7 + k as u64, |u_pos, u_dir, _| {
            sc.sample_infinite_emission(k, u_pos, u_dir).map(|(o, d, w)| (o, d, w * 1.1))
        });
        let z = z_scores(off, *want);
        assert!(z.iter().any(|z| z.abs() > 4.5), "emitter {k}: a 10% error passes (z {z:?})");
    }
    // All three through the light paths' power-weighted choice.
    let total: [f64; 3] = std::array::from_fn(|c| want.iter().map(|w| w[c]).sum());
    let got = flux_on_target(3 * n, 99, |u_pos, u_dir, u_sel| {
        sc.sample_emission(u_sel, u_pos, u_dir).map(|e| {
            assert!(e.n.is_none());
            (e.p, e.d, e.weight)
        })
    });
    let z = z_scores(got, total);
    assert!(z.iter().all(|z| z.abs() < 4.5), "{got:?} vs {total:?} (z {z:?})");
}

/// Every origin lies outside the bounding sphere, and every line through the sphere can be drawn:
/// the origins' projections cover the whole disk.
#[test]
fn origins_lie_outside_the_scene_on_the_covering_disk() {
    use haze_scene::Emitter;
    let d = Vec3::new(-0.2, -0.9, 0.4).normalize();
    let sc = scene(vec![Emitter::Directional { d, irradiance: Rgb::ONE }]);
    let sphere = sc.bounding_sphere();
    let (lo, hi) = sc.bounds();
    assert!((lo - sphere.center).length() <= sphere.radius && (hi - sphere.center).length() <= sphere.radius);
    let mut s = Sampler::from_seed(3);
    let mut rim = 0;
    for _ in 0..20_000 {
        let (o, dir, w) = sc.sample_infinite_emission(0, s.next_2d(), s.next_2d()).unwrap();
        assert_eq!(dir, d);
        assert!((w.mean() - PI * sphere.radius * sphere.radius).abs() < 1e-3 * w.mean());
        assert!((o - sphere.center).length() >= sphere.radius * (1.0 - 1e-5));
        let v = o - sphere.center;
        let across = (v - d * v.dot(d)).length();
        assert!(across <= sphere.radius * (1.0 + 1e-5));
        assert!(v.dot(d) < 0.0, "the origin is upstream");
        rim += (across > 0.95 * sphere.radius) as u32;
    }
    assert!(rim > 1000, "the disk's rim is drawn ({rim})");
}

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
    target: (Vec3, f32),
) -> [(f64, f64); 3] {
    let mut s = Sampler::from_seed(seed);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        let (u_sel, u_pos, u_dir) = (s.next_1d(), s.next_2d(), s.next_2d());
        let Some((o, d, w)) = sample(u_pos, u_dir, u_sel) else { continue };
        assert!(w.is_finite() && w.min_component() >= 0.0, "weight {w:?}");
        if intersect_sphere(&Ray::new(o, d), target.0, target.1).is_some() {
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
        let got = flux_on_target(
            n,
            7 + k as u64,
            |u_pos, u_dir, _| sc.sample_infinite_emission(k, u_pos, u_dir),
            TARGET,
        );
        let z = z_scores(got, *want);
        assert!(z.iter().all(|z| z.abs() < 4.5), "emitter {k}: {got:?} vs {want:?} (z {z:?})");
        // Control: the same test rejects a flux 10% off.
        let off = flux_on_target(
            n,
            7 + k as u64,
            |u_pos, u_dir, _| sc.sample_infinite_emission(k, u_pos, u_dir).map(|(o, d, w)| (o, d, w * 1.1)),
            TARGET,
        );
        let z = z_scores(off, *want);
        assert!(z.iter().any(|z| z.abs() > 4.5), "emitter {k}: a 10% error passes (z {z:?})");
    }
    // All three through the light paths' power-weighted choice.
    let total: [f64; 3] = std::array::from_fn(|c| want.iter().map(|w| w[c]).sum());
    let got = flux_on_target(
        3 * n,
        99,
        |u_pos, u_dir, u_sel| {
            sc.sample_emission(u_sel, u_pos, u_dir).map(|e| {
                assert!(e.n.is_none());
                (e.p, e.d, e.weight)
            })
        },
        TARGET,
    );
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

/// The light paths from infinity aimed at a small medium (T38b): a fog sphere of radius 0.5 in
/// a scene whose bounding sphere is about ten times wider. The mixture of the two disks delivers
/// the analytic flux onto the fog sphere and onto a sphere elsewhere (which only the scene's
/// disk reaches), its origins lie upstream outside the scene, a flux 10% off fails the same
/// test on the fog (control), and the fog sphere receives more than 2.5 times the paths of the plain disk.
#[test]
fn light_paths_from_infinity_aim_at_small_media() {
    use haze_scene::{Emitter, Shape};
    let fog = (Vec3::new(1.0, -0.5, 0.3), 0.5f32);
    let other = (Vec3::new(-3.0, 1.0, -2.0), 0.8f32);
    let xml = r#"<scene version="3.0.0">
        <sensor type="perspective"/>
        <medium type="homogeneous" id="fog"><rgb name="sigma_t" value="1"/><rgb name="albedo" value="0.8"/></medium>
        <shape type="sphere"><point name="center" x="1" y="-0.5" z="0.3"/><float name="radius" value="0.5"/>
            <bsdf type="null"/><ref name="interior" id="fog"/></shape>
        <shape type="sphere"><point name="center" x="-3" y="1" z="-2"/><float name="radius" value="0.8"/></shape>
        <shape type="sphere"><point name="center" x="6" y="4" z="5"/><float name="radius" value="0.5"/></shape>
    </scene>"#;
    let s = load_str(xml, Path::new("fog.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    let sun = Rgb::new(2.0, 1.5, 0.8);
    let sun_d = Vec3::new(0.3, -1.0, 0.2).normalize();
    let build = |shapes: Vec<Shape>, emitters| {
        Scene::new(None, s.camera.clone(), 1, IntegratorSpec::default(), shapes, s.media.clone(), emitters)
    };
    let map = envmap();
    let integral = envmap_integral(&map);
    let sc = build(
        s.shapes.clone(),
        vec![Emitter::Directional { d: sun_d, irradiance: sun }, Emitter::EnvMap(Arc::new(map))],
    );
    let media = sc.media_sphere().expect("the fog is small against the scene");
    let sphere = sc.bounding_sphere();
    assert!(
        (media.center - fog.0).length() < 1e-4 && media.radius < 0.9 && media.radius >= fog.1 * 3f32.sqrt()
    );
    // Flux onto `target` from `emitter` (mean and standard error per channel) and the paths that hit it.
    let flux = |sc: &Scene, target: (Vec3, f32), factor: f32, emitter: usize, seed: u64| {
        let mut hit = 0u32;
        let got = flux_on_target(
            300_000,
            seed,
            |u_pos, u_dir, _| {
                let (o, d, w) = sc.sample_infinite_emission(emitter, u_pos, u_dir)?;
                assert!(
                    (o - sphere.center).length() >= sphere.radius * (1.0 - 1e-5),
                    "origin inside the scene"
                );
                assert!((o - sphere.center).dot(d) < 0.0, "origin downstream");
                let hits = intersect_sphere(&Ray::new(o, d), target.0, target.1).is_some();
                hit += hits as u32;
                Some((o, d, w * factor))
            },
            target,
        );
        (got, hit)
    };
    for target in [fog, other] {
        let cross = PI as f64 * (target.1 as f64).powi(2);
        for emitter in 0..2 {
            let want: [f64; 3] =
                std::array::from_fn(|c| cross * if emitter == 0 { sun[c] as f64 } else { integral[c] });
            let (got, _) = flux(&sc, target, 1.0, emitter, 11 + emitter as u64);
            let z = z_scores(got, want);
            assert!(
                z.iter().all(|z| z.abs() < 4.5),
                "emitter {emitter}, {target:?}: {got:?} vs {want:?} (z {z:?})"
            );
            // Control, where the test has the power (most of the aimed paths hit the fog).
            if target == fog {
                let (off, _) = flux(&sc, target, 1.1, emitter, 11 + emitter as u64);
                let z = z_scores(off, want);
                assert!(z.iter().any(|z| z.abs() > 4.5), "emitter {emitter}: a 10% error passes (z {z:?})");
            }
        }
    }
    // The same scene without the fog's medium draws from the scene's disk alone.
    let plain = build(
        s.shapes.iter().map(|sh| Shape { interior: None, ..sh.clone() }).collect(),
        vec![Emitter::Directional { d: sun_d, irradiance: sun }],
    );
    assert!(plain.media_sphere().is_none());
    let (_, plain_hits) = flux(&plain, fog, 1.0, 0, 5);
    let (_, aimed_hits) = flux(&sc, fog, 1.0, 0, 5);
    assert!(aimed_hits as f32 > 2.5 * plain_hits as f32, "aimed {aimed_hits} vs plain {plain_hits}");
}

//! Single scattering on camera segments by next-event estimation (`docs/theory.md` §2, §6: the part of the
//! medium transport that no VRL or VPL produces).
//!
//! For every camera segment and every emitter, one sample: a point and point light is sampled
//! directly; for an area light a point `y` is first sampled on its surface by area. The camera
//! distance `u` is then sampled equiangularly towards the light point (Kulla & Fajardo 2012),
//! which cancels the `1/|x_u - y|^2` of the connection: low noise even where the segment passes
//! close to the light.
//!
//! ```text
//!   L_1 = Int_0^s T_c(u) sigma_s f_p(y -> x_u, -w_c) Tr(y, x_u) E(y -> x_u) / |x_u - y|^2 du
//! ```
//! with `E` the intensity (point, spot with falloff) or `L_e cos_y / p_area(y)` (area).
//!
//! A spot light's `E` is zero outside its cone, so for a spot the distance is sampled only on the
//! part of the segment inside the cone ([`Emitter::lit_interval`](haze_scene::emitter::Emitter::lit_interval); the cone with half-angle below 90
//! degrees is convex, so that part is one interval). The integrand vanishes elsewhere, so the
//! estimate stays unbiased, and camera segments that miss the beam cost no shadow ray. With the
//! whole segment as the interval, most samples of a narrow beam (the spot-beam benchmark's cone
//! is 10 degrees) land where the spot does not shine and estimate zero.

use crate::camera::{estimator_medium, CameraSegment};
use crate::hetero::scattering_factors;
use crate::vrl::sampling::{equiangular_pdf, sample_equiangular};
use glam::Vec2;
use haze_core::{Rgb, Sampler};
use haze_render::integrators::transmittance_to_sampled;
use haze_scene::marched::MarchedDistance;
use haze_scene::Scene;

/// One-sample estimate of single scattering along `cs` from all emitters (those at infinity by
/// [`from_infinity`]). In a heterogeneous medium the
/// equiangular distance is unchanged (it depends on geometry only) and the integrand's
/// `T_c(u) sigma_s` and `Tr` are estimated (`docs/theory.md` §12.5).
pub fn single_scattering(scene: &Scene, cs: &CameraSegment, sampler: &mut Sampler) -> Rgb {
    let med = estimator_medium(scene, cs.medium);
    if med.sigma_s.is_black() || cs.seg.len <= 0.0 {
        return Rgb::ZERO;
    }
    let hetero = scene.medium(cs.medium).as_grid();
    let mut total = Rgb::ZERO;
    for i in 0..scene.emitters.len() {
        let u_light = sampler.next_2d();
        let u_dist = sampler.next_1d();
        if scene.emitters[i].is_infinite() {
            total += from_infinity(scene, cs, i, u_light, u_dist, sampler);
            continue;
        }
        let Some(light) = scene.sample_emitter_point(i as u32, u_light) else { continue };
        // Where on the segment the light can arrive (module docs).
        let Some((a, b)) = scene.emitters[i].lit_interval(cs.seg.o, cs.seg.d, cs.seg.len) else { continue };
        let (u, pdf) = match &hetero {
            None => {
                // Equiangular parameters of the light point seen from the camera segment.
                let delta = (light.p - cs.seg.o).dot(cs.seg.d);
                let h = (light.p - cs.seg.at(delta)).length();
                let Some(u) = sample_equiangular(u_dist, delta, h, a, b) else { continue };
                (u, equiangular_pdf(u, delta, h, a, b))
            }
            // Mixed with the marched density (docs/theory.md §12.5, (T35)).
            Some(h) => match crate::hetero::single_distance(h, &cs.seg, light.p, (a, b), u_dist) {
                Some(up) => up,
                None => continue,
            },
        };
        if pdf.is_nan() || pdf <= 0.0 {
            continue;
        }
        let x = cs.seg.at(u);
        let to_light = light.p - x;
        let dist = to_light.length();
        if dist <= 0.0 {
            continue;
        }
        let wi = to_light / dist;
        let e_val = scene.emitted_intensity(&light, -wi) / light.pdf;
        if e_val.is_black() {
            continue;
        }
        let phase = med.phase.eval(-wi, -cs.seg.d);
        // `T_c(u) sigma_s`: exact in a homogeneous medium; in a heterogeneous one `sigma_s(x)`
        // and a ratio-tracking estimate of `T_c(u)` (T31), independent of the shadow ray's.
        let Some((cam, sigma_s)) = scattering_factors(scene.medium(cs.medium), &cs.seg, u, x, sampler) else {
            continue;
        };
        // Homogeneous media draw nothing here: bit for bit `transmittance_to`.
        let tr = transmittance_to_sampled(scene, x, None, wi, dist, Some(cs.medium), sampler);
        total += cs.tr_before * cam * sigma_s * tr * e_val * (phase / (dist * dist * pdf));
    }
    total
}

/// Share of the uniform distance in [`from_infinity`]'s mixture: keeps the pdf away from zero
/// where the exponential or the marched density is small but the light is not.
const UNIFORM_SHARE: f32 = 0.2;

/// Single scattering along `cs` from the emitter at infinity `i` (`constant`, `envmap`,
/// `directional`, `docs/theory.md` §13): no point to aim at, so the distance `u` is drawn
/// first, from the mixture of the uniform density on `[0, s]` (share [`UNIFORM_SHARE`]) and the
/// density of the first collision, truncated to the segment (the exponential of the mean
/// `sigma_t`, or in a heterogeneous medium the marched density, T34), which follows `T_c(u)`; then a
/// direction `w` towards the light as next-event estimation draws it
/// ([`Scene::sample_direction_of`]: the sun's one direction, the envmap's table, the uniform
/// sphere), and
///
/// ```text
///   L_1 ~ T_c(u) sigma_s f_p(-w, -w_c) Tr(x_u -> infinity along w) L(w) / (p(u) p(w))
/// ```
///
/// (a delta direction's `p(w)` is 1 and `L(w)` its irradiance). The same shadow transmittance
/// as volpath's next-event estimation (`transmittance_to_sampled` with an infinite distance).
fn from_infinity(
    scene: &Scene,
    cs: &CameraSegment,
    i: usize,
    u_light: Vec2,
    u_dist: f32,
    sampler: &mut Sampler,
) -> Rgb {
    let med = estimator_medium(scene, cs.medium);
    let hetero = scene.medium(cs.medium).as_grid();
    let len = cs.seg.len;
    // The collision density: `(sample, pdf)` closures over the truncated exponential or the
    // marched density (T34), or none (a thin segment: uniform alone).
    let sigma = med.sigma_t.mean();
    let marched = hetero.and_then(|h| MarchedDistance::new(h, cs.seg.o, cs.seg.d, len));
    let exponential = hetero.is_none() && sigma * len > 1e-4 && sigma.is_finite();
    let collision_pdf = |u: f32| -> f32 {
        if let Some(m) = &marched {
            m.pdf(u)
        } else if exponential {
            sigma * (-sigma * u).exp() / -(-sigma * len).exp_m1()
        } else {
            1.0 / len
        }
    };
    let u = if u_dist < UNIFORM_SHARE {
        (u_dist / UNIFORM_SHARE) * len
    } else {
        let v = (u_dist - UNIFORM_SHARE) / (1.0 - UNIFORM_SHARE);
        if let Some(m) = &marched {
            m.sample(v)
        } else if exponential {
            // Inversion of the truncated exponential: `-ln(1 - v (1 - e^{-sigma s})) / sigma`.
            (-(-v * -(-sigma * len).exp_m1()).ln_1p() / sigma).min(len)
        } else {
            v * len
        }
    };
    let pdf_u = UNIFORM_SHARE / len + (1.0 - UNIFORM_SHARE) * collision_pdf(u);
    if !(pdf_u > 0.0 && pdf_u.is_finite()) {
        return Rgb::ZERO;
    }
    let x = cs.seg.at(u);
    let Some(es) = scene.sample_direction_of(i, 1.0, x, u_light, |_| true) else { return Rgb::ZERO };
    if es.radiance.is_black() || es.pdf.is_nan() || es.pdf <= 0.0 {
        return Rgb::ZERO;
    }
    let phase = med.phase.eval(-es.wi, -cs.seg.d);
    let Some((cam, sigma_s)) = scattering_factors(scene.medium(cs.medium), &cs.seg, u, x, sampler) else {
        return Rgb::ZERO;
    };
    let tr = transmittance_to_sampled(scene, x, None, es.wi, f32::INFINITY, Some(cs.medium), sampler);
    cs.tr_before * cam * sigma_s * tr * es.radiance * (phase / (es.pdf * pdf_u))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vrl::Segment;
    use glam::Vec3;
    use haze_scene::Emitter;
    use haze_scene::{load_str, LoadOptions};
    use std::f32::consts::PI;
    use std::path::Path;

    /// Per channel, the mean of `n` one-sample estimates of [`single_scattering`] along `cs`
    /// (sampler seeded with `seed`) and its standard error.
    fn mean_and_error(scene: &Scene, cs: &CameraSegment, seed: u64, n: usize) -> [(f64, f64); 3] {
        let mut sampler = Sampler::from_seed(seed);
        let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let v = single_scattering(scene, cs, &mut sampler);
            for c in 0..3 {
                sum[c] += v[c] as f64;
                sum2[c] += (v[c] as f64).powi(2);
            }
        }
        std::array::from_fn(|c| {
            let mean = sum[c] / n as f64;
            (mean, ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt())
        })
    }

    /// Single scattering from a spot light along one segment (isotropic fog, no surfaces)
    /// against the integral of module docs by adaptive quadrature, for segments that cross the
    /// beam, start inside it, and pass beside the apex.
    #[test]
    fn spot_single_scattering_matches_quadrature() {
        let xml = r#"<scene version="3.0.0">
            <medium type="homogeneous" id="fog">
                <rgb name="sigma_t" value="0.4, 0.5, 0.6"/><float name="albedo" value="0.8"/>
            </medium>
            <sensor type="perspective">
                <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
                <ref id="fog"/>
                <film type="hdrfilm"><integer name="width" value="2"/><integer name="height" value="2"/></film>
            </sensor>
            <emitter type="spot">
                <transform name="to_world"><lookat origin="-2, 2, 0" target="1, 0, 0.5" up="0, 1, 0"/></transform>
                <rgb name="intensity" value="50, 40, 30"/>
                <float name="cutoff_angle" value="12"/><float name="beam_width" value="8"/>
            </emitter>
        </scene>"#;
        let scene = load_str(xml, Path::new("spot.xml"), Path::new("."), &LoadOptions::default()).unwrap();
        let Emitter::Spot { to_world, intensity, cutoff_angle, beam_width, .. } = scene.emitters[0].clone()
        else {
            panic!("a spot light")
        };
        let apex = to_world.transform_point3(Vec3::ZERO);
        let to_local = to_world.inverse();
        let med = estimator_medium(&scene, 0);
        let axis = to_world.transform_vector3(Vec3::Z).normalize();
        let across = axis.cross(Vec3::Y).normalize();
        let near = apex + 0.3 * axis - across;
        let segments = [
            // Across the beam, far from the apex; starting inside it; just in front of the apex.
            Segment::new(Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, -1.0), 8.0),
            Segment::new(apex + 2.0 * axis, Vec3::new(0.0, 0.6, -0.8), 3.0),
            Segment::new(near, across, 2.0),
        ];
        for seg in segments {
            let cs = CameraSegment { seg, medium: 0, tr_before: Rgb::ONE, events: 0 };
            let integrand = |u: f64, c: usize| {
                let x = seg.at(u as f32);
                let v = apex - x;
                let dist = v.length();
                let falloff = Emitter::spot_falloff(
                    cutoff_angle,
                    beam_width,
                    to_local.transform_vector3(-v / dist).normalize(),
                );
                let tau = med.sigma_t[c] * (u as f32 + dist);
                (intensity[c] * falloff * med.sigma_s[c] * (-tau).exp() / (4.0 * PI * dist * dist)) as f64
            };
            let (a, b) = haze_scene::emitter::cone_interval(&to_local, cutoff_angle, seg.o, seg.d, seg.len)
                .unwrap_or((0.0, 0.0));
            let exact: [f64; 3] = std::array::from_fn(|c| {
                if b > a {
                    haze_testkit::quadrature::integrate(|u| integrand(u, c), a as f64, b as f64, &[], 1e-5)
                } else {
                    0.0
                }
            });
            let estimate = mean_and_error(&scene, &cs, 5, 40_000);
            for c in 0..3 {
                let (mean, se) = estimate[c];
                let z = (mean - exact[c]) / se.max(1e-12 * exact[c].abs()).max(1e-30);
                assert!(z.abs() < 4.5, "{seg:?} channel {c}: {mean} vs {} (z {z:.2})", exact[c]);
                assert!(exact[c] > 0.0, "{seg:?}: the segment should see the beam");
            }
        }
    }

    /// Single scattering from the sun (a `directional` emitter, `from_infinity`) along segments
    /// inside a fog cube, against the integral `Int_0^s E sigma_s f_p T(u) T(x_u -> out) du` by
    /// quadrature (the shadow ray leaves the cube towards the sun): the distance mixture and the
    /// shadow transmittance to infinity. Chromatic fog, HG phase.
    #[test]
    fn sun_single_scattering_matches_quadrature() {
        let xml = r#"<scene version="3.0.0">
            <medium type="homogeneous" id="fog">
                <rgb name="sigma_t" value="0.5, 0.9, 1.6"/><float name="albedo" value="0.8"/>
                <phase type="hg"><float name="g" value="0.4"/></phase>
            </medium>
            <sensor type="perspective">
                <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="2"/><integer name="height" value="2"/></film>
            </sensor>
            <shape type="cube"><bsdf type="null"/><ref name="interior" id="fog"/></shape>
            <emitter type="directional">
                <vector name="direction" x="0.3" y="-1" z="-0.5"/>
                <rgb name="irradiance" value="3, 2, 1"/>
            </emitter>
        </scene>"#;
        let scene = load_str(xml, Path::new("sun.xml"), Path::new("."), &LoadOptions::default()).unwrap();
        let Emitter::Directional { d, irradiance } = scene.emitters[0].clone() else { panic!("the sun") };
        let med = estimator_medium(&scene, 0);
        let wi = -d;
        // Distance from `x` inside the cube [-1, 1]^3 to its boundary along `wi`.
        let exit = |x: Vec3| -> f32 {
            (0..3)
                .filter(|&k| wi[k] != 0.0)
                .map(|k| ((if wi[k] > 0.0 { 1.0 } else { -1.0 }) - x[k]) / wi[k])
                .fold(f32::INFINITY, f32::min)
        };
        let segments = [
            Segment::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0), 2.0),
            Segment::new(Vec3::new(-0.9, -0.8, 0.7), Vec3::new(1.0, 0.9, -0.8).normalize(), 2.5),
            Segment::new(Vec3::new(0.5, 0.9, -0.2), Vec3::new(0.0, -1.0, 0.1).normalize(), 0.3),
        ];
        for seg in segments {
            let cs = CameraSegment { seg, medium: 0, tr_before: Rgb::ONE, events: 0 };
            let phase = med.phase.eval(d, -seg.d);
            let exact: [f64; 3] = std::array::from_fn(|c| {
                let f = |u: f64| {
                    let x = seg.at(u as f32);
                    let tau = med.sigma_t[c] * (u as f32 + exit(x));
                    (irradiance[c] * med.sigma_s[c] * phase * (-tau).exp()) as f64
                };
                haze_testkit::quadrature::integrate(f, 0.0, seg.len as f64, &[], 1e-6)
            });
            let estimate = mean_and_error(&scene, &cs, 8, 40_000);
            for c in 0..3 {
                let (mean, se) = estimate[c];
                let z = (mean - exact[c]) / se.max(1e-6 * exact[c].abs()).max(1e-30);
                assert!(z.abs() < 4.5, "{seg:?} channel {c}: {mean} vs {} (z {z:.2})", exact[c]);
                // The test has power: a 5% error would fail it.
                assert!(
                    0.05 * exact[c] > 4.5 * se,
                    "{seg:?} channel {c}: se {se} too large for {}",
                    exact[c]
                );
            }
        }
    }

    /// Single scattering from an area light 0.01 beyond the fog's `null` boundary, the minimal
    /// configuration of `docs/validation.md` (`homo_emitter_inside_medium`;
    /// `scripts/validation/emitter_beyond_null_boundary.xml`), along the segment every point of
    /// which lies 0.11 below the light's plane: every shadow ray crosses the boundary just
    /// before its light point. The exact value 0.130676 is the f64 quadrature of
    /// `haze-render`'s `tests/analytic.rs` (`single_scattering_under_the_light`), which
    /// `scripts/validation/emitter_inside_medium.py` reproduces with numpy (Gauss-Legendre and
    /// Monte Carlo). Controls rejected by the same `|z| < 4.5`: Mitsuba 3.9.1's value there
    /// (0.074041 +- 0.000223, its shadow rays blocking their own light samples) and 1% too high.
    #[test]
    fn area_light_beyond_a_null_boundary_matches_quadrature() {
        let xml = r#"<scene version="3.0.0">
            <medium type="homogeneous" id="fog">
                <rgb name="sigma_t" value="1, 1, 1"/><float name="albedo" value="0.9"/>
            </medium>
            <sensor type="perspective">
                <transform name="to_world"><lookat origin="-0.9, 0, 0.9" target="1, 0, 0.9" up="0, 0, 1"/></transform>
                <ref id="fog"/>
                <film type="hdrfilm"><integer name="width" value="2"/><integer name="height" value="2"/></film>
            </sensor>
            <shape type="cube"><bsdf type="null"/><ref id="fog" name="interior"/></shape>
            <shape type="rectangle">
                <boolean name="flip_normals" value="true"/>
                <transform name="to_world"><scale value="0.5"/><translate z="1.01"/></transform>
                <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
                <emitter type="area"><rgb name="radiance" value="1"/></emitter>
            </shape>
        </scene>"#;
        let scene = load_str(xml, Path::new("beyond.xml"), Path::new("."), &LoadOptions::default()).unwrap();
        let seg = Segment::new(Vec3::new(-0.9, 0.0, 0.9), Vec3::X, 1.9);
        let cs = CameraSegment { seg, medium: 0, tr_before: Rgb::ONE, events: 0 };
        let (exact, mitsuba) = (0.130676, 0.074041);
        let estimate = mean_and_error(&scene, &cs, 13, 1_600_000);
        for (c, &(mean, se)) in estimate.iter().enumerate() {
            let z = |value: f64| (mean - value) / se;
            println!("channel {c}: single scattering {mean:.6} +- {se:.6}, quadrature {exact}");
            assert!(z(exact).abs() < 4.5, "channel {c}: {mean} +- {se} vs {exact} (z {:.2})", z(exact));
            assert!(z(mitsuba).abs() >= 4.5, "control: Mitsuba's {mitsuba} accepted");
            assert!(z(1.01 * exact).abs() >= 4.5, "control: 1% too high accepted ({mean} +- {se})");
        }
    }
}

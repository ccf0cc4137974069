//! Tests of the sampling families: each pdf integrates to one, histograms of samples match it
//! (chi-square), the returned pdf and the inverse agree with the sample, and the chi-square
//! test rejects a wrong pdf.

use super::*;
use glam::Quat;
use haze_core::Sampler;
use haze_testkit::chi2::{chi2_interval, chi2_interval_peaked};
use haze_testkit::quadrature::integrate;

// -- equiangular ---------------------------------------------------------------------------

/// `(delta, h, a, b)`: foot inside, outside, near the segment, on it (floored `h`).
const EQ_CASES: [(f32, f32, f32, f32); 6] = [
    (0.3, 0.5, 0.0, 1.0),
    (-2.0, 0.1, 0.0, 1.0),
    (4.0, 1.5, 0.5, 3.0),
    (0.5, 1e-3, 0.0, 1.0),
    (0.0, 1e-2, 0.0, 2.0),
    (0.73, 0.0, 0.0, 1.0),
];

#[test]
fn equiangular_pdf_integrates_to_one() {
    for &(delta, h, a, b) in &EQ_CASES {
        let eq = Equiangular::new(delta as f64, h as f64, a as f64, b as f64).unwrap();
        let i = integrate(&|t| eq.pdf(t), a as f64, b as f64, &[delta as f64], 1e-10);
        assert!((i - 1.0).abs() < 1e-7, "{delta} {h} {a} {b}: {i}");
        // The f32 wrapper agrees with the f64 density.
        for k in 0..=10 {
            let t = a + (b - a) * k as f32 / 10.0;
            let (p32, p64) = (equiangular_pdf(t, delta, h, a, b) as f64, eq.pdf(t as f64));
            assert!((p32 - p64).abs() <= 1e-6 * p64, "{p32} {p64}");
        }
    }
    assert_eq!(equiangular_pdf(0.5, 0.5, 1.0, 1.0, 1.0), 0.0);
    assert_eq!(equiangular_pdf(2.0, 0.5, 1.0, 0.0, 1.0), 0.0);
    assert!(sample_equiangular(0.5, 0.0, 1.0, 1.0, 1.0).is_none());
}

#[test]
fn equiangular_samples_match_pdf_chi2() {
    for (k, &(delta, h, a, b)) in EQ_CASES.iter().enumerate() {
        let mut s = Sampler::from_seed(100 + k as u64);
        let sample = || sample_equiangular(s.next_1d(), delta, h, a, b).unwrap() as f64;
        let pdf = |t: f64| equiangular_pdf(t as f32, delta, h, a, b) as f64;
        let r = if h >= 0.1 {
            chi2_interval(sample, pdf, a as f64, b as f64, 50, 100_000)
        } else {
            let eq = Equiangular::new(delta as f64, h as f64, a as f64, b as f64).unwrap();
            chi2_interval_peaked(sample, |t| eq.pdf(t), a as f64, b as f64, &[delta as f64], 50, 100_000)
        };
        assert!(r.passed(0.01), "case {k}: {r}");
    }
}

#[test]
fn equiangular_pdf_and_inverse_are_consistent() {
    let mut s = Sampler::from_seed(7);
    for &(delta, h, a, b) in &EQ_CASES {
        let eq = Equiangular::new(delta as f64, h as f64, a as f64, b as f64).unwrap();
        for _ in 0..200 {
            let u = s.next_1d();
            let t = sample_equiangular(u, delta, h, a, b).unwrap();
            assert!((a..=b).contains(&t));
            assert_eq!(equiangular_pdf(t, delta, h, a, b), eq.pdf(t as f64) as f32);
            // In f64 the inverse is exact; through f32 `t` it is exact up to the probability
            // one ulp of `t` carries, large only at the peak of the floored `h = 0` case.
            assert!((eq.invert(eq.sample(u as f64)) - u as f64).abs() < 1e-9);
            if h >= 1e-2 {
                let back = invert_equiangular_sample(t, delta, h, a, b).unwrap();
                assert!((back - u).abs() < 1e-4, "{delta} {h}: u {u} -> t {t} -> {back}");
            }
        }
    }
}

#[test]
fn equiangular_chi2_rejects_uniform_pdf() {
    let mut s = Sampler::from_seed(8);
    let r = chi2_interval(
        || sample_equiangular(s.next_1d(), 0.3, 0.5, 0.0, 1.0).unwrap() as f64,
        |_| 1.0,
        0.0,
        1.0,
        50,
        100_000,
    );
    assert!(!r.passed(0.01), "{r}");
}

// -- 1/h sampling on a VRL -----------------------------------------------------------------

/// A camera line and a VRL at distance `d`, angle `theta`, whose point closest to the camera
/// line is at VRL parameter `v_c`, rotated by a random rotation so that nothing is
/// axis-aligned. Returns `(cam_o, cam_d, vrl)`.
fn vrl_case(d: f32, theta: f32, v_c: f32, len: f32, seed: u64) -> (Vec3, Vec3, Segment) {
    let mut s = Sampler::from_seed(seed);
    let q = Quat::from_axis_angle(haze_core::sampling::sample_uniform_sphere(s.next_2d()), 6.0 * s.next_1d());
    let cam_o = Vec3::new(0.3, -0.2, -1.0);
    let e = Vec3::new(theta.sin(), 0.0, theta.cos());
    let closest = cam_o + Vec3::new(0.0, d, 0.8);
    let vrl_o = closest - v_c * e;
    (q * cam_o, (q * Vec3::Z).normalize(), Segment::new(q * vrl_o, (q * e).normalize(), len))
}

/// `(d, theta, v_c, len)`: across the closest point, entirely on one side, nearly
/// intersecting (`d = 1e-3 len`), nearly parallel above and below [`VRL_PARALLEL_SIN`],
/// intersecting (`d = 0`, floored).
const VRL_CASES: [(f32, f32, f32, f32); 7] = [
    (0.4, 1.0, 0.5, 1.0),
    (0.2, 0.6, -0.7, 2.0),
    (0.3, 2.5, 3.5, 2.0),
    (1e-3, 1.2, 0.4, 1.0),
    (0.02, 1e-3, 0.5, 1.0),
    (0.05, 1e-8, 0.5, 1.0),
    (0.0, 0.9, 0.5, 1.0),
];

#[test]
fn vrl_point_geometry_matches_distance_to_camera_line() {
    for (k, &(d, theta, v_c, len)) in VRL_CASES.iter().enumerate() {
        let (cam_o, cam_d, vrl) = vrl_case(d, theta, v_c, len, k as u64);
        let smp = VrlPointSampler::new(cam_o, cam_d, &vrl).unwrap();
        assert_eq!(smp.is_uniform(), theta < VRL_PARALLEL_SIN);
        for i in 0..=8 {
            let v = len * i as f32 / 8.0;
            let r = (vrl.at(v) - cam_o).as_dvec3();
            let along = r.dot(cam_d.as_dvec3());
            let h_true = (r - along * cam_d.as_dvec3()).length();
            let h = smp.h(v as f64);
            let floor = VRL_MIN_D_REL as f64 * len as f64;
            assert!((h - h_true.max(floor)).abs() < 1e-5 * len as f64, "case {k}, v {v}: {h} vs {h_true}");
            assert!((smp.foot(v as f64) - along).abs() < 1e-5, "case {k}");
        }
    }
}

#[test]
fn vrl_point_pdf_integrates_to_one() {
    for (k, &(d, theta, v_c, len)) in VRL_CASES.iter().enumerate() {
        let (cam_o, cam_d, vrl) = vrl_case(d, theta, v_c, len, k as u64);
        let smp = VrlPointSampler::new(cam_o, cam_d, &vrl).unwrap();
        let i = integrate(&|v| smp.pdf_f64(v), 0.0, len as f64, &[v_c as f64], 1e-10);
        assert!((i - 1.0).abs() < 1e-6, "case {k}: {i}");
        // The free functions agree with the sampler, and vanish outside the VRL.
        assert_eq!(vrl_point_pdf(cam_o, cam_d, &vrl, 0.3 * len), smp.pdf(0.3 * len));
        assert_eq!(vrl_point_pdf(cam_o, cam_d, &vrl, -0.1), 0.0);
        assert_eq!(vrl_point_pdf(cam_o, cam_d, &vrl, 1.01 * len), 0.0);
    }
}

#[test]
fn vrl_point_samples_match_pdf_chi2() {
    for (k, &(d, theta, v_c, len)) in VRL_CASES.iter().enumerate() {
        let (cam_o, cam_d, vrl) = vrl_case(d, theta, v_c, len, k as u64);
        let smp = VrlPointSampler::new(cam_o, cam_d, &vrl).unwrap();
        let mut s = Sampler::from_seed(200 + k as u64);
        let sample = || sample_vrl_point(cam_o, cam_d, &vrl, s.next_1d()).unwrap().0 as f64;
        let (a, b) = (0.0, len as f64);
        let r = if d >= 0.05 {
            chi2_interval(sample, |v| smp.pdf(v as f32) as f64, a, b, 50, 100_000)
        } else {
            chi2_interval_peaked(sample, |v| smp.pdf_f64(v), a, b, &[v_c as f64], 50, 100_000)
        };
        assert!(r.passed(0.01), "case {k}: {r}");
    }
}

#[test]
fn vrl_point_returned_pdf_and_inverse_are_consistent() {
    let mut s = Sampler::from_seed(9);
    for (k, &(d, theta, v_c, len)) in VRL_CASES.iter().enumerate() {
        let (cam_o, cam_d, vrl) = vrl_case(d, theta, v_c, len, k as u64);
        for _ in 0..200 {
            let u = s.next_1d();
            let (v, pdf) = sample_vrl_point(cam_o, cam_d, &vrl, u).unwrap();
            assert!((0.0..=len).contains(&v) && pdf.is_finite() && pdf > 0.0);
            assert_eq!(pdf, vrl_point_pdf(cam_o, cam_d, &vrl, v), "case {k}");
            let smp = VrlPointSampler::new(cam_o, cam_d, &vrl).unwrap();
            assert!((smp.invert_f64(smp.sample_f64(u as f64).0) - u as f64).abs() < 1e-9, "case {k}");
            let back = invert_vrl_point_sample(cam_o, cam_d, &vrl, v).unwrap();
            let tol = if d < 1e-2 { 2e-3 } else { 1e-5 };
            assert!((back - u).abs() < tol, "case {k}: u {u} -> v {v} -> {back}");
        }
    }
}

#[test]
fn vrl_point_chi2_rejects_uniform_pdf() {
    // The test must be able to fail: 1/h samples checked against the uniform density.
    let (d, theta, v_c, len) = VRL_CASES[0];
    let (cam_o, cam_d, vrl) = vrl_case(d, theta, v_c, len, 0);
    let mut s = Sampler::from_seed(10);
    let r = chi2_interval(
        || sample_vrl_point(cam_o, cam_d, &vrl, s.next_1d()).unwrap().0 as f64,
        |_| 1.0 / len as f64,
        0.0,
        len as f64,
        50,
        100_000,
    );
    assert!(!r.passed(0.01), "{r}");
}

/// A light point or closest point far from a short segment: the naive forms
/// (`delta + h tan(..)`, `v_c + d/sin sinh(..)`) lose about 1e-5 of the segment to
/// cancellation here; the forms written from the segment's end are exact to ~1e-12.
#[test]
fn far_configurations_sample_precisely() {
    for (delta, h) in [(-1e5, 2.0), (3e4, 1e-2), (-50.0, 1e-3)] {
        let eq = Equiangular::new(delta, h, 0.0, 1.0).unwrap();
        let i = integrate(&|t| eq.pdf(t), 0.0, 1.0, &[], 1e-12);
        assert!((i - 1.0).abs() < 1e-9, "{delta} {h}: {i}");
        for k in 0..=20 {
            let u = k as f64 / 20.0;
            let t = eq.sample(u);
            assert!((eq.invert(t) - u).abs() < 1e-9, "{delta} {h}: u {u} -> t {t} -> {}", eq.invert(t));
        }
    }
    // Lines 0.5 apart with sin(theta) = 2e-6 whose closest points are 5e7 away from a VRL
    // of length 1e-3 near the origin.
    let vrl = Segment::new(Vec3::new(100.0, 0.5, 0.0), Vec3::new(-2e-6, 0.0, 1.0), 1e-3);
    let smp = VrlPointSampler::new(Vec3::ZERO, Vec3::Z, &vrl).unwrap();
    assert!(!smp.is_uniform());
    let len = vrl.len as f64;
    let i = integrate(&|v| smp.pdf_f64(v), 0.0, len, &[], 1e-12);
    assert!((i - 1.0).abs() < 1e-9, "{i}");
    for k in 0..=20 {
        let u = k as f64 / 20.0;
        let (v, _) = smp.sample_f64(u);
        assert!((smp.invert_f64(v) - u).abs() < 1e-9, "u {u} -> v {v} -> {}", smp.invert_f64(v));
        // Nearly uniform here: v / len tracks u to within the density's variation (~1e-5).
        assert!((v / len - u).abs() < 1e-4, "u {u} -> v {v}");
    }
}

#[test]
fn degenerate_vrl_sampling_is_finite() {
    let (cam_o, cam_d) = (Vec3::ZERO, Vec3::Z);
    assert!(sample_vrl_point(cam_o, cam_d, &Segment::new(Vec3::X, Vec3::Y, 0.0), 0.5).is_none());
    // On the camera line itself (coincident lines), and crossing it exactly.
    for vrl in [
        Segment::new(Vec3::new(0.0, 0.0, 0.5), Vec3::Z, 1.0),
        Segment::new(Vec3::new(0.0, 0.0, 0.5), -Vec3::Z, 1.0),
        Segment::new(Vec3::new(-0.5, 0.0, 0.5), Vec3::X, 1.0),
        Segment::new(Vec3::new(0.0, 0.0, 0.5), Vec3::X, 1.0),
    ] {
        let smp = VrlPointSampler::new(cam_o, cam_d, &vrl).unwrap();
        for i in 0..=100 {
            let (v, pdf) = smp.sample(i as f32 / 100.0);
            assert!(v.is_finite() && pdf.is_finite() && pdf > 0.0, "{vrl:?}: {v} {pdf}");
        }
    }
}

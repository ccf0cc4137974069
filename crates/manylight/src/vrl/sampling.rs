//! Sampling a point on a segment so that the `1/w^2` of a point-to-point connection is cancelled
//! (notes §2): the equiangular family (Kulla & Fajardo 2012, a point on a segment seen from a
//! point) and the `1/h` family (Novak et al. 2012, a point on a VRL seen from the camera's line).
//!
//! Each family comes as `sample_*`, `*_pdf` and `invert_*_sample` (pbrt-v4 style). All pdfs are
//! per unit length along the segment. Arguments and results are `f32`; the arithmetic is `f64`,
//! because both families map a uniform number through `tan`/`sinh` of angles that crowd together
//! near a singularity, where `f32` cannot resolve samples a few `h` away from the peak.

use super::Segment;
use glam::{DVec3, Vec3};

/// Equiangular sampling floors the distance `h` from the light point to the line at
/// `EQUIANGULAR_MIN_H_REL * (b - a)`. With `h = 0` (the light point on the segment) the density
/// would be a Dirac peak; the floor turns it into a Cauchy peak of width `1e-6 (b - a)`. The
/// floored pdf is still a normalised pdf, so sampling with it is exact; see the estimators for
/// what the floor means for the contribution.
pub const EQUIANGULAR_MIN_H_REL: f32 = 1e-6;

/// Below this `sin(theta)` between the camera line and the VRL, [`VrlPointSampler`] samples the
/// VRL uniformly (`p(v) = 1/len`) instead of `∝ 1/h(v)`.
///
/// Why `1e-6`: the directions we are given are unit `f32` vectors, normalised with a rounding
/// error of about `6e-8` per component, so for lines that are meant to be parallel `sin(theta)`
/// comes out as noise of order `1e-7`; the closest point of the two lines, at distance
/// `~ d / sin(theta)` along them, is then meaningless. And the uniform density is what the
/// `1/h` density tends to: over the segment `h` changes by a factor at most
/// `sqrt(1 + (len sin(theta) / d)^2)`, which below the threshold is 1 unless the lines are also
/// within `~1e-6 len` of each other (coincident lines, where the integral itself diverges).
pub const VRL_PARALLEL_SIN: f32 = 1e-6;

/// [`VrlPointSampler`] floors the distance `d` between the two lines at `VRL_MIN_D_REL * len`.
/// At `d = 0` (intersecting lines) the `1/h` density has a non-integrable `1/|t'|` peak; with the
/// floor, `A_b - A_a <= 2 asinh(1e6) ~ 29` and the density stays finite. Distances below
/// `1e-6 len` are at the level of `f32` rounding of the input points anyway.
pub const VRL_MIN_D_REL: f32 = 1e-6;

// ---------------------------------------------------------------------------------------------
// Equiangular

/// Equiangular sampling of `t` in `[a, b]` on a line, seen from a point at distance `h` from the
/// line whose foot of the perpendicular is at parameter `delta` (Kulla & Fajardo 2012):
/// `theta(t) = atan((t - delta) / h)` is uniform, so
/// `t = delta + h tan(lerp(u, theta_a, theta_b))` and
/// `p(t) = h / ((theta_b - theta_a) (h^2 + (t - delta)^2))` per unit length.
///
/// `h` is floored at [`EQUIANGULAR_MIN_H_REL`]` * (b - a)`. Returns `None` unless `a < b` and all
/// inputs are finite.
pub fn sample_equiangular(u: f32, delta: f32, h: f32, a: f32, b: f32) -> Option<f32> {
    let eq = Equiangular::new(delta as f64, h as f64, a as f64, b as f64)?;
    Some((eq.sample(u as f64) as f32).clamp(a, b))
}

/// Density of [`sample_equiangular`] at `t`, per unit length; 0 outside `[a, b]` and for an
/// empty interval.
pub fn equiangular_pdf(t: f32, delta: f32, h: f32, a: f32, b: f32) -> f32 {
    Equiangular::new(delta as f64, h as f64, a as f64, b as f64).map_or(0.0, |eq| eq.pdf(t as f64) as f32)
}

/// Inverse of [`sample_equiangular`]: the uniform number that produces `t`.
pub fn invert_equiangular_sample(t: f32, delta: f32, h: f32, a: f32, b: f32) -> Option<f32> {
    let eq = Equiangular::new(delta as f64, h as f64, a as f64, b as f64)?;
    Some(eq.invert(t as f64) as f32)
}

/// The equiangular distribution with its constants precomputed (`f64`; see the module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Equiangular {
    pub(crate) delta: f64,
    /// Floored distance to the line.
    pub(crate) h: f64,
    a: f64,
    b: f64,
    theta_a: f64,
    /// `theta_b - theta_a`: the angle `[a, b]` subtends from the light point, in `(0, pi]`.
    pub(crate) span: f64,
}

impl Equiangular {
    pub(crate) fn new(delta: f64, h: f64, a: f64, b: f64) -> Option<Self> {
        if !(a < b && b - a < f64::INFINITY && delta.is_finite() && h.is_finite()) {
            return None;
        }
        let h = h.abs().max(EQUIANGULAR_MIN_H_REL as f64 * (b - a));
        let theta_a = ((a - delta) / h).atan();
        // tan(theta_b - theta_a) = (b - a) h / (h^2 + (a - delta)(b - delta)); atan2 keeps full
        // relative precision when the segment is far away and the two angles nearly equal.
        let span = ((b - a) * h).atan2(h * h + (a - delta) * (b - delta));
        (span > 0.0).then_some(Equiangular { delta, h, a, b, theta_a, span })
    }

    pub(crate) fn sample(&self, u: f64) -> f64 {
        (self.delta + self.h * (self.theta_a + u * self.span).tan()).clamp(self.a, self.b)
    }

    pub(crate) fn pdf(&self, t: f64) -> f64 {
        if !(t >= self.a && t <= self.b) {
            return 0.0;
        }
        let x = t - self.delta;
        self.h / (self.span * (self.h * self.h + x * x))
    }

    pub(crate) fn invert(&self, t: f64) -> f64 {
        ((((t - self.delta) / self.h).atan() - self.theta_a) / self.span).clamp(0.0, 1.0)
    }
}

// ---------------------------------------------------------------------------------------------
// A point on a VRL with density proportional to 1/h(v)

/// Samples `v` in `[0, len]` on a VRL with density `∝ 1/h(v)`, `h(v)` the distance from `y_v`
/// to the camera's *infinite* line `cam_o + s cam_d` (notes §2). Returns `(v, p(v))`, or `None`
/// for a zero-length VRL. `cam_d` and `vrl.d` must be unit vectors.
///
/// With `t' = v - v_c` measured from the VRL point closest to the camera line, `d` the distance
/// between the lines and `theta` the angle between them, `h(t')^2 = d^2 + t'^2 sin^2(theta)` and
/// `p(v) = sin(theta) / (h(t') (A_b - A_a))`, `A_z = asinh(z sin(theta) / d)`. Nearly parallel
/// lines fall back to `1/len` ([`VRL_PARALLEL_SIN`]); `d` is floored ([`VRL_MIN_D_REL`]).
pub fn sample_vrl_point(cam_o: Vec3, cam_d: Vec3, vrl: &Segment, u: f32) -> Option<(f32, f32)> {
    VrlPointSampler::new(cam_o, cam_d, vrl).map(|s| s.sample(u))
}

/// Density of [`sample_vrl_point`] at `v`, per unit length along the VRL (0 outside `[0, len]`).
pub fn vrl_point_pdf(cam_o: Vec3, cam_d: Vec3, vrl: &Segment, v: f32) -> f32 {
    VrlPointSampler::new(cam_o, cam_d, vrl).map_or(0.0, |s| s.pdf(v))
}

/// Inverse of [`sample_vrl_point`]: the uniform number that produces `v`.
pub fn invert_vrl_point_sample(cam_o: Vec3, cam_d: Vec3, vrl: &Segment, v: f32) -> Option<f32> {
    VrlPointSampler::new(cam_o, cam_d, vrl).map(|s| s.invert(v))
}

/// The `1/h` distribution on one VRL for one camera line, with the line-to-line geometry
/// precomputed (`f64`). Use it instead of the free functions when sampling or evaluating the
/// same pair several times.
#[derive(Clone, Copy, Debug)]
pub struct VrlPointSampler {
    len: f64,
    /// `y_v - cam_o` projected on the camera direction, `foot0 + v cos_theta`: the camera-line
    /// parameter of the foot of the perpendicular from `y_v`.
    foot0: f64,
    cos_theta: f64,
    /// `y_v - cam_o` perpendicular to the camera direction is `perp0 + v perp_dir`.
    perp0: DVec3,
    perp_dir: DVec3,
    kind: Kind,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Uniform,
    /// `d` floored; `v_c` the VRL parameter closest to the camera line; `a_lo = A(0 - v_c)`,
    /// `span = A(len - v_c) - A(0 - v_c)`.
    Sinh { sin_theta: f64, d: f64, v_c: f64, a_lo: f64, span: f64 },
}

impl VrlPointSampler {
    /// `None` for a zero-length (or non-finite) VRL.
    pub fn new(cam_o: Vec3, cam_d: Vec3, vrl: &Segment) -> Option<Self> {
        let len = vrl.len as f64;
        if !(len > 0.0 && len < f64::INFINITY) {
            return None;
        }
        let c = cam_d.as_dvec3();
        let e = vrl.d.as_dvec3();
        let w0 = (vrl.o - cam_o).as_dvec3();
        let (foot0, cos_theta) = (w0.dot(c), e.dot(c));
        let (perp0, perp_dir) = (w0 - foot0 * c, e - cos_theta * c);
        let sin_theta = c.cross(e).length();
        let kind = if sin_theta < VRL_PARALLEL_SIN as f64 {
            Kind::Uniform
        } else {
            // Minimise |perp0 + v perp_dir|: |perp_dir| = sin(theta).
            let v_c = -perp0.dot(perp_dir) / (sin_theta * sin_theta);
            let d_true = w0.dot(c.cross(e)).abs() / sin_theta;
            let d = d_true.max(VRL_MIN_D_REL as f64 * len);
            let a_lo = (-v_c * sin_theta / d).asinh();
            let span = ((len - v_c) * sin_theta / d).asinh() - a_lo;
            if !(span > 0.0 && span.is_finite() && v_c.is_finite()) {
                return None;
            }
            Kind::Sinh { sin_theta, d, v_c, a_lo, span }
        };
        if !(foot0.is_finite() && perp0.is_finite()) {
            return None;
        }
        Some(VrlPointSampler { len, foot0, cos_theta, perp0, perp_dir, kind })
    }

    /// `(v, p(v))`; `p(v)` equals [`Self::pdf`] at the returned `v`.
    pub fn sample(&self, u: f32) -> (f32, f32) {
        let v = (self.sample_f64(u as f64).0 as f32).clamp(0.0, self.len as f32);
        (v, self.pdf(v))
    }

    pub fn pdf(&self, v: f32) -> f32 {
        self.pdf_f64(v as f64) as f32
    }

    pub fn invert(&self, v: f32) -> f32 {
        self.invert_f64(v as f64) as f32
    }

    /// True when the lines are nearly parallel and `v` is sampled uniformly.
    pub fn is_uniform(&self) -> bool {
        matches!(self.kind, Kind::Uniform)
    }

    pub(crate) fn sample_f64(&self, u: f64) -> (f64, f64) {
        let v = match self.kind {
            Kind::Uniform => u * self.len,
            Kind::Sinh { sin_theta, d, v_c, a_lo, span } => v_c + d / sin_theta * (a_lo + u * span).sinh(),
        }
        .clamp(0.0, self.len);
        (v, self.pdf_f64(v))
    }

    pub(crate) fn pdf_f64(&self, v: f64) -> f64 {
        if !(v >= 0.0 && v <= self.len) {
            return 0.0;
        }
        match self.kind {
            Kind::Uniform => 1.0 / self.len,
            Kind::Sinh { sin_theta, span, .. } => sin_theta / (self.h(v) * span),
        }
    }

    pub(crate) fn invert_f64(&self, v: f64) -> f64 {
        match self.kind {
            Kind::Uniform => v / self.len,
            Kind::Sinh { sin_theta, d, v_c, a_lo, span } => (((v - v_c) * sin_theta / d).asinh() - a_lo) / span,
        }
        .clamp(0.0, 1.0)
    }

    /// Distance from `y_v` to the camera line as the pdf sees it: `sqrt(d^2 + t'^2 sin^2)` with
    /// the floored `d` ([`VRL_MIN_D_REL`]); for the uniform case the direct distance, floored at
    /// the same `1e-6 len`.
    pub(crate) fn h(&self, v: f64) -> f64 {
        match self.kind {
            Kind::Uniform => (self.perp0 + v * self.perp_dir).length().max(VRL_MIN_D_REL as f64 * self.len),
            Kind::Sinh { sin_theta, d, v_c, .. } => {
                let x = (v - v_c) * sin_theta;
                (d * d + x * x).sqrt()
            }
        }
    }

    /// Camera-line parameter of the foot of the perpendicular from `y_v` (the equiangular `delta`).
    pub(crate) fn foot(&self, v: f64) -> f64 {
        self.foot0 + v * self.cos_theta
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use haze_core::Sampler;
    use haze_testkit::chi2::{chi2_interval, chi2_test, Chi2Result};

    /// Global adaptive Gauss-Kronrod (7-15) quadrature of `f` over `[a, b]` split first at
    /// `breaks` (peaks of the integrand), to a relative tolerance.
    fn integrate(f: &dyn Fn(f64) -> f64, a: f64, b: f64, breaks: &[f64], rel_tol: f64) -> f64 {
        const XK: [f64; 8] = [
            0.991455371120812639,
            0.949107912342758525,
            0.864864423359769073,
            0.741531185599394440,
            0.586087235467691130,
            0.405845151377397167,
            0.207784955007898468,
            0.0,
        ];
        const WK: [f64; 8] = [
            0.022935322010529225,
            0.063092092629978553,
            0.104790010322250184,
            0.140653259715525919,
            0.169004726639267903,
            0.190350578064785410,
            0.204432940075298892,
            0.209482141084727828,
        ];
        const WG: [f64; 4] = [0.129484966168869693, 0.279705391489276668, 0.381830050505118945, 0.417959183673469388];
        let gk = |a: f64, b: f64| {
            let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
            let (mut k, mut g) = (WK[7] * f(c), WG[3] * f(c));
            for i in 0..7 {
                let s = f(c - r * XK[i]) + f(c + r * XK[i]);
                k += WK[i] * s;
                if i % 2 == 1 {
                    g += WG[i / 2] * s;
                }
            }
            (k * r, ((k - g) * r).abs())
        };
        let mut pts: Vec<f64> = std::iter::once(a)
            .chain(breaks.iter().copied().filter(|&x| x > a && x < b))
            .chain(std::iter::once(b))
            .collect();
        pts.sort_by(f64::total_cmp);
        let mut parts: Vec<(f64, f64, f64, f64)> =
            pts.windows(2).map(|w| (w[0], w[1], gk(w[0], w[1]).0, gk(w[0], w[1]).1)).collect();
        for _ in 0..5000 {
            let total: f64 = parts.iter().map(|p| p.2).sum();
            let err: f64 = parts.iter().map(|p| p.3).sum();
            if err <= rel_tol * total.abs() {
                break;
            }
            let i = (0..parts.len()).max_by(|&i, &j| parts[i].3.total_cmp(&parts[j].3)).unwrap();
            let (lo, hi, _, _) = parts.swap_remove(i);
            let mid = 0.5 * (lo + hi);
            for (x, y) in [(lo, mid), (mid, hi)] {
                let (k, e) = gk(x, y);
                parts.push((x, y, k, e));
            }
        }
        parts.iter().map(|p| p.2).sum()
    }

    /// Chi-square test with expected counts from adaptive quadrature of the pdf over each bin:
    /// `chi2_interval`'s midpoint rule cannot resolve the `1e-3`-wide peaks of some cases.
    fn chi2_peaked(
        mut sample: impl FnMut() -> f64,
        pdf: &dyn Fn(f64) -> f64,
        a: f64,
        b: f64,
        peak: f64,
        bins: usize,
        n: usize,
    ) -> Chi2Result {
        let w = (b - a) / bins as f64;
        let mut observed = vec![0.0; bins];
        let mut outside = 0;
        for _ in 0..n {
            let x = sample();
            if !(x >= a && x <= b) {
                outside += 1;
                continue;
            }
            observed[(((x - a) / w) as usize).min(bins - 1)] += 1.0;
        }
        let expected: Vec<f64> = (0..bins)
            .map(|i| {
                let (lo, hi) = (a + w * i as f64, a + w * (i + 1) as f64);
                integrate(pdf, lo, hi, &[peak], 1e-9) * n as f64
            })
            .collect();
        let mut r = chi2_test(&observed, &expected);
        r.outside_support += outside;
        r
    }

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
            let mut sample = || sample_equiangular(s.next_1d(), delta, h, a, b).unwrap() as f64;
            let pdf = |t: f64| equiangular_pdf(t as f32, delta, h, a, b) as f64;
            let r = if h >= 0.1 {
                chi2_interval(sample, pdf, a as f64, b as f64, 50, 100_000)
            } else {
                let eq = Equiangular::new(delta as f64, h as f64, a as f64, b as f64).unwrap();
                chi2_peaked(sample, &|t| eq.pdf(t), a as f64, b as f64, delta as f64, 50, 100_000)
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
        let q = Quat::from_axis_angle(
            haze_core::sampling::sample_uniform_sphere(s.next_2d()),
            6.0 * s.next_1d(),
        );
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
            let mut sample = || sample_vrl_point(cam_o, cam_d, &vrl, s.next_1d()).unwrap().0 as f64;
            let (a, b) = (0.0, len as f64);
            let r = if d >= 0.05 {
                chi2_interval(sample, |v| smp.pdf(v as f32) as f64, a, b, 50, 100_000)
            } else {
                chi2_peaked(sample, &|v| smp.pdf_f64(v), a, b, v_c as f64, 50, 100_000)
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
}

//! Sampling a point on a segment so that the `1/w^2` of a point-to-point connection is cancelled
//! (`docs/theory.md` §4): the equiangular family (Kulla & Fajardo 2012, a point on a segment seen from a
//! point) and the `1/h` family (Novak et al. 2012, a point on a VRL seen from the camera's line).
//!
//! Each family comes as `sample_*`, `*_pdf` and `invert_*_sample` (pbrt-v4 style). All pdfs are
//! per unit length along the segment. Arguments and results are `f32`; the arithmetic is `f64`,
//! because both families map a uniform number through `tan`/`sinh` of angles that crowd together
//! near a singularity, where `f32` cannot resolve samples a few `h` away from the peak.

use super::Segment;
use glam::{DVec3, Vec3};

mod trig;

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
    /// `theta_b - theta_a`: the angle `[a, b]` subtends from the light point, in `(0, pi]`.
    pub(crate) span: f64,
}

impl Equiangular {
    #[inline(always)]
    pub(crate) fn new(delta: f64, h: f64, a: f64, b: f64) -> Option<Self> {
        if !(a < b && b - a < f64::INFINITY && delta.is_finite() && h.is_finite()) {
            return None;
        }
        let h = h.abs().max(EQUIANGULAR_MIN_H_REL as f64 * (b - a));
        let span = subtended_angle(delta, h, a, b);
        (span > 0.0).then_some(Equiangular { delta, h, a, b, span })
    }

    /// `t = delta + h tan(theta_a + u span)`, written relative to the segment's end that the
    /// foot is not before, so that no term cancels and no `atan` is needed: for `delta >= a`,
    /// with `A = delta - a >= 0`, `tan(theta_a) = -A / h` and `phi = u span`, the tangent
    /// addition formula gives `t - a = sin(phi) (h^2 + A^2) / (h cos(phi) + A sin(phi))`, and
    /// with `tau = tan(phi / 2)` (`phi < pi`, so `tau` is finite)
    /// `t - a = 2 tau (h^2 + A^2) / (h (1 - tau^2) + 2 A tau)`; mirrored from `b` with
    /// `phi = (1 - u) span` for a foot before `a`. For a foot beyond `b` (`phi <= span <= pi/2`)
    /// or before `a` every term is positive: a distant light point, where both angles are near
    /// `+-pi/2`, loses nothing to cancellation. With the foot on the segment the denominator is
    /// `sqrt(h^2 + A^2) cos(theta_a + phi)`, as ill-conditioned near `theta = pi/2` as the
    /// `tan` of the direct form and no more.
    #[inline(always)]
    pub(crate) fn sample(&self, u: f64) -> f64 {
        let t = if self.delta >= self.a {
            self.a + tangent_offset(self.h, self.delta - self.a, u * self.span)
        } else {
            self.b - tangent_offset(self.h, self.b - self.delta, (1.0 - u) * self.span)
        };
        t.clamp(self.a, self.b)
    }

    pub(crate) fn pdf(&self, t: f64) -> f64 {
        if !(t >= self.a && t <= self.b) {
            return 0.0;
        }
        let x = t - self.delta;
        self.h / (self.span * (self.h * self.h + x * x))
    }

    /// The fraction of the subtended angle that `[a, t]` takes.
    pub(crate) fn invert(&self, t: f64) -> f64 {
        (subtended_angle(self.delta, self.h, self.a, t.clamp(self.a, self.b)) / self.span).clamp(0.0, 1.0)
    }
}

/// Distance from a segment end `e` to the point that makes angle `phi` in `[0, pi)` with
/// `e` as seen from a point at distance `h` from the line whose foot is `far >= 0` beyond `e`
/// ([`Equiangular::sample`]): `2 tau (h^2 + far^2) / (h (1 - tau^2) + 2 far tau)`,
/// `tau = tan(phi / 2)`.
#[inline]
fn tangent_offset(h: f64, far: f64, phi: f64) -> f64 {
    let tau = trig::tan(0.5 * phi);
    2.0 * tau * (h * h + far * far) / (h * (1.0 - tau * tau) + 2.0 * far * tau)
}

/// Angle that `[a, b]` on a line subtends from a point at distance `h > 0` whose foot is at
/// `delta`: `tan(theta_b - theta_a) = (b - a) h / (h^2 + (a - delta)(b - delta))`. The angle is
/// taken from the two legs of this tangent directly (`atan2`, [`trig::angle`]), which keeps full
/// relative precision when the segment is far away and the two angles nearly equal.
#[inline]
fn subtended_angle(delta: f64, h: f64, a: f64, b: f64) -> f64 {
    trig::angle((b - a) * h, h * h + (a - delta) * (b - delta))
}

// ---------------------------------------------------------------------------------------------
// A point on a VRL with density proportional to 1/h(v)

/// Samples `v` in `[0, len]` on a VRL with density `∝ 1/h(v)`, `h(v)` the distance from `y_v`
/// to the camera's *infinite* line `cam_o + s cam_d` (`docs/theory.md` §4.1). Returns `(v, p(v))`, or `None`
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
    /// `d` floored; `v_c` the VRL parameter closest to the camera line; `x_0 = -v_c sin / d`,
    /// the asinh argument at the VRL start, and `s_0 = sqrt(1 + x_0^2)`; `span = A_b - A_a`;
    /// `v_scale = d / sin`, the VRL length per unit of the asinh argument.
    Sinh {
        sin_theta: f64,
        d: f64,
        v_c: f64,
        x_0: f64,
        s_0: f64,
        span: f64,
        v_scale: f64,
    },
}

impl VrlPointSampler {
    /// `None` for a zero-length (or non-finite) VRL.
    #[inline(always)]
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
        let normal = c.cross(e);
        let sin2 = normal.length_squared();
        let sin_theta = sin2.sqrt();
        let kind = if sin_theta < VRL_PARALLEL_SIN as f64 {
            Kind::Uniform
        } else {
            // Minimise |perp0 + v perp_dir| (|perp_dir| = sin): v_c = -p / sin^2 with
            // p = perp0 . perp_dir; d = |w0 . normal| / sin (|normal| = sin). With
            // `sin_d = sin d`, x_0 = -v_c sin / d = p / sin_d and the asinh argument at the VRL end
            // is x_0 + len sin^2 / sin_d: the sampling constants need one division, not four.
            let p = perp0.dot(perp_dir);
            let sin_d_true = w0.dot(normal).abs();
            // `d = max(d_true, 1e-6 len)`, compared in squares so that the usual case does not
            // wait for `sin`.
            let floor = VRL_MIN_D_REL as f64 * len;
            let sin_d =
                if sin_d_true * sin_d_true >= floor * floor * sin2 { sin_d_true } else { floor * sin_theta };
            let x_0 = p / sin_d;
            let s_0 = (1.0 + x_0 * x_0).sqrt();
            let span = asinh_increase(x_0, s_0, len * sin2 / sin_d);
            let (v_c, d) = (-p / sin2, sin_d / sin_theta);
            if !(span > 0.0 && span.is_finite() && v_c.is_finite()) {
                return None;
            }
            Kind::Sinh { sin_theta, d, v_c, x_0, s_0, span, v_scale: d / sin_theta }
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
        let v = self.sample_v(u);
        (v, self.pdf_f64(v))
    }

    #[inline]
    fn sample_v(&self, u: f64) -> f64 {
        match self.kind {
            Kind::Uniform => u * self.len,
            Kind::Sinh { x_0, s_0, span, v_scale, .. } => v_scale * sinh_increase(x_0, s_0, u * span),
        }
        .clamp(0.0, self.len)
    }

    /// What the VRL estimator needs of a sample: `(v, h(v), 1 / (h(v) p(v)))`, the last without
    /// evaluating the pdf: `span / sin(theta)` for the `1/h` density (constant along the VRL),
    /// `len / h(v)` for the uniform one.
    #[inline]
    pub(crate) fn sample_for_estimator(&self, u: f64) -> (f64, f64, f64) {
        let v = self.sample_v(u);
        let h = self.h(v);
        let inv_hp = match self.kind {
            Kind::Uniform => self.len / h,
            Kind::Sinh { sin_theta, span, .. } => span / sin_theta,
        };
        (v, h, inv_hp)
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
            Kind::Sinh { sin_theta, d, x_0, s_0, span, .. } => {
                asinh_increase(x_0, s_0, v * sin_theta / d) / span
            }
        }
        .clamp(0.0, 1.0)
    }

    /// Distance from `y_v` to the camera line as the pdf sees it: `sqrt(d^2 + t'^2 sin^2)` with
    /// the floored `d` ([`VRL_MIN_D_REL`]); for the uniform case the direct distance, floored at
    /// the same `1e-6 len`.
    #[inline]
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
    #[inline]
    pub(crate) fn foot(&self, v: f64) -> f64 {
        self.foot0 + v * self.cos_theta
    }
}

/// `asinh(x + dx) - asinh(x)` for `dx >= 0` without cancellation, given `sx = S(x)`,
/// `S(x) = sqrt(1 + x^2)`. The VRL start can lie far from the closest point (`|x| >> dx`,
/// nearly parallel lines): there both asinh are large and nearly equal. For `x >= 0`,
/// `(x + dx + S(x + dx)) / (x + S(x)) = 1 + dx (1 + (2x + dx) / (S(x) + S(x + dx))) / (x + S(x))`,
/// all terms positive; an interval below zero is its mirror image. An interval across zero is
/// the sum `asinh(y) + asinh(z)` (`y = x + dx > 0`, `z = -x > 0`), the log of
/// `(y + S(y)) (z + S(z)) = 1 + yz + y S(z) + z S(y) + (y^2 + z^2 + y^2 z^2) / (S(y) S(z) + 1)`
/// (using `S(y) S(z) - 1 = (S(y)^2 S(z)^2 - 1) / (S(y) S(z) + 1)`). In each case one
/// logarithm of `1 + (positive terms)`.
#[inline]
fn asinh_increase(x: f64, sx: f64, dx: f64) -> f64 {
    let y = x + dx;
    let sy = (1.0 + y * y).sqrt();
    let z = if x >= 0.0 {
        dx * ((sx + sy) + (x + y)) / ((sx + sy) * (x + sx))
    } else if y <= 0.0 {
        // `asinh(-x) - asinh(-y)` with `0 <= -y`: the case above, mirrored.
        dx * ((sx + sy) - (x + y)) / ((sx + sy) * (sy - y))
    } else {
        let (x2, y2) = (x * x, y * y);
        y * sx - x * sy - x * y + (x2 + y2 + x2 * y2) / (sx * sy + 1.0)
    };
    ln_1p_positive(z)
}

/// `ln(1 + z)` for `z >= 0`: `ln_1p` where it matters, below 1; above, `ln(1 + z)` is as
/// precise (the rounding of `1 + z` costs at most `eps / ln 2` relative) and cheaper.
#[inline]
fn ln_1p_positive(z: f64) -> f64 {
    if z < 1.0 {
        z.ln_1p()
    } else {
        (1.0 + z).ln()
    }
}

/// `sinh(asinh(x) + phi) - x` for `phi >= 0` without cancellation, given `s = sqrt(1 + x^2)`:
/// `x (cosh(phi) - 1) + s sinh(phi)`, written for `x < 0` as
/// `sinh(phi) / (s + |x|) + |x| (1 - exp(-phi))` (all terms positive). One exponential: with
/// `E = exp(phi) - 1 >= 0`, `sinh(phi) = E (E + 2) / (2 (E + 1))`,
/// `cosh(phi) - 1 = E^2 / (2 (E + 1))` and `1 - exp(-phi) = E / (E + 1)`.
#[inline]
fn sinh_increase(x: f64, s: f64, phi: f64) -> f64 {
    let e = exp_m1_positive(phi);
    if x >= 0.0 {
        0.5 * e * (x * e + s * (e + 2.0)) / (e + 1.0)
    } else {
        // `E / (E + 1) (0.5 (E + 2) / (s + |x|) + |x|)` over one denominator.
        e * (0.5 * (e + 2.0) - x * (s - x)) / ((e + 1.0) * (s - x))
    }
}

/// `exp(phi) - 1` for `phi >= 0`: `exp_m1` below `1/2`; above, `exp(phi) - 1` loses at most a
/// factor `e^(1/2) / (e^(1/2) - 1) < 2.6` of `exp`'s half-ulp error, and is cheaper.
#[inline]
fn exp_m1_positive(phi: f64) -> f64 {
    if phi < 0.5 {
        phi.exp_m1()
    } else {
        phi.exp() - 1.0
    }
}

#[cfg(test)]
mod tests;

//! Microfacet distributions (Beckmann and GGX, isotropic or anisotropic) with Smith
//! shadowing-masking and sampling of all normals or of the visible normals only, as in
//! Mitsuba 3's `MicrofacetDistribution` (`microfacet.h`).
//!
//! Directions are in the local shading frame (`z` = macrosurface normal) and point away from the
//! surface. Microfacet normals `m` have `m.z > 0`.

use glam::{Vec2, Vec3};
use haze_core::sampling::sample_uniform_disk_concentric;
use haze_core::PI;

/// `distribution` parameter of the rough BSDFs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MicrofacetType {
    /// `exp(-tan^2(theta) / alpha^2) / (pi alpha^2 cos^4(theta))` (Mitsuba's default).
    Beckmann,
    /// Trowbridge-Reitz: `1 / (pi alpha^2 cos^4(theta) (1 + tan^2(theta) / alpha^2)^2)`.
    Ggx,
}

impl MicrofacetType {
    /// The Mitsuba name (`beckmann`, `ggx`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "beckmann" => Some(MicrofacetType::Beckmann),
            "ggx" => Some(MicrofacetType::Ggx),
            _ => None,
        }
    }
}

/// A microfacet distribution of roughness `alpha_u` along the shading frame's `x` axis (the
/// surface's `dp/du`) and `alpha_v` along `y` (RMS slopes for Beckmann); isotropic when equal.
/// The anisotropic forms are the isotropic ones in slope space stretched by `(alpha_u,
/// alpha_v)` (Heitz 2014, "Understanding the masking-shadowing function", Section 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub ty: MicrofacetType,
    pub alpha_u: f32,
    pub alpha_v: f32,
    /// Sample the distribution of normals visible from `wi` (Heitz and d'Eon 2014) instead of
    /// `D(m) cos(theta_m)`.
    pub sample_visible: bool,
}

impl Microfacet {
    /// `alpha` is clamped to at least 1e-4 as Mitsuba does (a smaller one is numerically a
    /// smooth surface).
    pub fn new(ty: MicrofacetType, alpha: f32, sample_visible: bool) -> Self {
        Self::anisotropic(ty, alpha, alpha, sample_visible)
    }

    /// Roughness `alpha_u` along `x`, `alpha_v` along `y`, each clamped to at least 1e-4 as
    /// [`Self::new`]'s.
    pub fn anisotropic(ty: MicrofacetType, alpha_u: f32, alpha_v: f32, sample_visible: bool) -> Self {
        Microfacet { ty, alpha_u: alpha_u.max(1e-4), alpha_v: alpha_v.max(1e-4), sample_visible }
    }

    /// The same distribution with both roughnesses multiplied by `factor` (Mitsuba's
    /// `scale_alpha`).
    pub fn scaled(self, factor: f32) -> Self {
        Microfacet { alpha_u: self.alpha_u * factor, alpha_v: self.alpha_v * factor, ..self }
    }

    /// True if `alpha_u == alpha_v`.
    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// The normal distribution `D(m)` (per unit projected... solid angle: `∫ D(m) m.z dm = 1`):
    /// with `e = (m.x / alpha_u)^2 + (m.y / alpha_v)^2`, Beckmann
    /// `exp(-e / m.z^2) / (pi alpha_u alpha_v m.z^4)`, GGX `1 / (pi alpha_u alpha_v (e + m.z^2)^2)`
    /// (Walter et al. 2007, eqs. 25 and 33, stretched; Mitsuba 3's `eval`).
    pub fn eval(&self, m: Vec3) -> f32 {
        let a2 = self.alpha_u * self.alpha_v;
        let cos2 = m.z * m.z;
        let (x, y) = (m.x / self.alpha_u, m.y / self.alpha_v);
        let xy = x * x + y * y;
        let d = match self.ty {
            MicrofacetType::Beckmann => (-xy / cos2).exp() / (PI * a2 * cos2 * cos2),
            MicrofacetType::Ggx => {
                let t = xy + cos2;
                1.0 / (PI * a2 * t * t)
            }
        };
        // Mitsuba's guard against underflow in later stages.
        if d * m.z > 1e-20 && d.is_finite() {
            d
        } else {
            0.0
        }
    }

    /// Smith's monodirectional shadowing-masking `G1(v, m)`; zero when `v` sees the back of
    /// the microfacet (`dot(v, m)` and `v.z` of different signs). The Beckmann one is
    /// Walter et al.'s (2007) rational fit. Anisotropic: the isotropic form at the roughness
    /// seen along `v`'s azimuth, `tan^2(theta) alpha^2 = ((alpha_u v.x)^2 + (alpha_v v.y)^2) / v.z^2`
    /// (Heitz 2014, eq. 80).
    pub fn smith_g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (self.alpha_u * v.x, self.alpha_v * v.y);
        let xy_alpha2 = x * x + y * y;
        if xy_alpha2 == 0.0 {
            return 1.0;
        }
        let tan_alpha2 = xy_alpha2 / (v.z * v.z);
        match self.ty {
            MicrofacetType::Beckmann => {
                let a = 1.0 / tan_alpha2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
            MicrofacetType::Ggx => 2.0 / (1.0 + (1.0 + tan_alpha2).sqrt()),
        }
    }

    /// Separable Smith shadowing-masking `G1(wi, m) G1(wo, m)`.
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3) -> f32 {
        self.smith_g1(wi, m) * self.smith_g1(wo, m)
    }

    /// Density of [`Self::sample`] producing `m`, per unit solid angle of `m`. `wi.z > 0`.
    pub fn pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        let d = self.eval(m);
        if self.sample_visible {
            d * self.smith_g1(wi, m) * wi.dot(m).abs() / wi.z
        } else {
            d * m.z
        }
    }

    /// Samples a microfacet normal seen from `wi` (`wi.z > 0`); returns it with its pdf
    /// ([`Self::pdf`]). With visible sampling, the slope-space method of Heitz and d'Eon (2014):
    /// stretch `wi` by `alpha`, sample the slopes of the unit-roughness distribution seen from
    /// it, rotate, unstretch.
    pub fn sample(&self, wi: Vec3, u: Vec2) -> (Vec3, f32) {
        let m = self.sample_normal(wi, u);
        (m, self.pdf(wi, m))
    }

    /// The normal of [`Self::sample`] without its pdf.
    pub fn sample_normal(&self, wi: Vec3, u: Vec2) -> Vec3 {
        if self.sample_visible {
            // Stretch to the unit-roughness configuration (Heitz and d'Eon 2014, Section 4.1).
            let wi_p = Vec3::new(self.alpha_u * wi.x, self.alpha_v * wi.y, wi.z).normalize();
            let sin_theta = (1.0 - wi_p.z * wi_p.z).max(0.0).sqrt();
            let (sin_phi, cos_phi) = if sin_theta > 0.0 {
                ((wi_p.y / sin_theta).clamp(-1.0, 1.0), (wi_p.x / sin_theta).clamp(-1.0, 1.0))
            } else {
                (0.0, 1.0)
            };
            let s = self.sample_visible_11(wi_p.z, u);
            let slope = Vec2::new(cos_phi * s.x - sin_phi * s.y, sin_phi * s.x + cos_phi * s.y)
                * Vec2::new(self.alpha_u, self.alpha_v);
            Vec3::new(-slope.x, -slope.y, 1.0).normalize()
        } else {
            // `D(m) cos(theta_m)`: the azimuth, then `tan^2(theta_m)` from its marginal at the
            // roughness `alpha(phi)` of that azimuth.
            let (phi, a2) = if self.is_isotropic() {
                (2.0 * PI * u.y, self.alpha_u * self.alpha_u)
            } else {
                // In slope space the density is a function of `r / alpha(phi)` with
                // `1 / alpha(phi)^2 = cos^2(phi) / alpha_u^2 + sin^2(phi) / alpha_v^2`, so the
                // azimuth has density `alpha(phi)^2 / (2 pi alpha_u alpha_v)`, whose inverse
                // CDF is `atan(alpha_v / alpha_u tan(2 pi u))` on the right branch
                // (Walter et al. 2007 stretched; Mitsuba 3's `MicrofacetDistribution::sample`).
                let phi = (self.alpha_v / self.alpha_u * (PI + 2.0 * PI * u.y).tan()).atan()
                    + PI * (2.0 * u.y + 0.5).floor();
                let (s, c) = phi.sin_cos();
                let (cu, sv) = (c / self.alpha_u, s / self.alpha_v);
                (phi, 1.0 / (cu * cu + sv * sv))
            };
            let tan2 = match self.ty {
                MicrofacetType::Beckmann => -a2 * (1.0 - u.x).ln(),
                MicrofacetType::Ggx => a2 * u.x / (1.0 - u.x),
            };
            let cos_theta = 1.0 / (1.0 + tan2).sqrt();
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
        }
    }

    /// Slopes of the visible normals of the unit-roughness distribution seen from a direction
    /// in the `xz` plane with cosine `cos_theta_i`.
    fn sample_visible_11(&self, cos_theta_i: f32, u: Vec2) -> Vec2 {
        match self.ty {
            MicrofacetType::Beckmann => {
                if cos_theta_i > 0.99999 {
                    let r = (-(1.0 - u.x).max(1e-12).ln()).sqrt();
                    let phi = 2.0 * PI * u.y;
                    return Vec2::new(r * phi.cos(), r * phi.sin());
                }
                // The slope x by inverting its marginal CDF (Heitz and d'Eon 2014) with
                // safeguarded Newton steps, then a Gaussian in y. In f32 with Mitsuba 3's
                // stopping rule (|CDF error| < 1e-5, at most 9 steps): f64 and 1e-7 cost twice
                // the time for slopes no f32 direction resolves.
                let cdf = BeckmannSlopeCdf::new(cos_theta_i);
                let x = u.x.clamp(1e-6, 1.0 - 1e-7);
                let slope = cdf.solve(x, beckmann_table().guess(cos_theta_i, x), 1e-5, 9);
                let y = (2.0 * u.y - 1.0).clamp(-1.0 + 1e-7, 1.0 - 1e-7);
                Vec2::new(slope, erfinv(y))
            }
            MicrofacetType::Ggx => {
                // Project a disk sample onto the visible half of the hemisphere (Heitz 2017,
                // "A simpler and exact sampling routine for the GGX distribution of visible
                // normals"), then convert the normal to a slope.
                let mut p = sample_uniform_disk_concentric(u);
                let s = 0.5 * (1.0 + cos_theta_i);
                p.y = (1.0 - p.x * p.x).max(0.0).sqrt() * (1.0 - s) + p.y * s;
                let z = (1.0 - p.length_squared()).max(0.0).sqrt();
                let sin_theta_i = (1.0 - cos_theta_i * cos_theta_i).max(0.0).sqrt();
                let norm = 1.0 / (sin_theta_i * p.y + cos_theta_i * z);
                Vec2::new(cos_theta_i * p.y - sin_theta_i * z, p.x) * norm
            }
        }
    }
}

/// The marginal CDF of the slope `x` of the visible normals of the unit-roughness Beckmann
/// distribution seen from an angle `theta_i` (Heitz and d'Eon 2014, section 4): the density is
/// proportional to `(1 - x tan(theta_i)) exp(-x^2)` on `x <= cot(theta_i)`, so
/// `C(x) = norm (1 + erf(x) + tan(theta_i) / sqrt(pi) exp(-x^2))`, `C(cot(theta_i)) = 1`.
///
/// Solved for `x` directly, with `1 + erf(x)` and `exp(-x^2)` from one exponential
/// ([`erfc_exp`]). Jakob's variant (Mitsuba 3) solves in `b = erf(x)`, which costs an `erfinv`
/// (a logarithm and a polynomial of degree 8) per evaluation and one more for the slope: a
/// visible Beckmann normal then cost 150-180 ns, as much as a closest-hit query; in `x` it costs
/// 130-150 ns, and 125-130 ns with the last Newton step unevaluated ([`Self::solve`];
/// docs/performance.md §4.2).
struct BeckmannSlopeCdf {
    tan_theta_i: f32,
    /// The largest slope, `cot(theta_i)`, capped at [`X_LIMIT`].
    x_max: f32,
    norm: f32,
}

/// Slopes are sought in `[-X_LIMIT, X_LIMIT]`: beyond, the CDF is within 1e-15 of 0 or 1
/// (`erfc(6) = 2e-17`), far below the stopping tolerance, and no `u` reaches there.
const X_LIMIT: f32 = 6.0;

impl BeckmannSlopeCdf {
    fn new(cos_theta_i: f32) -> Self {
        let ci = cos_theta_i;
        let sin_theta_i = (1.0 - ci * ci).max(0.0).sqrt();
        let tan_theta_i = sin_theta_i / ci;
        let cot_theta_i = ci / sin_theta_i;
        // C(cot) = norm (2 - erfc(cot) + tan / sqrt(pi) exp(-cot^2)) = 1.
        let (erfc, e) = erfc_exp(cot_theta_i);
        let norm = 1.0 / (2.0 - erfc + INV_SQRT_PI * tan_theta_i * e);
        BeckmannSlopeCdf { tan_theta_i, x_max: cot_theta_i.min(X_LIMIT), norm }
    }

    /// `C(x)`, the density `C'(x) = norm 2 / sqrt(pi) exp(-x^2) (1 - x tan(theta_i))` and its
    /// derivative `C''(x) = norm 2 / sqrt(pi) exp(-x^2) (-2 x (1 - x tan(theta_i)) - tan(theta_i))`.
    #[inline]
    fn eval(&self, x: f32) -> (f32, f32, f32) {
        let (erfc, e) = erfc_exp(x);
        // 1 + erf(x) without cancellation for x < 0, where it is erfc(-x).
        let one_plus_erf = if x < 0.0 { erfc } else { 2.0 - erfc };
        let c = self.norm * (one_plus_erf + INV_SQRT_PI * self.tan_theta_i * e);
        let k = self.norm * std::f32::consts::FRAC_2_SQRT_PI * e;
        let lin = 1.0 - x * self.tan_theta_i;
        (c, k * lin, k * (-2.0 * x * lin - self.tan_theta_i))
    }

    /// The slope `x` with `C(x) = u` to within `tol`: Newton steps from `x`, safeguarded by
    /// bisection (a step leaving the bracket is replaced by its midpoint), at most `steps`
    /// evaluations (Mitsuba 3's `sample_visible_11` stops at 1e-5 or after its steps). A step
    /// whose second-order residual `C'' step^2 / 2` is below [`ACCEPT`] `tol` ends the search
    /// without evaluating its result: from the table's start that is the last step of 97% of
    /// the samples, which then cost one evaluation instead of 1.6 (measured in isolation).
    #[inline]
    fn solve(&self, u: f32, x: f32, tol: f32, steps: u32) -> f32 {
        self.solve_counted(u, x, tol, steps).0
    }

    /// [`Self::solve`] and the number of evaluations of the CDF it made.
    #[inline]
    fn solve_counted(&self, u: f32, mut x: f32, tol: f32, steps: u32) -> (f32, u32) {
        let (mut lo, mut hi) = (-X_LIMIT, self.x_max);
        for evaluations in 1..=steps {
            if !(x >= lo && x <= hi) {
                x = 0.5 * (lo + hi);
            }
            let (c, density, d_density) = self.eval(x);
            let value = c - u;
            if value.abs() < tol {
                return (x, evaluations);
            }
            if value > 0.0 {
                hi = x;
            } else {
                lo = x;
            }
            let step = value / density;
            // The Newton step leaves a residual of C'' step^2 / 2 (to second order): when that
            // is well inside the tolerance, its result needs no evaluation of its own.
            if (0.5 * d_density * step * step).abs() < ACCEPT * tol && x - step >= lo && x - step <= hi {
                return (x - step, evaluations);
            }
            x -= step;
        }
        (x.clamp(lo, hi), steps)
    }
}

/// The fraction of the tolerance a Newton step's estimated residual must stay below for its
/// result to be taken unevaluated (the estimate is second order, so with a margin; the
/// inversion test checks the true CDF error of every result).
const ACCEPT: f32 = 0.25;
const INV_SQRT_PI: f32 = std::f32::consts::FRAC_2_SQRT_PI * 0.5;

/// The solution `x` of [`BeckmannSlopeCdf`] tabulated over `w = sqrt(1 - cos(theta_i))` and
/// `v = sqrt(1 - u)`, the starting point of its Newton steps (built once, 38 KB). In `v` the
/// slope is smooth where it approaches the edge-on one, whose density vanishes linearly; at the
/// other end, below [`U_TAIL`], it goes as `-sqrt(-ln u)`, and a second table over
/// `q = sqrt(-ln u)` takes over (an earlier table, docs/performance.md §4.2, held
/// `b = erf(x)`, smooth at both ends in `v`, but each Newton step in `b` costs an `erfinv`). A
/// table 4 times finer (132 KB) needed fewer evaluations in isolation and was no faster there.
struct BeckmannTable {
    /// Over `v` in `[0, 1]`, [`TABLE_V`] columns; its last cell is never read.
    main: Box<[f32]>,
    /// Over `q = sqrt(-ln u)` from `u = U_TAIL` to `1e-6`, [`TAIL_Q`] columns.
    tail: Box<[f32]>,
}

const TABLE_W: usize = 65;
const TABLE_V: usize = 129;
const TAIL_Q: usize = 17;

/// Below this `u` (the last cell of [`TABLE_V`], `v > 127/128`) the tail table is read: there
/// `x` goes as `-sqrt(-ln u)`, linear in `q`.
const U_TAIL: f32 = 1.0 - (127.0 / 128.0) * (127.0 / 128.0);

fn beckmann_table() -> &'static BeckmannTable {
    static TABLE: std::sync::OnceLock<BeckmannTable> = std::sync::OnceLock::new();
    TABLE.get_or_init(BeckmannTable::new)
}

/// The `q` range of the tail table.
fn tail_range() -> (f32, f32) {
    ((-U_TAIL.ln()).sqrt(), (-(1e-6f32).ln()).sqrt())
}

impl BeckmannTable {
    fn new() -> Self {
        let solve = |ci: f32, u: f32| {
            let u = u.clamp(1e-6, 1.0 - 1e-7);
            if ci > 0.99999 {
                erfinv(2.0 * u - 1.0)
            } else {
                BeckmannSlopeCdf::new(ci).solve(u, 0.0, 1e-7, 64)
            }
        };
        let (q0, q1) = tail_range();
        let (mut main, mut tail) = (Vec::new(), Vec::new());
        for i in 0..TABLE_W {
            let w = i as f32 / (TABLE_W - 1) as f32;
            let ci = (1.0 - w * w).max(1e-4);
            for j in 0..TABLE_V {
                let v = j as f32 / (TABLE_V - 1) as f32;
                main.push(solve(ci, 1.0 - v * v));
            }
            for j in 0..TAIL_Q {
                let q = q0 + (q1 - q0) * j as f32 / (TAIL_Q - 1) as f32;
                tail.push(solve(ci, (-q * q).exp()));
            }
        }
        BeckmannTable { main: main.into_boxed_slice(), tail: tail.into_boxed_slice() }
    }

    #[inline]
    fn guess(&self, cos_theta_i: f32, u: f32) -> f32 {
        let w = (1.0 - cos_theta_i).max(0.0).sqrt() * (TABLE_W - 1) as f32;
        let i = (w as usize).min(TABLE_W - 2);
        let fw = w - i as f32;
        let (table, cols, c) = if u >= U_TAIL {
            (&self.main, TABLE_V, (1.0 - u).max(0.0).sqrt() * (TABLE_V - 1) as f32)
        } else {
            let (q0, q1) = tail_range();
            let q = ((-u.ln()).sqrt() - q0) / (q1 - q0) * (TAIL_Q - 1) as f32;
            (&self.tail, TAIL_Q, q.max(0.0))
        };
        let j = (c as usize).min(cols - 2);
        let fc = c - j as f32;
        let row = |i: usize| {
            let r = &table[i * cols + j..i * cols + j + 2];
            r[0] + (r[1] - r[0]) * fc
        };
        let (x0, x1) = (row(i), row(i + 1));
        x0 + (x1 - x0) * fw
    }
}

/// `erfc(|x|)` and `exp(-x^2)`, from one exponential: Abramowitz and Stegun's 7.1.26,
/// `erfc(z) = t (a1 + t (a2 + t (a3 + t (a4 + t a5)))) exp(-z^2)`, `t = 1 / (1 + p z)`, absolute
/// error below 1.5e-7 for `z >= 0`, about the resolution of the f32 CDF values it is used for.
// The published coefficients, as printed; the compiler rounds them to f32.
#[allow(clippy::excessive_precision)]
#[inline]
pub(crate) fn erfc_exp(x: f32) -> (f32, f32) {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let e = (-z * z).exp();
    let p = t
        * (0.254_829_592
            + t * (-0.284_496_736 + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    (p * e, e)
}

/// Error function, `1 - erfc` from [`erfc_exp`].
#[cfg(test)]
fn erf(x: f32) -> f32 {
    (1.0 - erfc_exp(x).0).copysign(x)
}

/// Inverse error function on (-1, 1): Giles' (2010) single-precision approximation (relative
/// error below 4e-7).
// The published coefficients, as printed; the compiler rounds them to f32.
#[allow(clippy::excessive_precision)]
pub(crate) fn erfinv(y: f32) -> f32 {
    let w = -((1.0 - y) * (1.0 + y)).ln();
    if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_36e-8;
        for c in [
            3.432_739_39e-7,
            -3.523_387_7e-6,
            -4.391_506_54e-6,
            0.000_218_580_87,
            -0.001_253_725_03,
            -0.004_177_681_64,
            0.246_640_727,
            1.501_409_41,
        ] {
            p = c + p * w;
        }
        p * y
    } else {
        let w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257;
        for c in [
            0.000_100_950_558,
            0.001_349_343_22,
            -0.003_673_428_44,
            0.005_739_507_73,
            -0.007_622_461_3,
            0.009_438_870_47,
            1.001_674_06,
            2.832_976_82,
        ] {
            p = c + p * w;
        }
        p * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testing::{chi2_rotated, passed};
    use haze_core::Sampler;

    fn all() -> Vec<Microfacet> {
        let mut v = Vec::new();
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (alpha_u, alpha_v) in [(0.1, 0.1), (0.5, 0.5), (0.05, 0.3), (0.6, 0.15)] {
                for vis in [true, false] {
                    v.push(Microfacet::anisotropic(ty, alpha_u, alpha_v, vis));
                }
            }
        }
        v
    }

    #[test]
    fn erf_and_inverse_agree() {
        // Against libm's erf / erfc (Python's math.erf): absolute error and, in the tail,
        // relative error of erfc.
        for (x, want) in
            [(0.5, 0.520_499_877_813_046_5), (2.9, 0.999_958_902_121_900_5), (3.1, 0.999_988_351_342_632_8)]
        {
            // f32: the approximation's 1.2e-7 plus rounding.
            assert!((erf(x as f32) as f64 - want).abs() < 3e-7, "{x}");
            assert!((erf(-x as f32) as f64 + want).abs() < 3e-7);
        }
        for &y in &[-0.999f32, -0.5, 0.0, 0.3, 0.9, 0.99999] {
            let x = erfinv(y);
            let d = std::f32::consts::FRAC_2_SQRT_PI * (-x * x).exp();
            // |x - erfinv(y)| = |erf(x) - y| / erf'(x) to first order; in the tail, where
            // erf' is tiny, the CDF error (what sampling sees) instead.
            let err = (erf(x) - y).abs();
            assert!(err / d <= 1e-5 * x.abs().max(1e-1) || err <= 3e-7, "{y}: {x}");
        }
    }

    /// The Newton steps from the tabulated start reach Mitsuba's tolerance (|CDF error| < 1e-5)
    /// from grazing to normal incidence and at both ends of the CDF, with a finite slope inside
    /// the bracket. The table itself is checked against the solution it starts from (in
    /// probability: the CDF at the tabulated slope).
    #[test]
    fn beckmann_slope_inversion_converges_everywhere() {
        let table = beckmann_table();
        let (mut slow, mut single) = (0, 0);
        let mut n = 0;
        for &ci in &[1e-4f32, 1e-3, 0.01, 0.05, 0.2, 0.4, 0.6, 0.8, 0.95, 0.999, 0.99998] {
            let cdf = BeckmannSlopeCdf::new(ci);
            // The CDF is normalised: 1 at the edge-on slope (or the bracket's end).
            assert!(
                (cdf.eval(cdf.x_max).0 - 1.0).abs() < 1e-6,
                "cos {ci}: C(x_max) = {}",
                cdf.eval(cdf.x_max).0
            );
            assert!(cdf.eval(-X_LIMIT).0 < 1e-9, "cos {ci}");
            for k in 0..=400 {
                let u = (k as f32 / 400.0).clamp(1e-6, 1.0 - 1e-7);
                for u in [u, 7e-5, 1e-4, 1.0 - 1e-5] {
                    let guess = table.guess(ci, u);
                    let x = cdf.solve(u, guess, 1e-5, 9);
                    assert!(
                        x.is_finite() && (-X_LIMIT..=cdf.x_max).contains(&x),
                        "cos {ci} u {u}: slope {x}"
                    );
                    let err = (cdf.eval(x).0 - u).abs();
                    assert!(err < 1e-5, "cos {ci} u {u}: CDF error {err}");
                    let off = (cdf.eval(guess).0 - u).abs();
                    assert!(off < 3e-3, "cos {ci} u {u}: the table's slope {guess} is {off} off");
                    // Evaluations of the CDF from the table's start: one for most samples.
                    let (_, evaluations) = cdf.solve_counted(u, guess, 1e-5, 9);
                    slow += usize::from(evaluations > 2);
                    single += usize::from(evaluations == 1);
                    n += 1;
                }
            }
        }
        assert!(slow * 20 < n, "{slow} of {n} inversions needed more than two evaluations");
        assert!(single * 20 > n * 19, "only {single} of {n} inversions took a single evaluation");
    }

    /// The projected area of the microsurface is that of the macrosurface:
    /// `∫ D(m) m.z dm = 1`, and with visible normals `∫ G1(wi, m) max(0, wi.m) D(m) dm = wi.z`.
    #[test]
    fn normalisation() {
        let mut s = Sampler::from_seed(3);
        let wi = Vec3::new(0.6, 0.0, 0.8);
        for d in all() {
            let n = 400_000;
            let (mut a, mut b) = (0.0f64, 0.0f64);
            for _ in 0..n {
                // Uniform on the upper hemisphere, pdf 1/(2 pi).
                let m = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                let m = Vec3::new(m.x, m.y, m.z.abs());
                a += (d.eval(m) * m.z) as f64;
                b += (d.eval(m) * d.smith_g1(wi, m) * wi.dot(m).max(0.0)) as f64;
            }
            let scale = 2.0 * std::f64::consts::PI / n as f64;
            let tol = if d.alpha_u.min(d.alpha_v) < 0.2 { 0.05 } else { 0.01 };
            assert!((a * scale - 1.0).abs() < tol, "{d:?}: {}", a * scale);
            // Smith G1 of the Beckmann fit is approximate (Walter et al. report < 0.4 %).
            assert!((b * scale / 0.8 - 1.0).abs() < tol, "{d:?}: {}", b * scale / 0.8);
        }
    }

    #[test]
    fn sampling_matches_pdf() {
        for d in all() {
            for wi in
                [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.8, 0.0, 0.6), Vec3::new(-0.3, 0.9, 0.3).normalize()]
            {
                let mut s = Sampler::from_seed(11);
                let res = chi2_rotated(
                    || {
                        let (m, pdf) = d.sample(wi, s.next_2d());
                        assert!((pdf - d.pdf(wi, m)).abs() <= 1e-3 * pdf.max(1.0), "returned pdf");
                        Some(m)
                    },
                    |m| d.pdf(wi, m),
                    200_000,
                );
                assert!(passed(&res, 200_000), "{d:?} wi {wi}: {res}");
            }
        }
    }
}

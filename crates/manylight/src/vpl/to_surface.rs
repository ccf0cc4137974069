//! A point light (a medium VPL or a surface VPL) to a gathering surface point
//! (`docs/theory.md` §5.3, (T12d)): nothing left to sample,
//!
//! ```text
//! L = I(n) Tr(p, x) R(-n) / |x - p|^2,   n = (x - p) / |x - p|
//! ```
//!
//! with `R(d)` the receiver's `f(wi, d) |cos d|`. The `1/|x - p|^2` is the classic VPL
//! singularity near corners; `geometry_clamp = Some(c)` uses `min(1/|x - p|^2, c)` (Keller 1997),
//! which is biased.

use haze_core::{Rgb, Vec3};

/// The contribution (T12d) of the point light `p` of intensity `intensity(n)` to `x`.
pub fn point_light_to_point(
    x: Vec3,
    receiver: impl Fn(Vec3) -> Rgb,
    p: Vec3,
    intensity: impl Fn(Vec3) -> Rgb,
    geometry_clamp: Option<f32>,
    mut connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    let d = x - p;
    let d2 = d.length_squared();
    if d2.is_nan() || d2 <= 0.0 {
        return Rgb::ZERO;
    }
    let n = d / d2.sqrt();
    let f = receiver(-n);
    if f.is_black() {
        return Rgb::ZERO;
    }
    let i = intensity(n);
    if i.is_black() {
        return Rgb::ZERO;
    }
    let g = geometry_clamp.map_or(1.0 / d2, |c| (1.0 / d2).min(c));
    i * f * connect(p, x) * g
}

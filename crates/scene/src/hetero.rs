//! Heterogeneous media (Mitsuba 3 plugin `heterogeneous`): extinction and albedo from
//! [`Volume`]s, a majorant grid walked by a DDA, free-flight sampling by delta tracking and
//! transmittance by ratio tracking. Formulas and sources: `docs/theory.md` §12.1-12.4.
//!
//! Mitsuba 3's semantics that decide what is rendered (`src/media/heterogeneous.cpp`,
//! `Medium::sample_interaction`): `sigma_t(x) = scale * sigma_t_volume(x)`,
//! `sigma_s(x) = sigma_t(x) * albedo_volume(x)`, and the medium is clipped to the bounding box
//! of the `sigma_t` volume: outside it there is no extinction at all, even where the volume's
//! wrap mode would give a value.

use crate::flight::Flight;
use crate::volume::{Volume, VolumeData};
use glam::Vec3;
use haze_core::{Rgb, Sampler};

/// Cells per axis of the majorant grid (pbrt-v4's `GridMedium` uses 16^3).
pub const MAJORANT_RES: u32 = 16;

/// Relative margin on every majorant, so that f32 rounding of a trilinear lookup (a convex
/// combination, at most a few ulps above its largest cell) never exceeds it.
const MAJORANT_MARGIN: f32 = 1.0 + 1e-5;

/// Below this largest-channel transmittance, ratio tracking plays Russian roulette (pbrt-v4's
/// `TraceTransmittance`): survive with probability 1/4 and divide by it. Unbiased.
const RR_THRESHOLD: f32 = 0.05;
const RR_SURVIVE: f32 = 0.25;

/// A heterogeneous medium's coefficients (the phase function is the [`crate::Medium`]'s).
#[derive(Clone, Debug, PartialEq)]
pub struct Heterogeneous {
    pub sigma_t: Volume,
    pub albedo: Volume,
    pub scale: f32,
    pub majorants: MajorantGrid,
}

/// Piecewise-constant per-channel upper bounds of `sigma_t` over a regular grid of boxes
/// covering the medium's bounding box (`docs/theory.md` §12.2, (T28)).
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    pub lo: Vec3,
    pub hi: Vec3,
    pub res: [u32; 3],
    /// `res_x * res_y * res_z` bounds, x fastest.
    pub cells: Vec<Rgb>,
}

/// One piece of a ray inside a majorant cell: `[t0, t1)` with bound `sigma_maj`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MajorantSegment {
    pub t0: f32,
    pub t1: f32,
    pub sigma_maj: Rgb,
}

/// [`MajorantGrid::build`] keeps one cell when the cells' mean bound is at least this share of
/// the global bound (the grid would save under 10% of the tentative collisions).
const COLLAPSE_SHARE: f64 = 0.9;

impl MajorantGrid {
    /// Bounds of `scale * sigma_t` over `res` cells spanning `sigma_t`'s bounding box.
    pub fn build(sigma_t: &Volume, scale: f32, res: [u32; 3]) -> MajorantGrid {
        let (lo, hi) = sigma_t.bbox;
        let size = (hi - lo) / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let mut cells = Vec::with_capacity((res[0] * res[1] * res[2]) as usize);
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let a = lo + size * Vec3::new(x as f32, y as f32, z as f32);
                    // The last cell of each axis ends exactly at the box (no rounding gap).
                    let b = a + size;
                    let b = Vec3::new(
                        if x + 1 == res[0] { hi.x } else { b.x },
                        if y + 1 == res[1] { hi.y } else { b.y },
                        if z + 1 == res[2] { hi.z } else { b.z },
                    );
                    cells.push(sigma_t.max_over_box(a, b) * (scale * MAJORANT_MARGIN));
                }
            }
        }
        // A grid whose cells bound about as much as one global cell (a noisy grid with its
        // maximum almost everywhere) gains too little from the DDA to pay for its cell
        // crossings: one cell instead. The measure is ratio tracking's (and the largest
        // channel's): the mean over the cells of the largest channel's bound, the expected
        // tentative collisions per unit length, against the global bound's
        // (docs/performance.md §4.5: on the noisy peer grid the two were equal and one cell 8%
        // faster).
        let global = cells.iter().fold(Rgb::ZERO, |m, c| m.max(*c));
        let mean_max =
            cells.iter().map(|c| c.max_component() as f64).sum::<f64>() / cells.len().max(1) as f64;
        // (A grid whose cells all have the same bound meets this with equality.)
        if mean_max >= COLLAPSE_SHARE * global.max_component() as f64 {
            return MajorantGrid { lo, hi, res: [1; 3], cells: vec![global] };
        }
        MajorantGrid { lo, hi, res, cells }
    }

    /// The majorant cells a ray `o + t d` crosses for `t` in `[t_min, t_max]`, in order.
    #[inline]
    pub fn segments(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> MajorantIter<'_> {
        MajorantIter::new(self, o, d, t_min, t_max)
    }
}

/// 3D DDA over the majorant grid (Amanatides and Woo 1987; pbrt-v4's `DDAMajorantIterator`).
pub struct MajorantIter<'a> {
    grid: &'a MajorantGrid,
    t: f32,
    t_end: f32,
    cell: [i32; 3],
    step: [i32; 3],
    next_t: [f32; 3],
    delta_t: [f32; 3],
    done: bool,
}

impl<'a> MajorantIter<'a> {
    fn new(grid: &'a MajorantGrid, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Self {
        let mut it = MajorantIter {
            grid,
            t: 0.0,
            t_end: 0.0,
            cell: [0; 3],
            step: [0; 3],
            next_t: [f32::INFINITY; 3],
            delta_t: [f32::INFINITY; 3],
            done: true,
        };
        // Clip to the box (slab test).
        let (mut t0, mut t1) = (t_min.max(0.0), t_max);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < grid.lo[k] || o[k] > grid.hi[k] {
                    return it;
                }
            } else {
                let a = (grid.lo[k] - o[k]) / d[k];
                let b = (grid.hi[k] - o[k]) / d[k];
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        if t0.is_nan() || t1.is_nan() || t0 >= t1 {
            return it;
        }
        let p = o + d * t0;
        for k in 0..3 {
            let n = grid.res[k] as i32;
            let extent = grid.hi[k] - grid.lo[k];
            let size = extent / n as f32;
            let g = if extent > 0.0 { (p[k] - grid.lo[k]) / size } else { 0.0 };
            it.cell[k] = (g.floor() as i32).clamp(0, n - 1);
            if d[k] > 0.0 {
                it.step[k] = 1;
                it.next_t[k] = (grid.lo[k] + (it.cell[k] + 1) as f32 * size - o[k]) / d[k];
                it.delta_t[k] = size / d[k];
            } else if d[k] < 0.0 {
                it.step[k] = -1;
                it.next_t[k] = (grid.lo[k] + it.cell[k] as f32 * size - o[k]) / d[k];
                it.delta_t[k] = -size / d[k];
            }
        }
        it.t = t0;
        it.t_end = t1;
        it.done = false;
        it
    }
}

impl Iterator for MajorantIter<'_> {
    type Item = MajorantSegment;

    #[inline]
    fn next(&mut self) -> Option<MajorantSegment> {
        if self.done {
            return None;
        }
        let axis = if self.next_t[0] < self.next_t[1] {
            if self.next_t[0] < self.next_t[2] {
                0
            } else {
                2
            }
        } else if self.next_t[1] < self.next_t[2] {
            1
        } else {
            2
        };
        let t1 = self.next_t[axis].min(self.t_end).max(self.t);
        let g = self.grid;
        let idx = ((self.cell[2] * g.res[1] as i32 + self.cell[1]) * g.res[0] as i32 + self.cell[0]) as usize;
        let seg = MajorantSegment { t0: self.t, t1, sigma_maj: g.cells[idx] };
        self.t = t1;
        if self.next_t[axis] >= self.t_end {
            self.done = true;
        } else {
            self.cell[axis] += self.step[axis];
            if self.cell[axis] < 0 || self.cell[axis] >= g.res[axis] as i32 {
                self.done = true;
            }
            self.next_t[axis] += self.delta_t[axis];
        }
        Some(seg)
    }
}

impl Heterogeneous {
    /// `sigma_t(x) = scale * sigma_t_volume(x)`.
    #[inline]
    pub fn sigma_t(&self, p: Vec3) -> Rgb {
        self.sigma_t.eval(p) * self.scale
    }

    /// `sigma_t(x)` and `sigma_s(x) = sigma_t(x) albedo(x)` of the medium itself (T27): zero
    /// outside the `sigma_t` volume's box, where Mitsuba 3 clips the medium away (unlike
    /// [`Self::sigma_t`], which evaluates the volume wherever asked). For points the many-light
    /// estimators sample on their own (`docs/theory.md` §12.5), which may lie outside the box.
    #[inline]
    pub fn coefficients(&self, p: Vec3) -> (Rgb, Rgb) {
        let (lo, hi) = (self.majorants.lo, self.majorants.hi);
        if !(p.cmpge(lo).all() && p.cmple(hi).all()) {
            return (Rgb::ZERO, Rgb::ZERO);
        }
        let sigma_t = self.sigma_t(p);
        if sigma_t.is_black() {
            return (Rgb::ZERO, Rgb::ZERO);
        }
        (sigma_t, sigma_t * self.albedo.eval(p))
    }

    /// The part `[a, b]` of `[t0, t1]` from the first to the last majorant cell with a
    /// positive bound that the ray `o + t d` crosses, if any: outside it the medium is empty
    /// (outside the box by (T27), in a cell of zero majorant because the majorant bounds
    /// `sigma_t`), so segments can be clipped to it.
    pub fn clip(&self, o: Vec3, d: Vec3, t0: f32, t1: f32) -> Option<(f32, f32)> {
        let mut span: Option<(f32, f32)> = None;
        for g in self.majorants.segments(o, d, t0, t1) {
            if g.t1 > g.t0 && g.sigma_maj.max_component() > 0.0 {
                span = Some((span.map_or(g.t0, |s| s.0), g.t1));
            }
        }
        span
    }

    /// The mean of the majorant cells, per channel: the homogeneous proxy of the medium that
    /// the many-light methods' importances use (`docs/theory.md` §12.5).
    pub fn mean_majorant(&self) -> Rgb {
        let n = self.majorants.cells.len().max(1) as f32;
        self.majorants.cells.iter().fold(Rgb::ZERO, |m, c| m + *c) * (1.0 / n)
    }

    /// The largest majorant of any cell, per channel (a homogeneous bound of the medium).
    pub fn global_majorant(&self) -> Rgb {
        self.majorants.cells.iter().fold(Rgb::ZERO, |m, c| m.max(*c))
    }

    /// Delta tracking with the hero channel's majorant (Woodcock et al. 1965; in the
    /// null-scattering path integral of Miller et al. 2019, with path-level spectral MIS as
    /// pbrt-v4's `VolPathIntegrator`): tentative collisions are drawn from the hero's
    /// piecewise-constant majorant cell by cell; each is real with probability
    /// `sigma_t,h(x) / sigma_maj,h`, else null. Per channel the contributions are
    /// `T_maj sigma_s` (real), `T_maj sigma_n` (null), `T_maj` (pass), and the densities
    /// `T_maj sigma_t` (real), `T_maj sigma_n` (null), `T_maj` (pass), with
    /// `sigma_n = sigma_maj - sigma_t` (`docs/theory.md` §12.3, (T29)).
    pub fn sample_free_flight(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        hero: usize,
        sampler: &mut Sampler,
    ) -> Flight {
        // Product over the null collisions so far (the same factor for throughput and ratios).
        let mut acc = Rgb::ONE;
        // Majorant transmittance since the last collision.
        let mut t_maj = Rgb::ONE;
        for seg in self.majorants.segments(o, d, 0.0, t_max) {
            let m = seg.sigma_maj[hero];
            let mut t = seg.t0;
            if m > 0.0 {
                loop {
                    let step = -(1.0 - sampler.next_1d()).ln() / m;
                    if t + step >= seg.t1 {
                        break;
                    }
                    t += step;
                    t_maj *= seg.sigma_maj.exp_neg(step);
                    let p = o + d * t;
                    let sigma_t = self.sigma_t(p);
                    let p_real = (sigma_t[hero] / m).min(1.0);
                    if sampler.next_1d() < p_real {
                        let pdf = t_maj[hero] * sigma_t[hero];
                        if pdf.is_nan() || pdf <= 0.0 {
                            return Flight::Pass { weight: Rgb::ZERO, ratio: Rgb::ONE };
                        }
                        let sigma_s = sigma_t * self.albedo.eval(p);
                        return Flight::Scatter {
                            t,
                            weight: acc * t_maj * sigma_s / pdf,
                            sigma_s: Rgb::ONE,
                            ratio: acc * t_maj * sigma_t / pdf,
                        };
                    }
                    let sigma_n = (seg.sigma_maj - sigma_t).map(|x| x.max(0.0));
                    let pdf = t_maj[hero] * sigma_n[hero];
                    if pdf.is_nan() || pdf <= 0.0 {
                        return Flight::Pass { weight: Rgb::ZERO, ratio: Rgb::ONE };
                    }
                    acc *= t_maj * sigma_n / pdf;
                    t_maj = Rgb::ONE;
                }
            }
            t_maj *= seg.sigma_maj.exp_neg(seg.t1 - t);
        }
        let ph = t_maj[hero];
        if ph.is_nan() || ph <= 0.0 {
            return Flight::Pass { weight: Rgb::ZERO, ratio: Rgb::ONE };
        }
        let f = acc * t_maj / ph;
        Flight::Pass { weight: f, ratio: f }
    }

    /// Ratio tracking (Novák et al. 2014, "Residual ratio tracking for estimating attenuation
    /// in participating media", Sec. 3.2): tentative collisions from the grey majorant
    /// `mu = max_c sigma_maj,c` of each cell, and the estimate
    /// `T = prod_i (1 - sigma_t(x_i) / mu)` per channel, unbiased for
    /// `exp(-int_t0^t1 sigma_t)` (`docs/theory.md` §12.4, (T30)); with Russian roulette once every
    /// channel is below 0.05.
    ///
    /// A constant `sigma_t` (a `constvolume`) is homogeneous inside its box: there the exact
    /// `exp(-sigma_t L)` over the length `L` inside the box, no random numbers.
    pub fn transmittance(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, sampler: &mut Sampler) -> Rgb {
        if let VolumeData::Const(v) = self.sigma_t.data {
            let len: f32 = self.majorants.segments(o, d, t0, t1).map(|g| g.t1 - g.t0).sum();
            return (v * self.scale).exp_neg(len);
        }
        let mut tr = Rgb::ONE;
        for seg in self.majorants.segments(o, d, t0, t1) {
            let mu = seg.sigma_maj.max_component();
            if mu <= 0.0 {
                continue;
            }
            let mut t = seg.t0;
            loop {
                t += -(1.0 - sampler.next_1d()).ln() / mu;
                if t >= seg.t1 {
                    break;
                }
                let sigma_t = self.sigma_t(o + d * t);
                tr *= (Rgb::ONE - sigma_t / mu).map(|x| x.max(0.0));
                if tr.max_component() < RR_THRESHOLD {
                    if sampler.next_1d() >= RR_SURVIVE {
                        return Rgb::ZERO;
                    }
                    tr /= RR_SURVIVE;
                }
            }
        }
        tr
    }

    /// The exact optical depth `int_t0^t1 sigma_t(o + t d) dt` by midpoint quadrature with
    /// `n` steps (tests and diagnostics only; the renderer never integrates deterministically).
    pub fn optical_depth(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, n: usize) -> Rgb {
        let (lo, hi) = self.sigma_t.bbox;
        // The medium is clipped to the sigma_t volume's box.
        let inside = |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
        let h = (t1 - t0) / n as f32;
        let mut tau = Rgb::ZERO;
        for i in 0..n {
            let p = o + d * (t0 + (i as f32 + 0.5) * h);
            if inside(p) {
                tau += self.sigma_t(p) * h;
            }
        }
        tau
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Filter, Grid, Wrap};
    use glam::Affine3A;
    use std::sync::Arc;

    fn medium(res: [u32; 3], f: impl Fn(u32, u32, u32) -> f32, majorant_res: u32) -> Heterogeneous {
        medium_with(res, f, majorant_res, Affine3A::IDENTITY, Wrap::Clamp)
    }

    /// `medium` with the volume's `to_world` preceded by `extra` (e.g. a rotation) and `wrap`.
    fn medium_with(
        res: [u32; 3],
        f: impl Fn(u32, u32, u32) -> f32,
        majorant_res: u32,
        extra: Affine3A,
        wrap: Wrap,
    ) -> Heterogeneous {
        let mut data = Vec::new();
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    data.push(f(x, y, z));
                }
            }
        }
        let grid = Grid { res, channels: 1, data, bbox: (Vec3::ZERO, Vec3::ONE) };
        let to_world = extra
            * Affine3A::from_translation(Vec3::new(-1.0, -0.5, 0.2))
            * Affine3A::from_scale(Vec3::splat(2.0));
        let sigma_t =
            Volume::new(VolumeData::Grid { grid: Arc::new(grid), filter: Filter::Trilinear, wrap }, to_world);
        let majorants = MajorantGrid::build(&sigma_t, 3.0, [majorant_res; 3]);
        Heterogeneous { sigma_t, albedo: Volume::constant(Rgb::splat(0.5)), scale: 3.0, majorants }
    }

    /// A constant extinction gets the exact transmittance over the ray's length inside the box,
    /// and a grid with the same bound everywhere, or nearly everywhere, one majorant cell.
    #[test]
    fn constant_extinction_is_exact_and_uniform_bounds_collapse() {
        let sigma_t = Volume::new(
            VolumeData::Const(Rgb::new(0.5, 0.4, 0.3)),
            Affine3A::from_translation(Vec3::splat(-0.5)),
        );
        let majorants = MajorantGrid::build(&sigma_t, 5.0, [1; 3]);
        let m = Heterogeneous { sigma_t, albedo: Volume::constant(Rgb::ZERO), scale: 5.0, majorants };
        let mut s = Sampler::from_seed(1);
        // From x = -2 along +x at y = z = 0: 1 unit inside [-0.5, 0.5]^3.
        let tr = m.transmittance(Vec3::new(-2.0, 0.0, 0.0), Vec3::X, 0.0, 10.0, &mut s);
        let want = Rgb::new(2.5, 2.0, 1.5).map(|x| (-x).exp());
        for c in 0..3 {
            assert!((tr[c] - want[c]).abs() < 1e-6, "{tr} vs {want}");
        }
        let flat = medium([4, 4, 4], |_, _, _| 0.7, MAJORANT_RES);
        assert_eq!(flat.majorants.res, [1; 3]);
        let ramp = medium([4, 4, 4], |x, _, _| x as f32, MAJORANT_RES);
        assert_eq!(ramp.majorants.res, [MAJORANT_RES; 3]);
        // Noise with its maximum in nearly every cell: the cells' mean bound is above
        // `COLLAPSE_SHARE` of the global one, one cell; the same noise in half the box (the
        // other half empty): below it, the grid kept.
        let noise = |x: u32, y: u32, z: u32| 0.5 + 0.5 * (((x * 7 + y * 13 + z * 29) % 11) as f32 / 10.0);
        let noisy = medium([32, 32, 32], noise, MAJORANT_RES);
        assert_eq!(noisy.majorants.res, [1; 3]);
        assert_eq!(noisy.majorants.cells[0], noisy.global_majorant());
        let half = medium([32, 32, 32], |x, y, z| if x < 16 { noise(x, y, z) } else { 0.0 }, MAJORANT_RES);
        assert_eq!(half.majorants.res, [MAJORANT_RES; 3]);
    }

    /// The DDA's segments tile the clipped ray interval without gaps, and every lookup on a
    /// segment is below its majorant (random rays through a random grid).
    ///
    /// Also for a rotated volume (its box then holds points outside the rotated grid, where the
    /// wrap mode decides the value) and the repeat and mirror wrap modes.
    #[test]
    fn dda_segments_tile_the_ray_and_bound_the_density() {
        let f = |x: u32, y: u32, z: u32| ((x * 5 + y * 3 + z * 7) % 13) as f32 / 13.0;
        let rotation = Affine3A::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        for m in [
            medium([9, 7, 5], f, MAJORANT_RES),
            medium_with([9, 7, 5], f, MAJORANT_RES, rotation, Wrap::Clamp),
            medium_with([9, 7, 5], f, MAJORANT_RES, rotation, Wrap::Repeat),
            medium_with([9, 7, 5], f, 5, rotation, Wrap::Mirror),
            // A smooth field: its maximum over a box sits at a corner, so a bound that misses
            // part of the box shows.
            medium_with([24, 20, 16], |x, y, z| (x + 2 * y + 3 * z) as f32 / 100.0, 3, rotation, Wrap::Clamp),
        ] {
            check_dda(&m);
        }
    }

    fn check_dda(m: &Heterogeneous) {
        let mut s = Sampler::from_seed(11);
        let (lo, hi) = m.sigma_t.bbox;
        for _ in 0..500 {
            let o = lo - Vec3::splat(1.0)
                + (hi - lo + Vec3::splat(2.0)) * Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
            let d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let segs: Vec<_> = m.majorants.segments(o, d, 0.0, 10.0).collect();
            for w in segs.windows(2) {
                assert_eq!(w[0].t1, w[1].t0);
            }
            for seg in &segs {
                assert!(seg.t1 >= seg.t0);
                for i in 0..8 {
                    let t = seg.t0 + (seg.t1 - seg.t0) * (i as f32 + 0.5) / 8.0;
                    let v = m.sigma_t(o + d * t)[0];
                    assert!(v <= seg.sigma_maj[0], "{v} > {}", seg.sigma_maj[0]);
                }
            }
            // The covered length is the ray's length inside the box.
            let covered: f32 = segs.iter().map(|g| g.t1 - g.t0).sum();
            let n = 4000;
            let inside = (0..n)
                .filter(|i| {
                    let p = o + d * (10.0 * (*i as f32 + 0.5) / n as f32);
                    p.cmpge(lo).all() && p.cmple(hi).all()
                })
                .count() as f32
                * 10.0
                / n as f32;
            assert!((covered - inside).abs() < 0.02, "{covered} vs {inside}");
        }
    }
}

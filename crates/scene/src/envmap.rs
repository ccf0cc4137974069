//! The environment map of Mitsuba 3's `envmap` emitter: a latitude-longitude radiance image at
//! infinity, its bilinear lookup, and importance sampling of directions by luminance.
//!
//! Conventions (Mitsuba 3, `src/emitters/envmap.cpp`): in the emitter's local frame a direction
//! `d` has `u = atan2(d.x, -d.z) / 2 pi` (wrapped to `[0, 1)`) and `v = acos(d.y) / pi`, so
//! `+y` is the zenith (top image row) and `-z` is the image centre column's left edge
//! (`u = 0`). World directions go to the local frame through the inverse of `to_world`.
//! The image of `W x H` pixels is looked up with pixel centres at `u = (i + 1/2) / W`
//! horizontally (periodic) and rows at `v = j / (H - 1)` vertically (row 0 at the zenith,
//! row `H - 1` at the nadir), interpolated bilinearly, times `scale`.
//!
//! Sampling: a 2D piecewise-constant distribution over the `W x (H - 1)` cells between pixel
//! centres, each weighted by the mean luminance of its four corners times `sin(theta)` at its
//! centre. A cell's `(u, v)` rectangle is sampled uniformly; the pdf per steradian is
//! `pdf_uv / (2 pi^2 sin(theta))`. Mitsuba warps a bilinear density instead; both are exact
//! importance samplers of directions with the same support wherever the luminance is positive,
//! so the estimates agree in expectation (directions whose cell has zero weight are found by
//! BSDF or phase sampling, whose MIS weight is then 1).

use glam::{Mat4, Vec3};
use haze_core::{fastmath, Rgb, PI};
use std::path::Path;

/// An environment map ready for lookup and sampling.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    width: usize,
    height: usize,
    /// Row-major linear RGB radiance, already multiplied by `scale`.
    pixels: Vec<Rgb>,
    to_world: Mat4,
    to_local: Mat4,
    /// Total weight of the cells.
    total: f64,
    /// What [`Self::sample`] draws the row from: the `height - 1` cell rows by weight, as an
    /// alias table (one table entry read per choice instead of a binary search through the
    /// cumulative weights, a cache miss per step on large maps).
    rows: Alias,
    /// The `width x (height - 1)` cells, row-major: per row, the alias table of its cells by
    /// weight.
    cells: Vec<AliasSlot>,
    /// Per cell row `j`: `sin(theta_j) / 4 * cells / total / (2 pi^2)`, so that the solid-angle
    /// pdf of a direction with `sin(theta)` in cell `(i, j)` is `row_pdf[j] * (sum of the
    /// cell's four corner luminances) / sin(theta)` (`pdf_uv / (2 pi^2 sin(theta))` with
    /// `pdf_uv` the cell's weight over the mean weight). The four corners are the pixels the
    /// bilinear lookup of the same point reads, so the pdf needs no table of its own: one cache
    /// line fewer per lookup, and 8 bytes per cell instead of 16.
    row_pdf: Vec<f32>,
}

/// Walker's alias table (Vose's construction, "A linear algorithm for generating random
/// numbers with a given distribution", IEEE TSE 1991): slot `k` keeps itself with probability
/// `q[k]`, else goes to `alias[k]`.
#[derive(Clone, Debug, PartialEq)]
struct Alias {
    slots: Vec<AliasSlot>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct AliasSlot {
    /// f32, so that a slot is 8 bytes (the tables of a 512x256 map then take 1 MB, half as
    /// much cache); an error of an ulp in `q` moves ~1e-7 of a slot's probability.
    q: f32,
    alias: u32,
}

impl Alias {
    /// From non-negative weights; all-zero weights give the uniform table (never drawn from:
    /// a zero-weight row is never chosen).
    fn new(w: &[f64]) -> Self {
        let n = w.len();
        let sum: f64 = w.iter().sum();
        let mut slots: Vec<AliasSlot> = (0..n).map(|k| AliasSlot { q: 1.0, alias: k as u32 }).collect();
        if sum <= 0.0 {
            return Alias { slots };
        }
        let mut p: Vec<f64> = w.iter().map(|&x| x * n as f64 / sum).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&k| p[k] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            slots[s] = AliasSlot { q: p[s] as f32, alias: l as u32 };
            p[l] -= 1.0 - p[s];
            if p[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left has probability 1 up to rounding.
        for k in small.into_iter().chain(large) {
            slots[k] = AliasSlot { q: 1.0, alias: k as u32 };
        }
        Alias { slots }
    }

    /// The slot `u` in `[0, 1)` picks, and a fresh uniform position in `[0, 1)` from what is
    /// left of `u`.
    #[inline]
    fn sample(&self, u: f64) -> (usize, f64) {
        pick(self.slots.len(), u, |k| self.slots[k])
    }
}

/// The alias-table draw over `n` slots read through `slot`: slot `k = floor(u n)` keeps itself
/// if the rest of `u` falls below its `q`, else gives its alias; the rest of `u`, rescaled to
/// `[0, 1)`, is returned as a fresh uniform number.
#[inline]
fn pick(n: usize, u: f64, slot: impl Fn(usize) -> AliasSlot) -> (usize, f64) {
    let k = first_slot(n, u);
    let f = u * n as f64 - k as f64;
    let slot = slot(k);
    let q = slot.q as f64;
    let (k, f) = if f < q { (k, f / q) } else { (slot.alias as usize, (f - q) / (1.0 - q)) };
    (k, f.clamp(0.0, 1.0 - 1e-7))
}

/// The slot [`pick`] reads first for `u`.
#[inline]
fn first_slot(n: usize, u: f64) -> usize {
    ((u * n as f64) as usize).min(n - 1)
}

/// Asks the CPU to bring `x`'s cache line closer (a hint: no effect on results, never faults).
#[inline(always)]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing architecturally and cannot fault; `x` is a valid
    // reference anyway.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// A direction sampled from an [`EnvMap`].
#[derive(Clone, Copy, Debug)]
pub struct EnvMapSample {
    /// Unit world direction towards the environment.
    pub d: Vec3,
    /// Radiance arriving from `d`.
    pub radiance: Rgb,
    /// Solid-angle pdf of `d`.
    pub pdf: f32,
}

impl EnvMap {
    /// Builds the map from `width x height` row-major RGB pixels (row 0 at the zenith). Needs at
    /// least 2x3 pixels, as Mitsuba 3; `to_world` should be a rotation (its inverse maps world
    /// directions to the map).
    pub fn new(width: usize, height: usize, rgb: &[f32], scale: f32, to_world: Mat4) -> Result<Self, String> {
        if width < 2 || height < 3 {
            return Err(format!("the environment map must be at least 2x3 pixels, got {width}x{height}"));
        }
        assert_eq!(rgb.len(), width * height * 3);
        let pixels: Vec<Rgb> = rgb.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2]) * scale).collect();
        if pixels.iter().any(|p| !p.is_finite() || p.min_component() < 0.0) {
            return Err("the environment map has negative or non-finite pixels".into());
        }
        let rows = height - 1;
        let lum = |x: usize, y: usize| pixels[y * width + x % width].luminance().max(0.0) as f64;
        // Per row, the alias table of its cells' weights, and the rows' cumulative weights.
        let mut marginal = Vec::with_capacity(rows + 1);
        let mut slots = Vec::with_capacity(rows * width);
        marginal.push(0.0);
        for j in 0..rows {
            let sin_theta = (PI as f64 * (j as f64 + 0.5) / rows as f64).sin();
            let mut acc = 0.0;
            let weights: Vec<f64> = (0..width)
                .map(|i| 0.25 * (lum(i, j) + lum(i + 1, j) + lum(i, j + 1) + lum(i + 1, j + 1)) * sin_theta)
                .collect();
            for w in &weights {
                acc += w;
            }
            slots.extend(Alias::new(&weights).slots);
            marginal.push(marginal[j] + acc);
        }
        let row_weights: Vec<f64> = marginal.windows(2).map(|m| m[1] - m[0]).collect();
        let total = marginal[rows];
        let count = (width * rows) as f64;
        let row_pdf = (0..rows)
            .map(|j| {
                let sin_theta = (PI as f64 * (j as f64 + 0.5) / rows as f64).sin();
                let f = 0.25 * sin_theta * count / (total * 2.0 * (PI as f64).powi(2));
                if f.is_finite() {
                    f as f32
                } else {
                    0.0
                }
            })
            .collect();
        Ok(EnvMap {
            width,
            height,
            pixels,
            to_world,
            to_local: to_world.inverse(),
            total,
            rows: Alias::new(&row_weights),
            cells: slots,
            row_pdf,
        })
    }

    /// Reads an OpenEXR (`.exr`) or Radiance HDR (`.hdr`, `.rgbe`) latitude-longitude image.
    pub fn load(path: &Path, scale: f32, to_world: Mat4) -> Result<Self, String> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let (w, h, rgb) = match ext.as_str() {
            "exr" => read_exr(path)?,
            "hdr" | "rgbe" | "pic" => read_hdr(path)?,
            _ => {
                return Err(format!(
                    "unsupported environment map format '{}' (haze reads .exr and .hdr)",
                    path.display()
                ))
            }
        };
        Self::new(w, h, &rgb, scale, to_world)
    }

    /// `(u, v)` of the unit world direction `d`, with `u` in `[0, 1)` and `v` in `[0, 1]`, and
    /// `sin(theta)` of `d` in the map's frame.
    fn uv(&self, d: Vec3) -> (f32, f32, f32) {
        let l = self.to_local.transform_vector3(d).normalize();
        let u = fastmath::atan2(l.x, -l.z) * (0.5 / PI);
        let v = fastmath::acos(l.y) / PI;
        (u - u.floor(), v, (l.x * l.x + l.z * l.z).sqrt())
    }

    /// `x.rem_euclid(width)` for `x` in `[-width, 2 width)`, the only values it gets (`x` is
    /// half a pixel below a `u` in `[0, 1)` times the width, or a sampled cell point, which can
    /// round up to `width`), without `rem_euclid`'s `fmodf` call: the same value, since
    /// `fmodf` is exact and then either adds `width` (negative `x`) or subtracts it.
    #[inline]
    fn wrap(&self, x: f32) -> f32 {
        let w = self.width as f32;
        if x < 0.0 {
            x + w
        } else if x >= w {
            x - w
        } else {
            x
        }
    }

    /// Texture coordinates `(x, y)` in cell units: `x` in `[0, width)` with pixel `i` at `x = i`,
    /// `y` in `[0, height - 1]` with row `j` at `y = j`.
    fn texel(&self, u: f32, v: f32) -> (f32, f32) {
        (self.wrap(u * self.width as f32 - 0.5), v * (self.height - 1) as f32)
    }

    fn cell(&self, x: f32, y: f32) -> (usize, usize) {
        ((x as usize).min(self.width - 1), (y as usize).min(self.height - 2))
    }

    /// Radiance arriving from the unit world direction `d` (bilinear lookup).
    pub fn eval(&self, d: Vec3) -> Rgb {
        let (u, v, _) = self.uv(d);
        let (x, y) = self.texel(u, v);
        self.bilinear(x, y)
    }

    /// The bilinear lookup at texel coordinates `(x, y)` ([`Self::texel`]).
    fn bilinear(&self, x: f32, y: f32) -> Rgb {
        self.bilinear_pdf::<false>(x, y, 0.0).0
    }

    /// The bilinear lookup at texel coordinates `(x, y)` and, `if PDF`, the solid-angle pdf of
    /// a direction there with `sin(theta)` (else 0): both from the cell's four corner pixels
    /// ([`Self::row_pdf`]).
    #[inline(always)]
    fn bilinear_pdf<const PDF: bool>(&self, x: f32, y: f32, sin_theta: f32) -> (Rgb, f32) {
        let (i, j) = self.cell(x, y);
        self.cell_lookup::<PDF>(i, j, x - i as f32, y - j as f32, sin_theta)
    }

    /// [`Self::bilinear_pdf`] at the point `(fx, fy)` of cell `(i, j)`.
    #[inline(always)]
    fn cell_lookup<const PDF: bool>(
        &self,
        i: usize,
        j: usize,
        fx: f32,
        fy: f32,
        sin_theta: f32,
    ) -> (Rgb, f32) {
        // `i < width` (`cell`); the right neighbour wraps around (no `%`: an integer division).
        let i1 = if i + 1 == self.width { 0 } else { i + 1 };
        let px = |i: usize, j: usize| self.pixels[j * self.width + i];
        let (p00, p10, p01, p11) = (px(i, j), px(i1, j), px(i, j + 1), px(i1, j + 1));
        let top = p00 * (1.0 - fx) + p10 * fx;
        let bottom = p01 * (1.0 - fx) + p11 * fx;
        let pdf = if PDF && sin_theta > 0.0 {
            let lum = |p: Rgb| p.luminance().max(0.0);
            (lum(p00) + lum(p10) + lum(p01) + lum(p11)) * self.row_pdf[j] / sin_theta
        } else {
            0.0
        };
        (top * (1.0 - fy) + bottom * fy, pdf)
    }

    /// `Int L(w) dw` over the sphere, per channel: the pixels summed with their solid angles
    /// (`2 pi / W * pi / H * sin(theta)` at the pixel row's centre). An approximation of the
    /// bilinear map's integral, for choosing emitters by power (`emitter_tables.rs`) only.
    pub fn radiance_integral(&self) -> Rgb {
        let (w, h) = (self.width as f64, self.height as f64);
        let mut sum = [0.0f64; 3];
        for (j, row) in self.pixels.chunks_exact(self.width).enumerate() {
            let omega = 2.0 * PI as f64 / w * PI as f64 / h * (PI as f64 * (j as f64 + 0.5) / h).sin();
            for p in row {
                for (c, s) in sum.iter_mut().enumerate() {
                    *s += p[c] as f64 * omega;
                }
            }
        }
        Rgb::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
    }

    /// Solid-angle pdf with which [`Self::sample`] returns the unit world direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        self.eval_pdf(d).1
    }

    /// [`Self::eval`] and [`Self::pdf`] of `d` at once (an escaping ray needs both), mapping
    /// `d` to the image (`atan2`, `acos`) once.
    pub fn eval_pdf(&self, d: Vec3) -> (Rgb, f32) {
        let (u, v, sin_theta) = self.uv(d);
        let (x, y) = self.texel(u, v);
        self.bilinear_pdf::<true>(x, y, sin_theta)
    }

    /// Samples a direction with probability proportional to luminance (see the module
    /// documentation); `None` if the map is black or the sample falls on a pole.
    pub fn sample(&self, u: glam::Vec2) -> Option<EnvMapSample> {
        self.sample_if(u, |_| true)
    }

    /// [`Self::sample`], but `None` as soon as the direction is known and `accept` refuses it,
    /// before its pdf and radiance are read (two cache misses on a large map): for a caller
    /// whose estimate would be zero in that direction (a surface lit from behind).
    #[inline]
    pub fn sample_if(&self, u: glam::Vec2, accept: impl Fn(Vec3) -> bool) -> Option<EnvMapSample> {
        if self.total <= 0.0 {
            return None;
        }
        let (j, fy) = self.rows.sample(u.y as f64);
        let row = &self.cells[j * self.width..(j + 1) * self.width];
        let (i, fx) = pick(self.width, u.x as f64, |k| row[k]);
        let (fx, fy) = (fx as f32, fy as f32);
        let x = i as f32 + fx;
        let y = j as f32 + fy;
        // Back from texel to (u, v): pixel i sits at u = (i + 1/2) / W.
        let tu = (x + 0.5) / self.width as f32;
        let v = y / (self.height - 1) as f32;
        let (theta, phi) = (v * PI, tu * 2.0 * PI);
        let (sin_t, cos_t) = fastmath::sin_cos(theta);
        let (sin_p, cos_p) = fastmath::sin_cos(phi);
        if sin_t <= 0.0 {
            return None;
        }
        let local = Vec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t);
        let d = self.to_world.transform_vector3(local).normalize();
        if !accept(d) {
            return None;
        }
        // The radiance and pdf at the sampled point of cell `(i, j)` itself: `eval_pdf(d)`
        // would map `d` back to it through `atan2` and `acos` (the same point up to rounding),
        // and `x` or `y` rounded up to the next integer would name the next cell.
        let (radiance, pdf) = self.cell_lookup::<true>(i, j, fx, fy, sin_t);
        (pdf > 0.0).then_some(EnvMapSample { d, radiance, pdf })
    }

    /// Prefetches what [`Self::sample_if`] with the same `u` reads after the row's table (which
    /// stays cached: `height - 1` slots): the cell slot `u.x` falls on, and the four pixels
    /// around that cell (which give its radiance and pdf). When the slot keeps itself (its
    /// `q`), the sample then finds everything in cache; when it goes to its alias, that cell's
    /// lines are still fetched then. A caller that knows the random numbers of a coming sample calls this before other
    /// work (a ray traversal), so that the cache misses overlap it instead of stalling the
    /// sample (volpath's next-event estimation: docs/performance.md §4.1).
    #[inline]
    pub fn prefetch(&self, u: glam::Vec2) {
        if self.total <= 0.0 {
            return;
        }
        let (j, _) = self.rows.sample(u.y as f64);
        let k = first_slot(self.width, u.x as f64);
        prefetch(&self.cells[j * self.width + k]);
        // Not `% width`: an integer division, dearer than the prefetch itself.
        let k1 = if k + 1 == self.width { 0 } else { k + 1 };
        for r in [j, j + 1] {
            prefetch(&self.pixels[r * self.width + k]);
            prefetch(&self.pixels[r * self.width + k1]);
        }
    }
}

pub(crate) fn read_exr(path: &Path) -> Result<(usize, usize, Vec<f32>), String> {
    use exr::prelude::*;
    type Pixels = (usize, usize, Vec<f32>);
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| -> Pixels { (res.width(), res.height(), vec![0.0; res.width() * res.height() * 3]) },
        |img: &mut Pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = (pos.y() * img.0 + pos.x()) * 3;
            img.2[i..i + 3].copy_from_slice(&[r, g, b]);
        },
    )
    .map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    Ok(image.layer_data.channel_data.pixels)
}

pub(crate) fn read_hdr(path: &Path) -> Result<(usize, usize, Vec<f32>), String> {
    let img = image::open(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    let rgb = img.into_rgb32f();
    Ok((rgb.width() as usize, rgb.height() as usize, rgb.into_raw()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::Sampler;

    /// A small map with structure: a bright blob, a dark band and a smooth gradient.
    fn test_map(to_world: Mat4) -> EnvMap {
        let (w, h) = (16, 9);
        let mut rgb = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let base = 0.2 + 0.05 * x as f32;
                let blob = if (3..6).contains(&x) && (2..4).contains(&y) { 20.0 } else { 0.0 };
                let band = if y == 6 { 0.0 } else { 1.0 };
                rgb.extend_from_slice(&[(base + blob) * band, base * 0.5 * band, (1.0 + blob) * band]);
            }
        }
        EnvMap::new(w, h, &rgb, 1.5, to_world).unwrap()
    }

    #[test]
    fn lookup_follows_mitsuba_axes() {
        // Row 0 is the zenith (+y); u = 0 is -z; u = 1/4 is +x.
        let (w, h) = (4, 3);
        let mut rgb = vec![0.0; w * h * 3];
        for x in 0..w {
            rgb[x * 3] = 1.0; // zenith row red
            rgb[((h - 1) * w + x) * 3 + 2] = 1.0; // nadir row blue
        }
        // Middle row: pixel 1 (u = 3/8) green.
        rgb[(w + 1) * 3 + 1] = 1.0;
        let m = EnvMap::new(w, h, &rgb, 1.0, Mat4::IDENTITY).unwrap();
        assert_eq!(m.eval(Vec3::Y), Rgb::new(1.0, 0.0, 0.0));
        assert_eq!(m.eval(-Vec3::Y), Rgb::new(0.0, 0.0, 1.0));
        let phi = 2.0 * PI * 3.0 / 8.0;
        let d = Vec3::new(phi.sin(), 0.0, -phi.cos());
        assert!((m.eval(d).0[1] - 1.0).abs() < 1e-5, "{}", m.eval(d));
        // A rotation of the map rotates the lookup.
        let rot = Mat4::from_rotation_y(0.7);
        let r = EnvMap::new(w, h, &rgb, 1.0, rot).unwrap();
        assert!((r.eval(rot.transform_vector3(d)).0[1] - 1.0).abs() < 1e-5);
    }

    #[test]
    fn pdf_integrates_to_one_and_matches_samples() {
        let m = test_map(Mat4::from_rotation_x(0.4) * Mat4::from_rotation_y(1.1));
        // Integral of the pdf over the sphere by a fine stratified quadrature.
        let n = 600;
        let mut integral = 0.0f64;
        for a in 0..n {
            for b in 0..2 * n {
                let cos_t = 1.0 - 2.0 * (a as f32 + 0.5) / n as f32;
                let phi = 2.0 * PI * (b as f32 + 0.5) / (2 * n) as f32;
                let s = (1.0 - cos_t * cos_t).sqrt();
                let d = Vec3::new(s * phi.cos(), s * phi.sin(), cos_t);
                integral += m.pdf(d) as f64;
            }
        }
        integral *= 4.0 * PI as f64 / (2 * n * n) as f64;
        assert!((integral - 1.0).abs() < 0.01, "{integral}");
        // Samples report the pdf that pdf() gives, and a radiance-weighted mean matches
        // quadrature of the radiance (the estimator is unbiased).
        let mut sampler = Sampler::new(3, 0, 0);
        let mut est = Rgb::ZERO;
        let count = 200_000;
        let mut on_edges = 0;
        for _ in 0..count {
            let s = m.sample(sampler.next_2d()).unwrap();
            let p = m.pdf(s.d);
            if (p - s.pdf).abs() > 1e-3 * s.pdf {
                // A sample on the edge between two cells (a cell's point 0 is its edge) may map
                // back, rounded, into the neighbour, whose pdf differs: a set of measure zero,
                // so rare, and only within rounding of an edge.
                let (u, v, _) = m.uv(s.d);
                let (x, y) = m.texel(u, v);
                let edge = |t: f32| (t - t.round()).abs() < 1e-4;
                assert!(edge(x) || edge(y), "{p} vs {} at texel ({x}, {y})", s.pdf);
                on_edges += 1;
            }
            est += s.radiance / s.pdf;
        }
        assert!(on_edges <= 5, "{on_edges} samples map back into another cell");
        est /= count as f32;
        let mut quad = Rgb::ZERO;
        for a in 0..n {
            for b in 0..2 * n {
                let cos_t = 1.0 - 2.0 * (a as f32 + 0.5) / n as f32;
                let phi = 2.0 * PI * (b as f32 + 0.5) / (2 * n) as f32;
                let s = (1.0 - cos_t * cos_t).sqrt();
                quad += m.eval(Vec3::new(s * phi.cos(), s * phi.sin(), cos_t));
            }
        }
        quad *= 4.0 * PI / (2 * n * n) as f32;
        for c in 0..3 {
            assert!((est.0[c] / quad.0[c] - 1.0).abs() < 0.01, "{est} vs {quad}");
        }
    }

    /// Each slot's probability in the alias table (kept, plus aliased to) is its weight's
    /// share; zero weights are never drawn.
    #[test]
    fn alias_table_probabilities() {
        let w = [0.0, 3.0, 1.0, 0.0, 0.5, 7.25, 2.0];
        let table = Alias::new(&w);
        let n = w.len() as f64;
        let sum: f64 = w.iter().sum();
        let mut p = vec![0.0; w.len()];
        for (k, s) in table.slots.iter().enumerate() {
            p[k] += s.q as f64 / n;
            p[s.alias as usize] += (1.0 - s.q as f64) / n;
        }
        for k in 0..w.len() {
            assert!((p[k] - w[k] / sum).abs() < 1e-7, "slot {k}: {} vs {}", p[k], w[k] / sum);
        }
        for i in 0..1000 {
            let (k, f) = table.sample(i as f64 / 1000.0);
            assert!(w[k] > 0.0 && (0.0..1.0).contains(&f), "{k} {f}");
        }
    }

    /// The prefetch reads the slot and pixels that a sample with the same numbers starts from
    /// (by index, so an index off the tables would panic here), at the edges of `[0, 1]^2`
    /// too, where the cell wraps around to column 0 or sits in the last row.
    #[test]
    fn prefetch_stays_within_the_tables_at_the_edges() {
        let m = test_map(Mat4::IDENTITY);
        let edges = [0.0, 1e-7, 0.5, 1.0 - 1e-7, 1.0];
        for x in edges {
            for y in edges {
                m.prefetch(glam::Vec2::new(x, y));
                let _ = m.sample(glam::Vec2::new(x, y));
            }
        }
        let black = EnvMap::new(2, 3, &[0.0; 18], 1.0, Mat4::IDENTITY).unwrap();
        black.prefetch(glam::Vec2::new(1.0, 1.0));
        assert!(black.sample(glam::Vec2::new(0.5, 0.5)).is_none());
    }

    #[test]
    fn sampling_histogram_matches_pdf() {
        let m = test_map(Mat4::from_rotation_z(0.3));
        let mut sampler = Sampler::new(7, 0, 0);
        let r = haze_testkit::chi2::chi2_sphere(
            || m.sample(sampler.next_2d()).map_or(Vec3::NAN, |s| s.d),
            |d| m.pdf(d),
            200_000,
        );
        assert!(r.passed(0.01), "{r:?}");
    }
}

//! The per-pixel state of a padded sample pattern and the value of each dimension.
//!
//! A pixel sample `i` (its index within the pixel) is pattern index `s = i mod n` of round
//! `i / n`; dimension `d` of it is point `permute(s, n, seed(round, d))` of the generator's
//! point set (for `orthogonal`, one permutation shared by every dimension: the sample is one
//! row of the orthogonal array). Mitsuba 3's samplers define the point sets; the seeds here are
//! haze's (per pixel from the render's seed, per round and per dimension by hashing).

use super::permute::{hash2, permute};
use super::{SamplerKind, SamplerSpec};
use crate::streams::{PATTERN_PERMUTATIONS, PATTERN_SCRAMBLE};

/// The largest `f32` below 1: sums like `(p + jitter) / n` round up to 1 for large `n`.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The per-purpose permutation seeds' multipliers (`crate::streams::PATTERN_PERMUTATIONS`).
const SEED_INDEX: u32 = PATTERN_PERMUTATIONS[0];
const SEED_SUB_X: u32 = PATTERN_PERMUTATIONS[1];
const SEED_SUB_Y: u32 = PATTERN_PERMUTATIONS[2];

/// Where a pixel's pattern stands: the generator, the pixel's seeds, the sample and the
/// dimension to draw next.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pattern {
    kind: SamplerKind,
    jitter: bool,
    /// Points per round (`sample_count`).
    n: u32,
    /// 2D grid `(columns, rows)`; `orthogonal`: `(p, p)`.
    res: (u32, u32),
    /// Per pixel, from the render's seed.
    pixel_seed: u64,
    /// Per pixel and round.
    round_seed: u32,
    /// `ldsampler`'s digital shifts (xor) of the two coordinates, per pixel.
    scramble: (u32, u32),
    /// The sample's index within the round.
    index: u32,
    round: u32,
    /// The next dimension (Mitsuba 3's dimension index: one per `next_1d` or `next_2d`).
    dim: u32,
}

impl Pattern {
    /// The pattern of `spec` for the pixel keyed `pixel` of a render seeded `seed`; `None` for
    /// `independent`. Positioned at sample 0. Out of line: `Sampler::for_pixel`, made per pixel
    /// and pass, inlines the independent case and calls this only for a pattern.
    #[inline(never)]
    pub(crate) fn new(spec: &SamplerSpec, seed: u64, pixel: u64) -> Option<Pattern> {
        if spec.kind == SamplerKind::Independent {
            return None;
        }
        let pixel_seed = crate::hash::mix64(seed ^ crate::hash::mix64(pixel ^ crate::streams::PATTERN_PIXEL));
        let mut p = Pattern {
            kind: spec.kind,
            jitter: spec.jitter,
            n: spec.sample_count(),
            res: spec.resolution(),
            pixel_seed,
            round_seed: 0,
            scramble: (hash2(pixel_seed, PATTERN_SCRAMBLE[0]), hash2(pixel_seed, PATTERN_SCRAMBLE[1])),
            index: 0,
            round: 0,
            dim: 0,
        };
        p.start_sample(0);
        Some(p)
    }

    /// Moves to the pixel's sample `i` (its index within the pixel, over every pass), dimension 0.
    #[inline]
    pub(crate) fn start_sample(&mut self, i: u64) {
        self.round = (i / self.n as u64) as u32;
        self.index = (i % self.n as u64) as u32;
        self.round_seed = hash2(self.pixel_seed, self.round as u64);
        self.dim = 0;
    }

    /// The next dimension as one number; `jitter` draws the uniform offsets inside strata.
    pub(crate) fn next_1d(&mut self, jitter: &mut impl FnMut() -> f32) -> f32 {
        let d = self.take_dimension();
        let n = self.n;
        match self.kind {
            SamplerKind::Independent => unreachable!("independent sampling has no pattern"),
            SamplerKind::Stratified | SamplerKind::Multijitter => {
                // n intervals of width 1/n, one per sample.
                let p = permute(self.index, n, self.dim_seed(d));
                let j = if self.jitter { jitter() } else { 0.5 };
                unit((p as f32 + j) / n as f32)
            }
            SamplerKind::Orthogonal => self.bose(d, jitter),
            SamplerKind::LdSampler => {
                let i = self.ld_index(d);
                to_unit(i.reverse_bits() ^ self.scramble.0)
            }
        }
    }

    /// The next dimension as a point of the unit square (`orthogonal`: two dimensions, as in
    /// Mitsuba 3).
    pub(crate) fn next_2d(&mut self, jitter: &mut impl FnMut() -> f32) -> (f32, f32) {
        if self.kind == SamplerKind::Orthogonal {
            let x = self.next_1d(jitter);
            return (x, self.next_1d(jitter));
        }
        let d = self.take_dimension();
        let n = self.n;
        let (rx, ry) = self.res;
        match self.kind {
            SamplerKind::Stratified => {
                // One sample per cell of the r x r grid.
                let p = permute(self.index, n, self.dim_seed(d));
                let (x, y) = (p % rx, p / rx);
                let (jx, jy) = self.jitter_pair(jitter);
                (unit((x as f32 + jx) / rx as f32), unit((y as f32 + jy) / ry as f32))
            }
            SamplerKind::Multijitter => {
                // Kensler 2013, eq. 3 with shuffled sub-strata: cell (x, y) of the rx x ry grid,
                // and inside it sub-column sy(y) and sub-row sx(x), permutations shared by a row
                // and a column, so that the rx * ry x-offsets (and y-offsets) fall one per
                // interval of width 1 / n.
                let seed = self.dim_seed(d);
                let s = permute(self.index, n, seed.wrapping_mul(SEED_INDEX));
                let (x, y) = (s % rx, s / rx);
                let sx = permute(x, rx, seed.wrapping_mul(SEED_SUB_X));
                let sy = permute(y, ry, seed.wrapping_mul(SEED_SUB_Y));
                let (jx, jy) = self.jitter_pair(jitter);
                let u = (x as f32 + (sy as f32 + jx) / ry as f32) / rx as f32;
                let v = (y as f32 + (sx as f32 + jy) / rx as f32) / ry as f32;
                (unit(u), unit(v))
            }
            SamplerKind::LdSampler => {
                let i = self.ld_index(d);
                (to_unit(i.reverse_bits() ^ self.scramble.0), to_unit(sobol_2(i) ^ self.scramble.1))
            }
            SamplerKind::Independent | SamplerKind::Orthogonal => unreachable!(),
        }
    }

    #[inline]
    fn take_dimension(&mut self) -> u32 {
        let d = self.dim;
        self.dim = d.wrapping_add(1);
        d
    }

    /// The permutation seed of dimension `d` in this round.
    #[inline]
    fn dim_seed(&self, d: u32) -> u32 {
        hash2(self.round_seed as u64, d as u64)
    }

    fn jitter_pair(&self, jitter: &mut impl FnMut() -> f32) -> (f32, f32) {
        if self.jitter {
            let jx = jitter();
            (jx, jitter())
        } else {
            (0.5, 0.5)
        }
    }

    /// `ldsampler`'s point index for dimension `d`: the round's block of `n` points of the
    /// sequence, in an order shuffled per dimension. Blocks of `n = 4^k` consecutive points
    /// starting at a multiple of `n` are (0, 2k, 2)-nets, so every round is one.
    fn ld_index(&self, d: u32) -> u32 {
        let shuffled = permute(self.index, self.n, self.dim_seed(d));
        self.round.wrapping_mul(self.n).wrapping_add(shuffled)
    }

    /// Dimension `j` of the pattern index's row of the Bose orthogonal array OA(p^2, p + 1, p, 2)
    /// (Jarosz et al. 2019, "Orthogonal array sampling for Monte Carlo rendering", section 4; Mitsuba 3's
    /// `orthogonal` with strength 2): row `i = (a0, a1)` in base p; column 0 is `a0`, column 1
    /// `a1`, column `j >= 2` is `a0 + (j - 1) a1 mod p`. Any two of the first `p + 1` columns
    /// take every pair of values once, so every 2D projection of those dimensions has one sample
    /// per cell of the p x p grid. The multi-jittered offset inside the stratum is the paired
    /// column (`j`'s neighbour), which makes each dimension `n`-rooks stratified in 1D too.
    /// Columns past `p` repeat modulo p with fresh permutations.
    fn bose(&self, j: u32, jitter: &mut impl FnMut() -> f32) -> f32 {
        let p = self.res.0;
        let i = permute(self.index, self.n, self.round_seed);
        let (a0, a1) = (i / p, i % p);
        let column = |c: u32| -> u32 {
            match c {
                0 => a0,
                1 => a1,
                c => ((a0 as u64 + ((c - 1) % p) as u64 * a1 as u64) % p as u64) as u32,
            }
        };
        let (a_j, a_k) = match j {
            0 => (a0, a1),
            1 => (a1, a0),
            j => (column(j), column(if j % 2 == 1 { j - 1 } else { j + 1 })),
        };
        let seed = self.round_seed.wrapping_mul(j.wrapping_add(1));
        let stratum = permute(a_j, p, seed.wrapping_mul(SEED_INDEX));
        let sub = permute(a_k, p, seed.wrapping_mul(SEED_SUB_X));
        let jit = if self.jitter { jitter() } else { 0.5 };
        unit((stratum as f32 + (sub as f32 + jit) / p as f32) / p as f32)
    }
}

/// `x` kept below 1.
#[inline]
fn unit(x: f32) -> f32 {
    x.min(ONE_MINUS_EPSILON)
}

/// The top 24 bits of `bits` as a number in `[0, 1)`.
#[inline]
fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Sobol's second dimension as 32 bits (`x / 2^32`): generator matrix with columns
/// `v_0 = 2^31`, `v_{k+1} = v_k ^ (v_k >> 1)` (the upper-triangular Pascal matrix mod 2),
/// xored over the set bits of `index`.
pub(crate) fn sobol_2(mut index: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut x = 0u32;
    while index != 0 {
        if index & 1 == 1 {
            x ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    x
}

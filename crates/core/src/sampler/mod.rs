//! Mitsuba 3's sample generators: which one a render uses ([`SamplerSpec`]) and the per-pixel
//! patterns behind [`crate::Sampler`] ([`pattern`]).
//!
//! Every generator but `independent` is a *padded* pattern: each dimension of a pixel sample
//! (one `next_1d` or `next_2d` call, Mitsuba 3's dimension index) takes its value from a set of
//! `sample_count` well-distributed points of its own, the sample's index within the pixel
//! shuffled by a permutation seeded per pixel and dimension (Kollig and Keller 2002, "Efficient
//! multidimensional sampling"). Mitsuba 3's `stratified`, `multijitter`, `orthogonal` and
//! `ldsampler` (the (0,2)-sequence of van der Corput and Sobol's second dimension: Mitsuba 3.9
//! has no other Sobol sampler) differ only in that point set. A pixel sample index past
//! `sample_count` starts a new *round*: a fresh randomisation of the same set (for `ldsampler`
//! the sequence's next `sample_count` points), so time-budget renders and spp above the
//! pattern's size stay unbiased.
//!
//! The random jitter inside strata comes from the pixel's independent stream, the PCG32 stream
//! of `independent` (Mitsuba 3's `PCG32Sampler` base does the same); light paths, which belong
//! to no pixel, always draw from independent streams.

pub mod pattern;
pub mod permute;

#[cfg(test)]
mod tests;

use std::fmt;

/// The sample generators, by their Mitsuba 3 plugin names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Independent uniform numbers (a PCG32 stream per pixel and pass).
    Independent,
    /// Jittered strata: a `sqrt(n) x sqrt(n)` grid in 2D, `n` intervals in 1D.
    Stratified,
    /// Correlated multi-jittered sampling (Kensler 2013): a grid in 2D whose samples are also
    /// `n`-rooks stratified along both axes.
    Multijitter,
    /// Orthogonal arrays of strength 2 by the Bose construction (Jarosz et al. 2019): every 2D
    /// projection of the first `p + 1` dimensions multi-jittered, `n = p^2`, `p` prime.
    Orthogonal,
    /// The (0,2)-sequence with a random digital shift (xor) per pixel and a shuffled sample order
    /// per dimension (Kollig and Keller 2002; Mitsuba 1's default).
    LdSampler,
}

impl SamplerKind {
    /// Every generator, in the order help texts list them.
    pub const ALL: [SamplerKind; 5] = [
        SamplerKind::Independent,
        SamplerKind::Stratified,
        SamplerKind::Multijitter,
        SamplerKind::Orthogonal,
        SamplerKind::LdSampler,
    ];
    /// Their names, as `<sampler type="...">` and `--sampler` spell them.
    pub const NAMES: [&'static str; 5] =
        ["independent", "stratified", "multijitter", "orthogonal", "ldsampler"];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    pub fn from_name(name: &str) -> Option<SamplerKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// `sample_count` as Mitsuba 3.9 rounds it for this generator (it warns and renders the
    /// rounded count): `stratified` up to a square, `multijitter` to `ceil(n / floor(sqrt(n)))
    /// * floor(sqrt(n))`, `orthogonal` to the square of a prime (at least 4), `ldsampler` to a
    /// square power of two (at least 4); `independent` keeps `n`. `n >= 1`.
    pub fn round_sample_count(self, n: u32) -> u32 {
        let n = n.max(1);
        match self {
            SamplerKind::Independent => n,
            SamplerKind::Stratified => {
                let r = ceil_sqrt(n);
                r.saturating_mul(r)
            }
            SamplerKind::Multijitter => {
                let (x, y) = multijitter_resolution(n);
                x.saturating_mul(y)
            }
            SamplerKind::Orthogonal => {
                let mut p = ceil_sqrt(n).max(2);
                while !is_prime(p) {
                    p += 1;
                }
                p.saturating_mul(p)
            }
            SamplerKind::LdSampler => {
                let mut r = 2u32;
                while r.saturating_mul(r) < n {
                    r *= 2;
                }
                r.saturating_mul(r)
            }
        }
    }
}

impl fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The smallest `r` with `r * r >= n`.
fn ceil_sqrt(n: u32) -> u32 {
    let mut r = (n as f64).sqrt() as u32;
    while (r as u64) * (r as u64) < n as u64 {
        r += 1;
    }
    while r > 0 && ((r - 1) as u64) * ((r - 1) as u64) >= n as u64 {
        r -= 1;
    }
    r
}

fn is_prime(p: u32) -> bool {
    p >= 2 && (2..).take_while(|d| d * d <= p).all(|d| p % d != 0)
}

/// Mitsuba 3.9's `multijitter` grid for `n` samples: `y = floor(sqrt(n))` rows and
/// `x = ceil(n / y)` columns (aspect close to 1; `x * y` is the rounded count).
fn multijitter_resolution(n: u32) -> (u32, u32) {
    let mut y = ceil_sqrt(n);
    if y * y > n {
        y -= 1;
    }
    let y = y.max(1);
    (n.div_ceil(y), y)
}

/// Mitsuba 3's default `sample_count` for every sampler.
pub const DEFAULT_SAMPLE_COUNT: u32 = 4;

/// The sample generator of a render and its parameters (Mitsuba 3's names and defaults).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplerSpec {
    pub kind: SamplerKind,
    /// Samples per pixel of the pattern, as [`SamplerKind::round_sample_count`] rounds it.
    sample_count: u32,
    /// `stratified`, `multijitter`, `orthogonal`: a random offset inside each sub-stratum
    /// (`jitter`, default true); without it the stratum's centre (deterministic, biased).
    pub jitter: bool,
}

impl SamplerSpec {
    /// `kind` with `sample_count` rounded as Mitsuba 3 does and its default parameters.
    pub fn new(kind: SamplerKind, sample_count: u32) -> SamplerSpec {
        SamplerSpec { kind, sample_count: kind.round_sample_count(sample_count), jitter: true }
    }

    /// The `independent` sampler with `sample_count` samples per pixel.
    pub fn independent(sample_count: u32) -> SamplerSpec {
        SamplerSpec::new(SamplerKind::Independent, sample_count)
    }

    /// Samples per pixel (rounded for the generator).
    pub fn sample_count(&self) -> u32 {
        self.sample_count
    }

    /// The same generator and parameters for `n` samples per pixel (rounded).
    pub fn with_sample_count(self, n: u32) -> SamplerSpec {
        SamplerSpec { sample_count: self.kind.round_sample_count(n), ..self }
    }

    /// `kind` instead: the parameters are kept when the kind is the same, else the defaults.
    pub fn with_kind(self, kind: SamplerKind) -> SamplerSpec {
        if kind == self.kind {
            self
        } else {
            SamplerSpec::new(kind, self.sample_count)
        }
    }

    /// The grid of the 2D stratification: `(columns, rows)`.
    pub(crate) fn resolution(&self) -> (u32, u32) {
        match self.kind {
            SamplerKind::Multijitter => multijitter_resolution(self.sample_count),
            _ => {
                let r = ceil_sqrt(self.sample_count);
                (r, r)
            }
        }
    }
}

impl std::default::Default for SamplerSpec {
    fn default() -> Self {
        SamplerSpec::independent(DEFAULT_SAMPLE_COUNT)
    }
}

//! Seeded, reproducible random numbers.
//!
//! Every random decision in haze draws from a [`Sampler`] whose stream is a pure function of
//! `(seed, pixel, pass)` (or `(seed, light path, pass)` for light tracing), never of the thread
//! that runs it: the same seed gives a bit-identical image whatever the thread count. A pixel's
//! sampler may follow one of Mitsuba 3's sample patterns ([`crate::sampler`]), then its values
//! depend also on the sample's index within the pixel ([`Sampler::start_sample`]).

use crate::sampler::pattern::Pattern;
use crate::sampler::SamplerSpec;
use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg32;

/// Uniform numbers for one pixel's samples (or one light path): Mitsuba's `independent`, a
/// PCG32 stream, unless made by [`Sampler::for_pixel`] with a pattern, whose `next_1d` and
/// `next_2d` then take each dimension from it (`next_u32` always from the stream).
#[derive(Clone, Debug)]
pub struct Sampler {
    rng: Pcg32,
    pattern: Option<Pattern>,
}

pub use crate::hash::mix64;

impl Sampler {
    /// A stream determined by `seed` and two integer keys (e.g. pixel index and pass index).
    pub fn new(seed: u64, key_a: u64, key_b: u64) -> Self {
        let state = mix64(seed ^ mix64(key_a.wrapping_add(crate::streams::SAMPLER_STATE)));
        let stream = mix64(key_b ^ mix64(seed.wrapping_add(crate::streams::SAMPLER_SEQUENCE)));
        Sampler { rng: Pcg32::new(state, stream | 1), pattern: None }
    }

    /// The sampler of pixel `pixel` in pass `pass` of a render seeded `seed` with generator
    /// `spec`: the stream of [`Sampler::new`]`(seed, pixel, pass)` (so `independent` gives the
    /// same numbers), and `spec`'s pattern keyed by `(seed, pixel)`, at sample 0 until
    /// [`Sampler::start_sample`] says which sample comes.
    #[inline]
    pub fn for_pixel(spec: &SamplerSpec, seed: u64, pixel: u64, pass: u64) -> Self {
        let mut s = Sampler::new(seed, pixel, pass);
        // Made once per pixel and pass: `independent` inline, a pattern's setup out of line.
        if spec.kind != crate::sampler::SamplerKind::Independent {
            s.pattern = Pattern::new(spec, seed, pixel);
        }
        s
    }

    /// From a single 64-bit seed (tests and tools).
    pub fn from_seed(seed: u64) -> Self {
        Sampler { rng: Pcg32::seed_from_u64(seed), pattern: None }
    }

    /// The next values are those of the pixel's sample `index` (its index within the pixel
    /// over all passes), from its first dimension. No effect on an independent sampler.
    #[inline]
    pub fn start_sample(&mut self, index: u64) {
        if let Some(p) = &mut self.pattern {
            p.start_sample(index);
        }
    }

    /// Uniform in `[0, 1)`, 24 bits of precision so that the result is never 1.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        match self.pattern {
            None => uniform(&mut self.rng),
            Some(_) => self.pattern_1d(),
        }
    }

    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        match self.pattern {
            None => {
                let a = uniform(&mut self.rng);
                glam::Vec2::new(a, uniform(&mut self.rng))
            }
            Some(_) => self.pattern_2d(),
        }
    }

    // The patterns out of line: the independent stream (every light path, and pixels without a
    // pattern) inlines into the walks at a few instructions per number.
    #[inline(never)]
    fn pattern_1d(&mut self) -> f32 {
        let Sampler { rng, pattern } = self;
        match pattern {
            Some(p) => p.next_1d(&mut || uniform(rng)),
            None => uniform(rng),
        }
    }

    #[inline(never)]
    fn pattern_2d(&mut self) -> glam::Vec2 {
        let Sampler { rng, pattern } = self;
        match pattern {
            Some(p) => {
                let (x, y) = p.next_2d(&mut || uniform(rng));
                glam::Vec2::new(x, y)
            }
            None => glam::Vec2::new(uniform(rng), uniform(rng)),
        }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.rng.next_u32()
    }
}

/// Uniform in `[0, 1)` from the top 24 bits of the stream's next number.
#[inline]
fn uniform(rng: &mut Pcg32) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f32> = (0..8)
            .map({
                let mut s = Sampler::new(7, 3, 1);
                move |_| s.next_1d()
            })
            .collect();
        let b: Vec<f32> = (0..8)
            .map({
                let mut s = Sampler::new(7, 3, 1);
                move |_| s.next_1d()
            })
            .collect();
        let c: Vec<f32> = (0..8)
            .map({
                let mut s = Sampler::new(7, 3, 2);
                move |_| s.next_1d()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.iter().all(|x| (0.0..1.0).contains(x)));
    }

    #[test]
    fn uniform_mean_and_variance() {
        let mut s = Sampler::new(1, 2, 3);
        let n = 200_000;
        let (mut m, mut m2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let x = s.next_1d() as f64;
            m += x;
            m2 += x * x;
        }
        m /= n as f64;
        m2 /= n as f64;
        // Standard error of the mean is sqrt(1/12/n) ~ 6.5e-4.
        assert!((m - 0.5).abs() < 4e-3, "mean {m}");
        assert!((m2 - m * m - 1.0 / 12.0).abs() < 2e-3);
    }
}

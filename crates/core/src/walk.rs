//! Russian roulette, the rule every path walker applies (through `haze_render::walker`,
//! `Walker::roulette`): `volpath`, the many-light camera walk, light tracing and the caustic
//! paths. The walker, with its cap on a walk's vertices, lives in `haze-render`; the rule lives
//! here, below every crate that samples.
//!
//! Russian roulette (Arvo & Kirk 1990; pbrt-v4 Section 14.1.6): past the walker's roulette
//! depth a path survives with probability `q = min(m, MAX_SURVIVAL)`, where `m` is the largest
//! channel of its throughput relative to the pdf ratio of its hero-channel sampling (times
//! `eta^2` in volpath, Mitsuba's radiance scaling at refractions), and a survivor's throughput
//! is divided by `q`. The expectation is unchanged for any `q > 0`; the cap below 1 ends paths
//! whose throughput never drops (albedo-1 media, white mirrors) after about 20 further events
//! on average.

/// The largest survival probability of Russian roulette: a path with an undiminished throughput
/// still ends with probability 0.05 per event past the roulette depth.
pub const MAX_SURVIVAL: f32 = 0.95;

/// Russian roulette with the relative throughput `m` (module docs): `Some(q)`, the survival
/// probability to divide the throughput by, if the path survives the uniform number `u`;
/// `None` if it ends.
#[inline]
pub fn roulette(m: f32, u: f32) -> Option<f32> {
    let q = m.min(MAX_SURVIVAL);
    (u < q).then_some(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Survival probability is `min(m, 0.95)`: the fraction of uniform numbers that survive.
    #[test]
    fn roulette_survives_with_probability_q() {
        for &m in &[0.0f32, 0.1, 0.5, 0.94, 0.95, 1.0, 7.0] {
            let n = 10_000;
            let survived = (0..n).filter(|i| roulette(m, (*i as f32 + 0.5) / n as f32).is_some()).count();
            let q = m.min(MAX_SURVIVAL);
            assert!((survived as f32 / n as f32 - q).abs() <= 1.0 / n as f32, "m {m}: {survived}");
            if let Some(s) = roulette(m, 0.0) {
                assert_eq!(s, q);
            }
        }
    }

    /// Dividing by `q` keeps the expectation: the mean of `throughput / q` over survivors times
    /// their fraction is the throughput.
    #[test]
    fn roulette_keeps_the_expectation() {
        let n = 100_000;
        for &m in &[0.05f32, 0.3, 0.9, 2.0] {
            let sum: f64 =
                (0..n).filter_map(|i| roulette(m, (i as f32 + 0.5) / n as f32)).map(|q| 1.0 / q as f64).sum();
            assert!((sum / n as f64 - 1.0).abs() < 1e-3, "m {m}: {}", sum / n as f64);
        }
    }
}

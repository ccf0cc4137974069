//! Transmittance and free-flight sampling in homogeneous media with RGB extinction.
//!
//! Chromatic extinction is sampled with *path-level* spectral MIS (hero wavelength sampling,
//! Wilkie et al. 2014; for media, Miller, Georgiev and Jarosz 2019, "A null-scattering path
//! integral formulation of light transport", Sec. 5.4, also used by pbrt-v4 and Mitsuba 3's
//! `volpathmis`): one channel `h` (the hero) is chosen per path and every free-flight distance
//! is sampled from its exponential. Alongside the throughput `f/p_h` the integrator keeps the
//! ratios `r_c = p_c(path)/p_h(path)` of the pdfs the other channels would have had; the
//! one-sample MIS estimate of the path is `f / mean_c p_c = (f/p_h) / mean(r)`. Because
//! `r_h = 1`, `mean(r) >= 1/3`, and the channel-`c` throughput and `r_c` share their
//! transmittance factors, contributions stay bounded however different the channels are.

use crate::spectrum::Rgb;

/// `T_r(d) = exp(-sigma_t d)` per channel (Beer-Lambert).
#[inline]
pub fn transmittance(sigma_t: Rgb, d: f32) -> Rgb {
    if d.is_infinite() {
        return sigma_t.map(|s| if s > 0.0 { 0.0 } else { 1.0 });
    }
    sigma_t.exp_neg(d)
}

/// Outcome of sampling a free-flight distance along a segment of length `t_max` from the hero
/// channel's exponential.
#[derive(Clone, Copy, Debug)]
pub enum FreeFlight {
    /// A real interaction at distance `t`: `weight = T_r(t) / p_h(t)` with
    /// `p_c(t) = sigma_t[c] exp(-sigma_t[c] t)` (per unit length); multiply by `sigma_s` to get
    /// the scattering throughput. `ratio[c] = p_c(t) / p_h(t)`.
    Interaction { t: f32, weight: Rgb, ratio: Rgb },
    /// No interaction before `t_max`: `weight = T_r(t_max) / P_h` with
    /// `P_c = exp(-sigma_t[c] t_max)`, `ratio[c] = P_c / P_h`.
    Pass { weight: Rgb, ratio: Rgb },
}

/// Picks the hero channel from a uniform number.
pub fn hero_channel(u: f32) -> usize {
    ((u * 3.0) as usize).min(2)
}

/// The distance [`sample_free_flight`] samples from `u`, `-ln(1 - u) / sigma_t[hero]` (infinite
/// for a zero hero extinction), before it is compared with the surface: a caller that knows it
/// first can cut its ray there (a free flight that ends sooner needs no surface).
#[inline]
pub fn free_flight_distance(sigma_t: Rgb, hero: usize, u: f32) -> f32 {
    let s = sigma_t[hero];
    if s > 0.0 {
        -(1.0 - u).ln() / s
    } else {
        f32::INFINITY
    }
}

/// Samples a free-flight distance from the exponential of channel `hero`.
pub fn sample_free_flight(sigma_t: Rgb, t_max: f32, hero: usize, u: f32) -> FreeFlight {
    free_flight_at(sigma_t, t_max, hero, free_flight_distance(sigma_t, hero, u))
}

/// [`sample_free_flight`] given the distance `t` it sampled ([`free_flight_distance`]): an
/// interaction at `t` if it comes before `t_max`, else passing to `t_max`, with the weights of
/// channel `hero`'s exponential.
pub fn free_flight_at(sigma_t: Rgb, t_max: f32, hero: usize, t: f32) -> FreeFlight {
    if t < t_max {
        let tr = sigma_t.exp_neg(t);
        let pdf = sigma_t * tr;
        let ph = pdf[hero];
        FreeFlight::Interaction { t, weight: tr / ph, ratio: pdf / ph }
    } else {
        let tr = transmittance(sigma_t, t_max);
        let ph = tr[hero];
        if ph > 0.0 {
            FreeFlight::Pass { weight: tr / ph, ratio: tr / ph }
        } else {
            // Unreachable in exact arithmetic (the hero's pass probability is the probability
            // of getting here); f32 underflow of exp(-s t) for huge t can still produce it.
            FreeFlight::Pass { weight: Rgb::ZERO, ratio: Rgb::ONE }
        }
    }
}

/// Density (per unit length) of an interaction at `t` in channel `c`'s sampling,
/// `sigma_t[c] exp(-sigma_t[c] t)`.
pub fn free_flight_pdf(sigma_t: Rgb, t: f32) -> Rgb {
    sigma_t * sigma_t.exp_neg(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Sampler;

    /// One segment with a random hero: the MIS estimates `weight / mean(ratio)` of passing and
    /// of interacting (times `sigma_t`) reproduce Beer-Lambert transmittance `T_r(L)` and its
    /// complement `1 - T_r(L)` channel by channel, including a channel with zero extinction.
    #[test]
    fn free_flight_estimates_slab_transmittance() {
        let sigma_t = Rgb::new(0.5, 2.0, 0.0);
        let l = 1.3;
        let mut s = Sampler::from_seed(5);
        let n = 400_000;
        let (mut pass, mut absorbed) = (Rgb::ZERO, Rgb::ZERO);
        for _ in 0..n {
            let hero = hero_channel(s.next_1d());
            match sample_free_flight(sigma_t, l, hero, s.next_1d()) {
                FreeFlight::Pass { weight, ratio } => pass += weight / ratio.mean(),
                FreeFlight::Interaction { weight, ratio, .. } => absorbed += weight * sigma_t / ratio.mean(),
            }
        }
        let pass = pass / n as f32;
        let absorbed = absorbed / n as f32;
        let exact = transmittance(sigma_t, l);
        for c in 0..3 {
            assert!((pass[c] - exact[c]).abs() < 5e-3, "channel {c}: {} vs {}", pass[c], exact[c]);
            assert!((absorbed[c] - (1.0 - exact[c])).abs() < 5e-3, "channel {c}");
        }
    }

    #[test]
    fn free_flight_pdf_integrates_to_interaction_probability() {
        let sigma_t = Rgb::new(0.3, 1.0, 4.0);
        let l = 2.0;
        let m = 20_000;
        let h = l / m as f32;
        let integral: Rgb = (0..m).map(|i| free_flight_pdf(sigma_t, (i as f32 + 0.5) * h) * h).sum();
        let expected = Rgb::ONE - transmittance(sigma_t, l);
        for c in 0..3 {
            assert!((integral[c] - expected[c]).abs() < 1e-4, "{integral} vs {expected}");
        }
    }

    /// Sampled distances follow the hero channel's exponential (chi-square).
    #[test]
    fn free_flight_distances_follow_the_hero_exponential() {
        let sigma_t = Rgb::new(0.5, 2.0, 1.0);
        let mut s = Sampler::from_seed(8);
        let r = haze_testkit::chi2::chi2_interval(
            || match sample_free_flight(sigma_t, 3.0, 1, s.next_1d()) {
                FreeFlight::Interaction { t, .. } => t as f64,
                FreeFlight::Pass { .. } => 3.0,
            },
            |t| if t < 3.0 { 2.0 * (-2.0 * t).exp() } else { 0.0 },
            0.0,
            2.999,
            60,
            100_000,
        );
        // Passes land at exactly 3.0 and count as outside [0, 2.999]: expected fraction exp(-6).
        assert!(r.p_value >= 0.01 && r.outside_support < 400, "{r}");
    }
}

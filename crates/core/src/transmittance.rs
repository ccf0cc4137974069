//! Transmittance and free-flight sampling in homogeneous media with RGB extinction.
//!
//! Chromatic extinction is sampled with the one-sample spectral MIS of Miller, Georgiev and
//! Jarosz 2019 ("A null-scattering path integral formulation of light transport", Sec. 5.4;
//! also pbrt-v4 `VolPathIntegrator` and Mitsuba 3 `volpathmis`): pick a channel uniformly, sample
//! its exponential, and divide by the *mean* of the three channels' pdfs. This is unbiased for
//! every channel, including channels whose extinction is zero.

use crate::spectrum::Rgb;

/// `T_r(d) = exp(-sigma_t d)` per channel (Beer-Lambert).
#[inline]
pub fn transmittance(sigma_t: Rgb, d: f32) -> Rgb {
    if d.is_infinite() {
        return sigma_t.map(|s| if s > 0.0 { 0.0 } else { 1.0 });
    }
    sigma_t.exp_neg(d)
}

/// Outcome of sampling a free-flight distance along a segment of length `t_max`.
#[derive(Clone, Copy, Debug)]
pub enum FreeFlight {
    /// A real interaction at distance `t`. `weight = T_r(t) / p(t)` where
    /// `p(t) = mean_c sigma_t[c] exp(-sigma_t[c] t)` (per unit length); multiply by `sigma_s`
    /// to get the scattering throughput.
    Interaction { t: f32, weight: Rgb },
    /// No interaction before `t_max`. `weight = T_r(t_max) / P(pass)` with
    /// `P(pass) = mean_c exp(-sigma_t[c] t_max)`.
    Pass { weight: Rgb },
}

/// Samples a free-flight distance by spectral MIS. `u_channel` and `u` are independent uniforms.
pub fn sample_free_flight(sigma_t: Rgb, t_max: f32, u_channel: f32, u: f32) -> FreeFlight {
    let c = ((u_channel * 3.0) as usize).min(2);
    let s = sigma_t[c];
    let t = if s > 0.0 {
        -(1.0 - u).ln() / s
    } else {
        f32::INFINITY
    };
    if t < t_max {
        let tr = sigma_t.exp_neg(t);
        let pdf = (sigma_t * tr).mean();
        FreeFlight::Interaction {
            t,
            weight: tr / pdf,
        }
    } else {
        let tr = transmittance(sigma_t, t_max);
        let p = tr.mean();
        if p > 0.0 {
            FreeFlight::Pass { weight: tr / p }
        } else {
            FreeFlight::Pass { weight: Rgb::ZERO }
        }
    }
}

/// Density (per unit length) of an interaction at `t` under [`sample_free_flight`].
pub fn free_flight_pdf(sigma_t: Rgb, t: f32) -> f32 {
    (sigma_t * sigma_t.exp_neg(t)).mean()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Sampler;

    /// The expected weight of a pass plus interactions integrated along a slab reproduces
    /// Beer-Lambert transmittance and its complement: E[pass weight] = T_r(L), and
    /// E[interaction weight * sigma_t] = 1 - T_r(L), channel by channel.
    #[test]
    fn free_flight_estimates_slab_transmittance() {
        let sigma_t = Rgb::new(0.5, 2.0, 0.0);
        let l = 1.3;
        let mut s = Sampler::from_seed(5);
        let n = 400_000;
        let (mut pass, mut absorbed) = (Rgb::ZERO, Rgb::ZERO);
        for _ in 0..n {
            match sample_free_flight(sigma_t, l, s.next_1d(), s.next_1d()) {
                FreeFlight::Pass { weight } => pass += weight,
                FreeFlight::Interaction { weight, .. } => absorbed += weight * sigma_t,
            }
        }
        let pass = pass / n as f32;
        let absorbed = absorbed / n as f32;
        let exact = transmittance(sigma_t, l);
        for c in 0..3 {
            assert!(
                (pass[c] - exact[c]).abs() < 5e-3,
                "channel {c}: {} vs {}",
                pass[c],
                exact[c]
            );
            assert!((absorbed[c] - (1.0 - exact[c])).abs() < 5e-3, "channel {c}");
        }
    }

    #[test]
    fn free_flight_pdf_integrates_to_interaction_probability() {
        let sigma_t = Rgb::new(0.3, 1.0, 4.0);
        let l = 2.0;
        let m = 20_000;
        let h = l / m as f32;
        let integral: f32 = (0..m)
            .map(|i| free_flight_pdf(sigma_t, (i as f32 + 0.5) * h) * h)
            .sum();
        let expected = 1.0 - transmittance(sigma_t, l).mean();
        assert!(
            (integral - expected).abs() < 1e-4,
            "{integral} vs {expected}"
        );
    }
}

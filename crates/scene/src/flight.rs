//! The outcome of a free flight, shared by both kinds of medium (`crate::medium`) and the grid
//! medium's delta tracking (`crate::hetero`); a leaf, so that neither imports the other for it.

use haze_core::Rgb;

/// Outcome of a free flight along a ray up to its surface, in the path-level spectral MIS form
/// of `haze_core::transmittance` (hero-channel sampling; `docs/theory.md` §12.3).
#[derive(Clone, Copy, Debug)]
pub enum Flight {
    /// A real collision at `t`: the throughput gains `weight` and then `sigma_s` (the
    /// scattering coefficient at `t`), the pdf ratios `ratio`. Two factors so that each walker
    /// keeps its own order of multiplication (bit for bit what it computed before the media
    /// shared this routine); a grid medium's delta tracking puts `sigma_s(x)` into `weight`
    /// and gives `sigma_s = 1`.
    Scatter { t: f32, weight: Rgb, sigma_s: Rgb, ratio: Rgb },
    /// No real collision before the surface.
    Pass { weight: Rgb, ratio: Rgb },
}

/// A free flight begun before the ray's surface is known (`Medium::begin_flight`).
#[derive(Clone, Copy, Debug)]
pub enum FlightStart {
    /// A homogeneous medium's distance, drawn from the hero channel's exponential: a walker
    /// may cut its surface query there, since a flight that ends sooner needs no surface.
    Drawn(f32),
    /// A grid medium tracks its collisions once the surface is known.
    Tracked,
}

impl FlightStart {
    /// How far the walker's surface query must look: the drawn distance, or the whole ray.
    pub fn query_limit(self, t_max: f32) -> f32 {
        match self {
            FlightStart::Drawn(t) => t.min(t_max),
            FlightStart::Tracked => t_max,
        }
    }
}

//! Participating media. Mitsuba 3 plugin `homogeneous`.

use haze_core::{Phase, Rgb};

/// Index of a medium in [`crate::Scene::media`].
pub type MediumId = u32;

/// Homogeneous medium: constant extinction `sigma_t` and single-scattering albedo, both RGB,
/// already multiplied by Mitsuba's `scale`. `sigma_s = albedo * sigma_t`,
/// `sigma_a = sigma_t - sigma_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The XML `id`, for messages.
    pub name: String,
    pub sigma_t: Rgb,
    pub albedo: Rgb,
    pub phase: Phase,
}

impl Medium {
    pub fn sigma_s(&self) -> Rgb {
        self.sigma_t * self.albedo
    }
}

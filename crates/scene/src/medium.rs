//! Participating media. Mitsuba 3 plugins `homogeneous` and `heterogeneous`
//! ([`crate::hetero`]).

use crate::hetero::Heterogeneous;
use haze_core::{Phase, Rgb};
use std::sync::Arc;

/// Index of a medium in [`crate::Scene::media`].
pub type MediumId = u32;

/// A medium. Homogeneous (`hetero` is `None`): constant extinction `sigma_t` and
/// single-scattering albedo, both RGB, already multiplied by Mitsuba's `scale`;
/// `sigma_s = albedo * sigma_t`, `sigma_a = sigma_t - sigma_s`.
///
/// Heterogeneous (`hetero` is `Some`): the coefficients vary in space and live in `hetero`;
/// `sigma_t` then holds the global majorant and `albedo` the albedo volume's maximum, bounds
/// and never the medium itself: code that reads them must branch on [`Medium::is_homogeneous`]
/// (the many-light estimators use `hetero`'s coefficients and ratio tracking there,
/// `docs/theory.md` §12.5).
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The XML `id`, for messages.
    pub name: String,
    pub sigma_t: Rgb,
    pub albedo: Rgb,
    pub phase: Phase,
    pub hetero: Option<Arc<Heterogeneous>>,
}

impl Medium {
    pub fn homogeneous(name: String, sigma_t: Rgb, albedo: Rgb, phase: Phase) -> Medium {
        Medium { name, sigma_t, albedo, phase, hetero: None }
    }

    pub fn is_homogeneous(&self) -> bool {
        self.hetero.is_none()
    }

    pub fn sigma_s(&self) -> Rgb {
        self.sigma_t * self.albedo
    }
}

//! Surface scattering models (Mitsuba 3 plugins `null`, `diffuse`, `dielectric`).
//!
//! Local shading frame: `z` is the shading normal. `wi` points *away* from the surface towards
//! where the light (or the path) came from, `wo` away from it towards where it goes, as in
//! Mitsuba and pbrt. Values include the cosine factor only where said.

use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Index-matched boundary: light passes unchanged; only media change.
    Null,
    /// Lambertian reflector, `f = reflectance / pi`.
    Diffuse { reflectance: Rgb },
    /// Smooth dielectric interface with relative index `eta = int_ior / ext_ior`.
    Dielectric { eta: f32 },
}

impl Bsdf {
    pub fn is_null(&self) -> bool {
        matches!(self, Bsdf::Null)
    }
    /// True when the BSDF has no effect on light at all besides absorbing it
    /// (a black diffuse surface): paths end there.
    pub fn is_black(&self) -> bool {
        matches!(self, Bsdf::Diffuse { reflectance } if reflectance.is_black())
    }
}

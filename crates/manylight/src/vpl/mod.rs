//! Virtual point lights: every scattering vertex of a light path, carrying the path's flux,
//! lights every camera segment; the camera point is sampled equiangularly towards the VPL.
//!
//! - [`estimator`]: one VPL's contribution to one camera segment.

pub mod estimator;

pub use estimator::{sample_vpl_contribution, vpl_integrand, Vpl};

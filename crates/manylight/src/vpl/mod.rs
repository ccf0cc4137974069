//! Virtual point lights: every scattering vertex of a light path, carrying the path's flux,
//! lights every camera segment; the camera point is sampled equiangularly towards the VPL.
//!
//! - [`estimator`]: one VPL's contribution to one camera segment.
//! - [`surface`]: surface VPLs and a point light's contribution to one camera segment.
//! - [`to_surface`]: a point light's contribution to a gathering surface point.

pub mod estimator;
pub mod surface;
pub mod to_surface;

pub use estimator::{sample_vpl_contribution, vpl_integrand, Vpl};
pub use surface::{point_light_to_segment_integrand, sample_point_light_to_segment, SurfaceVpl};
pub use to_surface::point_light_to_point;

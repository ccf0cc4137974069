//! Virtual ray lights (Novak et al. 2012): every medium segment of a light path, carrying the
//! path's flux, lights every camera segment through the medium-to-medium integral of `docs/theory.md` §3.
//!
//! - [`Segment`]: a straight piece of a ray (camera segments and VRLs).
//! - [`sampling`]: the equiangular and `1/h` sampling families with their pdfs.
//! - [`estimator`]: one VRL's contribution to one camera segment, with joint importance
//!   sampling of the two points.
//! - [`surface`]: one VRL's contribution to a gathering surface point.

pub mod estimator;
pub mod sampling;
mod segment;
pub mod surface;

pub use estimator::{sample_vrl_contribution, vrl_integrand, Vrl, VrlMedium};
pub use segment::Segment;

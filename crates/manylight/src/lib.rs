//! Many-light rendering of participating media (Novak et al. 2012; Vibert et al. 2019).
//!
//! - [`vrl`]: virtual ray lights — joint importance sampling of a camera-segment point and a
//!   VRL point, and the medium-to-medium contribution estimator.
//! - [`vpl`]: virtual point lights — equiangular sampling towards a VPL and its estimator.
//! - [`lighttrace`]: light tracing that turns light-path segments into VRLs and vertices into VPLs.

pub mod camera;
pub mod depth;
pub mod gather;
mod hetero;
pub mod integrators;
pub mod lighttrace;
mod memory;
pub mod single;
pub mod splat;
pub mod tree;
pub mod vpl;
pub mod vrl;

//! Core building blocks shared by every part of haze: RGB spectra, rays and frames, the seeded
//! random number generator, sampling routines with their pdfs, phase functions and
//! transmittance.
//!
//! Conventions used across the crate (and the whole renderer):
//! - Directions are unit `Vec3` unless a doc comment says otherwise.
//! - Phase functions take *propagation* directions: `cos_theta = dot(d_in, d_out)`, so forward
//!   scattering is `cos_theta = 1` (Henyey-Greenstein with `g > 0` favours it).
//! - Every pdf states its measure: per unit length (distances), per steradian (directions) or
//!   per unit area (points on surfaces).

pub mod color;
pub mod fastmath;
pub mod frame;
pub mod hash;
pub mod phase;
pub mod ray;
pub mod rng;
pub mod sampler;
pub mod sampling;
pub mod spectrum;
pub mod streams;
pub mod transmittance;
pub mod walk;

pub use frame::Frame;
pub use glam::{Mat4, Vec2, Vec3};
pub use phase::Phase;
pub use ray::Ray;
pub use rng::Sampler;
pub use sampler::{SamplerKind, SamplerSpec};
pub use spectrum::Rgb;

/// Relative offset used to move ray origins off a surface (scaled by the magnitude of the point).
pub const RAY_EPSILON: f32 = 1e-4;

pub const PI: f32 = std::f32::consts::PI;
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
pub const INV_4PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

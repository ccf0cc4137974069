//! Rendering: integrators that estimate radiance along camera rays, the film that accumulates
//! them with per-pixel variance, and the progressive, reproducible render loop.
//!
//! Flow: [`progressive::render`] runs passes; each pass asks the integrator for its per-pass
//! data ([`Integrator::begin_pass`], e.g. virtual lights), then renders every pixel in parallel
//! with a sampler seeded by `(seed, pixel, pass)` and adds the result to the [`Film`].

pub mod components;
pub mod film;
pub mod image_io;
pub mod integrators;
pub mod metrics;
pub mod progressive;
pub mod walker;

pub use components::{Component, PathRadiance};
pub use film::Film;
pub use integrators::{Integrator, VolPath};
pub use progressive::{render, render_volpath, RenderOutput, RenderSettings};

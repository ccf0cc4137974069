//! haze's scene: the model the integrators read (shapes, BSDFs, media, emitters, camera), ray
//! intersection, and the Mitsuba 3 XML loader that builds it ([`xml::load_file`]).
//!
//! Names follow Mitsuba 3's plugins and parameters (`homogeneous`, `sigma_t`, `hg`, `area`,
//! `to_world`, ...), so a reader who knows a scene file finds the code that handles it.

pub mod accel;
pub mod bitmap;
pub mod boundary;
pub mod bsdf;
pub mod camera;
pub mod emitter;
pub mod emitter_tables;
pub mod envmap;
mod flight;
pub mod hetero;
pub mod interaction;
pub mod lights;
pub mod marched;
pub mod media_bounds;
pub mod medium;
pub mod mesh_attribute;
pub mod projector;
pub mod scene;
pub mod shape;
pub mod texture;
pub mod vdb;
pub mod volume;
pub mod xml;

pub use boundary::Boundary;
pub use bsdf::Bsdf;
pub use camera::Camera;
pub use emitter::Emitter;
pub use envmap::EnvMap;
pub use interaction::SurfaceInteraction;
pub use medium::{Flight, FlightStart, Homogeneous, Medium, MediumId, MediumKind};
pub use scene::{depth_limit, IntegratorSpec, Scene, MAX_PATH_DEPTH};
pub use shape::{Geometry, Shape, TriangleMesh};
pub use texture::Texture;
pub use xml::{load_file, load_file_with_sources, load_str, LoadError, LoadOptions};

//! haze's front-end API: what the `haze` command line and the Python binding share, so that
//! neither holds rendering logic of its own.
//!
//! - [`options`]: every option of a render, once (name, default, check, help, the methods it
//!   applies to), and the method names.
//! - [`methods`]: an integrator chosen by name (`volpath`, `vrl`, `vpl`, `vrl_lightcuts`,
//!   `vpl_lightcuts`) with its options, and rendering with it.
//! - [`passes`]: rendering a range of passes and merging ranges rendered elsewhere, bit for bit
//!   (the pass tree).
//! - [`lights`]: the virtual lights of one pass.
//!
//! The crates below stay the place for the science: `haze-scene` (loader, scene model),
//! `haze-render` (film, progressive passes, volpath, metrics), `haze-manylight` (virtual lights,
//! light tree, lightcuts).

pub mod lights;
pub mod methods;
pub mod options;
pub mod passes;

pub use haze_core as core;
pub use haze_manylight as manylight;
pub use haze_render as render;
pub use haze_scene as scene;
pub use methods::{method_kind, prepare, replacement_note, Method};
pub use options::{method_names, CompensatedClamp, MethodKind, MethodOptions, Options, Spelling, OPTIONS};

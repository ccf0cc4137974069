//! haze's lab: measurements for research, kept out of the shipped crates (no shipped crate
//! depends on this one). Methods and options come from `haze-engine`'s table; what is measured
//! below the method (tree builders, a cut's selection variance) reaches into `haze-manylight`.
//!
//! - `benches/lightcuts.rs`: light-tree build times by builder and thread count, the bound cut's
//!   sizes against the light count, the frame time of `vrl_lightcuts` against `vrl`.
//! - `benches/stochastic.rs`: the stochastic cut's gather cost per camera segment against the
//!   light count.
//! - `examples/selection_probe.rs` with [`selection`]: the variance the stochastic cut's light
//!   selection adds.
//! - `examples/accel_bench.rs`: closest-hit and shadow queries of seeded random rays.
//! - `examples/majorant_probe.rs`: the majorant grid against one global majorant.
//!
//! `haze bench` (the command line) measures the shipped methods' throughput.

pub mod selection;
pub mod setup;

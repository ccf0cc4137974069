//! The virtual lights of one pass, as the many-light integrators trace them (for research use:
//! the Python package returns them as arrays).

use anyhow::Result;
use haze_manylight::lighttrace::{trace_light_paths, LightSet, LightTraceSettings};
use haze_scene::Scene;

/// Traces `paths` light paths of pass `pass` with `seed`, with the scene's path-length limits
/// (`LightTraceSettings::from_max_depth`), exactly as a many-light integrator's pass does.
/// Every flux is already divided by `paths`, so the fluxes of the first segments of all paths
/// (those starting at the emitters) sum to the emitted power.
pub fn trace_lights(scene: &Scene, paths: u64, seed: u64, pass: u32) -> Result<LightSet> {
    if paths == 0 {
        anyhow::bail!("the number of light paths must be at least 1");
    }
    let settings = LightTraceSettings::from_max_depth(scene.integrator.max_depth);
    Ok(trace_light_paths(scene, paths, seed, pass, &settings)?)
}

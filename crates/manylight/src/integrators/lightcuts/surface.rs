//! What the lightcut integrators add for the whole image (`docs/theory.md` §2.1): surface VPLs
//! lighting camera segments, and every light (VRLs or VPLs of both trees, surface VPLs) lighting
//! gathering surface points. **Ours:** the surface VPLs get a tree of their own (built like the
//! medium trees, over their points and fluxes), and every tree is cut stochastically for a
//! gathering point too, with the point receiver's importance (`tree::importance::PointImportance`):
//! the same `cut_size` nodes, one light sampled in each, unbiased by the argument of
//! `docs/theory.md` §11 (every light with flux keeps a positive probability).

use crate::tree::lights::LightSummary;
use crate::tree::Aabb;
use crate::vpl::SurfaceVpl;

/// What the surface VPL tree knows of one surface VPL: a point with its flux as power.
pub fn surface_vpl_summary(v: &SurfaceVpl) -> LightSummary {
    LightSummary {
        bounds: Aabb::from_points(v.p, v.p),
        intensity: v.flux.max_component(),
        flux_bound: v.flux,
        length: 0.0,
        power: v.flux,
    }
}

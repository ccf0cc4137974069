//! The many-light integrators `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts`: one
//! integrator ([`LightcutsIntegrator`]) generic over the light kind, with a cut strategy. Each
//! pass traces its own light paths ([`crate::lighttrace`]), then every camera ray sums emitted
//! light, single scattering by next-event estimation ([`crate::single`]) and the contributions
//! of the virtual lights of the pass, all of them (the exhaustive cut: `vrl`, `vpl`) or a cut
//! of their tree (`docs/theory.md` §2: `L = emitted + single + sum over virtual lights`,
//! nothing counted twice).

mod lightcuts;

#[cfg(feature = "test-controls")]
pub use lightcuts::TestControls;
pub use lightcuts::{
    BoundCut, Builder, Clamps, ClusterKind, CutObserver, CutSizeProbe, CutStrategy, ExhaustiveCut, Forest,
    LightcutPass, LightcutsIntegrator, Observed, PassView, SegmentCut, StochasticCut, TreeSettings, Vpls,
    Vrls,
};

/// `vrl` ([`LightcutsIntegrator::exhaustive`]).
pub type VrlIntegrator = LightcutsIntegrator<Vrls, ExhaustiveCut>;
/// `vpl` ([`LightcutsIntegrator::exhaustive`]).
pub type VplIntegrator = LightcutsIntegrator<Vpls, ExhaustiveCut>;

use crate::camera::{estimator_medium, CameraSegment};
pub use crate::gather::PathTracedMedia;
use crate::lighttrace::{paths_for_vrl_count, LightSet, LightTraceSettings};
use crate::vrl::VrlMedium;
use haze_core::streams::SURFACE_VPL_INDEX;
use haze_render::integrators::transmittance_to;
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};

/// How many light paths each pass traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightBudget {
    /// Exactly this many light paths per pass.
    Paths(u64),
    /// About this many VRLs per pass: the path count is fixed once from a pilot run, so the
    /// estimate stays unbiased (see `paths_for_vrl_count`).
    Vrls(u64),
}

/// What the many-light integrators share.
#[derive(Clone, Debug)]
pub struct ManyLightSettings {
    pub budget: LightBudget,
    pub trace: LightTraceSettings,
    /// Caustic paths per pass (`crate::splat`): `None` for the default (one per pixel), `Some(0)`
    /// to leave the caustics seen directly to the camera continuation.
    pub caustic_paths: Option<u64>,
    /// `Some(c)`: the `1/d^2` of surface VPL -> gathering point connections is clamped at `c`
    /// and the clamped part recovered by the compensation walk (`crate::gather`, Kollig &
    /// Keller 2004): unbiased, without the rare huge samples of VPLs near the point.
    pub compensated_clamp: Option<f32>,
    /// The media in which the camera walk path-traces instead of gathering
    /// (`crate::gather::PathTracedMedia`).
    pub path_traced_media: PathTracedMedia,
}

/// The clamp distance of the scene-relative `compensated_clamp` (the default, `auto`), as a
/// fraction of the radius `R` of the scene's bounding sphere: surface VPL -> surface point
/// connections shorter than `R / COMPENSATED_CLAMP_DIVISOR` are clamped and their clamped part
/// recovered by the compensation walk (`crate::gather`, (T12e) of docs/theory.md §2.1).
/// Chosen on measurements (docs/theory.md §2.1, "The compensated clamp"): on Mitsuba 3's media
/// test scenes (`R` 6.3) the distance 1 (`R / 6.3`) removes the heavy tails of the backdrop's
/// gathering, and at equal time distances of `R / 2.8` to `R / 3.9` (`c = 1` on scenes of
/// `R` 2.8 to 3.9) were neutral on three homogeneous scenes.
pub const COMPENSATED_CLAMP_DIVISOR: f32 = 6.0;

/// The scene-relative `compensated_clamp` of `scene`: `c = (COMPENSATED_CLAMP_DIVISOR / R)^2`,
/// the `1/d^2` clamp of the distance `R / COMPENSATED_CLAMP_DIVISOR` (`R` > 0 always,
/// `BoundingSphere::around`). Relative, so that a scene modelled in millimetres and the same
/// scene in metres render alike.
pub fn scene_compensated_clamp(scene: &Scene) -> f32 {
    let d = scene.bounding_sphere().radius / COMPENSATED_CLAMP_DIVISOR;
    1.0 / (d * d)
}

/// The caustic-path tracer of `settings` for `scene`, if the scene has caustics to trace.
pub(crate) fn caustic_tracer(
    scene: &Scene,
    settings: &ManyLightSettings,
) -> Option<crate::splat::CausticTracer> {
    let pixels = scene.camera.width as u64 * scene.camera.height as u64;
    let paths = settings.caustic_paths.unwrap_or(pixels);
    // A caustic path after `e` delta events joined to the pinhole has `e + 1` events.
    crate::splat::CausticTracer::new(scene, paths, crate::depth::max_events(scene).saturating_sub(1))
}

/// Resolves the light budget to a number of paths per pass, and checks that every emitter can
/// start light paths.
pub(crate) fn paths_per_pass(
    scene: &Scene,
    settings: &ManyLightSettings,
    seed: u64,
) -> Result<u64, EmissionError> {
    scene.check_emission()?;
    match settings.budget {
        LightBudget::Paths(n) => Ok(n.max(1)),
        LightBudget::Vrls(n) => paths_for_vrl_count(scene, n, seed, &settings.trace),
    }
}

/// The scene's media in the form the estimators take, indexed by medium id.
pub fn media_of(scene: &Scene) -> Vec<VrlMedium> {
    media(scene)
}

pub(crate) fn media(scene: &Scene) -> Vec<VrlMedium> {
    (0..scene.media.len() as MediumId).map(|m| estimator_medium(scene, m)).collect()
}

/// Transmittance and visibility from a virtual-light point `y` (in medium `from`) to a camera
/// point `x`, crossing null boundaries.
#[inline]
pub(crate) fn connect(scene: &Scene, from: MediumId, y: glam::Vec3, x: glam::Vec3) -> haze_core::Rgb {
    let v = x - y;
    let dist = v.length();
    if dist <= 0.0 {
        return haze_core::Rgb::ZERO;
    }
    // The connection ends *at* x, in the medium; `transmittance_to` shortens by a relative 1e-4
    // so that a surface exactly at x does not count.
    transmittance_to(scene, y, None, v / dist, dist, Some(from))
}

/// Transmittance and visibility from the surface VPL `vpl` to a point `x` (the origin offset
/// off the surface, the medium of the side the connection leaves by).
#[inline]
pub(crate) fn connect_surface(scene: &Scene, vpl: &crate::vpl::SurfaceVpl, x: glam::Vec3) -> haze_core::Rgb {
    let v = x - vpl.p;
    let dist = v.length();
    if dist <= 0.0 {
        return haze_core::Rgb::ZERO;
    }
    let d = v / dist;
    let medium = scene.medium_leaving(vpl.shape, vpl.p, vpl.n, d, vpl.medium);
    transmittance_to(scene, vpl.p, Some(vpl.n), d, dist, medium)
}

/// The surface VPLs of a light set in the form the estimators take.
pub(crate) fn surface_vpls(set: &LightSet) -> Vec<crate::vpl::SurfaceVpl> {
    set.surface_vpls.iter().map(|r| r.to_surface_vpl()).collect()
}

/// Surface VPL `vpl` (index `i` of its pass) -> camera segment (T12c), with its own random
/// number from `key` (`SURFACE_VPL_INDEX`): the brute-force sum and the lightcut integrators'
/// power-sampled sum evaluate the same term. `hetero` is `crate::hetero::any(scene)`, asked once
/// by the caller.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn surface_vpl_to_segment(
    scene: &Scene,
    hetero: bool,
    vpl: &crate::vpl::SurfaceVpl,
    i: usize,
    cs: &CameraSegment,
    cam_medium: &VrlMedium,
    key: u64,
    clamp: Option<f32>,
) -> haze_core::Rgb {
    if !crate::depth::connects(scene, vpl.events, cs.events) {
        return haze_core::Rgb::ZERO;
    }
    if hetero {
        let u = light_uniforms(key, SURFACE_VPL_INDEX | i as u32);
        return crate::hetero::surface_vpl_to_segment(scene, vpl, cs, cam_medium, u, clamp);
    }
    let bsdf = &scene.shapes[vpl.shape as usize].bsdf;
    crate::vpl::sample_point_light_to_segment(
        &cs.seg,
        cam_medium,
        vpl.p,
        |w| vpl.intensity(bsdf, w),
        light_uniforms(key, SURFACE_VPL_INDEX | i as u32).x,
        clamp,
        |_, x| connect_surface(scene, vpl, x),
    )
}

/// Surface VPL `vpl` -> gathering point `gp` (T12d).
#[inline]
pub(crate) fn surface_vpl_to_point(
    scene: &Scene,
    vpl: &crate::vpl::SurfaceVpl,
    gp: &crate::gather::GatherPoint,
    clamp: Option<f32>,
) -> haze_core::Rgb {
    if !crate::depth::connects(scene, vpl.events, gp.events) {
        return haze_core::Rgb::ZERO;
    }
    let bsdf = &scene.shapes[vpl.shape as usize].bsdf;
    crate::vpl::point_light_to_point(
        gp.p,
        |d| gp.reflectance(d),
        vpl.p,
        |w| vpl.intensity(bsdf, w),
        clamp,
        |_, x| connect_surface(scene, vpl, x),
    )
}

/// Medium VPL `vpl` -> gathering point `gp` (`docs/theory.md` §5.3), the phase function of
/// the VPL's medium (from `media`) as its intensity.
#[inline]
pub(crate) fn medium_vpl_to_point(
    scene: &Scene,
    vpl: &crate::vpl::Vpl,
    gp: &crate::gather::GatherPoint,
    media: &[VrlMedium],
    clamp: Option<f32>,
) -> haze_core::Rgb {
    if !crate::depth::connects(scene, vpl.events, gp.events) {
        return haze_core::Rgb::ZERO;
    }
    let phase = &media[vpl.medium as usize].phase;
    crate::vpl::point_light_to_point(
        gp.p,
        |d| gp.reflectance(d),
        vpl.p,
        |n| vpl.flux * phase.eval(vpl.d_in, n),
        clamp,
        |y, x| connect(scene, vpl.medium, y, x),
    )
}

/// Two uniform numbers for light `light` from a per-camera-segment key: every light gets
/// random numbers of its own, independent of the order in which lights are evaluated, so a
/// lightcut that evaluates every leaf reproduces the brute-force sum exactly (up to the order
/// of floating-point additions).
#[inline]
pub(crate) fn light_uniforms(key: u64, light: u32) -> glam::Vec2 {
    let h =
        haze_core::rng::mix64(key ^ haze_core::rng::mix64(light as u64 ^ haze_core::streams::LIGHT_UNIFORMS));
    let scale = 1.0 / (1u32 << 24) as f32;
    glam::Vec2::new((h >> 40) as f32 * scale, ((h >> 8) & 0xff_ffff) as f32 * scale)
}

/// Splits light records into the two groups of `gather::Gather::segment` (medium-only, after a
/// surface bounce), in huge pages: the gather reads them at random (`crate::memory`).
pub(crate) fn split_groups<R, L>(
    records: &[R],
    after_surface: impl Fn(&R) -> bool,
    make: impl Fn(&R) -> L,
) -> [Vec<L>; 2] {
    let second = records.iter().filter(|r| after_surface(r)).count();
    let mut groups =
        [crate::memory::huge_page_vec(records.len() - second), crate::memory::huge_page_vec(second)];
    for r in records {
        groups[after_surface(r) as usize].push(make(r));
    }
    groups
}

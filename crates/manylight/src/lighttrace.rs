//! Light tracing into virtual lights: every medium segment of a light path becomes a virtual ray
//! light (VRL), every medium scattering vertex a virtual point light (VPL) and every non-delta
//! surface vertex a surface VPL (`docs/theory.md` §2.1, §5.2).
//!
//! ## What is recorded, and why it is unbiased
//! Free-flight distances are sampled from the hero channel's exponential with path-level
//! spectral MIS (as in `volpath`; `haze_core::transmittance`). A segment starts at `o` (the
//! emitter, a scattering vertex, or a surface) and ends where the sampled distance or the next
//! surface puts it ("short" VRLs, the segments of the light path themselves). Its point at
//! distance `v` exists with the probability that the sampled distance exceeds `v`,
//! `T_hero(v)`, so the light arriving there is, per channel,
//!
//! ```text
//!   Phi(v) = beta * T(v) / mean_c(r_c T_c(v))
//! ```
//!
//! with `beta` the throughput (power / paths) at `o` divided by the hero pdfs so far and `r` the
//! pdf ratios of the other channels. For grey extinction `T` cancels and `Phi` is constant along
//! the segment. [`VrlRecord::flux_at`] evaluates it. A VPL at a scattering vertex carries
//! `beta sigma_s / mean(r)` after that vertex (`sigma_s` of the vertex included).
//!
//! ## Heterogeneous media (`docs/theory.md` §12.5, (T31))
//! In a heterogeneous medium the free flight is sampled by delta tracking (`volpath`'s routine,
//! `haze_scene::Medium::end_flight`), and
//! a VPL sits at every real collision with flux `beta sigma_s(x) / mean(r)` (`sigma_s(x)` is in
//! the flight's weight). The VRL is not the sampled piece: it is the whole segment up to the
//! next surface, clipped to the majorant cells with a positive bound (the medium is empty
//! elsewhere: `Heterogeneous::clip`), with
//! `ratio = 0` and `beta` the light leaving its start, `beta / mean(r)`; the light at distance
//! `v` is `beta T(0, v)` with the medium's transmittance, which the estimators estimate by ratio
//! tracking along the VRL (`crate::hetero`). Its point at `v` exists with probability 1, so no
//! pdf of the free flight enters, and the vertex delta tracking samples only continues the path.
//!
//! Between vertices a light path moves through the one path walker
//! (`haze_render::walker::Walker`: the leg's free flight, null crossings, bounces, roulette and
//! the cap on a walk's vertices); this file keeps what it records at each vertex.
//!
//! Dielectric interfaces are crossed with the adjoint BSDF: light tracing transports importance,
//! so the `1/eta^2` radiance compression of refraction is not applied (Veach 1997, Sec. 5.2).

use glam::Vec3;
use haze_core::ray::offset_origin;
use haze_core::streams::{LIGHT_PILOT, LIGHT_STREAM};
use haze_core::transmittance::hero_channel;
use haze_core::{Ray, Rgb, Sampler};
use haze_render::walker::Walker;
use haze_scene::lights::{EmissionError, EmissionSample};
use haze_scene::Flight;
use haze_scene::{MediumId, MediumKind, Scene};
use rayon::prelude::*;

/// One medium segment of a light path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VrlRecord {
    pub o: Vec3,
    /// Unit direction of propagation.
    pub d: Vec3,
    pub len: f32,
    /// Throughput at `o` in watts (emitted power / number of light paths / hero pdfs so far).
    pub beta: Rgb,
    /// Spectral-MIS pdf ratios `p_c / p_hero` of the path up to `o`; zero for a VRL of a
    /// heterogeneous medium, whose `beta` is then already `beta / mean(r)` (module docs).
    pub ratio: Rgb,
    pub medium: MediumId,
    /// True if the light path bounced off a non-null surface before this segment: paths through
    /// it belong to the `surface` component.
    pub after_surface: bool,
    /// Scattering events of the light path before this segment (`crate::depth`).
    pub events: u32,
}

impl VrlRecord {
    /// Flux at distance `v` along the segment, `beta T(v) / mean(r T(v))` (see module docs).
    #[inline]
    pub fn flux_at(&self, sigma_t: Rgb, v: f32) -> Rgb {
        let t = sigma_t.exp_neg(v);
        if self.ratio.is_black() {
            // A VRL in a heterogeneous medium (module docs): `beta T(v)`, here with
            // `T = exp(-sigma_t v)` for the caller's homogeneous `sigma_t`.
            return self.beta * t;
        }
        let m = (self.ratio * t).mean();
        if m > 0.0 {
            self.beta * t / m
        } else {
            Rgb::ZERO
        }
    }

    /// Largest flux anywhere on the segment, per channel (for light-cluster bounds):
    /// `Phi_c(v) <= 3 beta_c / r_c` because `mean(r T) >= r_c T_c / 3`; `beta` for a zero
    /// `ratio` (`T <= 1`).
    pub fn flux_bound(&self) -> Rgb {
        if self.ratio.is_black() {
            return self.beta;
        }
        Rgb(std::array::from_fn(
            |c| if self.ratio[c] > 0.0 { 3.0 * self.beta[c] / self.ratio[c] } else { 0.0 },
        ))
    }
}

impl VrlRecord {
    /// The VRL the estimators take (its flux at `v` is [`Self::flux_at`]).
    pub fn to_vrl(&self) -> crate::vrl::Vrl {
        crate::vrl::Vrl {
            seg: crate::vrl::Segment::new(self.o, self.d, self.len),
            flux: self.beta,
            ratio: self.ratio,
            medium: self.medium,
            events: self.events,
        }
    }
}

impl VplRecord {
    /// The VPL the estimators take.
    pub fn to_vpl(&self) -> crate::vpl::Vpl {
        crate::vpl::Vpl {
            p: self.p,
            d_in: self.d_in,
            flux: self.flux,
            medium: self.medium,
            events: self.events,
        }
    }
}

/// A medium scattering vertex of a light path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VplRecord {
    pub p: Vec3,
    /// Propagation direction of the light arriving at `p`.
    pub d_in: Vec3,
    /// Light leaving the vertex per unit phase function, in watts: `beta sigma_s / mean(r)`.
    pub flux: Rgb,
    pub medium: MediumId,
    pub after_surface: bool,
    /// Scattering events of the light path before this vertex (`crate::depth`).
    pub events: u32,
}

/// A non-delta surface vertex of a light path (not the emitter's own point): a surface VPL.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceVplRecord {
    pub p: Vec3,
    /// Geometric normal (the shape's exterior side).
    pub n: Vec3,
    /// Shading frame (`z` the shading normal; `x` along `dp/du` for anisotropic BSDFs:
    /// `Scene::shading_frame`).
    pub frame: haze_core::Frame,
    /// Unit direction from `p` towards the previous vertex of the light path.
    pub w_prev: Vec3,
    /// Light arriving at the vertex, in watts: `beta / mean(r)` before the BSDF.
    pub flux: Rgb,
    pub shape: u32,
    /// Where the BSDF's textures are looked up (`SurfaceInteraction::tex`: uv, and the
    /// triangle and barycentrics a `mesh_attribute` reads).
    pub tex: haze_scene::texture::TexPoint,
    /// The medium the light path arrived in (the shape decides the medium of each side).
    pub medium: Option<MediumId>,
    /// Scattering events of the light path before this vertex (`crate::depth`).
    pub events: u32,
}

impl SurfaceVplRecord {
    /// The surface VPL the estimators take.
    pub fn to_surface_vpl(&self) -> crate::vpl::SurfaceVpl {
        let frame = self.frame;
        crate::vpl::SurfaceVpl {
            p: self.p,
            n: self.n,
            frame,
            w_prev: frame.to_local(self.w_prev),
            flux: self.flux,
            shape: self.shape,
            tex: self.tex,
            medium: self.medium,
            events: self.events,
        }
    }
}

/// The virtual lights of one pass.
#[derive(Clone, Debug, Default)]
pub struct LightSet {
    pub vrls: Vec<VrlRecord>,
    pub vpls: Vec<VplRecord>,
    pub surface_vpls: Vec<SurfaceVplRecord>,
    /// Light paths traced (the normalisation: every flux is already divided by it).
    pub paths: u64,
}

/// Settings of light tracing.
#[derive(Clone, Debug)]
pub struct LightTraceSettings {
    /// Most scattering events (medium and non-null surface) a light path may have before a
    /// virtual light it records (`crate::depth::light_events`); the path ends past it.
    pub max_events: u32,
    /// Events after which Russian roulette on the relative throughput starts.
    pub rr_events: u32,
}

impl LightTraceSettings {
    /// Limits that keep every camera connection within the scene's `max_depth` as `volpath`
    /// counts it (`crate::depth`): a light after `e` events joined to a primary camera segment
    /// makes a path of `e + 2` events, so `e <= max_depth - 3`; each connection checks its own
    /// camera side. With `max_depth` 1 or 2 no light is usable: the paths record lights of no
    /// events, which every connection refuses.
    pub fn from_max_depth(max_depth: i32) -> Self {
        let max_events = crate::depth::light_events(max_depth).unwrap_or(0);
        LightTraceSettings { max_events, rr_events: 8 }
    }
}

/// Traces `paths` light paths for `pass` and collects their virtual lights. Path `i` uses the
/// sampler `Sampler::new(seed ^ LIGHT_STREAM, i, pass)`, and chunks are concatenated in path
/// order, so the result does not depend on the thread count.
pub fn trace_light_paths(
    scene: &Scene,
    paths: u64,
    seed: u64,
    pass: u32,
    settings: &LightTraceSettings,
) -> Result<LightSet, EmissionError> {
    scene.check_emission()?;
    const CHUNK: u64 = 256;
    let chunks: Vec<LightSet> = (0..paths.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut set = LightSet::default();
            for i in c * CHUNK..((c + 1) * CHUNK).min(paths) {
                let mut s = Sampler::new(seed ^ LIGHT_STREAM, i, pass as u64);
                trace_one(scene, &mut s, 1.0 / paths as f32, settings, &mut set);
            }
            set
        })
        .collect();
    let mut out = LightSet { paths, ..Default::default() };
    out.vrls.reserve(chunks.iter().map(|c| c.vrls.len()).sum());
    out.vpls.reserve(chunks.iter().map(|c| c.vpls.len()).sum());
    out.surface_vpls.reserve(chunks.iter().map(|c| c.surface_vpls.len()).sum());
    for c in chunks {
        out.vrls.extend_from_slice(&c.vrls);
        out.vpls.extend_from_slice(&c.vpls);
        out.surface_vpls.extend_from_slice(&c.surface_vpls);
    }
    Ok(out)
}

/// Number of light paths that yields about `target` VRLs, from a pilot of `pilot` paths traced
/// with a stream of its own. Fixing the path count in advance (rather than stopping once
/// `target` VRLs exist) keeps the estimate unbiased: a data-dependent stopping rule would not.
pub fn paths_for_vrl_count(
    scene: &Scene,
    target: u64,
    seed: u64,
    settings: &LightTraceSettings,
) -> Result<u64, EmissionError> {
    let pilot = 2000u64;
    let set = trace_light_paths(scene, pilot, seed ^ LIGHT_PILOT, u32::MAX, settings)?;
    let per_path = set.vrls.len() as f64 / pilot as f64;
    if per_path == 0.0 {
        return Ok(target.max(1));
    }
    Ok(((target as f64 / per_path).ceil() as u64).max(1))
}

/// The ray of an emission sample and the medium it starts in.
///
/// An area light's ray starts in the medium on its emitting side by the rule every walk uses
/// leaving a surface point (`Scene::medium_leaving`, `docs/theory.md` §14): the media its shape
/// declares, or those of every boundary touching the point; where neither declares any, the
/// medium the point lies in.
pub(crate) fn emission_ray(scene: &Scene, e: &EmissionSample) -> (Ray, Option<MediumId>) {
    let Some(n) = e.n else { return (Ray::new(e.p, e.d), scene.medium_at(e.p)) };
    let origin = offset_origin(e.p, n, e.d);
    let shape = scene.emitters[e.emitter as usize]
        .area_shape()
        .expect("an emission sample with a normal is an area light's");
    // A shape declaring media decides alone (or with what touches it): no need to look around.
    let around =
        if scene.shapes[shape as usize].is_medium_transition() { None } else { scene.medium_at(origin) };
    (Ray::new(origin, e.d), scene.medium_leaving(shape, e.p, n, e.d, around))
}

fn trace_one(
    scene: &Scene,
    s: &mut Sampler,
    inv_paths: f32,
    settings: &LightTraceSettings,
    out: &mut LightSet,
) {
    let Some(e) = scene.sample_emission(s.next_1d(), s.next_2d(), s.next_2d()) else { return };
    let power = e.weight * inv_paths;
    let (ray, medium) = emission_ray(scene, &e);
    let mut walker = Walker::new(ray, medium);
    let hero = hero_channel(s.next_1d());
    // Relative throughput (starts at 1) and pdf ratios; the flux is power * t.
    let mut t = Rgb::ONE;
    let mut r = Rgb::ONE;
    let mut events = 0u32;
    let mut after_surface = false;
    let max_len = scene_extent(scene) * 4.0;

    while walker.next_vertex() {
        // The leg's free flight (`Walker::sample_leg`: in a homogeneous medium the distance
        // first, and the surface query stops there, volpath's order).
        let medium = walker.medium;
        let (leg, flight) = walker.sample_leg(scene, hero, s, |_| {});
        let ray = walker.ray;
        let t_surface = leg.t_surface;
        if let (Some(m), Some(flight)) = (medium, flight) {
            let med = scene.medium(m);
            match &med.kind {
                // Heterogeneous (module docs): one VRL over the whole segment where the medium
                // is (`clip`), carrying `T(0, v)` along itself; delta tracking gave the next
                // vertex.
                MediumKind::Grid(h) => {
                    if let Some((a, b)) = h.clip(ray.o, ray.d, 0.0, t_surface.min(max_len)) {
                        out.vrls.push(VrlRecord {
                            o: ray.at(a),
                            d: ray.d,
                            len: b - a,
                            beta: power * t / r.mean(),
                            ratio: Rgb::ZERO,
                            medium: m,
                            after_surface,
                            events,
                        });
                    }
                }
                // Homogeneous: the VRL up to the next vertex, its flux `Phi(v)` closed form.
                MediumKind::Homogeneous(_) => {
                    let len = match flight {
                        Flight::Scatter { t, .. } => t,
                        Flight::Pass { .. } => t_surface,
                    };
                    if len > 0.0 {
                        out.vrls.push(VrlRecord {
                            o: ray.o,
                            d: ray.d,
                            len: len.min(max_len),
                            beta: power * t,
                            ratio: r,
                            medium: m,
                            after_surface,
                            events,
                        });
                    }
                }
            }
            match flight {
                Flight::Scatter { t: dist, weight, sigma_s, ratio } => {
                    // A grid's `weight` holds `sigma_s(x)` over the hero's pdf (T29), its
                    // `sigma_s` is one.
                    t *= weight * sigma_s;
                    r *= ratio;
                    let at = Vertex { m, after_surface, power, phase: &med.phase };
                    if !scatter(&at, ray.at(dist), &mut walker, &mut t, r, &mut events, s, settings, out) {
                        return;
                    }
                    continue;
                }
                Flight::Pass { weight, ratio } => {
                    t *= weight;
                    r *= ratio;
                }
            }
        }
        let Some(h) = leg.hit.map(|h| scene.interaction(&h)) else { return };
        let shape = &scene.shapes[h.shape as usize];
        if walker.cross_if_null(scene, &h) {
            continue;
        }
        if shape.bsdf.is_black() {
            return;
        }
        if !shape.bsdf.is_specular() {
            out.surface_vpls.push(SurfaceVplRecord {
                p: h.p,
                n: h.n,
                frame: scene.shading_frame(&h),
                w_prev: -ray.d,
                flux: power * t / r.mean(),
                shape: h.shape,
                tex: h.tex(),
                medium,
                events,
            });
        }
        let frame = scene.shading_frame(&h);
        let Some(bs) = shape.bsdf.sample(frame.to_local(-ray.d), s.next_1d(), s.next_2d(), h.tex()) else {
            return;
        };
        // Adjoint transport: undo the radiance-only 1/eta^2 factor of refraction.
        t *= bs.weight * (bs.eta * bs.eta);
        let d = frame.to_world(bs.wo);
        after_surface = true;
        // A thin sheet's straight transmission (`null` sample) is no event (crate::depth).
        if !bs.null {
            events += 1;
            if events > settings.max_events || !survives_roulette(s, &mut t, r, events, settings) {
                return;
            }
        }
        walker.bounce(scene, &h, d);
    }
}

/// What a medium scattering vertex of a light path needs besides the path's state.
struct Vertex<'a> {
    m: MediumId,
    after_surface: bool,
    power: Rgb,
    phase: &'a haze_core::Phase,
}

/// A medium scattering vertex at `p` (throughput `t` with `sigma_s` already in, pdf ratios `r`):
/// its VPL, the event count and Russian roulette, then the phase-sampled ray on. False if the
/// path ends there.
#[allow(clippy::too_many_arguments)]
fn scatter(
    at: &Vertex,
    p: Vec3,
    walker: &mut Walker,
    t: &mut Rgb,
    r: Rgb,
    events: &mut u32,
    s: &mut Sampler,
    settings: &LightTraceSettings,
    out: &mut LightSet,
) -> bool {
    out.vpls.push(VplRecord {
        p,
        d_in: walker.ray.d,
        flux: at.power * *t / r.mean(),
        medium: at.m,
        after_surface: at.after_surface,
        events: *events,
    });
    *events += 1;
    if *events > settings.max_events || !survives_roulette(s, t, r, *events, settings) {
        return false;
    }
    let (d, _) = at.phase.sample(walker.ray.d, s.next_2d());
    walker.scatter(p, d);
    true
}

/// Russian roulette (`Walker::roulette`) on the relative throughput `t / mean(r)` once
/// `events > rr_events`.
fn survives_roulette(
    s: &mut Sampler,
    t: &mut Rgb,
    r: Rgb,
    events: u32,
    settings: &LightTraceSettings,
) -> bool {
    if events <= settings.rr_events {
        return true;
    }
    let Some(q) = Walker::roulette((*t / r.mean()).max_component(), s) else {
        return false;
    };
    *t /= q;
    true
}

/// Diagonal of the scene's geometry (1 if there is none): caps the length of a VRL in an
/// unbounded medium, where a segment escaping to infinity would otherwise be infinitely long.
pub(crate) fn scene_extent(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds();
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 {
        d
    } else {
        1.0
    }
}

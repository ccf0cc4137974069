//! The camera side of the whole image (`docs/theory.md` §2.1): camera chains through null
//! boundaries and delta surfaces, gathering on every medium segment they cross and at their
//! first non-delta surface vertex, and the continuation from one gathering vertex through
//! delta chains (caustics into gathering vertices).
//!
//! The path-space table of docs/theory.md §2.1 says which connection makes which path; this file makes the
//! camera half of each row: emitters hit by a gathering chain (counted fully), next-event
//! estimation on gathering segments (`single.rs`) and at gathering points
//! (`haze_render::integrators::surface_nee`, no MIS), and the caller's virtual-light sums.

use crate::camera::{CameraSegment, MAX_SEGMENTS};
use crate::vrl::Segment;
use glam::{Vec2, Vec3};
use haze_core::ray::offset_origin;
use haze_core::transmittance::transmittance;
use haze_core::{Frame, Ray, Rgb, Sampler};
use haze_render::integrators::{surface_nee, SurfaceMis};
use haze_render::{Component, PathRadiance};
use haze_scene::{Bsdf, MediumId, Scene, SurfaceInteraction};
use std::cell::RefCell;

/// A gathering surface point: where a camera chain met a non-delta surface.
pub struct GatherPoint<'a> {
    pub p: Vec3,
    /// Geometric normal.
    pub n: Vec3,
    pub frame: Frame,
    /// Unit direction towards the camera side, local to `frame`.
    pub wi: Vec3,
    pub bsdf: &'a Bsdf,
    pub uv: Vec2,
}

impl GatherPoint<'_> {
    /// `f(wi, d) |cos d|` towards the unit world direction `d` (towards the light).
    #[inline]
    pub fn reflectance(&self, d: Vec3) -> Rgb {
        self.bsdf.eval(self.wi, self.frame.to_local(d), self.uv)
    }
}

/// Light from the virtual lights gathered by the caller.
pub(crate) trait Gather {
    /// One camera segment's light from `[medium-only lights, lights after a surface bounce
    /// (surface VPLs included)]`, without the segment's `tr_before`. `key` seeds the per-light
    /// random numbers (`integrators::light_uniforms`).
    fn segment(&self, cs: &CameraSegment, key: u64) -> [Rgb; 2];
    /// A gathering point's light from every virtual light (all of it `surface`), without the
    /// camera path's throughput.
    fn point(&self, gp: &GatherPoint, key: u64) -> Rgb;
    /// True if light tracing splats the caustics seen directly (`crate::splat`), so that the
    /// continuation must not count them; false only in tests that compare the two strategies.
    fn splats_caustics(&self) -> bool {
        true
    }
}

thread_local! {
    /// Per-thread gathering segments of the current chain: the hot loop allocates nothing.
    static CHAIN: RefCell<Vec<ChainSegment>> = RefCell::new(Vec::with_capacity(MAX_SEGMENTS));
}

/// Camera-path events (delta surfaces and continuations) after which Russian roulette starts.
const RR_EVENTS: u32 = 8;

/// A gathering segment of a chain.
#[derive(Clone, Copy)]
struct ChainSegment {
    cs: CameraSegment,
    /// The camera path had a surface event before it (its light is `surface`).
    after_surface: bool,
    /// The camera sees it directly (`whole_path_radiance`'s `direct`): the continuation from
    /// its points leaves area emitters behind delta chains to light tracing.
    direct: bool,
}

/// How a chain ended.
enum ChainEnd {
    /// Left the scene, was absorbed, or hit the event limit.
    Stop,
    /// At a non-delta surface vertex.
    Surface(SurfaceInteraction),
}

/// The radiance along `ray` (from `medium`) of every path in the table of docs/theory.md §2.1, split by component.
pub(crate) fn whole_path_radiance(
    scene: &Scene,
    mut ray: Ray,
    mut medium: Option<MediumId>,
    sampler: &mut Sampler,
    gather: &impl Gather,
) -> PathRadiance {
    let max_events = haze_scene::depth_limit(scene.integrator.max_depth);
    let mut out = PathRadiance::default();
    let mut beta = Rgb::ONE;
    let mut surface_seen = false;
    let mut gathering = true;
    let mut events = 0u32;
    // The camera sees the chain's end directly (no delta sample but thin sheets' straight
    // crossings): only the first chain, until a delta sample changes the direction.
    let mut direct = true;
    // The continued chain after a directly seen gathering point: its area emitters are light
    // tracing's (`crate::splat`), not counted here.
    let mut skip_area_emitters = false;
    CHAIN.with_borrow_mut(|chain| loop {
        chain.clear();
        let end = walk_chain(
            scene,
            &mut ray,
            &mut medium,
            sampler,
            &mut beta,
            &mut surface_seen,
            &mut gathering,
            &mut direct,
            skip_area_emitters,
            &mut events,
            max_events,
            chain,
            &mut out,
        );
        let seen_directly = std::mem::replace(&mut direct, false);
        skip_area_emitters = false;
        for ChainSegment { cs, after_surface, .. } in chain.iter() {
            let single = crate::single::single_scattering(scene, cs, sampler);
            let key = ((sampler.next_u32() as u64) << 32) | sampler.next_u32() as u64;
            let [medium_only, after] = gather.segment(cs, key);
            let (c_single, c_multiple) = if *after_surface {
                (Component::Surface, Component::Surface)
            } else {
                (Component::Single, Component::Multiple)
            };
            out.add(c_single, single);
            out.add(c_multiple, cs.tr_before * medium_only);
            out.add(Component::Surface, cs.tr_before * after);
        }
        let hit = match end {
            ChainEnd::Surface(h) if gathering => Some(h),
            _ => None,
        };
        let mut frame_wi = None;
        if let Some(h) = &hit {
            let shape = &scene.shapes[h.shape as usize];
            let frame = Frame::from_normal(h.ns);
            let wi = frame.to_local(-ray.d);
            let nee = surface_nee(scene, sampler, h, &frame, wi, medium, SurfaceMis::None);
            let key = ((sampler.next_u32() as u64) << 32) | sampler.next_u32() as u64;
            let gp = GatherPoint { p: h.p, n: h.n, frame, wi, bsdf: &shape.bsdf, uv: h.uv };
            out.add(Component::Surface, beta * (nee + gather.point(&gp, key)));
            frame_wi = Some((frame, wi));
        }
        // Continue from one gathering vertex of the chain, chosen uniformly.
        let scattering = chain.iter().filter(|c| !scene.medium(c.cs.medium).sigma_s().is_black()).count();
        let candidates = scattering + hit.is_some() as usize;
        if candidates == 0 || events + 1 >= max_events {
            return out;
        }
        events += 1;
        let k = ((sampler.next_1d() * candidates as f32) as usize).min(candidates - 1);
        let (u1, u2) = (sampler.next_1d(), sampler.next_2d());
        if k < scattering {
            let ChainSegment { cs, after_surface, direct: seen } = *chain
                .iter()
                .filter(|c| !scene.medium(c.cs.medium).sigma_s().is_black())
                .nth(k)
                .expect("k < count");
            skip_area_emitters = seen && gather.splats_caustics();
            // A uniform point of the segment, pdf 1/len; phase sampling is exact (weight 1).
            let med = scene.medium(cs.medium);
            let u = u1 * cs.seg.len;
            beta = match med.hetero.as_deref() {
                None => {
                    cs.tr_before
                        * transmittance(med.sigma_t, u)
                        * med.sigma_s()
                        * (cs.seg.len * candidates as f32)
                }
                // `T(0, u) sigma_s(x)` estimated (T31).
                Some(h) => {
                    cs.tr_before
                        * crate::hetero::along(h, &cs.seg, cs.seg.at(u), sampler)
                        * (cs.seg.len * candidates as f32)
                }
            };
            surface_seen = after_surface;
            let (d, _) = med.phase.sample(cs.seg.d, u2);
            ray = Ray::new(cs.seg.at(u), d);
            medium = Some(cs.medium);
        } else {
            skip_area_emitters = seen_directly && gather.splats_caustics();
            let (Some(h), Some((frame, wi))) = (hit, frame_wi) else { return out };
            let shape = &scene.shapes[h.shape as usize];
            let Some(bs) = shape.bsdf.sample(wi, u1, u2, h.uv) else { return out };
            beta *= bs.weight * candidates as f32;
            surface_seen = true;
            let d = frame.to_world(bs.wo);
            medium = shape.medium_towards(d, h.n, medium);
            ray = Ray::new(offset_origin(h.p, h.n, d), d);
        }
        gathering = false;
        if events > RR_EVENTS {
            let q = beta.max_component().min(0.95);
            if sampler.next_1d() >= q {
                return out;
            }
            beta /= q;
        }
        if beta.is_black() {
            return out;
        }
    })
}

/// Walks one chain from `ray` through null boundaries and delta surfaces. While `gathering`,
/// every medium interval goes into `chain` and emitters met are added to `out` (area emitters
/// not under `skip_area_emitters`); a delta surface sample that is not `null` (straight through
/// a thin sheet) turns gathering on and `direct` off.
#[allow(clippy::too_many_arguments)]
fn walk_chain(
    scene: &Scene,
    ray: &mut Ray,
    medium: &mut Option<MediumId>,
    sampler: &mut Sampler,
    beta: &mut Rgb,
    surface_seen: &mut bool,
    gathering: &mut bool,
    direct: &mut bool,
    skip_area_emitters: bool,
    events: &mut u32,
    max_events: u32,
    chain: &mut Vec<ChainSegment>,
    out: &mut PathRadiance,
) -> ChainEnd {
    for _ in 0..10_000 {
        let hit = scene.intersect(ray);
        let len = hit.map_or(ray.t_max, |h| h.t);
        if let Some(m) = *medium {
            match scene.medium(m).hetero.as_deref() {
                None => {
                    if *gathering && len.is_finite() && len > 0.0 && chain.len() < MAX_SEGMENTS {
                        let cs = CameraSegment {
                            seg: Segment::new(ray.o, ray.d, len),
                            medium: m,
                            tr_before: *beta,
                        };
                        chain.push(ChainSegment { cs, after_surface: *surface_seen, direct: *direct });
                    }
                    *beta *= transmittance(scene.medium(m).sigma_t, len);
                }
                Some(h) => {
                    // The gathering segment is the part where the majorant is positive (the
                    // medium is empty elsewhere, T27, T28, so the throughput there is `beta`); the walk
                    // goes on with a ratio-tracking estimate of the interval's transmittance
                    // (T30), independent of the estimates on the segment (docs/theory.md §12.5).
                    if *gathering && chain.len() < MAX_SEGMENTS {
                        if let Some((a, b)) = h.clip(ray.o, ray.d, 0.0, len) {
                            let seg = Segment::new(ray.at(a), ray.d, b - a);
                            let cs = CameraSegment { seg, medium: m, tr_before: *beta };
                            chain.push(ChainSegment { cs, after_surface: *surface_seen, direct: *direct });
                        }
                    }
                    *beta *= h.transmittance(ray.o, ray.d, 0.0, len, sampler);
                }
            }
        }
        let emitted = if *surface_seen { Component::Surface } else { Component::Emitted };
        let Some(h) = hit else {
            if *gathering {
                out.add(emitted, *beta * scene.environment_radiance(ray.d));
            }
            return ChainEnd::Stop;
        };
        if *gathering && !skip_area_emitters {
            if let Some((_, le)) = scene.area_radiance(h.shape, h.n, -ray.d) {
                out.add(emitted, *beta * le);
            }
        }
        let shape = &scene.shapes[h.shape as usize];
        if shape.cross_if_null(h.p, h.n, ray, medium) {
            continue;
        }
        if shape.bsdf.is_black() || beta.is_black() {
            return ChainEnd::Stop;
        }
        if !shape.bsdf.is_specular() {
            return ChainEnd::Surface(h);
        }
        *events += 1;
        if *events >= max_events {
            return ChainEnd::Stop;
        }
        let frame = Frame::from_normal(h.ns);
        let Some(bs) = shape.bsdf.sample(frame.to_local(-ray.d), sampler.next_1d(), sampler.next_2d(), h.uv)
        else {
            return ChainEnd::Stop;
        };
        *beta *= bs.weight;
        *surface_seen = true;
        if !bs.null {
            *gathering = true;
            *direct = false;
        }
        let d = frame.to_world(bs.wo);
        *medium = shape.medium_towards(d, h.n, *medium);
        *ray = Ray::new(offset_origin(h.p, h.n, d), d);
        if *events > RR_EVENTS {
            let q = beta.max_component().min(0.95);
            if sampler.next_1d() >= q {
                return ChainEnd::Stop;
            }
            *beta /= q;
        }
    }
    ChainEnd::Stop
}

//! The camera side of the whole image (`docs/theory.md` §2.1): camera chains through null
//! boundaries, delta surfaces and rough interfaces (next-event estimation there, then a BSDF
//! sample), gathering on every medium segment they cross and at their first other non-delta
//! surface vertex, and the continuation from one gathering vertex through delta chains
//! (caustics into gathering vertices).
//!
//! The path-space table of docs/theory.md §2.1 says which connection makes which path; this file makes the
//! camera half of each row: emitters hit by a gathering chain (counted fully), next-event
//! estimation on gathering segments (`single.rs`) and at gathering points
//! (`haze_render::integrators::surface_nee`, MIS-weighted against the continuation's BSDF
//! sample, `Walk::mis_from`), and the caller's virtual-light sums.
//!
//! Between vertices a chain moves through the one path walker (`haze_render::walker::Walker`):
//! legs through the medium (`trace_leg`, then the leg's transmittance), null crossings,
//! bounces, roulette and the cap on a walk's vertices.

use crate::camera::{CameraSegment, MAX_SEGMENTS};
use crate::vrl::Segment;
use glam::Vec3;
use haze_core::transmittance::hero_channel;
use haze_core::{Frame, Ray, Rgb, Sampler};
use haze_render::integrators::{area_hit_weight, environment_hits, surface_nee, HandOff, PathState, VolPath};
use haze_render::walker::Walker;
use haze_render::{Component, PathRadiance};
use haze_scene::bsdf::BsdfSample;
use haze_scene::texture::TexPoint;
use haze_scene::{Bsdf, Medium, MediumId, Scene, SurfaceInteraction};
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
    /// Where the BSDF's textures are looked up (`SurfaceInteraction::tex`).
    pub tex: TexPoint,
    /// Scattering events of the camera path before this point (`crate::depth`).
    pub events: u32,
}

impl GatherPoint<'_> {
    /// `f(wi, d) |cos d|` towards the unit world direction `d` (towards the light).
    #[inline]
    pub fn reflectance(&self, d: Vec3) -> Rgb {
        self.bsdf.eval(self.wi, self.frame.to_local(d), self.tex)
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
    /// `Some(1)`: the primary chain splits at its first two-lobe delta vertex
    /// (`ChainEnd::Split`), the branches weighted by their lobe probabilities times this
    /// factor; `None` only in tests that compare with the unsplit walk, other factors only in
    /// their negative control.
    fn split(&self) -> Option<f32> {
        Some(1.0)
    }
    /// `Some(c)`: `point` clamps the `1/d^2` of its surface VPLs at `c`, and the walk recovers
    /// the clamped part (`Walk::compensate_from`).
    fn compensated_clamp(&self) -> Option<f32>;
    /// The media in which a gathering chain hands the rest of its path to volpath.
    fn path_traced_media(&self) -> PathTracedMedia;
}

/// The media in which the camera walk of a many-light method does not gather: a gathering
/// chain that enters one hands the rest of its path to volpath's walk (free flight,
/// next-event estimation with MIS, phase and BSDF sampling; `docs/theory.md` §2.1, "Path-traced
/// media"). The virtual lights are still traced there, and light the media and surfaces the
/// camera gathers at elsewhere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathTracedMedia {
    /// Gather everywhere.
    None,
    /// Heterogeneous media, where every measured scene rendered better by volpath
    /// (docs/results.md: the smoke plume at densities 1-8, the cumulus under sun and sky).
    #[default]
    Heterogeneous,
    /// Every medium that scatters.
    All,
}

impl PathTracedMedia {
    /// True if a gathering chain in `medium` hands its path to volpath.
    #[inline]
    pub fn covers(self, medium: &Medium) -> bool {
        match self {
            PathTracedMedia::None => false,
            PathTracedMedia::Heterogeneous => medium.as_grid().is_some(),
            PathTracedMedia::All => medium.as_grid().is_some() || medium.scatters(),
        }
    }
}

thread_local! {
    /// Per-thread gathering segments of the current chain: the hot loop allocates nothing.
    static CHAIN: RefCell<Vec<ChainSegment>> = RefCell::new(Vec::with_capacity(MAX_SEGMENTS));
    /// The same for the branches after the primary chain's split (`ChainEnd::Split`).
    static BRANCH_CHAIN: RefCell<Vec<ChainSegment>> = RefCell::new(Vec::with_capacity(MAX_SEGMENTS));
}

/// Camera-path events (delta surfaces and continuations) after which Russian roulette starts.
const RR_EVENTS: u32 = 8;

/// A gathering segment of a chain.
#[derive(Clone, Copy)]
struct ChainSegment {
    cs: CameraSegment,
    /// The camera path had a surface event before it (its light is `surface`).
    after_surface: bool,
    /// The camera sees it directly (`Walk::direct`): the continuation from its points leaves
    /// area emitters behind delta chains to light tracing.
    direct: bool,
    /// Already gathered (a split's prefix: gathered once, before the branches).
    gathered: bool,
    /// Factor of a continuation from it: the branch's lobe probability for a split's prefix,
    /// else 1.
    scale: f32,
}

/// The state of a camera walk between chains.
#[derive(Clone, Copy)]
struct Walk {
    /// Where the chain goes (its ray and medium), through the one path walker.
    walker: Walker,
    beta: Rgb,
    surface_seen: bool,
    gathering: bool,
    events: u32,
    /// The camera sees the chain's end directly (no delta sample but thin sheets' straight
    /// crossings): only the first chain, until a delta sample changes the direction.
    direct: bool,
    /// The continued chain after a directly seen gathering vertex: its area emitters are light
    /// tracing's (`crate::splat`), not counted here.
    skip_area_emitters: bool,
    /// The primary chain splits at its first delta vertex with two lobes (`ChainEnd::Split`),
    /// with this factor on the lobe probabilities (1; `Gather::split`).
    may_split: Option<f32>,
    /// The gathering point this chain continues from by a non-delta BSDF sample, while only
    /// null boundaries and thin sheets' straight crossings lie behind: the surface VPL
    /// connections to it were clamped (`Gather::compensated_clamp`), and the chain's surface
    /// vertex `y` gathers again, as a gathering point, weighted by the part clamped off,
    /// `(1 - c |y - x|^2)+`. Kollig & Keller (2004, "Illumination in the presence of weak
    /// singularities", Section 3): the surface VPLs at distance `d` estimate
    /// `∫ L(y -> x) f_x cos_x dω` with `dω = cos_y dA / d^2`; clamping `1/d^2` at `c` leaves
    /// `∫ L(y -> x) f_x cos_x (1 - c d^2)+ dω`, which a BSDF-sampled direction from `x`, the
    /// radiance leaving `y` estimated by a camera walk from `y`, estimates without the VPLs'
    /// singularity.
    compensate_from: Option<Vec3>,
    /// The chain continues from the gathering point or rough interface `x` by a non-delta BSDF
    /// sample of effective density `p` (`p_bsdf / k` from a gathering point, one of `k`
    /// gathering vertices chosen; `p_bsdf` from a rough interface), and only null boundaries and
    /// thin sheets' straight crossings lie behind: the emitters it meets are direct light at
    /// `x`, which next-event estimation there also samples. Both weigh it by the power
    /// heuristic (`surface_nee`'s `bsdf_share`), so that neither strategy's tail is left alone
    /// where the other samples well (an environment map whose bright part
    /// the point does not see: NEE alone left Mitsuba 3's `test_homo_emitter_inside_medium`
    /// backdrop 2-5x too dark at 108 spp, a heavy tail).
    mis_from: Option<(Vec3, f32)>,
}

/// How a chain ended.
enum ChainEnd {
    /// Left the scene, was absorbed, or hit the event limit.
    Stop,
    /// At a non-delta surface vertex.
    Surface(SurfaceInteraction),
    /// At the primary chain's first delta vertex with two lobes (glass: reflection and
    /// refraction), followed both ways instead of one chosen by its probability: each branch's
    /// throughput is `beta f |cos| / p * p` (the lobe's weight times its probability, so the
    /// two sum to the expectation of the choice). This removes the noise of the choice itself,
    /// the largest in pixels where glass reflects a small lamp (on `scenes/glass-beam.xml` the
    /// lamp seen in the ball, 40% of the variance left after the caustic paths).
    Split([(Walk, f32); 2]),
}

/// The radiance along `ray` (from `medium`) of every path in the table of docs/theory.md §2.1, split by component.
pub(crate) fn whole_path_radiance(
    scene: &Scene,
    ray: Ray,
    medium: Option<MediumId>,
    sampler: &mut Sampler,
    gather: &impl Gather,
) -> PathRadiance {
    let mut out = PathRadiance::default();
    let start = Walk {
        walker: Walker::camera(ray, medium),
        beta: Rgb::ONE,
        surface_seen: false,
        gathering: true,
        events: 0,
        direct: true,
        skip_area_emitters: false,
        may_split: gather.split(),
        compensate_from: None,
        mis_from: None,
    };
    CHAIN.with_borrow_mut(|chain| {
        chain.clear();
        walk(scene, start, chain, sampler, gather, &mut out);
    });
    out
}

/// Walks chains from `st` until the path ends: gathers on each chain's segments and at its
/// gathering point, then continues from one gathering vertex. `chain` may start with a split's
/// prefix (gathered already, continuations from it scaled by the branch's probability).
fn walk(
    scene: &Scene,
    mut st: Walk,
    chain: &mut Vec<ChainSegment>,
    sampler: &mut Sampler,
    gather: &impl Gather,
    out: &mut PathRadiance,
) {
    let max_events = haze_scene::depth_limit(scene.integrator.max_depth);
    // The most events a path may have (`max_depth - 1`, crate::depth).
    let max_light_path = crate::depth::max_events(scene);
    loop {
        let end = walk_chain(scene, &mut st, max_events, max_light_path, gather, sampler, chain, out);
        let seen_directly = std::mem::replace(&mut st.direct, false);
        st.skip_area_emitters = false;
        st.may_split = None;
        for ChainSegment { cs, after_surface, .. } in chain.iter().filter(|c| !c.gathered) {
            // Next-event estimation on the segment makes paths of `c + 1` events (crate::depth).
            let single = if cs.events < max_light_path {
                crate::single::single_scattering(scene, cs, sampler)
            } else {
                Rgb::ZERO
            };
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
        if let ChainEnd::Split(branches) = end {
            // Each branch walks on with this chain as its prefix: gathered once (above), and a
            // continuation from it counted with the branch's probability, so that the two
            // branches' continuations from the prefix sum to one.
            BRANCH_CHAIN.with_borrow_mut(|sub| {
                for (branch, p) in branches {
                    sub.clear();
                    sub.extend(chain.iter().map(|c| ChainSegment {
                        gathered: true,
                        scale: c.scale * p,
                        ..*c
                    }));
                    walk(scene, branch, sub, sampler, gather, out);
                }
            });
            return;
        }
        let hit = match end {
            ChainEnd::Surface(h) if st.gathering => Some(h),
            ChainEnd::Surface(h) => match (st.compensate_from, gather.compensated_clamp()) {
                (Some(x), Some(c)) => {
                    let w = 1.0 - c * (h.p - x).length_squared();
                    st.beta *= w.max(0.0);
                    (w > 0.0).then_some(h)
                }
                _ => None,
            },
            _ => None,
        };
        st.compensate_from = None;
        st.mis_from = None;
        // The gathering vertices a continuation may start from: the chain's scattering segments
        // and the point.
        let scattering = chain.iter().filter(|c| scene.medium(c.cs.medium).scatters()).count();
        let candidates = scattering + hit.is_some() as usize;
        let mut frame_wi = None;
        if let Some(h) = &hit {
            let shape = &scene.shapes[h.shape as usize];
            let frame = scene.shading_frame(h);
            let wi = frame.to_local(-st.walker.ray.d);
            // Next-event estimation here makes paths of `c + 1` events (crate::depth); whenever
            // it may, so may the continuation's BSDF sample from here (`st.events + 1 <
            // max_events`), its MIS partner (`Walk::mis_from`), chosen with probability `1/k`.
            let nee = if st.events < max_light_path {
                surface_nee(scene, sampler, h, &frame, wi, st.walker.medium, 1.0 / candidates as f32)
            } else {
                Rgb::ZERO
            };
            let key = ((sampler.next_u32() as u64) << 32) | sampler.next_u32() as u64;
            let gp =
                GatherPoint { p: h.p, n: h.n, frame, wi, bsdf: &shape.bsdf, tex: h.tex(), events: st.events };
            out.add(Component::Surface, st.beta * (nee + gather.point(&gp, key)));
            frame_wi = Some((frame, wi));
        }
        // Continue from one gathering vertex of the chain, chosen uniformly.
        // The continuation's vertex is an event after those before it: a segment's own count
        // (delta vertices may separate a chain's segments) or the gathering point's.
        let fewest = chain.iter().map(|c| c.cs.events).chain(hit.is_some().then_some(st.events)).min();
        if candidates == 0 || fewest.is_none_or(|c| c + 1 >= max_events) {
            return;
        }
        let k = ((sampler.next_1d() * candidates as f32) as usize).min(candidates - 1);
        let (u1, u2) = (sampler.next_1d(), sampler.next_2d());
        let mut delta_lobe = false;
        if k < scattering {
            let c = *chain.iter().filter(|c| scene.medium(c.cs.medium).scatters()).nth(k).expect("k < count");
            st.events = c.cs.events + 1;
            if st.events >= max_events {
                return;
            }
            st.skip_area_emitters = c.direct && gather.splats_caustics();
            // A uniform point of the segment, pdf 1/len; phase sampling is exact (weight 1).
            let cs = c.cs;
            let med = scene.medium(cs.medium);
            let u = u1 * cs.seg.len;
            st.beta = match crate::hetero::scattering_factors(med, &cs.seg, u, cs.seg.at(u), sampler) {
                Some((cam, sigma_s)) => {
                    cs.tr_before * cam * sigma_s * (cs.seg.len * candidates as f32 * c.scale)
                }
                None => Rgb::ZERO,
            };
            st.surface_seen = c.after_surface;
            let (d, _) = med.phase.sample(cs.seg.d, u2);
            st.walker.medium = Some(cs.medium);
            st.walker.scatter(cs.seg.at(u), d);
        } else {
            st.skip_area_emitters = seen_directly && gather.splats_caustics();
            st.events += 1;
            if st.events >= max_events {
                return;
            }
            let (Some(h), Some((frame, wi))) = (hit, frame_wi) else { return };
            let shape = &scene.shapes[h.shape as usize];
            let Some(bs) = shape.bsdf.sample(wi, u1, u2, h.tex()) else { return };
            st.beta *= bs.weight * candidates as f32;
            st.surface_seen = true;
            st.compensate_from = (!bs.specular).then_some(h.p);
            st.mis_from = (!bs.specular).then_some((h.p, bs.pdf / candidates as f32));
            if bs.specular {
                // A delta lobe of a gathering BSDF (smooth `plastic`'s coat): no connection
                // evaluates it (`eval` holds the other lobes only), so the chain after it
                // gathers as after a delta surface, its area emitters included (caustic paths
                // aim only at delta shapes).
                delta_lobe = true;
                st.skip_area_emitters = false;
            }
            st.walker.bounce(scene, &h, frame.to_world(bs.wo));
        }
        chain.clear();
        st.gathering = delta_lobe;
        if !survives_roulette(&mut st, sampler) {
            return;
        }
        if st.beta.is_black() {
            return;
        }
    }
}

/// The walk after the delta sample `bs` at `h` (frame `frame`) of the state `st`.
fn after_delta(st: &Walk, h: &SurfaceInteraction, frame: &Frame, bs: &BsdfSample, scene: &Scene) -> Walk {
    let mut walker = st.walker;
    walker.bounce(scene, h, frame.to_world(bs.wo));
    Walk {
        walker,
        beta: st.beta * bs.weight,
        events: st.events + !bs.null as u32,
        surface_seen: true,
        gathering: st.gathering || !bs.null,
        direct: st.direct && bs.null,
        compensate_from: st.compensate_from.filter(|_| bs.null),
        mis_from: st.mis_from.filter(|_| bs.null),
        ..*st
    }
}

/// Walks one chain from `st.ray` through null boundaries and delta surfaces. While gathering,
/// every medium interval goes into `chain` and emitters met are added to `out` (area emitters
/// not under `skip_area_emitters`); a delta surface sample that is not `null` (straight through
/// a thin sheet) turns gathering on and `direct` off. Under `may_split` the first delta vertex
/// with two lobes ends the chain with both (`ChainEnd::Split`).
#[allow(clippy::too_many_arguments)]
fn walk_chain(
    scene: &Scene,
    st: &mut Walk,
    max_events: u32,
    max_light_path: u32,
    gather: &impl Gather,
    sampler: &mut Sampler,
    chain: &mut Vec<ChainSegment>,
    out: &mut PathRadiance,
) -> ChainEnd {
    // A branch of a split, or a thin sheet's reflection, may arrive past the limit.
    if st.events >= max_events {
        return ChainEnd::Stop;
    }
    while st.walker.next_vertex() {
        // Before the intersection, which volpath's walk makes itself (a heterogeneous medium's
        // grid beyond the surface, or missed, only means that volpath's walk passes it).
        if st.gathering
            && st.walker.medium.is_some_and(|m| gather.path_traced_media().covers(scene.medium(m)))
        {
            hand_off(scene, st, gather, sampler, out);
            return ChainEnd::Stop;
        }
        let leg = st.walker.trace_leg(scene);
        let hit = leg.hit.map(|h| scene.interaction(&h));
        let (ray, len) = (st.walker.ray, leg.t_surface);
        if let Some(m) = st.walker.medium {
            // The gathering segment is where the medium may interact (`Medium::support`: a grid
            // medium is empty outside its positive-majorant cells, T27, T28, so the throughput
            // there is `beta`); the walk goes on with the interval's transmittance (closed form,
            // or a ratio-tracking estimate (T30) independent of the estimates on the segment,
            // docs/theory.md §12.5).
            if st.gathering && chain.len() < MAX_SEGMENTS {
                if let Some((a, b)) =
                    scene.medium(m).support(ray.o, ray.d, 0.0, len).filter(|s| s.1.is_finite())
                {
                    chain.push(ChainSegment {
                        cs: CameraSegment {
                            seg: Segment::new(ray.at(a), ray.d, b - a),
                            medium: m,
                            tr_before: st.beta,
                            events: st.events,
                        },
                        after_surface: st.surface_seen,
                        direct: st.direct,
                        gathered: false,
                        scale: 1.0,
                    });
                }
            }
            st.beta *= st.walker.transmittance(scene, len, sampler);
        }
        let emitted = if st.surface_seen { Component::Surface } else { Component::Emitted };
        // `hide_emitters` hides what the camera sees at no event, as volpath's `depth == 0`.
        let hidden = st.events == 0 && scene.integrator.hide_emitters;
        let Some(h) = hit else {
            match st.mis_from {
                None if st.gathering && !hidden => {
                    out.add(emitted, st.beta * scene.environment_radiance(st.walker.ray.d));
                }
                Some((_, p_bsdf)) => {
                    for (le, w) in environment_hits(scene, st.walker.ray.d, p_bsdf) {
                        out.add(emitted, st.beta * le * w);
                    }
                }
                None => {}
            }
            return ChainEnd::Stop;
        };
        // Emitters met after a non-delta sample's null crossings only are weighed against the
        // next-event estimation at the sample's vertex; the others count fully while gathering
        // (no other strategy finds them), except under `skip_area_emitters`.
        if let Some((e, le)) = scene.area_radiance(h.shape, h.n, h.tex(), -st.walker.ray.d) {
            match st.mis_from {
                None if st.gathering && !st.skip_area_emitters && !hidden => out.add(emitted, st.beta * le),
                Some((x, p_bsdf)) => {
                    let w = area_hit_weight(scene, e, x, p_bsdf, &h);
                    out.add(emitted, st.beta * le * w);
                }
                None => {}
            }
        }
        let shape = &scene.shapes[h.shape as usize];
        if st.walker.cross_if_null(scene, &h) {
            continue;
        }
        if shape.bsdf.is_black() || st.beta.is_black() {
            return ChainEnd::Stop;
        }
        if !shape.bsdf.is_specular() {
            if !(st.gathering && shape.bsdf.is_rough_interface()) {
                return ChainEnd::Surface(h);
            }
            // A rough interface in a gathering chain (docs/theory.md §2.1, "Rough interfaces"):
            // direct light by next-event estimation, then a BSDF sample (the two weighed by MIS,
            // `Walk::mis_from`), and the chain goes on gathering beyond. The paths a virtual light would
            // make by a connection to this point are those the gathering beyond makes.
            // The frame the BSDF is sampled and evaluated in, as volpath's: an anisotropic
            // or textured roughness follows `dp/du`, which a frame built from the normal alone
            // ignores (`Scene::shading_frame`).
            let frame = scene.shading_frame(&h);
            let wi = frame.to_local(-st.walker.ray.d);
            // Weighed against the BSDF sample below, taken whenever this estimate is (both need
            // `st.events + 1 < max_events`).
            if st.events < max_light_path {
                let nee = surface_nee(scene, sampler, &h, &frame, wi, st.walker.medium, 1.0);
                out.add(Component::Surface, st.beta * nee);
            }
            if st.events + 1 >= max_events {
                return ChainEnd::Stop;
            }
            let (u1, u2) = (sampler.next_1d(), sampler.next_2d());
            let Some(bs) = shape.bsdf.sample(wi, u1, u2, h.tex()) else {
                return ChainEnd::Stop;
            };
            // Seen directly, its light through delta chains is the caustic paths' (`splat.rs`).
            let skip_area_emitters = st.direct && gather.splats_caustics();
            *st = after_delta(st, &h, &frame, &bs, scene);
            st.skip_area_emitters = skip_area_emitters;
            st.mis_from = Some((h.p, bs.pdf));
            st.direct = false;
            if !survives_roulette(st, sampler) {
                return ChainEnd::Stop;
            }
            continue;
        }
        // A delta vertex is an event unless its sample is `null` (a thin sheet's straight
        // transmission, as volpath counts it): `after_delta` counts it; the walk ends where no
        // further vertex could be an event within the limit.
        if st.events + 1 >= max_events && !shape.bsdf.may_pass_through() {
            return ChainEnd::Stop;
        }
        let frame = scene.shading_frame(&h);
        let wi = frame.to_local(-st.walker.ray.d);
        let (u1, u2) = (sampler.next_1d(), sampler.next_2d());
        if let Some(factor) = st.may_split {
            // The two lobes of a two-lobe delta BSDF: `u1` below and above every lobe
            // probability picks each (the BSDFs choose a lobe by `u1 < p`).
            let lobes =
                (shape.bsdf.sample(wi, 0.0, u2, h.tex()), shape.bsdf.sample(wi, ONE_MINUS_EPS, u2, h.tex()));
            if let (Some(a), Some(b)) = lobes {
                if a.pdf < 1.0 && b.pdf < 1.0 && (a.transmitted != b.transmitted || a.null != b.null) {
                    let branch = |bs: &BsdfSample| {
                        let p = bs.pdf * factor;
                        let mut next = after_delta(st, &h, &frame, bs, scene);
                        next.may_split = None;
                        next.beta *= p;
                        (next, p)
                    };
                    return ChainEnd::Split([branch(&a), branch(&b)]);
                }
            }
        }
        let Some(bs) = shape.bsdf.sample(wi, u1, u2, h.tex()) else {
            return ChainEnd::Stop;
        };
        *st = after_delta(st, &h, &frame, &bs, scene);
        if st.events >= max_events {
            return ChainEnd::Stop;
        }
        if !survives_roulette(st, sampler) {
            return ChainEnd::Stop;
        }
    }
    ChainEnd::Stop
}

/// The rest of the path of the gathering chain `st`, whose ray starts in a path-traced medium, by
/// volpath's walk: its throughput, event counts and component class carry over, and the emitter
/// hits that the walk's other strategies count are left to them (`HandOff`): behind a delta
/// chain from a vertex the camera sees directly the caustic paths'. Emitter hits before
/// volpath's first event count fully, as the gathering chain counts them, except after a rough
/// interface: there volpath weighs them against that interface's next-event estimation, as the
/// chain would (`Walk::mis_from`). Paths partition by their first camera vertex that is not a
/// delta or null one: in a path-traced medium (or beyond one on the chain) volpath's, elsewhere
/// the gather's.
fn hand_off(scene: &Scene, st: &Walk, gather: &impl Gather, sampler: &mut Sampler, out: &mut PathRadiance) {
    let volpath = VolPath::from_spec(&scene.integrator);
    let hero = hero_channel(sampler.next_1d());
    let path = PathState {
        walker: st.walker,
        beta: st.beta,
        depth: st.events,
        // Before a surface event every event was a medium event (`Component::classify`).
        medium_events: st.events,
        surface_events: st.surface_seen as u32,
        specular_chain: st.mis_from.is_none(),
        last_p: st.mis_from.map_or(st.walker.ray.o, |(x, _)| x),
        last_pdf: st.mis_from.map_or(1.0, |(_, p)| p),
        hand_off: HandOff {
            skip_area: st.skip_area_emitters,
            direct: st.direct && gather.splats_caustics(),
            pending: false,
        },
        ..PathState::camera(st.walker.ray, st.walker.medium, hero)
    };
    volpath.trace(scene, path, sampler, out);
}

/// Russian roulette after [`RR_EVENTS`] events: the walk survives with probability
/// `q = min(max(beta), 0.95)` and its throughput is divided by `q` (`Walker::roulette`); false if
/// it ends.
fn survives_roulette(st: &mut Walk, sampler: &mut Sampler) -> bool {
    if st.events > RR_EVENTS {
        let Some(q) = Walker::roulette(st.beta.max_component(), sampler) else {
            return false;
        };
        st.beta /= q;
    }
    true
}

/// The largest f32 below 1.
const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

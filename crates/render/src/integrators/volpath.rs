//! `volpath`: unbiased volumetric path tracing in homogeneous and heterogeneous media — the
//! reference every many-light method in haze is checked against. Heterogeneous media are
//! sampled by delta tracking and their transmittance estimated by ratio tracking, both against
//! a majorant grid (`haze_scene::hetero`, `docs/theory.md` §12.2-12.4).
//!
//! Follows Mitsuba 3's `volpath` in its observable conventions, because the validation
//! references come from it:
//! - `depth` counts scattering events (medium and non-null surface); a null-surface crossing is
//!   not an event. A path stops once `depth >= max_depth`; a medium event that reaches
//!   `max_depth` contributes nothing; surface NEE needs `depth + 1 < max_depth`. So the last
//!   vertex the depth allows adds only what it emits: no NEE, and no BSDF sample unless the
//!   BSDF may pass light through (thin glass: not an event), since its direction would not be
//!   followed.
//! - Russian roulette once `depth > rr_depth`, survival `q = min(max(throughput) eta^2, 0.95)`
//!   (`Walker::roulette`, shared by every walk: `crate::walker`).
//! - Media change only at shapes that declare an interior or exterior medium.
//! - Emitters are sampled uniformly; NEE and phase/BSDF sampling are combined with the power
//!   heuristic; emitters hit directly by the camera or after a specular chain count fully.
//!
//! One deliberate difference: chromatic extinction uses path-level spectral MIS over the hero
//! channel (see `haze_core::transmittance`), as Mitsuba's `volpathmis` does, rather than plain
//! `volpath`'s single hero channel. Both are unbiased; MIS has far lower variance when channels
//! differ. Every contribution is divided by `mean(r)`, the pdf ratios of the path so far.

use super::nee::{area_hit_weight, environment_hits, surface_nee, transmittance_to_sampled};
use super::Integrator;
use crate::components::{Component, PathRadiance};
use crate::walker::Walker;
use glam::Vec3;
use haze_core::sampling::power_heuristic;
use haze_core::transmittance::hero_channel;
use haze_core::{Ray, Rgb, Sampler};
use haze_scene::bsdf::BsdfSample;
use haze_scene::Flight;
use haze_scene::{IntegratorSpec, MediumId, Scene};

#[derive(Clone, Debug)]
pub struct VolPath {
    /// `-1` for unlimited.
    pub max_depth: i32,
    pub rr_depth: u32,
    pub hide_emitters: bool,
}

impl VolPath {
    pub fn from_spec(spec: &IntegratorSpec) -> Self {
        VolPath { max_depth: spec.max_depth, rr_depth: spec.rr_depth, hide_emitters: spec.hide_emitters }
    }
}

impl Integrator for VolPath {
    type PassData = ();

    fn name(&self) -> &str {
        "volpath"
    }

    fn begin_pass(&self, _scene: &Scene, _seed: u64, _pass: u32) {}

    fn passes_batchable(&self) -> bool {
        true
    }

    fn radiance(
        &self,
        scene: &Scene,
        _pass: &(),
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        let mut out = PathRadiance::default();
        let hero = hero_channel(sampler.next_1d());
        self.trace(scene, PathState::camera(ray, medium, hero), sampler, &mut out);
        out
    }
}

/// The state of a volpath walk between vertices: where it goes (`ray` in `medium`), what it
/// carries, and what it needs for roulette, the depth rule and MIS. A path from the camera
/// starts with [`PathState::camera`]; the many-light methods' camera walk hands a path over in
/// the middle (`haze_manylight::gather`, the media it path-traces) with its own counts.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    /// Where the walk goes: its ray, medium and what its next query may use.
    pub walker: Walker,
    /// Throughput `f / p_hero`.
    pub beta: Rgb,
    /// The pdf ratios `r_c = p_c / p_hero` of the path so far (path-level spectral MIS).
    pub r: Rgb,
    pub hero: usize,
    /// Product of the relative IORs crossed (for roulette, as Mitsuba's `volpath`).
    pub eta: f32,
    /// Scattering events so far (medium and non-null surface), the depth rule's count.
    pub depth: u32,
    pub medium_events: u32,
    pub surface_events: u32,
    /// Every scattering so far was specular: an emitter hit now is not MIS-weighted, because
    /// next-event estimation could not have found it.
    pub specular_chain: bool,
    /// The pdf and position of the last non-specular sampling, for MIS at emitter hits.
    pub last_pdf: f32,
    pub last_p: Vec3,
    /// The emitter hits another estimator counts (none for a path of volpath's own).
    pub hand_off: HandOff,
}

impl PathState {
    /// A camera path along `ray` from `medium`, its hero channel `hero`.
    pub fn camera(ray: Ray, medium: Option<MediumId>, hero: usize) -> PathState {
        PathState {
            walker: Walker::camera(ray, medium),
            beta: Rgb::ONE,
            r: Rgb::ONE,
            hero,
            eta: 1.0,
            depth: 0,
            medium_events: 0,
            surface_events: 0,
            specular_chain: true,
            last_pdf: 1.0,
            last_p: ray.o,
            hand_off: HandOff::default(),
        }
    }
}

/// The emitter hits of a path handed over by the many-light camera walk that the walk's other
/// strategies count, so that each path is counted once (`docs/theory.md` §2.1).
#[derive(Clone, Copy, Debug, Default)]
pub struct HandOff {
    /// Skip area emitters until the next non-delta event: they lie behind a delta chain from a
    /// vertex the camera sees directly, light tracing's caustic paths splat them.
    pub skip_area: bool,
    /// The camera sees the path's current end directly (no direction change so far), and the
    /// caustic paths splat such vertices' delta-chain light.
    pub direct: bool,
    /// The last event was such a directly seen non-delta vertex, with no delta sample since:
    /// a delta sample now starts `skip_area`.
    pub pending: bool,
}

impl HandOff {
    /// A medium event.
    #[inline]
    fn scattered(&mut self) {
        self.skip_area = false;
        self.pending = std::mem::take(&mut self.direct);
    }

    /// A surface sample `bs` (a `null` one changes nothing: not an event, no new direction).
    #[inline]
    fn sampled(&mut self, bs: &BsdfSample) {
        if bs.null {
            return;
        }
        if bs.specular {
            if std::mem::take(&mut self.pending) {
                self.skip_area = true;
            }
            self.direct = false;
        } else {
            self.scattered();
        }
    }
}

impl VolPath {
    /// Walks the path `st` to its end, adding its contributions to `out`: free flight, null
    /// crossings, next-event estimation with MIS, phase and BSDF sampling, roulette.
    pub fn trace(&self, scene: &Scene, st: PathState, sampler: &mut Sampler, out: &mut PathRadiance) {
        // `-1` (unlimited) and anything longer stop at the hard cap, `MAX_PATH_DEPTH`.
        let max_depth = haze_scene::depth_limit(self.max_depth);
        let PathState {
            mut walker,
            mut beta,
            mut r,
            hero,
            mut eta,
            mut depth,
            mut medium_events,
            mut surface_events,
            mut specular_chain,
            mut last_pdf,
            mut last_p,
            mut hand_off,
        } = st;
        while walker.next_vertex() {
            if depth > self.rr_depth {
                let m = (beta / r.mean()).max_component() * eta * eta;
                let Some(q) = Walker::roulette(m, sampler) else { break };
                beta /= q;
            }
            if depth >= max_depth || beta.is_black() {
                break;
            }

            // The leg's free flight (`Walker::sample_leg`). Whether the path scatters in a
            // homogeneous medium or reaches a surface, the sampler's next numbers are those of
            // its next-event estimation (in a heterogeneous medium delta tracking draws first,
            // and the hint is wasted): an environment map's cache misses for that sample then
            // overlap the traversal. No emitter can light a point in this medium: its next-event
            // estimation below is skipped, and so is the hint; so it is at the last vertex the
            // depth allows, which estimates nothing (a vertex at `depth` does next-event
            // estimation only if `depth + 1 < max_depth`, on a surface or in a medium).
            let medium = walker.medium;
            let unlit = scene.medium_unlit(medium);
            let (leg, flight) = walker.sample_leg(scene, hero, sampler, |s| {
                if !unlit && depth + 1 < max_depth {
                    scene.prefetch_emitter_sample(s);
                }
            });
            let ray = walker.ray;

            if let (Some(mid), Some(flight)) = (medium, flight) {
                let med = scene.medium(mid);
                match flight {
                    // `sigma_s` multiplies after the depth check, as it always did (the same
                    // rounding; a grid medium's `weight` already holds `sigma_s(x)`).
                    Flight::Scatter { t, weight, sigma_s, ratio } => {
                        let p = ray.at(t);
                        hand_off.scattered();
                        beta *= weight;
                        r *= ratio;
                        depth += 1;
                        medium_events += 1;
                        if depth >= max_depth {
                            break;
                        }
                        beta *= sigma_s;
                        // A black throughput (albedo 0) has nothing left to estimate: no shadow ray.
                        if beta.is_black() {
                            break;
                        }
                        let class = Component::classify(medium_events, surface_events);

                        // Next-event estimation, MIS with phase sampling; in a medium no
                        // emitter can light, only its random numbers (the same stream).
                        let (u_light, u_dir) = (sampler.next_1d(), sampler.next_2d());
                        let light =
                            if unlit { None } else { scene.sample_emitter_direction(p, u_light, u_dir) };
                        if let Some(es) = light {
                            let ph = med.phase.eval(ray.d, es.wi);
                            if ph > 0.0 {
                                let tr =
                                    transmittance_to_sampled(scene, p, None, es.wi, es.dist, medium, sampler);
                                if !tr.is_black() {
                                    let w = if es.is_delta { 1.0 } else { power_heuristic(es.pdf, ph) };
                                    out.add(class, beta * es.radiance * tr * (ph * w / (es.pdf * r.mean())));
                                }
                            }
                        }

                        // Phase sampling is exact, so the throughput weight is 1.
                        let (d, pdf) = med.phase.sample(ray.d, sampler.next_2d());
                        last_pdf = pdf;
                        last_p = p;
                        specular_chain = false;
                        walker.scatter(p, d);
                        continue;
                    }
                    Flight::Pass { weight, ratio } => {
                        beta *= weight;
                        r *= ratio;
                    }
                }
            }

            let class = Component::classify(medium_events, surface_events);
            let count_direct = depth == 0 || specular_chain;
            let visible = !(depth == 0 && self.hide_emitters);

            let Some(h) = leg.hit.map(|h| scene.interaction(&h)) else {
                if visible && count_direct {
                    // Weight 1: no pdf needed (an environment map's pdf is a lookup in its
                    // sampling table, a cache miss, for every escaping camera or glass path).
                    for e in scene.emitters.iter().filter(|e| e.is_environment()) {
                        out.add(class, beta * e.environment_radiance(ray.d) * (1.0 / r.mean()));
                    }
                } else if visible {
                    // Each environment emitter is weighted against its own NEE pdf.
                    for (le, w) in environment_hits(scene, ray.d, last_pdf) {
                        out.add(class, beta * le * (w / r.mean()));
                    }
                }
                break;
            };

            if visible && !hand_off.skip_area {
                if let Some((e, le)) = scene.area_radiance(h.shape, h.n, h.tex(), -ray.d) {
                    let w = if count_direct { 1.0 } else { area_hit_weight(scene, e, last_p, last_pdf, &h) };
                    out.add(class, beta * le * (w / r.mean()));
                }
            }

            let shape = &scene.shapes[h.shape as usize];
            if walker.cross_if_null(scene, &h) {
                continue;
            }
            if shape.bsdf.is_black() {
                break;
            }
            // The last vertex the depth allows estimates nothing more (next-event estimation
            // below needs `depth + 1 < max_depth`), and a sampled direction would only be
            // followed to stop at the depth check, unless the BSDF passes light through without
            // a scattering event (thin glass), which does not count towards the depth. The
            // path's estimate is the same; only its sampler draws less (so at one sample per
            // pass, the default, the image is the same bit for bit).
            if depth + 1 >= max_depth && !shape.bsdf.may_pass_through() {
                break;
            }

            let frame = scene.shading_frame(&h);
            let wi = frame.to_local(-ray.d);

            if !shape.bsdf.is_specular() && depth + 1 < max_depth {
                let direct = surface_nee(scene, sampler, &h, &frame, wi, medium, 1.0);
                out.add(Component::Surface, beta * direct / r.mean());
            }

            // With delta lights only, `bs.pdf` (`last_pdf`) weighs nothing: not computed.
            let with_pdf = !scene.bsdf_pdfs_unused();
            let Some(bs) =
                shape.bsdf.sample_with(wi, sampler.next_1d(), sampler.next_2d(), h.tex(), with_pdf)
            else {
                break;
            };
            beta *= bs.weight;
            eta *= bs.eta;
            let d = frame.to_world(bs.wo);
            surface_events += 1;
            hand_off.sampled(&bs);
            // A null-typed sample (thindielectric transmission) is not a scattering event for
            // Mitsuba's volpath: no depth, and the MIS state of the last real vertex is kept.
            if !bs.null {
                depth += 1;
                last_p = h.p;
                last_pdf = bs.pdf;
                specular_chain = bs.specular;
            }
            walker.bounce(scene, &h, d);
        }
    }
}

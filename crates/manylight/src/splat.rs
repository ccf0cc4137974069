//! Caustics seen directly, by light tracing to the camera: dedicated *caustic paths* from the
//! point, spot, area and directional emitters aimed at the scene's delta surfaces (glass, thin sheets),
//! followed through delta chains, and connected to the pinhole from every point where they
//! can scatter towards it: each medium segment after the first direction-changing delta
//! vertex (single scattering, one point per segment) and the first non-delta surface point.
//! The splats go into the pixels around their image (`docs/theory.md` §2.1, row "caustics
//! seen directly"). A caustic path moves between vertices through the one path walker
//! (`haze_render::walker::Walker`: legs through the medium, null crossings, bounces, the cap).
//!
//! Without it those paths (`emitter D+ x camera`, `x` a medium point or a surface point the
//! camera sees directly) are found only by the camera path's continuation from `x` hitting the
//! emitter through the delta chain, a small target behind a glass ball: on
//! `scenes/glass-beam.xml` about 80% of the many-light methods' variance (the ceiling lamp's
//! caustics in the haze and on the floor). Point and spot lights' caustics cannot be hit at all,
//! so before this the spot's single-scattered beam behind the ball was missing.
//!
//! ## Aiming the paths (a projection map, Jensen 1996)
//! Each delta shape gets a bounding sphere. A caustic path picks an emitter `k` with
//! probability `P_k` (power towards the spheres, mixed with 10% uniform), a point `y` on it
//! (area lights: uniform, `1/A`), and a direction `ω` from the cone mixture of the spheres seen
//! from `y`: sphere `j` with probability `Ω_j / Σ Ω`, then uniform in its cone, so
//! `p(ω) = n(ω) / Σ_j Ω_j` with `n(ω)` the number of cones holding `ω`. Every path whose first
//! surface is a delta surface has `ω` in one of the cones, so the estimator is unbiased:
//!
//! ```text
//!   beta_0 = L_e(y, ω) |cos_y| / (N P_k p(y) p(ω))      (point/spot: the intensity, no cos)
//! ```
//!
//! The path is then followed deterministically through media (`beta *= T(len)`, Beer-Lambert,
//! or a ratio-tracking estimate in a heterogeneous medium; no free-flight sampling: every
//! segment is a beam) and by BSDF sampling through delta
//! surfaces (adjoint: `eta^2` undone as in light tracing). It ends at its first non-delta
//! surface, at the first surface if that is not a delta one, or when it leaves.
//!
//! ## The importance of a pixel (pinhole camera)
//! Pixel `j`'s value is the filter-weighted mean of the radiance over the film,
//! `I_j = Int w_j(p) L(p) dp` (film coordinates `p` in pixels, `w_j` the reconstruction filter
//! around the pixel normalised over the film, `camera::PixelFilter`). On the image plane at
//! distance 1 (area `A = 4 tan(fov_x/2) tan(fov_y/2)`) a pixel is `A / (W H)`, and
//! `dA_plane = dω / cos^3 θ` (θ from the optical axis), so
//!
//! ```text
//!   I_j = Int w_j(p(ω)) (W H / A) L(ω) / cos^3 θ dω .
//! ```
//!
//! A light point `x` of intensity `I(ω_c)` towards the camera at distance `d` adds `I T / d^2`
//! to `Int L dω` around its image point `p(x)`, hence the splat
//!
//! ```text
//!   C_j = w_j(p(x)) (W H / A) I(ω_c) T(x, camera) / (d^2 cos^3 θ) ,
//! ```
//!
//! with `I = beta f(ω_c, ω_prev) |cos ω_c|` at a surface point (the surface VPL's intensity) and,
//! on a beam `x_v = o + v d` drawn equiangularly towards the camera (`p(v) = h / (Θ d^2)`,
//! Kulla & Fajardo 2012), `I / p(v) = beta T(v) sigma_s f_p(d, ω_c) Θ d^2 / h`. The camera side
//! of these paths, which the continuation no longer counts, is exactly what the connection
//! sees: a direct view through media, null boundaries and thin sheets' straight transmission
//! (`gather.rs`).

use crate::vpl::SurfaceVpl;
use glam::{Vec2, Vec3};
use haze_core::sampling::{sample_uniform_cone, sample_uniform_sphere};
use haze_core::streams::CAUSTIC_PATHS;
use haze_core::{Frame, Rgb, Sampler, PI};
use haze_render::integrators::transmittance_to;
use haze_render::walker::Walker;
use haze_scene::camera::{FilmProjector, PixelFilter};
use haze_scene::lights::EmissionSample;
use haze_scene::{MediumId, Scene};
use rayon::prelude::*;

/// One pass's light-tracing splats: per pixel (row-major, as the film), the light the pass's
/// caustic paths bring to it.
#[derive(Clone, Debug, Default)]
pub struct CameraSplats {
    pixels: Vec<Rgb>,
}

impl CameraSplats {
    /// The splatted light of pixel `pixel` (`y * width + x`); zero for a pass without caustic
    /// paths.
    #[inline]
    pub fn get(&self, pixel: u64) -> Rgb {
        self.pixels.get(pixel as usize).copied().unwrap_or(Rgb::ZERO)
    }

    /// The splats times `s`.
    pub fn scaled(mut self, s: f32) -> Self {
        if s != 1.0 {
            for c in &mut self.pixels {
                *c *= s;
            }
        }
        self
    }
}

/// A delta shape's bounding sphere.
#[derive(Clone, Copy, Debug)]
struct Target {
    c: Vec3,
    r: f32,
}

/// Targets whose cones [`CausticTracer::sample_direction`] keeps on the stack.
const CACHED_CONES: usize = 16;

/// The caustic paths' sampler: the targets and the emitter probabilities, built once per scene.
#[derive(Clone, Debug)]
pub struct CausticTracer {
    targets: Vec<Target>,
    /// `(emitter index, P_k)` of the point, spot and area emitters, and their CDF.
    emitters: Vec<(u32, f32)>,
    cdf: Vec<f32>,
    paths: u64,
    max_events: u32,
    /// Longest beam (four scene diagonals): a beam escaping into an unbounded medium.
    max_len: f32,
}

impl CausticTracer {
    /// `paths` caustic paths per pass, at most `max_events` delta vertices (non-null samples)
    /// each before their connection (`crate::depth`: `e + 1 <= max_depth - 1`); `None` if the
    /// scene has no delta surface or no point, spot, area or directional emitter (then there are no such
    /// caustics), or if `paths` is 0.
    pub fn new(scene: &Scene, paths: u64, max_events: u32) -> Option<Self> {
        let targets: Vec<Target> = scene
            .shapes
            .iter()
            .filter(|s| s.bsdf.is_specular() && !s.bsdf.is_null())
            .filter_map(|s| s.geometry.bounding_sphere())
            .map(|(c, r)| Target { c, r })
            .collect();
        if targets.is_empty() || paths == 0 {
            return None;
        }
        let mut weights: Vec<(u32, f32)> = (0..scene.emitters.len() as u32)
            .filter_map(|k| emitter_weight(scene, k, &targets).map(|w| (k, w)))
            .collect();
        if weights.is_empty() {
            return None;
        }
        let total: f32 = weights.iter().map(|w| w.1).sum();
        let n = weights.len() as f32;
        for w in &mut weights {
            w.1 = if total > 0.0 { 0.9 * w.1 / total + 0.1 / n } else { 1.0 / n };
        }
        let mut acc = 0.0;
        let cdf = weights
            .iter()
            .map(|w| {
                acc += w.1;
                acc
            })
            .collect();
        Some(CausticTracer {
            targets,
            emitters: weights,
            cdf,
            paths,
            max_events,
            max_len: 4.0 * crate::lighttrace::scene_extent(scene),
        })
    }

    /// The splats of one pass's caustic paths (path `i` draws from
    /// `Sampler::new(seed ^ CAUSTIC_PATHS, i, pass)`). Deterministic: chunks of paths run in
    /// parallel, the sums in path order.
    pub fn splats(&self, scene: &Scene, seed: u64, pass: u32) -> CameraSplats {
        const CHUNK: u64 = 1024;
        let view = View::new(scene);
        let inv = 1.0 / self.paths as f32;
        let chunks: Vec<Vec<(f32, f32, Rgb)>> = (0..self.paths.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut hits = Vec::new();
                for i in c * CHUNK..((c + 1) * CHUNK).min(self.paths) {
                    let mut s = Sampler::new(seed ^ CAUSTIC_PATHS, i, pass as u64);
                    self.trace(scene, &view, &mut s, inv, &mut hits);
                }
                hits
            })
            .collect();
        accumulate(scene, chunks.into_iter().flatten())
    }

    /// The emission sample of a caustic path (see the module docs), or `None`.
    fn sample_emission(&self, scene: &Scene, s: &mut Sampler) -> Option<EmissionSample> {
        let u = s.next_1d() * self.cdf.last().copied().unwrap_or(1.0);
        let i = self.cdf.partition_point(|&c| c < u).min(self.emitters.len() - 1);
        let (k, p_k) = self.emitters[i];
        let (u_pos, u_pick, u_dir) = (s.next_2d(), s.next_1d(), s.next_2d());
        if let Some((d, irradiance)) = scene.emitters[k as usize].parallel_light() {
            let (p, p_pos) = self.sample_sun_line(scene, d, u_pick, u_dir)?;
            return Some(EmissionSample { p, d, n: None, weight: irradiance / (p_k * p_pos), emitter: k });
        }
        let ep = scene.sample_emitter_point(k, u_pos)?;
        let (d, pdf_dir) = self.sample_direction(ep.p, u_pick, u_dir)?;
        let le = scene.emitted_intensity(&ep, d);
        if le.is_black() {
            return None;
        }
        Some(EmissionSample {
            p: ep.p,
            d,
            n: ep.surface.map(|(n, _)| n),
            weight: le / (p_k * ep.pdf * pdf_dir),
            emitter: k,
        })
    }

    /// A line of the sun's direction `d` aimed at the targets (the parallel-light form of the
    /// cone mixture): target `j` with probability `pi r_j^2 / Σ pi r_k^2`, a uniform point of
    /// the disk of radius `r_j` around `c_j` perpendicular to `d`; the line's density per unit
    /// area of that plane is `n(line) / Σ pi r_k^2`, `n` the number of target disks it crosses.
    /// Every line of direction `d` that meets a delta shape crosses its bounding sphere's disk,
    /// so the estimate is unbiased. The origin is moved upstream to outside the scene's
    /// bounding sphere, so whatever lies between the sun and the target shades the path.
    /// Returns the origin and the density.
    fn sample_sun_line(&self, scene: &Scene, d: Vec3, u_pick: f32, u: Vec2) -> Option<(Vec3, f32)> {
        let total: f32 = self.targets.iter().map(|t| PI * t.r * t.r).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut pick = u_pick * total;
        let mut chosen = self.targets[self.targets.len() - 1];
        for t in &self.targets {
            let area = PI * t.r * t.r;
            if pick < area {
                chosen = *t;
                break;
            }
            pick -= area;
        }
        let frame = Frame::from_normal(d);
        let q = haze_core::sampling::sample_uniform_disk_concentric(u);
        let on_plane = chosen.c + chosen.r * frame.to_world(Vec3::new(q.x, q.y, 0.0));
        let crossing = self
            .targets
            .iter()
            .filter(|t| {
                let v = on_plane - t.c;
                (v - d * v.dot(d)).length_squared() <= t.r * t.r
            })
            .count()
            .max(1);
        let sphere = scene.bounding_sphere();
        let back = (on_plane - sphere.center).length() + sphere.radius;
        Some((on_plane - d * back, crossing as f32 / total))
    }

    /// A direction from `p` by the cone mixture, with its pdf `n(ω) / Σ Ω_j`.
    fn sample_direction(&self, p: Vec3, u_pick: f32, u: Vec2) -> Option<(Vec3, f32)> {
        // Cones as (axis, cos_max, solid angle); a point inside a sphere sees all directions.
        let cone = |t: &Target| {
            let v = t.c - p;
            let d2 = v.length_squared();
            if d2 <= t.r * t.r * 1.0001 {
                return (Vec3::Z, -1.0f32, 4.0 * PI);
            }
            let cos_max = (1.0 - t.r * t.r / d2).max(0.0).sqrt();
            (v / d2.sqrt(), cos_max, 2.0 * PI * (1.0 - cos_max))
        };
        // Each cone once, on the stack for the usual handful of targets (the three passes
        // below read them); more targets recompute them.
        let mut cached = [(Vec3::Z, 0.0f32, 0.0f32); CACHED_CONES];
        let n = self.targets.len();
        let fits = n <= CACHED_CONES;
        if fits {
            for (c, t) in cached.iter_mut().zip(&self.targets) {
                *c = cone(t);
            }
        }
        let cone_of = |k: usize| if fits { cached[k] } else { cone(&self.targets[k]) };
        let total: f32 = (0..n).map(|k| cone_of(k).2).sum();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let mut pick = u_pick * total;
        let mut chosen = cone_of(n - 1);
        for k in 0..n {
            let c = cone_of(k);
            if pick < c.2 {
                chosen = c;
                break;
            }
            pick -= c.2;
        }
        let (axis, cos_max, _) = chosen;
        let d = if cos_max <= -1.0 {
            sample_uniform_sphere(u)
        } else {
            Frame::from_normal(axis).to_world(sample_uniform_cone(u, cos_max))
        };
        let holding = (0..n)
            .filter(|&k| {
                let (axis, cos_max, _) = cone_of(k);
                cos_max <= -1.0 || d.dot(axis) >= cos_max
            })
            .count()
            .max(1);
        Some((d, holding as f32 / total))
    }

    /// Follows one caustic path and pushes its splats.
    fn trace(
        &self,
        scene: &Scene,
        view: &View<'_>,
        s: &mut Sampler,
        inv_paths: f32,
        out: &mut Vec<(f32, f32, Rgb)>,
    ) {
        let Some(e) = self.sample_emission(scene, s) else { return };
        let (ray, medium) = crate::lighttrace::emission_ray(scene, &e);
        let mut walker = Walker::new(ray, medium);
        let mut beta = e.weight * inv_paths;
        let mut through_delta = false;
        // As light tracing caps its VRLs in an unbounded medium.
        let max_len = self.max_len;
        let mut events = 0;
        while walker.next_vertex() {
            let leg = walker.trace_leg(scene);
            let ray = walker.ray;
            if let Some(m) = walker.medium {
                let len = leg.t_surface.min(max_len);
                if through_delta && len > 0.0 {
                    let u = s.next_1d();
                    if let Some(splat) = view.connect_beam(scene, ray.o, ray.d, len, m, beta, u, s) {
                        out.push(splat);
                    }
                }
                // A heterogeneous medium's beam by ratio tracking (docs/theory.md §12.4, §12.5).
                beta *= walker.transmittance(scene, len, s);
            }
            let Some(h) = leg.hit.map(|h| scene.interaction(&h)) else { return };
            let shape = &scene.shapes[h.shape as usize];
            if walker.cross_if_null(scene, &h) {
                continue;
            }
            if shape.bsdf.is_black() || beta.is_black() {
                return;
            }
            if !shape.bsdf.is_specular() {
                if through_delta {
                    let frame = scene.shading_frame(&h);
                    let vpl = SurfaceVpl {
                        events: 0,
                        p: h.p,
                        n: h.n,
                        frame,
                        w_prev: frame.to_local(-ray.d),
                        flux: beta,
                        shape: h.shape,
                        tex: h.tex(),
                        medium: walker.medium,
                    };
                    if let Some(splat) = view.connect_surface(scene, &vpl) {
                        out.push(splat);
                    }
                }
                return;
            }
            let frame = scene.shading_frame(&h);
            let Some(bs) = shape.bsdf.sample(frame.to_local(-ray.d), s.next_1d(), s.next_2d(), h.tex())
            else {
                return;
            };
            through_delta |= !bs.null;
            // A thin sheet's straight transmission (`null` sample) is no event.
            events += !bs.null as u32;
            if events > self.max_events {
                return;
            }
            // Adjoint transport, as in light tracing: the radiance-only 1/eta^2 is undone.
            beta *= bs.weight * (bs.eta * bs.eta);
            walker.bounce(scene, &h, frame.to_world(bs.wo));
        }
    }
}

/// The power emitter `k` sends towards the targets, roughly (for `P_k`:
/// `Scene::emitter_power_towards` with the targets' cones and disks), or `None` if it starts no
/// caustic path: environments (`constant`, `envmap`), whose caustics seen directly the camera
/// path's continuation through the delta chain finds, since it can hit them (`gather.rs` leaves
/// only area emitters to these paths); the sun cannot be hit, so its caustics come from here.
fn emitter_weight(scene: &Scene, k: u32, targets: &[Target]) -> Option<f32> {
    // The solid angle of the targets' cones from `p` (all directions inside a sphere).
    let omega = |p: Vec3| -> f32 {
        targets
            .iter()
            .map(|t| {
                let d2 = (t.c - p).length_squared();
                if d2 <= t.r * t.r {
                    4.0 * PI
                } else {
                    2.0 * PI * (1.0 - (1.0 - t.r * t.r / d2).max(0.0).sqrt())
                }
            })
            .sum()
    };
    // The targets' disks across any direction.
    let disks = |_: Vec3| -> f32 { targets.iter().map(|t| PI * t.r * t.r).sum() };
    scene.emitter_power_towards(k, omega, disks)
}

/// Sums splats into the film's pixels with the reconstruction filter.
fn accumulate(scene: &Scene, hits: impl Iterator<Item = (f32, f32, Rgb)>) -> CameraSplats {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut hits = hits.peekable();
    if hits.peek().is_none() {
        return CameraSplats::default();
    }
    let mut pixels = vec![Rgb::ZERO; w * h];
    if cam.filter == PixelFilter::Box {
        for (px, py, c) in hits {
            let (x, y) = ((px as usize).min(w - 1), (py as usize).min(h - 1));
            pixels[y * w + x] += c;
        }
        return CameraSplats { pixels };
    }
    let (zx, zy) = (filter_norms(cam.filter, w), filter_norms(cam.filter, h));
    let r = cam.filter.radius();
    for (px, py, c) in hits {
        let x0 = ((px - r - 0.5).floor().max(0.0)) as usize;
        let x1 = ((px + r - 0.5).ceil() as usize).min(w - 1);
        let y0 = ((py - r - 0.5).floor().max(0.0)) as usize;
        let y1 = ((py + r - 0.5).ceil() as usize).min(h - 1);
        for y in y0..=y1 {
            let fy = cam.filter.eval(py - (y as f32 + 0.5)) / zy[y];
            if fy == 0.0 {
                continue;
            }
            for x in x0..=x1 {
                let fx = cam.filter.eval(px - (x as f32 + 0.5)) / zx[x];
                pixels[y * w + x] += c * (fx * fy);
            }
        }
    }
    CameraSplats { pixels }
}

/// `Z_i = Int_0^n f(x - (i + 1/2)) dx` for every pixel `i` of an axis of `n` pixels: the
/// normalisation of the filter restricted to the film (`PixelFilter` samples the same
/// restricted profile). Simpson's rule on each side of the peak (32 intervals a side: exact for
/// the tent, better than 1e-6 relative for the Gaussian).
fn filter_norms(filter: PixelFilter, n: usize) -> Vec<f32> {
    let r = filter.radius() as f64;
    let simpson = |a: f64, b: f64, c: f64| {
        if b <= a {
            return 0.0;
        }
        const K: usize = 32;
        let hh = (b - a) / K as f64;
        let f = |x: f64| filter.eval((x - c) as f32) as f64;
        let mut s = f(a) + f(b);
        for i in 1..K {
            s += f(a + i as f64 * hh) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * hh / 3.0
    };
    (0..n)
        .map(|i| {
            let c = i as f64 + 0.5;
            let (lo, hi) = ((c - r).max(0.0), (c + r).min(n as f64));
            (simpson(lo, c, c) + simpson(c, hi, c)) as f32
        })
        .collect()
}

/// The pinhole's projection (`Camera::film_projector`) and the splats it makes.
struct View<'a> {
    projector: FilmProjector<'a>,
    /// The pinhole.
    o: Vec3,
}

impl<'a> View<'a> {
    fn new(scene: &'a Scene) -> Self {
        let projector = scene.camera.film_projector().expect("caustic paths need a pinhole camera");
        View { o: projector.o, projector }
    }

    /// A beam's single scattering towards the camera: the beam `o + v d`, `v` in `[0, len]`, in
    /// homogeneous medium `m` with `beta` at `o`; one point drawn equiangularly towards the
    /// camera with `u` (module docs).
    #[allow(clippy::too_many_arguments)]
    fn connect_beam(
        &self,
        scene: &Scene,
        o: Vec3,
        d: Vec3,
        len: f32,
        m: MediumId,
        beta: Rgb,
        u: f32,
        s: &mut Sampler,
    ) -> Option<(f32, f32, Rgb)> {
        let med = scene.medium(m);
        if !med.scatters() {
            return None;
        }
        let seg = crate::vrl::Segment::new(o, d, len);
        let (v, theta_over_h) = crate::vpl::estimator::sample_distance_towards(&seg, self.o, u, None)?;
        let x = seg.at(v);
        let pr = self.projector.project(x)?;
        let to_cam = self.o - x;
        let dist = to_cam.length();
        if dist <= 0.0 {
            return None;
        }
        let wc = to_cam / dist;
        let f = med.phase.eval(d, wc);
        let tr = transmittance_to(scene, x, None, wc, dist * (1.0 - pr.near), Some(m));
        if tr.is_black() {
            return None;
        }
        // `T(v) sigma_s`: exact in a homogeneous medium; in a heterogeneous one `sigma_s(x)` and a
        // ratio-tracking estimate of `T(v)` (docs/theory.md §12.5, (T31)).
        let c = match crate::hetero::scattering_factors(med, &seg, v, x, s) {
            Some((cam, sigma_s)) => beta * cam * sigma_s * tr * (f * theta_over_h * pr.density),
            None => Rgb::ZERO,
        };
        Some((pr.px, pr.py, c))
    }

    /// A surface point's splat: `vpl`'s intensity towards the camera (module docs).
    fn connect_surface(&self, scene: &Scene, vpl: &SurfaceVpl) -> Option<(f32, f32, Rgb)> {
        let pr = self.projector.project(vpl.p)?;
        let v = self.o - vpl.p;
        let d = v.length();
        if d <= 0.0 {
            return None;
        }
        let wc = v / d;
        let shape = &scene.shapes[vpl.shape as usize];
        let intensity = vpl.intensity(&shape.bsdf, wc);
        if intensity.is_black() {
            return None;
        }
        let medium = scene.medium_leaving(vpl.shape, vpl.p, vpl.n, wc, vpl.medium);
        let tr = transmittance_to(scene, vpl.p, Some(vpl.n), wc, d * (1.0 - pr.near), medium);
        if tr.is_black() {
            return None;
        }
        Some((pr.px, pr.py, intensity * tr * (pr.density / (d * d))))
    }
}

//! Shadow rays through media and index-matched (`null`) boundaries.

use glam::Vec3;
use haze_core::ray::offset_origin;
use haze_core::{Frame, Ray, Rgb, Sampler};
use haze_scene::accel::{Leaving, ShadowHit, ShadowQuery, MAX_SHADOW_HITS};
use haze_scene::texture::TexPoint;
use haze_scene::{Boundary, Bsdf, Medium, MediumId, Scene, SurfaceInteraction};

/// Relative shortening of a shadow segment so that the surface it aims at does not count as an
/// occluder: `t_max = |y - o| (1 - SHADOW_EPSILON)`. haze has used `1e-4` since the first
/// volpath; Mitsuba 3 uses `ShadowEpsilon = 10 RayEpsilon`, about `8.9e-4` in f32.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// Transmittance from `p` along the unit direction `d` over distance `dist` (infinite for
/// environment light), starting in `medium`. Null surfaces are crossed (changing medium where
/// the shape declares media, as Mitsuba 3 does), thin dielectrics too, scaled by their
/// transmittance (Mitsuba's `eval_null_transmission`); any other surface blocks. Homogeneous media
/// give the exact Beer-Lambert factor, so this is deterministic.
///
/// `n_start` is the geometric normal at `p` when `p` is on a surface (used to offset the origin),
/// `None` in a medium.
///
/// For a finite `dist` the ray is aimed from its (offset) origin `o` at the target
/// `y = p + dist d` and ends at `|y - o| (1 - SHADOW_EPSILON)`: Mitsuba 3's
/// `Interaction::spawn_ray_to` (`d = normalize(y - o)`, `maxt = |y - o| (1 - ShadowEpsilon)`).
/// Keeping `d` instead would run the ray parallel to `p y`, displaced by the origin offset
/// `eps n_s`; it then meets the plane of the emitter's own triangle (normal `n_l`) at
/// `dist - eps (n_l . n_s) / (n_l . d)`, which for a light seen at a grazing angle (`n_l . d`
/// small) lies before any relative shortening, so the light occluded itself (issue 8: up to 40%
/// too dark next to an angled area light).
///
/// The ray is traced once ([`Scene::shadow_hits`]: any blocker ends it, pass-through surfaces
/// are collected and crossed in order along the same line), so no crossing moves it: it ends
/// where it was aimed, `|y - o| SHADOW_EPSILON` before the light, however many null or thin
/// surfaces it crosses. Mitsuba 3's volpath does not: after each crossing its `sample_emitter`
/// continues from the crossing point offset along the surface's normal (`spawn_ray`, the same
/// direction) with the length left, so its last ray ends displaced by the summed offsets, past
/// a light closer than about `(1 + |p|) / 10` behind the boundary (along the light's normal),
/// and the light blocks its own sample. That loss is Mitsuba's part of `homo_emitter_inside_medium`
/// (`docs/validation.md`); `tests/analytic.rs` checks haze against quadrature there.
///
/// Heterogeneous media have no deterministic transmittance: their segments are estimated by
/// ratio tracking with a sampler seeded from the ray (unbiased per query; prefer
/// [`transmittance_to_sampled`], which draws from the caller's sampler).
pub fn transmittance_to(
    scene: &Scene,
    p: Vec3,
    n_start: Option<Vec3>,
    d: Vec3,
    dist: f32,
    medium: Option<MediumId>,
) -> Rgb {
    transmittance_impl(scene, p, n_start, None, d, dist, medium, None)
}

/// [`transmittance_to`] with the ratio-tracking estimates of heterogeneous segments
/// (`docs/theory.md` §12.4) drawn from `sampler`; homogeneous media draw nothing, so scenes
/// without heterogeneous media render bit for bit as with [`transmittance_to`].
pub fn transmittance_to_sampled(
    scene: &Scene,
    p: Vec3,
    n_start: Option<Vec3>,
    d: Vec3,
    dist: f32,
    medium: Option<MediumId>,
    sampler: &mut Sampler,
) -> Rgb {
    transmittance_impl(scene, p, n_start, None, d, dist, medium, Some(sampler))
}

/// [`transmittance_to_sampled`] from a point `p` on shape `shape` with geometric normal `n`:
/// the same value, the shadow ray's traversal skipping the shape where it cannot be hit again
/// ([`Scene::leaving`]: a convex mesh left outwards, a flat one).
#[allow(clippy::too_many_arguments)]
pub fn transmittance_from_surface_sampled(
    scene: &Scene,
    shape: u32,
    p: Vec3,
    n: Vec3,
    d: Vec3,
    dist: f32,
    medium: Option<MediumId>,
    sampler: &mut Sampler,
) -> Rgb {
    transmittance_impl(scene, p, Some(n), Some(shape), d, dist, medium, Some(sampler))
}

/// The transmittance of medium `med` along `ray` over `[t0, t1]` ([`Medium::transmittance`]:
/// closed form, or ratio tracking in a grid) with numbers from `sampler` or, without one, from
/// a sampler seeded by the ray's bits.
fn segment_transmittance(
    med: &Medium,
    ray: &Ray,
    t0: f32,
    t1: f32,
    sampler: &mut Option<&mut Sampler>,
) -> Rgb {
    match sampler {
        Some(s) => med.transmittance(ray.o, ray.d, t0, t1, s),
        None => {
            let key = [ray.o.x, ray.o.y, ray.o.z, ray.d.x, ray.d.y, ray.d.z, t0]
                .iter()
                .fold(0u64, |k, v| haze_core::rng::mix64(k ^ v.to_bits() as u64));
            med.transmittance(
                ray.o,
                ray.d,
                t0,
                t1,
                &mut Sampler::new(haze_core::streams::SHADOW_RATIO_TRACKING, key, t1.to_bits() as u64),
            )
        }
    }
}

/// Accumulates the leg `[t0, t1]` of a shadow ray in `med`: its closed-form optical depth
/// ([`Medium::optical_depth`]) into `tau`, else its transmittance into `tr`; the ray's
/// transmittance is `tr exp(-tau)`.
#[inline]
fn attenuate(
    med: &Medium,
    ray: &Ray,
    t0: f32,
    t1: f32,
    sampler: &mut Option<&mut Sampler>,
    tau: &mut Rgb,
    tr: &mut Rgb,
) {
    match med.optical_depth(t1 - t0) {
        Some(depth) => *tau += depth,
        None => *tr *= segment_transmittance(med, ray, t0, t1, sampler),
    }
}

/// `n_start`: the geometric normal at `p` when `p` is on a surface; `shape`: that surface's
/// shape when the caller knows it, so that the ray may skip it ([`Scene::leaving`]).
#[allow(clippy::too_many_arguments)]
fn transmittance_impl(
    scene: &Scene,
    p: Vec3,
    n_start: Option<Vec3>,
    shape: Option<u32>,
    d: Vec3,
    dist: f32,
    mut medium: Option<MediumId>,
    mut sampler: Option<&mut Sampler>,
) -> Rgb {
    // Towards a light at infinity from a medium from which infinity cannot be reached (every
    // surface blocks, the medium attenuates every channel): zero, whatever the geometry. In the
    // dielectric_envmap peer every environment-map sample from inside the glass was such a ray.
    if !dist.is_finite() && scene.infinity_unreachable_from(medium) {
        return Rgb::ZERO;
    }
    let target = dist.is_finite().then(|| p + d * dist);
    let origin = match n_start {
        Some(n) => offset_origin(p, n, d),
        None => p,
    };
    // One traversal for the whole shadow ray: it stops at the first blocker found, else returns
    // the null boundaries and thin dielectrics on the segment, crossed here in `t` order with
    // the optical depth summed over them (one `exp` at the end instead of one per segment).
    let Some(ray) = shadow_ray(origin, target, d) else { return Rgb::ONE };
    // Decided on the ray as traced (aimed at the target from the offset origin).
    let leaving = match (shape, n_start) {
        (Some(shape), Some(n)) => scene.leaving(shape, n, ray.d),
        _ => Leaving::NONE,
    };
    let mut hits = [ShadowHit::default(); MAX_SHADOW_HITS];
    let n = match scene.shadow_hits_leaving(&ray, leaving, &mut hits) {
        ShadowQuery::Blocked => return Rgb::ZERO,
        ShadowQuery::Clear(n) => n,
        ShadowQuery::Unsupported => return transmittance_segments(scene, origin, target, d, medium, sampler),
    };
    let hits = &mut hits[..n];
    // Ties (a ray through a shared edge meets both triangles) in BVH order: deterministic.
    hits.sort_by(|a, b| a.t.total_cmp(&b.t));
    let mut tau = Rgb::ZERO;
    let mut tr = Rgb::ONE;
    let mut last = 0.0f32;
    let mut i = 0;
    while i < hits.len() {
        let h = &hits[i];
        if let Some(m) = medium {
            attenuate(scene.medium(m), &ray, last, h.t, &mut sampler, &mut tau, &mut tr);
        }
        last = h.t;
        let (shape_id, n) = scene.shadow_crossing(h);
        let shape = &scene.shapes[shape_id as usize];
        if !shape.bsdf.is_null() {
            // A thin dielectric: its transmittance needs the shading normal and uv.
            let si = scene.shadow_interaction(h);
            tr *= crossing_factor(&shape.bsdf, ray.d, si.ns, si.tex());
        }
        i += 1;
        if scene.shadow_touches(shape_id, h) {
            // Surfaces touching this one (`docs/theory.md` §14) are crossed together: the
            // medium beyond is decided by all their boundaries at once (T40), not by their
            // order along the ray.
            let mut boundary = Boundary::of(shape, n);
            let slab = 2.0 * haze_core::RAY_EPSILON * (1.0 + ray.at(h.t).abs().max_element());
            let cos = ray.d.dot(n).abs();
            while i < hits.len() && (hits[i].t - h.t) * cos <= slab {
                let (other, n) = scene.shadow_crossing(&hits[i]);
                let other = &scene.shapes[other as usize];
                if !other.bsdf.is_null() {
                    let si = scene.shadow_interaction(&hits[i]);
                    tr *= crossing_factor(&other.bsdf, ray.d, si.ns, si.tex());
                }
                boundary = boundary.with(other, n);
                i += 1;
            }
            medium = boundary.medium_towards(ray.d, medium);
        } else {
            medium = shape.medium_towards(ray.d, n, medium);
        }
        if tr.is_black() {
            return Rgb::ZERO;
        }
    }
    if let Some(m) = medium {
        attenuate(scene.medium(m), &ray, last, ray.t_max, &mut sampler, &mut tau, &mut tr);
    }
    tr * exp_neg(tau)
}

/// The shadow segment from `origin`: towards the target `y` when there is one, aimed from
/// `origin` and ending at `|y - origin| (1 - SHADOW_EPSILON)` (Mitsuba 3's `spawn_ray_to`, see
/// [`transmittance_to`]), else along `d` to infinity. `None` when the target is at or behind
/// `origin` (an offset past it, e.g. a null surface at the light itself): nothing is between.
#[inline]
fn shadow_ray(origin: Vec3, target: Option<Vec3>, d: Vec3) -> Option<Ray> {
    match target {
        Some(y) => {
            let v = y - origin;
            let len = v.length();
            if len == 0.0 || v.dot(d) <= 0.0 {
                return None;
            }
            Some(Ray { o: origin, d: v / len, t_max: len * (1.0 - SHADOW_EPSILON) })
        }
        None => Some(Ray { o: origin, d, t_max: f32::INFINITY }),
    }
}

/// What a shadow ray along `d` keeps of its throughput crossing a surface with `bsdf`, shading
/// normal `ns`: 1 for `null`, a thin dielectric's transmittance (Mitsuba's
/// `eval_null_transmission`), 0 for any other surface (it blocks).
#[inline]
fn crossing_factor(bsdf: &Bsdf, d: Vec3, ns: Vec3, uv: TexPoint) -> Rgb {
    if bsdf.is_null() {
        Rgb::ONE
    } else {
        bsdf.null_transmission(Frame::from_normal(ns).to_local(-d), uv)
    }
}

/// Next-event estimation of direct light at the non-delta surface vertex `h` reached from the
/// direction `wi` (local to `frame`, the shading frame at `h`) in `medium` (the medium the path
/// arrived in): one emitter sample, `f(wi, wo) |cos wo| L_e Tr / p` with its MIS weight
/// (`volpath`'s surface NEE). The caller multiplies by its path throughput.
///
/// The weight is the power heuristic against the BSDF sample from `h` that the caller takes
/// with probability `bsdf_share` and whose emitter hits it weighs with the same pair: that
/// strategy's density is `bsdf_share * p_bsdf` (Veach 1997, eq. 9.13, the one-sample choice
/// folded into the pdf). `volpath` always takes it (1); the many-light methods continue from
/// one of `k` gathering vertices (`1/k`).
pub fn surface_nee(
    scene: &Scene,
    sampler: &mut haze_core::Sampler,
    h: &SurfaceInteraction,
    frame: &Frame,
    wi: Vec3,
    medium: Option<MediumId>,
    bsdf_share: f32,
) -> Rgb {
    let shape = &scene.shapes[h.shape as usize];
    // Directions in which `f` is zero are refused before an environment map reads their pdf
    // and radiance: the same `wo` as below, so exactly the samples whose `f` is black.
    let front_only = shape.bsdf.front_only();
    let accept = |d: Vec3| !front_only || (wi.z > 0.0 && frame.to_local(d).z > 0.0);
    let Some(es) = scene.sample_emitter_direction_if(h.p, sampler.next_1d(), sampler.next_2d(), accept)
    else {
        return Rgb::ZERO;
    };
    if scene.towards_sealed_inside(h.shape, h.n, es.wi) {
        return Rgb::ZERO;
    }
    let wo = frame.to_local(es.wi);
    // The pdf only where the MIS weight needs it, computed with `f` (shared terms).
    let (f, bsdf_pdf) = if es.is_delta {
        (shape.bsdf.eval(wi, wo, h.tex()), 0.0)
    } else {
        let (f, pdf) = shape.bsdf.eval_pdf(wi, wo, h.tex());
        (f, bsdf_share * pdf)
    };
    if f.is_black() {
        return Rgb::ZERO;
    }
    let tr = transmittance_from_surface_sampled(
        scene,
        h.shape,
        h.p,
        h.n,
        es.wi,
        es.dist,
        scene.medium_towards(h, es.wi, medium),
        sampler,
    );
    if tr.is_black() {
        return Rgb::ZERO;
    }
    let w = if es.is_delta { 1.0 } else { haze_core::sampling::power_heuristic(es.pdf, bsdf_pdf) };
    f * es.radiance * tr * (w / es.pdf)
}

/// `exp(-tau)` per channel, with a single `exp` when the channels are equal (grey media).
#[inline]
/// The environment radiance a BSDF-sampled direction `d` escapes into, each environment emitter
/// with its MIS weight against next-event estimation: `(L_e, w)` with `w` the power heuristic of
/// the BSDF sample's density `p_bsdf` against that emitter's NEE pdf in `d` (Veach 1997, eq.
/// 9.13). The partner of [`surface_nee`] for the paths that continue by a BSDF sample.
pub fn environment_hits(scene: &Scene, d: Vec3, p_bsdf: f32) -> impl Iterator<Item = (Rgb, f32)> + '_ {
    scene
        .environment_emission(d)
        .map(move |(le, pdf)| (le, haze_core::sampling::power_heuristic(p_bsdf, pdf)))
}

/// The MIS weight of area emitter `emitter` hit at `h` by a BSDF sample of density `p_bsdf` taken
/// at `from`: the power heuristic against next-event estimation's pdf of sampling that point from
/// `from` (Veach 1997, eq. 9.13; the partner of [`surface_nee`]).
pub fn area_hit_weight(scene: &Scene, emitter: u32, from: Vec3, p_bsdf: f32, h: &SurfaceInteraction) -> f32 {
    haze_core::sampling::power_heuristic(p_bsdf, scene.area_emitter_pdf(emitter, from, h.p, h.n))
}

fn exp_neg(tau: Rgb) -> Rgb {
    let [r, g, b] = tau.0;
    if r == 0.0 && g == 0.0 && b == 0.0 {
        Rgb::ONE
    } else if r == g && g == b {
        Rgb::splat((-r).exp())
    } else {
        tau.map(|x| (-x).exp())
    }
}

/// The general shadow ray of [`transmittance_to`], one closest-hit query per crossed surface,
/// each segment re-aimed at the target: for rays [`Scene::shadow_hits`] cannot answer (more
/// than `MAX_SHADOW_HITS` pass-through surfaces, or pass-through spheres and disks).
fn transmittance_segments(
    scene: &Scene,
    mut origin: Vec3,
    target: Option<Vec3>,
    d: Vec3,
    mut medium: Option<MediumId>,
    mut sampler: Option<&mut Sampler>,
) -> Rgb {
    let mut tr = Rgb::ONE;
    for _ in 0..256 {
        let Some(ray) = shadow_ray(origin, target, d) else { return tr };
        let hit = scene.intersect(&ray);
        let seg = hit.map_or(ray.t_max, |h| h.t);
        if let Some(m) = medium {
            let med = scene.medium(m);
            tr *= match med.optical_depth(seg) {
                Some(depth) => exp_neg(depth),
                None => segment_transmittance(med, &ray, 0.0, seg, &mut sampler),
            };
            if tr.is_black() {
                return Rgb::ZERO;
            }
        }
        let Some(h) = hit else { return tr };
        let shape = &scene.shapes[h.shape as usize];
        tr *= crossing_factor(&shape.bsdf, ray.d, h.ns, h.tex());
        if tr.is_black() {
            return Rgb::ZERO;
        }
        medium = scene.medium_towards(&h, ray.d, medium);
        origin = offset_origin(h.p, h.n, ray.d);
    }
    // A ray that keeps hitting null surfaces 256 times is caught in degenerate geometry.
    Rgb::ZERO
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;
    use haze_scene::{Bsdf, Camera, Emitter, Geometry, IntegratorSpec, Shape, Texture, TriangleMesh};

    /// The quad `x in [x0, x1]`, `z in [-1, 1]` at height `y`, normal `+y` or `-y`, opaque black.
    fn quad(name: &str, x0: f32, x1: f32, y: f32, up: bool) -> Shape {
        let p = vec![
            Vec3::new(x0, y, -1.0),
            Vec3::new(x1, y, -1.0),
            Vec3::new(x1, y, 1.0),
            Vec3::new(x0, y, 1.0),
        ];
        // `[0, 1, 2]`: `(p1 - p0) x (p2 - p0)` is along `x cross z = -y`.
        let indices = if up { vec![[0, 2, 1], [0, 3, 2]] } else { vec![[0, 1, 2], [0, 2, 3]] };
        Shape {
            name: name.into(),
            geometry: Geometry::Mesh(TriangleMesh::new(p, None, None, indices, false)),
            bsdf: Bsdf::Diffuse { reflectance: Texture::Constant(Rgb::ZERO) },
            interior: None,
            exterior: None,
            emitter: None,
        }
    }

    fn scene(shapes: Vec<Shape>) -> Scene {
        scene_with_media(shapes, vec![])
    }

    fn scene_with_media(shapes: Vec<Shape>, media: Vec<haze_scene::Medium>) -> Scene {
        scene_with(shapes, media, vec![Emitter::Area { shape: 1, radiance: Rgb::ONE.into() }])
    }

    /// A one-pixel camera at the origin, in vacuum.
    fn camera() -> Camera {
        Camera::pinhole(Mat4::IDENTITY, 30.0, (1, 1))
    }

    fn scene_with(shapes: Vec<Shape>, media: Vec<haze_scene::Medium>, emitters: Vec<Emitter>) -> Scene {
        Scene::new(None, camera(), 1, IntegratorSpec::default(), shapes, media, emitters)
    }

    /// Shadow rays from a floor (`y = 0`, offset origin `~1e-4 (1 + |p|)` along `+y`) to a
    /// downward-facing light 0.05 above it, seen at grazing angles (`cos_l` about 0.05), as next to
    /// `angled_cube.obj` in Mitsuba's `test_*area_light` scenes. A ray that keeps the unperturbed
    /// direction meets the light's plane `eps / cos_l` (about 4e-3) before the target and
    /// the light occludes itself; aimed from the offset origin, it reaches the light, and a
    /// blocker 1e-3 below the light still blocks.
    #[test]
    fn shadow_rays_reach_a_light_seen_at_a_grazing_angle() {
        let floor = quad("floor", -5.0, 5.0, 0.0, true);
        let light = quad("light", 1.5, 3.0, 0.05, false);
        let open = scene(vec![floor.clone(), light.clone()]);
        let blocked = scene(vec![floor, light, quad("blocker", 2.0, 3.0, 0.049, true)]);
        for px in [0.2f32, 0.6, 1.0, 1.2] {
            let p = Vec3::new(px, 0.0, 0.1);
            for i in 0..8 {
                for j in 0..8 {
                    let y = Vec3::new(1.6 + 0.18 * i as f32, 0.05, -0.9 + 0.25 * j as f32);
                    let v = y - p;
                    let (d, dist) = (v.normalize(), v.length());
                    let tr = transmittance_to(&open, p, Some(Vec3::Y), d, dist, None);
                    assert_eq!(tr, Rgb::ONE, "light occluded from {p} towards {y}");
                    // The blocker covers x in [2, 3]; every ray to a target past x = 2.1 crosses
                    // y = 0.049 over it, at least 0.02 before the light.
                    if y.x > 2.1 {
                        let tr = transmittance_to(&blocked, p, Some(Vec3::Y), d, dist, None);
                        assert_eq!(tr, Rgb::ZERO, "blocker missed from {p} towards {y}");
                    }
                }
            }
        }
    }

    /// One homogeneous, isotropic medium of extinction `sigma_t`.
    fn fog(sigma_t: Rgb) -> Vec<haze_scene::Medium> {
        vec![haze_scene::Medium::homogeneous(
            "fog".into(),
            sigma_t,
            Rgb::splat(0.5),
            haze_core::Phase::Isotropic,
        )]
    }

    /// Shadow rays to infinity from a homogeneous medium in a scene whose surfaces all block
    /// return zero without being traced; the same rays in the same scene with an extra `null`
    /// quad far away (which no ray meets, but which makes the scene need the traced answer) give
    /// the same transmittance: zero where every channel attenuates, whether the ray meets the
    /// floor or escapes, and one in a channel with `sigma_t = 0` that escapes.
    #[test]
    fn shadow_rays_to_infinity_skipped_only_where_the_answer_is_zero() {
        let floor = quad("floor", -5.0, 5.0, 0.0, true);
        let light = quad("light", 1.5, 3.0, 0.05, false);
        let mut null = quad("null", 100.0, 101.0, 50.0, true);
        null.bsdf = Bsdf::Null;
        for sigma_t in [Rgb::splat(0.3), Rgb::new(0.3, 0.0, 0.2)] {
            let blocking = scene_with_media(vec![floor.clone(), light.clone()], fog(sigma_t));
            let traced = scene_with_media(vec![floor.clone(), light.clone(), null.clone()], fog(sigma_t));
            assert_eq!(
                (blocking.infinity_unreachable_from(Some(0)), traced.infinity_unreachable_from(Some(0))),
                (sigma_t.min_component() > 0.0, false)
            );
            let p = Vec3::new(0.3, 1.0, 0.2);
            for d in [
                Vec3::Y,
                -Vec3::Y,
                Vec3::new(1.0, -0.5, 0.3).normalize(),
                Vec3::new(-0.2, 0.7, 0.1).normalize(),
            ] {
                let skipped = transmittance_to(&blocking, p, None, d, f32::INFINITY, Some(0));
                let full = transmittance_to(&traced, p, None, d, f32::INFINITY, Some(0));
                assert_eq!(skipped, full, "sigma_t {sigma_t:?} towards {d}");
                let escapes = d.y > 0.0;
                let want = if escapes { sigma_t.map(|s| if s > 0.0 { 0.0 } else { 1.0 }) } else { Rgb::ZERO };
                assert_eq!(full, want, "sigma_t {sigma_t:?} towards {d}");
            }
        }
    }

    /// volpath skips next-event estimation in a medium only when every emitter is at infinity
    /// and infinity cannot be reached from the medium.
    #[test]
    fn a_medium_is_unlit_only_when_every_emitter_is_at_infinity() {
        let shapes = vec![quad("floor", -5.0, 5.0, 0.0, true), quad("light", 1.5, 3.0, 0.05, false)];
        let sky = Emitter::Constant { radiance: Rgb::ONE };
        let area = Emitter::Area { shape: 1, radiance: Rgb::ONE.into() };
        let unlit = |sigma_t: Rgb, emitters: Vec<Emitter>, medium: Option<u32>| {
            scene_with(shapes.clone(), fog(sigma_t), emitters).medium_unlit(medium)
        };
        assert!(unlit(Rgb::splat(0.3), vec![sky.clone()], Some(0)));
        assert!(!unlit(Rgb::splat(0.3), vec![sky.clone(), area], Some(0)), "an area light in the scene");
        assert!(!unlit(Rgb::new(0.3, 0.0, 0.3), vec![sky.clone()], Some(0)), "a channel with sigma_t = 0");
        assert!(!unlit(Rgb::splat(0.3), vec![sky.clone()], None), "vacuum");
        let mut null = quad("null", 100.0, 101.0, 50.0, true);
        null.bsdf = Bsdf::Null;
        let mut with_null = shapes.clone();
        with_null.push(null);
        assert!(
            !scene_with(with_null, fog(Rgb::splat(0.3)), vec![sky]).medium_unlit(Some(0)),
            "a null surface"
        );
    }

    /// A closed cube `[-1, 1]^3` (24 vertices, unshared between faces: welded by position),
    /// diffuse, with medium 0 inside.
    fn box_with_fog_inside() -> Shape {
        Shape {
            name: "box".into(),
            geometry: Geometry::Mesh(haze_scene::shape::cube_mesh(&Mat4::IDENTITY, false)),
            bsdf: Bsdf::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) },
            interior: Some(0),
            exterior: None,
            emitter: None,
        }
    }

    /// The geometric claim behind `Scene::towards_sealed_inside`, checked against the tracer: from
    /// points on a sealed box, every shadow ray aimed into the box at a point outside it is
    /// blocked when traced, and the skip is claimed for exactly the rays that point inwards.
    #[test]
    fn shadow_rays_into_a_sealed_shape_are_all_blocked() {
        let light = Emitter::Point { position: Vec3::new(0.3, 4.0, -0.2), intensity: Rgb::ONE };
        let sc = scene_with(vec![box_with_fog_inside()], fog(Rgb::splat(0.2)), vec![light]);
        let Geometry::Mesh(m) = &sc.shapes[0].geometry else { unreachable!() };
        let mut s = haze_core::Sampler::from_seed(17);
        let (mut inward, mut outward) = (0, 0);
        for _ in 0..4000 {
            let i = (s.next_1d() * m.indices.len() as f32) as usize % m.indices.len();
            let [a, b, c] = m.vertices(i);
            let (u, v) = (s.next_1d(), s.next_1d());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let p = a + (b - a) * u + (c - a) * v;
            let n = m.face_normal(i);
            // A target outside the box, in any direction: largest coordinate 1.2 to 4.2.
            let dir = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let target = dir / dir.abs().max_element() * (1.2 + 3.0 * s.next_1d());
            let v = target - p;
            let (d, dist) = (v.normalize(), v.length());
            let skip = sc.towards_sealed_inside(0, n, d);
            assert_eq!(skip, n.dot(d) < 0.0, "from {p} (n {n}) towards {target}");
            let medium = sc.shapes[0].medium_towards(d, n, None);
            let tr = transmittance_to(&sc, p, Some(n), d, dist, medium);
            if skip {
                assert_eq!(tr, Rgb::ZERO, "an inward ray from {p} (n {n}) reached {target}");
                inward += 1;
            } else {
                outward += usize::from(tr != Rgb::ZERO);
            }
        }
        assert!(inward > 1000 && outward > 1000, "{inward} inward, {outward} unblocked outward");
    }

    /// A shape is sealed only when it is closed, stops shadow rays and every emitter is a point
    /// or spot light outside it or at infinity; a medium only when it is inside sealed shapes
    /// alone and the camera is not in it. volpath then skips next-event estimation in it.
    #[test]
    fn sealed_shapes_and_media_only_where_no_emitter_is_reachable() {
        let outside = Emitter::Point { position: Vec3::new(0.3, 4.0, -0.2), intensity: Rgb::ONE };
        let inside = Emitter::Point { position: Vec3::new(0.3, 0.4, -0.2), intensity: Rgb::ONE };
        let sky = Emitter::Constant { radiance: Rgb::ONE };
        let (n, d) = (-Vec3::Y, Vec3::Y);
        let check = |shapes: Vec<Shape>, emitters: Vec<Emitter>| {
            let sc = scene_with(shapes, fog(Rgb::splat(0.2)), emitters);
            (sc.towards_sealed_inside(0, n, d), sc.medium_unlit(Some(0)))
        };
        assert_eq!(check(vec![box_with_fog_inside()], vec![outside.clone()]), (true, true));
        assert_eq!(check(vec![box_with_fog_inside()], vec![outside.clone(), sky.clone()]), (true, true));
        assert_eq!(check(vec![box_with_fog_inside()], vec![outside.clone(), inside]), (false, false));
        // An area light anywhere (here a quad far outside).
        let lamp = quad("lamp", 10.0, 11.0, 10.0, false);
        let area = Emitter::Area { shape: 1, radiance: Rgb::ONE.into() };
        assert_eq!(check(vec![box_with_fog_inside(), lamp], vec![outside.clone(), area]), (false, false));
        // A surface that lets shadow rays through, and an open box.
        let mut null = box_with_fog_inside();
        null.bsdf = Bsdf::Null;
        assert_eq!(check(vec![null], vec![outside.clone()]), (false, false));
        let mut open = box_with_fog_inside();
        let Geometry::Mesh(m) = &mut open.geometry else { unreachable!() };
        m.indices.pop();
        assert_eq!(check(vec![open], vec![outside.clone()]), (false, false));
        // The medium also outside another shape, or around the camera: the box stays sealed,
        // the medium does not.
        let mut shell = quad("shell", 20.0, 21.0, 0.0, true);
        shell.exterior = Some(0);
        assert_eq!(check(vec![box_with_fog_inside(), shell], vec![outside.clone()]), (true, false));
        let sc = Scene::new(
            None,
            Camera { medium: Some(0), ..camera() },
            1,
            IntegratorSpec::default(),
            vec![box_with_fog_inside()],
            fog(Rgb::splat(0.2)),
            vec![outside],
        );
        assert!(!sc.medium_unlit(Some(0)), "the camera in the medium");
    }
}

//! The scene the integrators render: camera, shapes, media, emitters, integrator settings, and
//! ray queries through the acceleration structure.

use crate::accel::{Accel, CameraGrid, Leaving, PreliminaryHit, ShadowHit, ShadowQuery, MAX_SHADOW_HITS};
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::emitter_tables::{BoundingSphere, EmitterTables};
use crate::interaction::SurfaceInteraction;
use crate::medium::{Medium, MediumId};
use crate::shape::convex::{self, ClearSides};
use crate::shape::{closed, Geometry, Shape};
use glam::Vec3;
use haze_core::{Frame, Ray};
use std::path::PathBuf;
use std::sync::OnceLock;

/// The `<integrator>` element: its plugin name and the parameters every integrator shares.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorSpec {
    /// Plugin name, e.g. `volpath`.
    pub name: String,
    /// Longest path, counted in scattering events as Mitsuba 3 does; `-1` means unlimited.
    /// Mitsuba's default is `-1`.
    pub max_depth: i32,
    /// Depth from which Russian roulette starts. Mitsuba's default is 5.
    pub rr_depth: u32,
    /// Do not show emitters seen directly by the camera.
    pub hide_emitters: bool,
    /// Where the scene declares its `<integrator>` (`file:line`); `None` when it has none.
    pub declared_at: Option<String>,
    /// Set when haze has no integrator of the scene's type (`direct`, `ptracer`, `aov`, ...):
    /// the error, naming file and line, that rendering the scene with its own integrator gives.
    /// A render that names its integrator (`--integrator`) replaces it and never reads this.
    pub unsupported: Option<String>,
}

/// Hard cap on the scattering events of one path, whatever `max_depth` says. With
/// `max_depth -1` and Russian roulette off (`rr_depth` at least this), a path in a closed room
/// of white walls or albedo-1 fog would never end; it ends here instead, and
/// [`IntegratorSpec::path_cap_warning`] says so before rendering. Paths this long carry
/// vanishingly little energy in any scene that absorbs at all.
pub const MAX_PATH_DEPTH: u32 = 1 << 16;

/// Longest path in scattering events for a `max_depth` setting: unlimited (`-1`) means
/// [`MAX_PATH_DEPTH`], and nothing is longer than that.
pub fn depth_limit(max_depth: i32) -> u32 {
    u32::try_from(max_depth).map_or(MAX_PATH_DEPTH, |d| d.min(MAX_PATH_DEPTH))
}

impl IntegratorSpec {
    /// A warning when the settings let a path run to [`MAX_PATH_DEPTH`] without Russian
    /// roulette: the cap, not the scene, then ends the path.
    pub fn path_cap_warning(&self) -> Option<String> {
        let unbounded = self.max_depth < 0 || self.max_depth as u32 > MAX_PATH_DEPTH;
        (unbounded && self.rr_depth >= MAX_PATH_DEPTH).then(|| {
            format!(
                "max_depth {} with rr_depth {} (no Russian roulette): paths are cut at haze's \
                 hard cap of {MAX_PATH_DEPTH} scattering events",
                self.max_depth, self.rr_depth
            )
        })
    }
}

impl Default for IntegratorSpec {
    fn default() -> Self {
        IntegratorSpec {
            name: "volpath".into(),
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            declared_at: None,
            unsupported: None,
        }
    }
}

pub struct Scene {
    /// The file the scene came from, if any (for messages).
    pub path: Option<PathBuf>,
    pub camera: Camera,
    /// Samples per pixel from the sampler's `sample_count` (Mitsuba default 4).
    pub spp: u32,
    /// The sensor's `<sampler>` (`independent` unless the loader sets another; a render rounds
    /// its spp for the generator, `SamplerSpec::with_sample_count`).
    pub sampler: haze_core::SamplerSpec,
    pub integrator: IntegratorSpec,
    pub shapes: Vec<Shape>,
    pub media: Vec<Medium>,
    pub emitters: Vec<Emitter>,
    pub(crate) emitter_tables: EmitterTables,
    pub(crate) accel: Accel,
    /// The film grid of leaf lists that answers camera rays ([`Self::intersect_camera`]), built
    /// before a render's first pass ([`Self::prepare_camera_grid`]) or else on the first camera
    /// ray. It answers any ray from its pinhole correctly, so a camera
    /// changed after it was built makes it useless to other rays, never wrong.
    camera_grid: OnceLock<Option<CameraGrid>>,
    /// Every shape stops shadow rays ([`Shape::blocks_shadow_rays`]: no `null` or thin
    /// dielectric surface).
    every_surface_blocks: bool,
    /// Every emitter is at infinity (environment maps and constant environments).
    every_emitter_at_infinity: bool,
    /// Every emitter is a delta light ([`Emitter::is_delta`]; true without emitters).
    every_emitter_delta: bool,
    /// Per shape: the sign that turns its hits' geometric normals outwards when the shape is
    /// sealed ([`sealed_shapes`]), 0 when it is not.
    sealed: Vec<f32>,
    /// Per medium: it is sealed ([`sealed_media`]).
    sealed_media: Vec<bool>,
    /// Per shape: the sides of its faces from which it cannot be hit again
    /// ([`convex::clear_sides`]; none for analytic shapes, which the BVH does not hold).
    clear: Vec<ClearSides>,
    /// Per shape, per primitive: the face touches a medium boundary (`shape::coincident`), so
    /// its hits are settled by `Scene::resolve_hit` (`boundary.rs`, `docs/theory.md` §14); an
    /// empty list when no face of the shape does.
    pub(crate) touching: Vec<Vec<bool>>,
    /// Some shape declares media.
    pub(crate) any_transition: bool,
}

/// [`Scene::sealed`]: a shape is sealed when it is a closed surface
/// ([`crate::shape::closed::outward_sign`]) that stops shadow rays and holds no emitter: every
/// emitter is a point or spot light certainly outside it ([`crate::shape::closed::contains`]),
/// or at infinity. Any area emitter makes no shape sealed (whether an emitting surface lies
/// inside another is not decided). Only shapes where the answer is used are examined: those
/// whose BSDF next-event estimation samples (not specular: [`Scene::towards_sealed_inside`])
/// and those with an interior medium ([`sealed_media`]).
fn sealed_shapes(shapes: &[Shape], emitters: &[Emitter]) -> Vec<f32> {
    let mut points = Vec::new();
    for e in emitters {
        match e {
            Emitter::Point { position, .. } => points.push(*position),
            Emitter::Spot { to_world, .. } => points.push(to_world.transform_point3(Vec3::ZERO)),
            Emitter::Projector(p) => points.push(p.position()),
            Emitter::Constant { .. } | Emitter::EnvMap(_) | Emitter::Directional { .. } => {}
            Emitter::Area { .. } => return vec![0.0; shapes.len()],
        }
    }
    shapes
        .iter()
        .map(|s| {
            if !s.blocks_shadow_rays() || s.bsdf.is_specular() && s.interior.is_none() {
                return 0.0;
            }
            closed::outward_sign_if_outside(&s.geometry, &points).unwrap_or(0.0)
        })
        .collect()
}

/// [`Scene::sealed_media`]: a medium is sealed when the camera is not in it and it is the
/// interior, and nowhere an exterior, of at least one shape, all of them sealed. A path in it
/// entered it through one of those shapes towards its inside (media change only at shapes that
/// declare them) and is inside that shape until it crosses it again, so every shadow ray from
/// it must cross a sealed surface: next-event estimation from it is zero.
fn sealed_media(shapes: &[Shape], sealed: &[f32], media: usize, camera: Option<MediumId>) -> Vec<bool> {
    (0..media as MediumId)
        .map(|m| {
            let mut bounds =
                shapes.iter().zip(sealed).filter(|(s, _)| s.interior == Some(m) || s.exterior == Some(m));
            camera != Some(m)
                && shapes.iter().any(|s| s.interior == Some(m))
                && bounds.all(|(s, &sign)| s.interior == Some(m) && s.exterior != Some(m) && sign != 0.0)
        })
        .collect()
}

impl Scene {
    /// Assembles a scene and builds its acceleration structure.
    pub fn new(
        path: Option<PathBuf>,
        camera: Camera,
        spp: u32,
        integrator: IntegratorSpec,
        shapes: Vec<Shape>,
        media: Vec<Medium>,
        emitters: Vec<Emitter>,
    ) -> Self {
        let accel = Accel::build(&shapes);
        let (lo, hi) = accel.bounds();
        let sphere = BoundingSphere::around(lo, hi);
        let mut emitter_tables = EmitterTables::new(&emitters, &shapes, sphere);
        emitter_tables.media =
            crate::media_bounds::media_sphere(&shapes, &media, camera.medium, (lo, hi), sphere);
        let every_surface_blocks = shapes.iter().all(Shape::blocks_shadow_rays);
        let every_emitter_at_infinity = emitters.iter().all(Emitter::is_infinite);
        let every_emitter_delta = emitters.iter().all(Emitter::is_delta);
        let sealed = sealed_shapes(&shapes, &emitters);
        let sealed_media = sealed_media(&shapes, &sealed, media.len(), camera.medium);
        let clear = shapes
            .iter()
            .map(|s| match &s.geometry {
                Geometry::Mesh(m) => convex::clear_sides(m),
                _ => ClearSides::default(),
            })
            .collect();
        let touching = crate::shape::coincident::touching_faces(&shapes);
        let any_transition = shapes.iter().any(Shape::is_medium_transition);
        Scene {
            emitter_tables,
            path,
            camera,
            spp,
            sampler: haze_core::SamplerSpec::independent(spp),
            integrator,
            shapes,
            media,
            emitters,
            accel,
            camera_grid: OnceLock::new(),
            every_surface_blocks,
            every_emitter_at_infinity,
            every_emitter_delta,
            sealed,
            sealed_media,
            clear,
            touching,
            any_transition,
        }
    }

    /// What a ray leaving shape `shape` at a hit with geometric normal `n` in direction `d` (its
    /// origin offset to that side, `haze_core::ray::offset_origin`) cannot hit: the shape itself
    /// when it is clear on that side ([`convex::clear_sides`]: a convex mesh left outwards, a
    /// flat one left either way) and `d` is at least [`convex::MIN_COSINE`] off the face's
    /// plane, else nothing. For [`Self::intersect_preliminary_leaving`] and
    /// [`Self::shadow_hits_leaving`].
    #[inline]
    pub fn leaving(&self, shape: u32, n: Vec3, d: Vec3) -> Leaving {
        let c = self.clear[shape as usize];
        let cos = n.dot(d);
        if c.front && cos >= convex::MIN_COSINE || c.back && cos <= -convex::MIN_COSINE {
            Leaving::shape(shape)
        } else {
            Leaving::NONE
        }
    }

    /// True when a shadow ray leaving shape `shape` at a hit with geometric normal `n` in
    /// direction `d` is certainly blocked: the shape is sealed ([`sealed_shapes`]) and `d` points
    /// into it. The ray starts inside a closed surface that stops shadow rays and must leave it
    /// to reach any emitter, all of which are outside (`shape::closed`). In the roughdielectric
    /// peer, every light sample at a hit on a glass sphere towards the sphere's inside (for the
    /// refracted or internally reflected lobe) was such a ray; Mitsuba traces them.
    #[inline]
    pub fn towards_sealed_inside(&self, shape: u32, n: Vec3, d: Vec3) -> bool {
        let s = self.sealed[shape as usize];
        s != 0.0 && s * n.dot(d) < 0.0
    }

    /// True when light from infinity cannot reach any point in `medium`: every shape stops
    /// shadow rays, so a ray from the point either meets a surface and is blocked or stays in
    /// `medium` for ever, and `medium` is homogeneous and attenuates every channel (`T = 0`
    /// over an infinite distance). Shadow rays towards environment lights from such a medium
    /// are then zero without being traced (`nee.rs`); Mitsuba traces them.
    pub fn infinity_unreachable_from(&self, medium: Option<MediumId>) -> bool {
        self.every_surface_blocks
            && medium.is_some_and(|m| {
                self.medium(m).as_homogeneous().is_some_and(|h| h.sigma_t.min_component() > 0.0)
            })
    }

    /// True when next-event estimation from any point in `medium` is zero: every emitter is at
    /// infinity and infinity is unreachable from `medium` ([`Self::infinity_unreachable_from`]),
    /// or the medium is sealed ([`sealed_media`]: it is inside closed surfaces that stop shadow
    /// rays, and every emitter is outside them). volpath then skips the emitter sample (drawing
    /// its random numbers all the same), not only its shadow ray.
    pub fn medium_unlit(&self, medium: Option<MediumId>) -> bool {
        medium.is_some_and(|m| self.sealed_media[m as usize])
            || self.every_emitter_at_infinity && self.infinity_unreachable_from(medium)
    }

    /// True when a path can find emitted light only by next-event estimation (every emitter
    /// is a point or spot light): a BSDF sample's pdf, which weighs hits of emitters against
    /// next-event estimation, is then never needed ([`crate::bsdf::Bsdf::sample_with`]).
    pub fn bsdf_pdfs_unused(&self) -> bool {
        self.every_emitter_delta
    }

    /// Closest hit with `t` in `(0, ray.t_max)`, settled against the surfaces touching it
    /// ([`Self::resolve_hit`]).
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        self.accel.intersect(&self.shapes, ray).map(|h| self.resolve_hit(h))
    }

    /// The closest hit of [`Self::intersect`] with only its distance computed
    /// ([`Accel::intersect_preliminary`]); [`Self::interaction`] completes it.
    pub fn intersect_preliminary(&self, ray: &Ray) -> Option<PreliminaryHit> {
        self.accel.intersect_preliminary(ray)
    }

    /// [`Self::intersect_preliminary`] for a ray that cannot hit what `leaving` names
    /// ([`Self::leaving`]): the same answer, the BVH skipping that shape. Always inlined, as
    /// [`Accel::intersect_preliminary_leaving`] is (why there).
    #[inline(always)]
    pub fn intersect_preliminary_leaving(&self, ray: &Ray, leaving: Leaving) -> Option<PreliminaryHit> {
        self.accel.intersect_preliminary_leaving(ray, leaving)
    }

    /// [`Self::intersect_preliminary`] for a ray the camera generated (its line through the
    /// pinhole): the same answer, from the camera grid ([`CameraGrid`], built on the first
    /// call) instead of the tree. Any other ray is answered by the tree.
    pub fn intersect_camera(&self, ray: &Ray) -> Option<PreliminaryHit> {
        // Built here on one thread (inside a render's parallel loop a pool build could deadlock:
        // see `CameraGrid::build`); the render loop builds it before, on the pool.
        match self.camera_grid.get_or_init(|| CameraGrid::build(&self.accel, &self.camera, false)) {
            Some(grid) => self.accel.intersect_camera(grid, ray),
            None => self.accel.intersect_preliminary(ray),
        }
    }

    /// Builds the camera grid of [`Self::intersect_camera`] now, its rows in parallel on
    /// rayon's pool (the same grid as a build on the first camera ray) unless called from one
    /// of the pool's threads. For callers about to render: at 256x256 pixels the grid's 65,536
    /// cells took about 0.1 s on one thread, while the other threads waited.
    pub fn prepare_camera_grid(&self) {
        // On one thread when called from a pool thread (see `CameraGrid::build`).
        let parallel = rayon::current_thread_index().is_none();
        self.camera_grid.get_or_init(|| CameraGrid::build(&self.accel, &self.camera, parallel));
    }

    /// The surface interaction of a hit from [`Self::intersect_preliminary`], settled against
    /// the surfaces touching it ([`Self::resolve_hit`]).
    #[inline]
    pub fn interaction(&self, hit: &PreliminaryHit) -> SurfaceInteraction {
        self.resolve_hit(self.accel.interaction(&self.shapes, hit))
    }

    /// The local shading frame of the hit `h` (`z` = its shading normal): for a shape whose
    /// BSDF is anisotropic ([`crate::bsdf::Bsdf::is_anisotropic`]) its `x` axis follows the
    /// surface's `dp/du` as in Mitsuba 3 ([`crate::shape::tangents::tangent_frame`]); for every
    /// other BSDF, which is the same about the normal, the cheaper [`Frame::from_normal`].
    /// Integrators shade in this frame.
    #[inline]
    pub fn shading_frame(&self, h: &SurfaceInteraction) -> Frame {
        let shape = &self.shapes[h.shape as usize];
        if shape.bsdf.is_anisotropic() {
            let (dp_du, _) = crate::shape::tangents::uv_tangents(&shape.geometry, h.prim, h.p, h.n);
            crate::shape::tangents::tangent_frame(h.ns, dp_du)
        } else {
            Frame::from_normal(h.ns)
        }
    }

    /// True if anything blocks `ray` before `ray.t_max`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
    }

    /// One BVH traversal for a shadow ray: blocked, or the pass-through surfaces on it
    /// (unordered; see `Accel::shadow_hits`).
    pub fn shadow_hits(&self, ray: &Ray, hits: &mut [ShadowHit; MAX_SHADOW_HITS]) -> ShadowQuery {
        self.accel.shadow_hits(&self.shapes, ray, hits)
    }

    /// [`Self::shadow_hits`] for a ray that cannot hit what `leaving` names ([`Self::leaving`]).
    pub fn shadow_hits_leaving(
        &self,
        ray: &Ray,
        leaving: Leaving,
        hits: &mut [ShadowHit; MAX_SHADOW_HITS],
    ) -> ShadowQuery {
        self.accel.shadow_hits_leaving(&self.shapes, ray, leaving, hits)
    }

    /// The surface interaction of a hit from [`Self::shadow_hits`].
    pub fn shadow_interaction(&self, hit: &ShadowHit) -> SurfaceInteraction {
        self.accel.shadow_interaction(&self.shapes, hit)
    }

    /// The shape and geometric normal of a hit from [`Self::shadow_hits`]
    /// ([`Accel::shadow_crossing`]).
    pub fn shadow_crossing(&self, hit: &ShadowHit) -> (u32, Vec3) {
        self.accel.shadow_crossing(hit)
    }

    pub fn medium(&self, id: MediumId) -> &Medium {
        &self.media[id as usize]
    }

    /// The sphere around the scene's geometry through which light from infinity enters
    /// ([`BoundingSphere::around`] [`Self::bounds`]).
    pub fn bounding_sphere(&self) -> BoundingSphere {
        self.emitter_tables.sphere
    }

    /// The sphere around the scattering media that light paths from infinity also aim at
    /// (`docs/theory.md` §13, (T38b)), if any.
    pub fn media_sphere(&self) -> Option<BoundingSphere> {
        self.emitter_tables.media
    }

    /// Axis-aligned bounds of all finite geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.accel.bounds()
    }
}

//! Surfaces that touch (`docs/theory.md` §14): where a medium boundary lies flush against
//! another surface (a fog box on a floor, water in its glass, two media sharing a face), a ray
//! meets both at the same distance and a closest-hit query returns either, arbitrarily; the ray
//! offset after the interaction (`haze_core::ray::offset_origin`) then steps over the other one
//! unseen. The scene settles such hits here, once for every walk (volpath, the many-light camera
//! walk, light tracing, caustic paths, shadow rays), by two rules:
//!
//! 1. *The surface that is not `null` wins the tie*: a null boundary only says where a medium
//!    ends; the floor under the fog is still a floor ([`Scene::resolve_hit`]).
//! 2. *The medium beyond is decided by every touching boundary together* ([`Boundary`]): a ray
//!    leaving in direction `d` enters the interior of a boundary it enters (`d . n <= 0`) or
//!    the exterior of one it leaves, never a medium it is leaving.
//!
//! Only shapes marked at load time (`crate::shape::coincident`) look for touching surfaces, so
//! other scenes take the single-surface path (the shape's own media, Mitsuba 3's rule).

use crate::accel::{ProbeHit, MAX_PROBE_HITS};
use crate::interaction::SurfaceInteraction;
use crate::medium::MediumId;
use crate::shape::Shape;
use crate::Scene;
use glam::Vec3;
use haze_core::ray::offset_origin;
use haze_core::{Ray, RAY_EPSILON};

/// Most medium boundaries one [`Boundary`] holds (more that touch at one point are ignored).
pub const MAX_BOUNDARY_SIDES: usize = 4;

/// One medium boundary among the surfaces that touch at a point: its geometric normal and media.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Side {
    n: Vec3,
    interior: Option<MediumId>,
    exterior: Option<MediumId>,
}

/// The medium boundaries at a surface point: one shape's, or those of every surface that
/// touches there. Without any, a ray keeps its medium (the shape declares none).
#[derive(Clone, Copy, Debug, Default)]
pub struct Boundary {
    sides: [Side; MAX_BOUNDARY_SIDES],
    len: u8,
}

impl Boundary {
    /// The boundary of `shape` alone, at a point with geometric normal `n`.
    #[inline]
    pub fn of(shape: &Shape, n: Vec3) -> Self {
        let mut b = Boundary::default();
        b.push(shape, n);
        b
    }

    /// This boundary and `shape`'s at the same point (geometric normal `n` there).
    #[inline]
    pub fn with(mut self, shape: &Shape, n: Vec3) -> Self {
        self.push(shape, n);
        self
    }

    /// Adds `shape` (geometric normal `n` at the point) if it declares media and is not in yet.
    fn push(&mut self, shape: &Shape, n: Vec3) {
        if !shape.is_medium_transition() || self.len as usize == MAX_BOUNDARY_SIDES {
            return;
        }
        let side = Side { n, interior: shape.interior, exterior: shape.exterior };
        let len = self.len as usize;
        // The same shape seen twice (two triangles at an edge, or the probe and the hit).
        if self.sides[..len]
            .iter()
            .any(|s| s.interior == side.interior && s.exterior == side.exterior && s.n.dot(n) > 0.0)
        {
            return;
        }
        self.sides[len] = side;
        self.len += 1;
    }

    /// True when crossing here can change the medium.
    #[inline]
    pub fn is_transition(&self) -> bool {
        self.len > 0
    }

    /// The medium a ray leaving the point in direction `d` is in, `current` if no boundary
    /// touches here. With one boundary: its exterior when `d . n > 0`, else its interior
    /// (Mitsuba 3's `SurfaceInteraction::target_medium`, [`Shape::medium_towards`]). With
    /// several (`docs/theory.md` §14): the first declared interior of a boundary the ray
    /// enters, else the first exterior of a boundary it leaves, skipping any medium that some
    /// boundary says the ray is leaving (the exterior of one it enters, the interior of one it
    /// leaves); the single-boundary answer of the first one if every candidate is skipped.
    #[inline]
    pub fn medium_towards(&self, d: Vec3, current: Option<MediumId>) -> Option<MediumId> {
        match self.len {
            0 => current,
            1 => {
                let s = &self.sides[0];
                if d.dot(s.n) > 0.0 {
                    s.exterior
                } else {
                    s.interior
                }
            }
            _ => self.medium_towards_several(d, current),
        }
    }

    /// [`Self::medium_towards`] with two boundaries or more.
    #[cold]
    fn medium_towards_several(&self, d: Vec3, current: Option<MediumId>) -> Option<MediumId> {
        let sides = &self.sides[..self.len as usize];
        let enters = |s: &Side| d.dot(s.n) <= 0.0;
        let left_behind = |m: Option<MediumId>| {
            sides.iter().any(|s| if enters(s) { s.exterior == m } else { s.interior == m })
        };
        if let Some(s) = sides.iter().find(|s| enters(s) && s.interior.is_some() && !left_behind(s.interior))
        {
            return s.interior;
        }
        if let Some(s) = sides.iter().find(|s| !enters(s) && !left_behind(s.exterior)) {
            return s.exterior;
        }
        Boundary { len: 1, ..*self }.medium_towards(d, current)
    }
}

/// Half the length of the probe through a surface point `p` along its normal that finds the
/// surfaces touching there: twice the ray offset at `p` (`haze_core::ray::offset_origin`), so
/// every surface the offset could step over is found.
#[inline]
fn probe_reach(p: Vec3) -> f32 {
    2.0 * RAY_EPSILON * (1.0 + p.abs().max_element())
}

impl Scene {
    /// True when shape `shape` has a face touching a medium boundary
    /// (`crate::shape::coincident`).
    #[inline]
    pub fn touches(&self, shape: u32) -> bool {
        // `touching` is empty when nothing in the scene touches: one length test.
        self.touching.get(shape as usize).is_some_and(|faces| !faces.is_empty())
    }

    /// True when the face `prim` of shape `shape` touches a medium boundary, so that its hits
    /// are settled by [`Self::resolve_hit`] and [`Self::medium_towards`].
    #[inline]
    pub fn touches_at(&self, shape: u32, prim: u32) -> bool {
        self.touching
            .get(shape as usize)
            .is_some_and(|faces| faces.get(prim as usize).copied().unwrap_or(false))
    }

    /// True when the face a shadow ray crosses at `h` ([`Self::shadow_hits`]) touches a medium
    /// boundary ([`Self::touches_at`]).
    #[inline]
    pub fn shadow_touches(&self, shape: u32, h: &crate::accel::ShadowHit) -> bool {
        self.touches(shape) && self.touches_at(shape, self.accel.shadow_prim(h))
    }

    /// False when leaving shape `shape` cannot enter another medium than the path arrived in,
    /// even where it touches a boundary: it declares no media and only reflects
    /// ([`crate::Bsdf::transmits`]), so every direction leaves on the side the path came from,
    /// whose medium rule 1 kept right (the floor under the fog reflects into the fog). Those
    /// shapes skip the probe: a floor under fog boxes is much of the image.
    #[inline]
    fn medium_may_change(&self, shape: u32) -> bool {
        let s = &self.shapes[shape as usize];
        s.is_medium_transition() || s.bsdf.transmits()
    }

    /// The surfaces crossed by the segment `p ± probe_reach(p) a` (`a` a unit vector).
    fn probe_at(&self, p: Vec3, a: Vec3, out: &mut [ProbeHit; MAX_PROBE_HITS]) -> usize {
        let reach = probe_reach(p);
        self.accel.probe(&Ray { o: p - a * reach, d: a, t_max: 2.0 * reach }, out)
    }

    /// The medium boundaries at the point `p` of shape `shape` (geometric normal `n`): the
    /// shape's own, and where it touches other surfaces, theirs too.
    pub fn boundary_at(&self, shape: u32, p: Vec3, n: Vec3) -> Boundary {
        let mut b = Boundary::of(&self.shapes[shape as usize], n);
        if self.touches(shape) {
            self.add_touching(&mut b, p, n);
        }
        b
    }

    /// Adds to `b` the boundaries of the surfaces the probe along `n` through `p` crosses.
    #[cold]
    fn add_touching(&self, b: &mut Boundary, p: Vec3, n: Vec3) {
        let mut hits = [ProbeHit::EMPTY; MAX_PROBE_HITS];
        let count = self.probe_at(p, n, &mut hits);
        for h in &hits[..count] {
            b.push(&self.shapes[h.shape as usize], h.n);
        }
    }

    /// The hit `h` of a closest-hit query, settled against the surfaces touching it: if `h` is
    /// on a `null` surface and a surface that is not `null` touches it there, that surface's
    /// interaction (at `h`'s distance) instead (`docs/theory.md` §14, rule 1). Every
    /// closest-hit answer of the scene goes through here ([`Self::intersect`],
    /// [`Self::interaction`]). A normal- or bump-mapped surface's hit gets its perturbed shading
    /// normal here too.
    #[inline]
    pub fn resolve_hit(&self, h: SurfaceInteraction) -> SurfaceInteraction {
        let h = if !self.touches_at(h.shape, h.prim) || !self.shapes[h.shape as usize].bsdf.is_null() {
            h
        } else {
            self.resolve_touching(h)
        };
        match &self.shapes[h.shape as usize].bsdf {
            crate::bsdf::Bsdf::Perturbed(p) => self.perturb(h, p),
            _ => h,
        }
    }

    /// `h` with the shading normal of the normal or bump map `p` (see [`crate::bsdf::Perturbed`]).
    #[cold]
    fn perturb(&self, h: SurfaceInteraction, p: &crate::bsdf::Perturbed) -> SurfaceInteraction {
        let geometry = &self.shapes[h.shape as usize].geometry;
        let (dp_du, dp_dv) = crate::shape::tangents::uv_tangents(geometry, h.prim, h.p, h.n);
        SurfaceInteraction { ns: p.shading_normal(h.tex(), h.n, h.ns, dp_du, dp_dv), ..h }
    }

    #[cold]
    fn resolve_touching(&self, h: SurfaceInteraction) -> SurfaceInteraction {
        let mut hits = [ProbeHit::EMPTY; MAX_PROBE_HITS];
        let count = self.probe_at(h.p, h.n, &mut hits);
        // The solid surface nearest to the hit's plane.
        let reach = probe_reach(h.p);
        let solid = hits[..count]
            .iter()
            .filter(|ph| !self.shapes[ph.shape as usize].bsdf.is_null())
            .min_by(|a, b| (a.t - reach).abs().total_cmp(&(b.t - reach).abs()));
        match solid {
            Some(ph) => SurfaceInteraction { t: h.t, ..self.accel.interaction(&self.shapes, &ph.hit) },
            None => h,
        }
    }

    /// The medium a ray leaving the surface interaction `h` in direction `d` is in, having
    /// arrived in `current`: [`Boundary::medium_towards`] of the boundaries at `h`.
    #[inline]
    pub fn medium_towards(
        &self,
        h: &SurfaceInteraction,
        d: Vec3,
        current: Option<MediumId>,
    ) -> Option<MediumId> {
        if self.touches_at(h.shape, h.prim) && self.medium_may_change(h.shape) {
            self.medium_towards_touching(h, d, current)
        } else {
            self.shapes[h.shape as usize].medium_towards(d, h.n, current)
        }
    }

    #[cold]
    fn medium_towards_touching(
        &self,
        h: &SurfaceInteraction,
        d: Vec3,
        current: Option<MediumId>,
    ) -> Option<MediumId> {
        let mut b = Boundary::of(&self.shapes[h.shape as usize], h.n);
        self.add_touching(&mut b, h.p, h.n);
        b.medium_towards(d, current)
    }

    /// [`Self::medium_towards`] from the point `p` of shape `shape` with geometric normal `n`
    /// (a surface light's vertex, an emitter's sample), the face unknown: any face of a shape
    /// that touches somewhere probes.
    #[inline]
    pub fn medium_leaving(
        &self,
        shape: u32,
        p: Vec3,
        n: Vec3,
        d: Vec3,
        current: Option<MediumId>,
    ) -> Option<MediumId> {
        if self.touches(shape) && self.medium_may_change(shape) {
            self.boundary_at(shape, p, n).medium_towards(d, current)
        } else {
            self.shapes[shape as usize].medium_towards(d, n, current)
        }
    }

    /// A walk's step through the surface interaction `h` where its BSDF is `null` (a boundary
    /// that only changes the medium, not a scattering event): `ray` goes on in the same
    /// direction from just past the hit point, in the medium beyond ([`Self::medium_towards`]).
    /// Returns false, changing nothing, for any other BSDF. The one step of volpath, the
    /// many-light camera walk, light tracing and the caustic paths.
    #[inline]
    pub fn cross_if_null(
        &self,
        h: &SurfaceInteraction,
        ray: &mut Ray,
        medium: &mut Option<MediumId>,
    ) -> bool {
        if !self.shapes[h.shape as usize].bsdf.is_null() {
            return false;
        }
        *medium = self.medium_towards(h, ray.d, *medium);
        *ray = Ray::new(offset_origin(h.p, h.n, ray.d), ray.d);
        true
    }

    /// The medium boundaries through the camera's pinhole, for a render loop to find once and
    /// ask per camera ray: `camera_boundary().medium_towards(ray.d, declared)` is the medium of
    /// a camera ray whose camera declares `declared` (`docs/theory.md` §14: a camera on the
    /// boundary of a fog box sees the fog in the directions into the box, whichever side its
    /// declared medium is). None, so the declared medium, without media transitions or unless
    /// the camera is a pinhole: rays of a thin lens or an orthographic camera start apart.
    pub fn camera_boundary(&self) -> Boundary {
        if !self.any_transition || !self.camera.is_pinhole() {
            return Boundary::default();
        }
        // A few probes: cheap once per round, and no cache to key by the camera's position.
        self.boundary_through(self.camera.to_world.transform_point3(Vec3::ZERO))
    }

    /// The medium boundaries passing within the ray offset of the point `p`, found by probes
    /// along three axes and a diagonal.
    fn boundary_through(&self, p: Vec3) -> Boundary {
        let mut b = Boundary::default();
        let diagonal = Vec3::ONE.normalize();
        for a in [Vec3::X, Vec3::Y, Vec3::Z, diagonal] {
            let mut hits = [ProbeHit::EMPTY; MAX_PROBE_HITS];
            let count = self.probe_at(p, a, &mut hits);
            for h in &hits[..count] {
                b.push(&self.shapes[h.shape as usize], h.n);
            }
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::shape::Geometry;

    fn boundary(interior: Option<MediumId>, exterior: Option<MediumId>) -> Shape {
        Shape {
            name: "b".into(),
            geometry: Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false },
            bsdf: Bsdf::Null,
            interior,
            exterior,
            emitter: None,
        }
    }

    fn two(a: (&Shape, Vec3), b: (&Shape, Vec3)) -> Boundary {
        let mut x = Boundary::of(a.0, a.1);
        x.push(b.0, b.1);
        x
    }

    #[test]
    fn one_boundary_is_mitsubas_rule() {
        let fog = boundary(Some(0), None);
        let b = Boundary::of(&fog, Vec3::Y);
        assert_eq!(b.medium_towards(Vec3::Y, Some(0)), None);
        assert_eq!(b.medium_towards(-Vec3::Y, None), Some(0));
        let plain = boundary(None, None);
        assert!(!Boundary::of(&plain, Vec3::Y).is_transition());
        assert_eq!(Boundary::of(&plain, Vec3::Y).medium_towards(Vec3::Y, Some(3)), Some(3));
    }

    /// Two boxes sharing a face (`a` below, `b` above, the face at `y = 0`): a ray up enters
    /// `b`, a ray down enters `a`, whichever face is listed first.
    #[test]
    fn two_media_sharing_a_face() {
        let (a, b) = (boundary(Some(0), None), boundary(Some(1), None));
        for x in [two((&a, Vec3::Y), (&b, -Vec3::Y)), two((&b, -Vec3::Y), (&a, Vec3::Y))] {
            assert_eq!(x.medium_towards(Vec3::Y, None), Some(1));
            assert_eq!(x.medium_towards(-Vec3::Y, None), Some(0));
        }
    }

    /// Box `b` inside box `a`, a face of each in the plane `y = 0` (normals up): up leaves both
    /// into vacuum, down enters `b`, whatever the order.
    #[test]
    fn nested_media_with_a_common_face() {
        let (a, b) = (boundary(Some(0), None), boundary(Some(1), Some(0)));
        for x in [two((&a, Vec3::Y), (&b, Vec3::Y)), two((&b, Vec3::Y), (&a, Vec3::Y))] {
            assert_eq!(x.medium_towards(Vec3::Y, Some(1)), None);
            assert_eq!(x.medium_towards(-Vec3::Y, None), Some(1));
        }
    }
}

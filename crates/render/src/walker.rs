//! The path walker: how every walk of haze moves from vertex to vertex. `volpath`
//! ([`crate::integrators::VolPath`]), the many-light camera walk (`haze-manylight`'s
//! `gather.rs`), light tracing (`lighttrace.rs`) and the caustic paths (`splat.rs`) each keep
//! what they do *at* a vertex (next-event estimation, depositing virtual lights, gathering,
//! splatting); between vertices they all go through a [`Walker`]:
//!
//! - **one leg** from the ray's origin to its surface, either with a free flight that may end in
//!   the medium first ([`Walker::sample_leg`]: pbrt-v4's `SampleT_maj` role, through
//!   [`haze_scene::Medium::begin_flight`]/[`end_flight`](haze_scene::Medium::end_flight): closed
//!   form in a homogeneous medium, delta tracking in a grid) or through the medium to the surface
//!   ([`Walker::trace_leg`], whose throughput a walk multiplies by
//!   [`Walker::transmittance`]: closed form or ratio tracking);
//! - **null crossings** ([`Walker::cross_if_null`]: a `null` surface changes the medium, not the
//!   direction, and is no scattering event), **bounces** off a surface
//!   ([`Walker::bounce`]) and **medium scattering** ([`Walker::scatter`]);
//! - **Russian roulette**, [`Walker::roulette`] (the rule of `haze_core::walk`: survival
//!   `q = min(m, 0.95)`, each walk choosing its own relative throughput `m` and roulette depth);
//! - **the cap** [`MAX_WALK_VERTICES`] on the vertices one walk visits ([`Walker::next_vertex`]).
//!
//! Queries: the first leg of a camera ray is answered from the scene's camera grid
//! (`Scene::intersect_camera`, the tree's answer); a leg that leaves a shape the ray cannot hit
//! again (`Scene::leaving`: a convex mesh left outwards, a flat one either way) skips that
//! shape's subtrees. Both give the tree's answer, so the walk is the same as with plain queries;
//! only fewer nodes are visited. The surface interaction is built only when the walk reaches the
//! surface (`Scene::interaction`).

use haze_core::ray::offset_origin;
use haze_core::{Ray, Rgb, Sampler};
use haze_scene::accel::{Leaving, PreliminaryHit};
use haze_scene::SurfaceInteraction;
use haze_scene::{Flight, MediumId, Scene};

/// Most vertices (surface hits, null crossings, medium collisions) of one walk. Null crossings
/// and, before the roulette depth, delta surfaces are not roulette events, so a ray caught
/// between coincident null surfaces by rounding could otherwise loop for ever. No physical path
/// comes near it: past its roulette depth a walk survives an event with probability at most
/// 0.95 (about 20 more events on average; `0.95^100000` is zero in f32), and a light path of
/// unlimited depth (`max_depth -1`) carries all its events in one walk, hence the margin. So
/// the cap changes no image; it only bounds a walk's time.
pub const MAX_WALK_VERTICES: u32 = 100_000;

/// Where a walk is between two vertices: its ray, the medium the ray travels in, and what the
/// next scene query may use (module docs).
#[derive(Clone, Copy, Debug)]
pub struct Walker {
    pub ray: Ray,
    pub medium: Option<MediumId>,
    /// The shape the ray cannot hit again, having left it (`Scene::leaving`).
    leaving: Leaving,
    /// The next query is the camera ray's, answered from the scene's camera grid.
    camera_ray: bool,
    /// Vertices visited so far, against [`MAX_WALK_VERTICES`].
    vertices: u32,
}

/// One leg of a walk: the surface the ray hits, if any, and its distance.
#[derive(Clone, Copy, Debug)]
pub struct Leg {
    pub hit: Option<PreliminaryHit>,
    /// The hit's distance, or the ray's `t_max` if it hits nothing.
    pub t_surface: f32,
}

impl Walker {
    /// A walk along `ray` in `medium`.
    pub fn new(ray: Ray, medium: Option<MediumId>) -> Walker {
        Walker { ray, medium, leaving: Leaving::NONE, camera_ray: false, vertices: 0 }
    }

    /// A walk along the camera ray `ray` (through the pinhole) in `medium`: its first query is
    /// answered from the scene's camera grid.
    pub fn camera(ray: Ray, medium: Option<MediumId>) -> Walker {
        Walker { camera_ray: true, ..Walker::new(ray, medium) }
    }

    /// Counts one more vertex; false once the walk has visited [`MAX_WALK_VERTICES`] (it must
    /// end).
    #[inline]
    pub fn next_vertex(&mut self) -> bool {
        self.vertices += 1;
        self.vertices <= MAX_WALK_VERTICES
    }

    /// The closest surface along `query` (the walk's ray, possibly shortened).
    #[inline]
    fn query(&mut self, scene: &Scene, query: &Ray) -> Option<PreliminaryHit> {
        if std::mem::take(&mut self.camera_ray) {
            scene.intersect_camera(query)
        } else {
            scene.intersect_preliminary_leaving(query, self.leaving)
        }
    }

    /// A leg through the medium without collisions: the closest surface along the ray. A walk
    /// that crosses the medium this way (the camera walk, the caustic paths: they estimate
    /// along the whole interval) multiplies its throughput by [`Self::transmittance`].
    #[inline]
    pub fn trace_leg(&mut self, scene: &Scene) -> Leg {
        let ray = self.ray;
        let hit = self.query(scene, &ray);
        Leg { hit, t_surface: hit.map_or(ray.t_max, |h| h.t()) }
    }

    /// A leg with a free flight in the walk's medium (hero channel `hero`): `Some(flight)` in a
    /// medium, `Flight::Scatter` if the flight ends before the surface, `Flight::Pass` with the
    /// weights of passing it otherwise; `None` outside media. In a homogeneous medium the
    /// distance is drawn first, and the query stops there: the surface matters only if it lies
    /// nearer, and the traversal prunes every box beyond. `before_query` runs between the two
    /// (volpath prefetches its coming next-event sample there, to overlap its cache misses with
    /// the traversal).
    #[inline]
    pub fn sample_leg(
        &mut self,
        scene: &Scene,
        hero: usize,
        sampler: &mut Sampler,
        before_query: impl FnOnce(&mut Sampler),
    ) -> (Leg, Option<Flight>) {
        let ray = self.ray;
        let start = self.medium.map(|m| scene.medium(m).begin_flight(hero, sampler));
        let query = match start {
            Some(s) => Ray { t_max: s.query_limit(ray.t_max), ..ray },
            None => ray,
        };
        before_query(sampler);
        let hit = self.query(scene, &query);
        let t_surface = hit.map_or(ray.t_max, |h| h.t());
        let flight = match (self.medium, start) {
            (Some(m), Some(s)) => Some(scene.medium(m).end_flight(s, ray.o, ray.d, t_surface, hero, sampler)),
            _ => None,
        };
        (Leg { hit, t_surface }, flight)
    }

    /// The transmittance of the walk's medium along the ray over `[0, len]` (one outside
    /// media): `exp(-sigma_t len)` in a homogeneous medium, a ratio-tracking estimate from
    /// `sampler` in a grid ((T30), `docs/theory.md` §12.4).
    #[inline]
    pub fn transmittance(&self, scene: &Scene, len: f32, sampler: &mut Sampler) -> Rgb {
        match self.medium {
            Some(m) => scene.medium(m).transmittance(self.ray.o, self.ray.d, 0.0, len, sampler),
            None => Rgb::ONE,
        }
    }

    /// Crosses the surface `h` if it is `null` (the same direction, the medium beyond; no
    /// scattering event): true if it did.
    #[inline]
    pub fn cross_if_null(&mut self, scene: &Scene, h: &SurfaceInteraction) -> bool {
        if !scene.cross_if_null(h, &mut self.ray, &mut self.medium) {
            return false;
        }
        self.leaving = scene.leaving(h.shape, h.n, self.ray.d);
        true
    }

    /// Leaves the surface `h` in direction `d`: the ray from `h`'s offset origin, in the medium
    /// on `d`'s side.
    #[inline]
    pub fn bounce(&mut self, scene: &Scene, h: &SurfaceInteraction, d: glam::Vec3) {
        self.medium = scene.medium_towards(h, d, self.medium);
        self.ray = Ray::new(offset_origin(h.p, h.n, d), d);
        self.leaving = scene.leaving(h.shape, h.n, d);
    }

    /// Goes on from the medium vertex `p` in direction `d` (same medium).
    #[inline]
    pub fn scatter(&mut self, p: glam::Vec3, d: glam::Vec3) {
        self.ray = Ray::new(p, d);
        self.leaving = Leaving::NONE;
    }

    /// Russian roulette with the walk's relative throughput `m` (`haze_core::walk::roulette`,
    /// one number from `sampler`): `Some(q)`, the survival probability to divide the throughput
    /// by, or `None` if the walk ends.
    #[inline]
    pub fn roulette(m: f32, sampler: &mut Sampler) -> Option<f32> {
        haze_core::walk::roulette(m, sampler.next_1d())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cap counts every vertex and ends the walk after exactly `MAX_WALK_VERTICES`.
    #[test]
    fn cap_ends_the_walk() {
        let mut w = Walker::new(Ray::new(glam::Vec3::ZERO, glam::Vec3::Z), None);
        let n = (0..MAX_WALK_VERTICES + 10).take_while(|_| w.next_vertex()).count();
        assert_eq!(n as u32, MAX_WALK_VERTICES);
    }
}

//! Where the scattering media lie: the sphere that light paths from infinity aim part of their
//! origins at (`docs/theory.md` §13, (T38b)).
//!
//! A bounded medium (a fog box, a cloud's grid) often fills a small part of the scene's
//! bounding sphere: under a sky behind a large backdrop, Mitsuba 3's `test_hetero_sigmat` sends
//! 2% of its light paths through the cube of smoke. What this module finds only makes the light
//! paths denser where it is; the mixture density of (T38b) keeps the estimate unbiased whatever
//! it returns.

use crate::emitter_tables::BoundingSphere;
use crate::medium::{Medium, MediumId};
use crate::shape::{Geometry, Shape};
use glam::Vec3;

/// Light paths from infinity aim at the media's sphere only when its radius is at most this
/// share of the scene's: the density there then grows at least `0.5 (1 / 0.5)^2 + 0.5 = 2.5`
/// times, for half the density elsewhere.
pub const MAX_RADIUS_SHARE: f32 = 0.5;

/// The sphere around every scattering medium, when each is bounded and together they are small
/// against the scene (`scene`, [`MAX_RADIUS_SHARE`]); `None` otherwise.
///
/// A medium is bounded by the shapes that declare it as their interior when none declares it
/// as its exterior and the camera is not in it without such a shape (a fog filling the
/// world); a heterogeneous medium is also bounded by its grid (it is empty outside, Mitsuba 3's
/// clipping). Media that scatter nothing make no virtual lights and are left out. Everything
/// is clipped to the scene's geometry bounds `(lo, hi)`, inside which light paths start.
pub fn media_sphere(
    shapes: &[Shape],
    media: &[Medium],
    camera: Option<MediumId>,
    (lo, hi): (Vec3, Vec3),
    scene: BoundingSphere,
) -> Option<BoundingSphere> {
    let mut all = empty();
    for (m, medium) in media.iter().enumerate() {
        let m = m as MediumId;
        if !medium.scatters() {
            continue;
        }
        let inside = shapes.iter().filter(|s| s.interior == Some(m));
        let by_shapes = (shapes.iter().all(|s| s.exterior != Some(m))
            && (camera != Some(m) || shapes.iter().any(|s| s.interior == Some(m))))
        .then(|| inside.map(shape_bounds).fold(empty(), union));
        let by_grid = medium.as_grid().map(|h| h.sigma_t.bbox);
        let bounds = match (by_shapes, by_grid) {
            (Some(a), Some(b)) => intersection(a, b),
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => return None,
        };
        all = union(all, bounds);
    }
    let (a, b) = intersection(all, (lo, hi));
    if a.cmpgt(b).any() {
        return None;
    }
    let sphere = BoundingSphere::around(a, b);
    (sphere.radius <= MAX_RADIUS_SHARE * scene.radius).then_some(sphere)
}

fn empty() -> (Vec3, Vec3) {
    (Vec3::INFINITY, Vec3::NEG_INFINITY)
}

fn union(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> (Vec3, Vec3) {
    (a.0.min(b.0), a.1.max(b.1))
}

fn intersection(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> (Vec3, Vec3) {
    (a.0.max(b.0), a.1.min(b.1))
}

/// Axis-aligned bounds of a shape (a disk's: of the transformed unit square around it).
fn shape_bounds(shape: &Shape) -> (Vec3, Vec3) {
    match &shape.geometry {
        Geometry::Mesh(m) => m.positions.iter().fold(empty(), |b, &p| union(b, (p, p))),
        Geometry::Sphere { center, radius, .. } => {
            (*center - Vec3::splat(*radius), *center + Vec3::splat(*radius))
        }
        Geometry::Disk { to_world, .. } => [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .iter()
            .map(|&(x, y)| to_world.transform_point3(Vec3::new(x, y, 0.0)))
            .fold(empty(), |b, p| union(b, (p, p))),
    }
}

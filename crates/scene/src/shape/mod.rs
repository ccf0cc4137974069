//! Shapes: triangle meshes (`obj`, `ply`, `rectangle`, `cube`) and the analytic `sphere` and
//! `disk`, each with its BSDF, optional interior/exterior media and optional area emitter.

pub mod analytic;
pub mod closed;
pub mod coincident;
pub mod convex;
mod mesh;
mod primitives;
mod sample;
pub mod tangents;

pub use mesh::TriangleMesh;
pub use primitives::{cube_mesh, cylinder_mesh, rectangle_mesh, CYLINDER_SEGMENTS};
pub use sample::{AreaSampler, SurfaceSample};

use crate::bsdf::Bsdf;
use crate::medium::MediumId;
use glam::{Mat4, Vec3};

/// Geometry of a shape, in world space.
#[derive(Clone, Debug)]
pub enum Geometry {
    Mesh(TriangleMesh),
    /// Sphere; normals point outwards (inwards with `flip_normals`).
    Sphere {
        center: Vec3,
        radius: f32,
        flip_normals: bool,
    },
    /// Unit disk in the local `z = 0` plane, normal `+z`, mapped by `to_world` (which may scale
    /// non-uniformly: a disk can become an ellipse).
    Disk {
        to_world: Mat4,
        flip_normals: bool,
    },
}

impl Geometry {
    /// A sphere around the geometry, `(centre, radius)`, for aiming at it: the sphere itself; a
    /// disk's centre with its longer semi-axis; a mesh's box centre with its farthest vertex.
    /// The last two are widened by 1e-3 relative (and a mesh by 1e-5 more) so that rounding
    /// never leaves a point of the surface outside. `None` for a mesh without finite vertices.
    pub fn bounding_sphere(&self) -> Option<(Vec3, f32)> {
        match self {
            Geometry::Sphere { center, radius, .. } => Some((*center, *radius)),
            Geometry::Disk { to_world, .. } => {
                let ex = to_world.transform_vector3(Vec3::X).length();
                let ey = to_world.transform_vector3(Vec3::Y).length();
                Some((to_world.transform_point3(Vec3::ZERO), ex.max(ey) * 1.001))
            }
            Geometry::Mesh(m) => {
                let (lo, hi) = m
                    .positions
                    .iter()
                    .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), p| {
                        (lo.min(*p), hi.max(*p))
                    });
                if !lo.is_finite() || !hi.is_finite() {
                    return None;
                }
                let c = 0.5 * (lo + hi);
                let r = m.positions.iter().map(|p| (*p - c).length()).fold(0.0f32, f32::max);
                Some((c, r * 1.001 + 1e-5))
            }
        }
    }
}

#[derive(Clone, Debug)]
pub struct Shape {
    /// The XML `id` if given, else a description such as `obj "meshes/a.obj"`, for messages.
    pub name: String,
    pub geometry: Geometry,
    pub bsdf: Bsdf,
    /// Medium on the side opposite the normal.
    pub interior: Option<MediumId>,
    /// Medium on the side the normal points to.
    pub exterior: Option<MediumId>,
    /// Index into [`crate::Scene::emitters`] of the area emitter attached to this shape.
    pub emitter: Option<u32>,
}

impl Shape {
    /// True if the shape stops shadow rays: light crosses `null` surfaces and thin dielectrics
    /// (`Bsdf::null_transmission`), nothing else.
    pub fn blocks_shadow_rays(&self) -> bool {
        !self.bsdf.transmits_null()
    }

    /// True if crossing this shape can change the current medium (Mitsuba 3 changes media only
    /// at shapes that declare an interior or exterior medium).
    pub fn is_medium_transition(&self) -> bool {
        self.interior.is_some() || self.exterior.is_some()
    }

    /// Medium a ray enters when it leaves this shape's surface in direction `d` (geometric normal
    /// `n`): the exterior medium on the side `n` points to, the interior one on the other side,
    /// or `current` unchanged if the shape declares no media. This shape alone: walks ask the
    /// scene (`Scene::medium_towards`), which also weighs the surfaces touching it.
    pub fn medium_towards(
        &self,
        d: glam::Vec3,
        n: glam::Vec3,
        current: Option<MediumId>,
    ) -> Option<MediumId> {
        if !self.is_medium_transition() {
            current
        } else if d.dot(n) > 0.0 {
            self.exterior
        } else {
            self.interior
        }
    }
}

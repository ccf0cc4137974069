//! The record of a ray-surface hit, shared by the acceleration structure that finds it and the
//! scene that answers ray queries with it.

use crate::mesh_attribute::TexPoint;
use glam::{Vec2, Vec3};

/// A ray-surface hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub t: f32,
    pub p: Vec3,
    /// Geometric normal, on the shape's exterior side (flipped with `flip_normals`).
    pub n: Vec3,
    /// Shading normal (interpolated vertex normals if the mesh has them, else `n`), on the same
    /// side as `n`.
    pub ns: Vec3,
    pub uv: Vec2,
    pub shape: u32,
    /// The triangle's index in its mesh (0 on analytic shapes).
    pub prim: u32,
    /// Barycentric weights `(b1, b2)` of the triangle's vertices 1 and 2 (zero on analytic
    /// shapes), for textures that read vertex attributes.
    pub bary: Vec2,
}

impl SurfaceInteraction {
    /// Where textures are looked up at this hit.
    #[inline]
    pub fn tex(&self) -> TexPoint {
        TexPoint { uv: self.uv, prim: self.prim, bary: self.bary }
    }
}

//! The record of a ray-surface hit, shared by the acceleration structure that finds it and the
//! scene that answers ray queries with it.

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
    pub prim: u32,
}

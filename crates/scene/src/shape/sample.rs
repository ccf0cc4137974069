//! Uniform sampling of points on shapes by area (for area lights).

use super::analytic::{disk_uv, sphere_uv};
use super::{Geometry, Shape};
use crate::mesh_attribute::TexPoint;
use glam::{Vec2, Vec3};
use haze_core::sampling::{sample_uniform_disk_concentric, sample_uniform_sphere, sample_uniform_triangle};

/// A point sampled on a surface; `pdf` is per unit area.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSample {
    pub p: Vec3,
    /// Geometric normal on the exterior side (flipped with `flip_normals`).
    pub n: Vec3,
    pub pdf: f32,
    /// Where textures are looked up at the point, as at a ray's hit there
    /// (`SurfaceInteraction::tex`): a textured area emitter's radiance.
    pub tex: TexPoint,
}

/// Area-sampling table for one shape: total area and, for meshes, the CDF over triangles.
#[derive(Clone, Debug, Default)]
pub struct AreaSampler {
    pub area: f32,
    cdf: Vec<f32>,
}

impl AreaSampler {
    pub fn new(shape: &Shape) -> Self {
        match &shape.geometry {
            Geometry::Mesh(m) => {
                let mut cdf = Vec::with_capacity(m.indices.len());
                let mut acc = 0.0f64;
                for i in 0..m.indices.len() {
                    acc += m.triangle_area(i) as f64;
                    cdf.push(acc as f32);
                }
                AreaSampler { area: acc as f32, cdf }
            }
            Geometry::Sphere { radius, .. } => {
                AreaSampler { area: 4.0 * haze_core::PI * radius * radius, cdf: vec![] }
            }
            Geometry::Disk { to_world, .. } => {
                let ex = to_world.transform_vector3(Vec3::X);
                let ey = to_world.transform_vector3(Vec3::Y);
                AreaSampler { area: haze_core::PI * ex.cross(ey).length(), cdf: vec![] }
            }
        }
    }

    /// Uniform point on the shape: pdf `1 / area`.
    pub fn sample(&self, shape: &Shape, u: Vec2) -> SurfaceSample {
        let pdf = 1.0 / self.area;
        match &shape.geometry {
            Geometry::Mesh(m) => {
                let target = u.x * self.area;
                let i = self.cdf.partition_point(|&c| c < target).min(self.cdf.len() - 1);
                let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
                let width = self.cdf[i] - lo;
                // Reuse the leftover of u.x for the triangle's first coordinate.
                let ux = if width > 0.0 { ((target - lo) / width).clamp(0.0, 0.999_999_94) } else { 0.5 };
                let b = sample_uniform_triangle(Vec2::new(ux, u.y));
                let [p0, p1, p2] = m.vertices(i);
                let p = p0 * (1.0 - b.x - b.y) + p1 * b.x + p2 * b.y;
                // A mesh without uvs has the barycentrics as uvs, as at a hit (and in Mitsuba 3).
                let uv = match &m.uvs {
                    Some(uvs) => {
                        let [i0, i1, i2] = m.indices[i].map(|k| k as usize);
                        uvs[i0] * (1.0 - b.x - b.y) + uvs[i1] * b.x + uvs[i2] * b.y
                    }
                    None => b,
                };
                let tex = TexPoint { uv, prim: i as u32, bary: b };
                SurfaceSample { p, n: m.face_normal(i), pdf, tex }
            }
            Geometry::Sphere { center, radius, flip_normals } => {
                let d = sample_uniform_sphere(u);
                let n = if *flip_normals { -d } else { d };
                SurfaceSample { p: *center + d * *radius, n, pdf, tex: sphere_uv(n).into() }
            }
            Geometry::Disk { to_world, flip_normals } => {
                let q = sample_uniform_disk_concentric(u);
                let p = to_world.transform_point3(Vec3::new(q.x, q.y, 0.0));
                let ex = to_world.transform_vector3(Vec3::X);
                let ey = to_world.transform_vector3(Vec3::Y);
                let n = ex.cross(ey).normalize();
                SurfaceSample { p, n: if *flip_normals { -n } else { n }, pdf, tex: disk_uv(q).into() }
            }
        }
    }
}

//! Meshes of Mitsuba's built-in planar shapes, with Mitsuba's local geometry.

use super::TriangleMesh;
use glam::{Mat4, Vec2, Vec3};

/// `rectangle`: the square `[-1, 1]^2` in the local `z = 0` plane, normal `+z`.
/// Segments around a tessellated `cylinder`: the polygon's largest distance from the true
/// surface is `1 - cos(pi / 512) = 1.9e-5` radii, and vertex normals are the exact radial ones.
pub const CYLINDER_SEGMENTS: usize = 512;

/// `cylinder`: the open tube `x^2 + y^2 = 1, 0 <= z <= 1` (no caps, Mitsuba 3's), placed by
/// `to_world`, as a triangle mesh of [`CYLINDER_SEGMENTS`] quads with outward radial vertex
/// normals and `uv = (phi / 2 pi, z)`. `to_world` must be invertible.
pub fn cylinder_mesh(to_world: &Mat4, flip_normals: bool) -> TriangleMesh {
    let n = CYLINDER_SEGMENTS;
    let normal_matrix = glam::Mat3::from_mat4(*to_world).inverse().transpose();
    let (mut positions, mut normals, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..=n {
        let phi = std::f32::consts::TAU * i as f32 / n as f32;
        let (s, c) = if i == n { (0.0, 1.0) } else { phi.sin_cos() };
        for z in [0.0, 1.0] {
            positions.push(to_world.transform_point3(Vec3::new(c, s, z)));
            normals.push((normal_matrix * Vec3::new(c, s, 0.0)).normalize_or_zero());
            uvs.push(Vec2::new(i as f32 / n as f32, z));
        }
    }
    // Vertex 2i is (phi_i, z = 0), 2i + 1 is (phi_i, z = 1); counter-clockwise seen from outside.
    let mut indices = Vec::with_capacity(2 * n);
    for i in 0..n as u32 {
        let (b0, t0, b1, t1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        indices.push([b0, b1, t1]);
        indices.push([b0, t1, t0]);
    }
    TriangleMesh::new(positions, Some(normals), Some(uvs), indices, flip_normals)
}

pub fn rectangle_mesh(to_world: &Mat4, flip_normals: bool) -> TriangleMesh {
    let p = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uv = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
    TriangleMesh::new(
        p.iter().map(|&v| to_world.transform_point3(v)).collect(),
        None,
        Some(uv.to_vec()),
        vec![[0, 1, 2], [0, 2, 3]],
        flip_normals,
    )
}

/// `cube`: the cube `[-1, 1]^3`, outward normals, 12 triangles (24 vertices so that each face
/// has its own normals).
pub fn cube_mesh(to_world: &Mat4, flip_normals: bool) -> TriangleMesh {
    let mut positions = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(12);
    // Each face: normal axis, sign. Vertices ordered counter-clockwise seen from outside.
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from(std::array::from_fn::<f32, 3, _>(|i| if i == axis { sign } else { 0.0 }));
            let a =
                Vec3::from(std::array::from_fn::<f32, 3, _>(|i| if i == (axis + 1) % 3 { 1.0 } else { 0.0 }));
            let b = n.cross(a);
            let base = positions.len() as u32;
            for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(to_world.transform_point3(n + a * s + b * t));
            }
            indices.push([base, base + 1, base + 2]);
            indices.push([base, base + 2, base + 3]);
        }
    }
    TriangleMesh::new(positions, None, None, indices, flip_normals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_normals_point_outwards_and_area_is_24() {
        let m = cube_mesh(&Mat4::IDENTITY, false);
        let mut area = 0.0;
        for (i, tri) in m.indices.iter().enumerate() {
            let c =
                (m.positions[tri[0] as usize] + m.positions[tri[1] as usize] + m.positions[tri[2] as usize])
                    / 3.0;
            assert!(m.face_normal(i).dot(c) > 0.0, "face {i} points inwards");
            area += m.triangle_area(i);
        }
        assert!((area - 24.0).abs() < 1e-4);
    }

    #[test]
    fn rectangle_normal_is_plus_z() {
        let m = rectangle_mesh(&Mat4::IDENTITY, false);
        assert!((m.face_normal(0) - Vec3::Z).length() < 1e-6);
        let f = rectangle_mesh(&Mat4::IDENTITY, true);
        assert!((f.face_normal(0) + Vec3::Z).length() < 1e-6);
    }
}

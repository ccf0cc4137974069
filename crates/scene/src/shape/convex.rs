//! Sides from which a mesh cannot be hit again.
//!
//! If every vertex of a mesh lies on or behind the plane of every one of its faces (behind: on
//! the side opposite the face's geometric normal `n`), every triangle lies in the closed half
//! space behind each face's plane. A ray that leaves a face towards its front (`d . n > 0`)
//! from an origin offset in front of the plane moves away from that plane for all `t > 0`, so
//! it cannot meet the mesh again: the mesh is *clear in front*. This holds for convex meshes
//! (closed or not: a convex bowl left outwards) with outward normals. With every vertex on or in
//! front of every face's plane (inward normals), the mesh is *clear behind*; a flat mesh (a
//! rectangle, a disk of triangles) is clear on both sides. The BVH then skips such a mesh's
//! subtrees for rays leaving it that way (`accel::Leaving`), which answers the same closest hit
//! and the same shadow-ray crossings with fewer node visits and leaf tests.
//!
//! Rounding: a vertex counts as on a face's plane within [`COPLANAR`] times the magnitude of the
//! two points involved (a few f32 spacings: the vertices are f32, the planes computed in f64).
//! A ray leaves from an origin offset by `RAY_EPSILON (1 + |p|)` (`haze_core::ray::offset_origin`),
//! a hundred times more, and only rays leaving at least [`MIN_COSINE`] away from the face's
//! plane skip the mesh (`Scene::leaving`), so a mesh convex only to within the tolerance is
//! still never hit from where the ray really is.

use super::TriangleMesh;
use glam::DVec3;
use rayon::prelude::*;

/// Relative tolerance of "on the plane" (see the module documentation).
pub const COPLANAR: f64 = 1e-6;

/// Least `|d . n|` of a ray that skips the mesh it leaves: rays closer to tangent are traced
/// against it as always (a negligible share; their side is still certain, but this keeps the
/// argument free of how far a grazing ray travels near the plane).
pub const MIN_COSINE: f32 = 1e-3;

/// The checks below cost one dot product per (face, vertex) pair, stopping at the first face
/// that sees vertices on both sides; meshes with more pairs than this are not checked (and never
/// skipped). The peer scenes' convex sphere (3,072 faces, 4.7e6 pairs) takes 7-14 ms on two
/// cores, so a mesh at the limit adds about 0.1 s to its scene's loading.
pub const MAX_PAIRS: u64 = 40_000_000;

/// From which sides of its faces a mesh is clear (module documentation): `front` for rays
/// leaving along the geometric normal `TriangleMesh::face_normal` (which `flip_normals` flips),
/// `back` for rays leaving against it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClearSides {
    pub front: bool,
    pub back: bool,
}

/// The sides of [`ClearSides`] for `m`: neither when a vertex lies in front of one face's plane
/// and another behind one (not convex), when the mesh has no face of non-zero area, or when it is
/// too large to check ([`MAX_PAIRS`]).
pub fn clear_sides(m: &TriangleMesh) -> ClearSides {
    // The vertices faces use (an unreferenced position is no geometry), each once.
    let mut used: Vec<u32> = m.indices.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    if used.is_empty() || (used.len() as u64).saturating_mul(m.indices.len() as u64) > MAX_PAIRS {
        return ClearSides::default();
    }
    let points: Vec<DVec3> = used.iter().map(|&v| m.positions[v as usize].as_dvec3()).collect();
    // The planes of the faces with a normal, in f64: unit normal (as `face_normal` orients it),
    // a point on the face, and the point's magnitude for the tolerance.
    let sign = if m.flip_normals { -1.0 } else { 1.0 };
    let planes: Vec<(DVec3, DVec3, f64)> = (0..m.indices.len())
        .filter_map(|i| {
            let [a, b, c] = m.vertices(i).map(|p| p.as_dvec3());
            let n = (b - a).cross(c - a);
            let len = n.length();
            (len > 0.0 && len.is_finite()).then(|| (n * (sign / len), a, a.abs().max_element()))
        })
        .collect();
    if planes.is_empty() {
        return ClearSides::default();
    }
    // The furthest any vertex lies in front of (max) and behind (min) a face's plane, each
    // shrunk by the tolerance; the search stops once both signs are seen.
    let sides = planes
        .par_iter()
        .try_fold(
            || (true, true),
            |(front, back), &(n, a, scale)| {
                let (mut front, mut back) = (front, back);
                for &p in &points {
                    let d = n.dot(p - a);
                    let tol = COPLANAR * (scale + p.abs().max_element()) + f64::MIN_POSITIVE;
                    front &= d <= tol;
                    back &= d >= -tol;
                    if !front && !back {
                        return Err(());
                    }
                }
                Ok((front, back))
            },
        )
        .try_reduce(|| (true, true), |x, y| Ok((x.0 && y.0, x.1 && y.1)));
    match sides {
        Ok((front, back)) => ClearSides { front, back },
        Err(()) => ClearSides::default(),
    }
}

/// A UV sphere of `n` rings and `2n` segments about the origin, normals outwards (for tests).
#[cfg(test)]
pub(crate) fn uv_sphere(n: u32, radius: f32) -> TriangleMesh {
    use glam::Vec3;
    {
        let mut positions = vec![Vec3::Y * radius, -Vec3::Y * radius];
        for i in 1..n {
            let theta = std::f32::consts::PI * i as f32 / n as f32;
            for j in 0..2 * n {
                let phi = std::f32::consts::PI * j as f32 / n as f32;
                positions
                    .push(radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
            }
        }
        let ring = |i: u32, j: u32| 2 + (i - 1) * 2 * n + j % (2 * n);
        let mut indices = Vec::new();
        for j in 0..2 * n {
            indices.push([0, ring(1, j + 1), ring(1, j)]);
            indices.push([1, ring(n - 1, j), ring(n - 1, j + 1)]);
            for i in 1..n - 1 {
                indices.push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
                indices.push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
            }
        }
        TriangleMesh::new(positions, None, None, indices, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::cube_mesh;
    use glam::{Mat4, Vec3};

    fn mesh(positions: Vec<Vec3>, indices: Vec<[u32; 3]>, flip: bool) -> TriangleMesh {
        TriangleMesh::new(positions, None, None, indices, flip)
    }

    #[test]
    fn convex_closed_meshes_are_clear_in_front_only() {
        let cube = cube_mesh(
            &Mat4::from_scale_rotation_translation(
                Vec3::new(1.0, 2.0, 0.5),
                glam::Quat::from_rotation_y(0.3),
                Vec3::new(10.0, -3.0, 2.0),
            ),
            false,
        );
        assert_eq!(clear_sides(&cube), ClearSides { front: true, back: false });
        let sphere = uv_sphere(24, 1.3);
        // The sphere's winding points outwards: every face normal away from the centre.
        assert!((0..sphere.indices.len()).all(|i| sphere.face_normal(i).dot(sphere.vertices(i)[0]) > 0.0));
        assert_eq!(clear_sides(&sphere), ClearSides { front: true, back: false });
        // `flip_normals` turns the normals inwards: the same mesh is clear behind them.
        let flipped = TriangleMesh { flip_normals: true, ..sphere.clone() };
        assert_eq!(clear_sides(&flipped), ClearSides { front: false, back: true });
        // An open convex bowl (the sphere's lower half) is clear in front too.
        let bowl = mesh(
            sphere.positions.clone(),
            sphere
                .indices
                .iter()
                .copied()
                .filter(|t| t.iter().all(|&v| sphere.positions[v as usize].y <= 1e-6))
                .collect(),
            false,
        );
        assert!(bowl.indices.len() < sphere.indices.len());
        assert_eq!(clear_sides(&bowl), ClearSides { front: true, back: false });
    }

    #[test]
    fn flat_meshes_are_clear_on_both_sides() {
        // A tessellated square, tilted off the axes (plane distances not exactly zero in f64).
        let to_world = Mat4::from_rotation_translation(
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.4, 0.7, 0.1),
            Vec3::new(3.0, 1.0, -2.0),
        );
        let mut positions = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                positions.push(to_world.transform_point3(Vec3::new(i as f32 * 0.25, j as f32 * 0.25, 0.0)));
            }
        }
        let mut indices = Vec::new();
        for i in 0..4u32 {
            for j in 0..4u32 {
                let v = i * 5 + j;
                indices.push([v, v + 5, v + 6]);
                indices.push([v, v + 6, v + 1]);
            }
        }
        assert_eq!(clear_sides(&mesh(positions, indices, false)), ClearSides { front: true, back: true });
    }

    #[test]
    fn concave_and_disjoint_meshes_are_clear_on_no_side() {
        // A sphere with one vertex pushed inwards: a dimple, in front of its neighbours' planes.
        let mut dimpled = uv_sphere(16, 1.0);
        dimpled.positions[2 + 5 * 32 + 7] *= 0.9;
        assert_eq!(clear_sides(&dimpled), ClearSides::default());
        // A dimple far below any tolerance still counts: 1e-3 of the radius.
        let mut shallow = uv_sphere(16, 1.0);
        shallow.positions[2 + 5 * 32 + 7] *= 0.999;
        assert_eq!(clear_sides(&shallow), ClearSides::default());
        // Two convex spheres in one mesh: each lies in front of faces of the other.
        let (a, b) = (uv_sphere(8, 1.0), uv_sphere(8, 1.0));
        let offset = a.positions.len() as u32;
        let positions: Vec<Vec3> =
            a.positions.iter().copied().chain(b.positions.iter().map(|p| *p + Vec3::X * 3.0)).collect();
        let indices =
            a.indices.iter().copied().chain(b.indices.iter().map(|t| t.map(|v| v + offset))).collect();
        assert_eq!(clear_sides(&mesh(positions, indices, false)), ClearSides::default());
        // No face of non-zero area.
        let degenerate = mesh(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], vec![[0, 1, 2]], false);
        assert_eq!(clear_sides(&degenerate), ClearSides::default());
    }

    /// Vertices no face uses do not count; meshes past the size limit are not checked.
    #[test]
    fn unused_vertices_and_the_size_limit() {
        let mut sphere = uv_sphere(8, 1.0);
        sphere.positions.push(Vec3::splat(5.0));
        assert_eq!(clear_sides(&sphere), ClearSides { front: true, back: false });
        let big = uv_sphere(80, 1.0);
        assert!((big.indices.len() as u64) * (big.positions.len() as u64) > MAX_PAIRS);
        assert_eq!(clear_sides(&big), ClearSides::default());
    }
}

//! Which shapes have surfaces that touch a medium boundary: a face of one shape lying in the
//! plane of a face of another (or of the same) shape, overlapping it with positive area, where
//! at least one of the two declares media. A fog box resting on a floor, a smoke volume against
//! a wall, a glass and the null boundary of the water inside it. At such a place a ray meets both
//! surfaces at the same distance, and which one a closest-hit query returns is arbitrary; the
//! scene resolves those hits by the rule of `docs/theory.md` §14 (`crate::coincident`), but only
//! on the faces marked here, so scenes without touching surfaces pay nothing, and hits on the
//! other faces of a shape that touches somewhere (the top of the fog box on the floor) little.
//!
//! The test is conservative where it is cheap to be (a disk is taken as its bounding square) and
//! exact enough elsewhere: two triangles touch when every vertex of each lies within
//! `2 RAY_EPSILON (1 + |p|)` of the other's plane (the distance below which the ray offset,
//! `haze_core::ray::offset_origin`, steps over a surface unseen) and their projections onto that
//! plane overlap with positive area (sharing an edge is not touching). Candidate pairs come from
//! a hash on the plane (normal and offset, quantised), each boundary triangle entered in every
//! cell within the tolerance of its key, so no pair is lost at a cell's edge.

use super::{Geometry, Shape};
use glam::{Vec2, Vec3};
use haze_core::RAY_EPSILON;
use std::collections::HashMap;

/// Cell size of a normal component in the plane hash.
const NORMAL_CELL: f32 = 1.0 / 16.0;
/// Largest difference between two normals' components that may still be one plane (tiny
/// triangles placed within the offset distance of each other may tilt that much).
const NORMAL_TOLERANCE: f32 = 1e-2;

/// A planar piece of a shape: a triangle, or half of a disk's bounding square.
#[derive(Clone, Copy, Debug)]
struct Piece {
    shape: u32,
    /// The triangle's index in its mesh; 0 for a disk (its hits' `prim`).
    prim: u32,
    v: [Vec3; 3],
    n: Vec3,
}

/// The offset distance at `p` (`haze_core::ray::offset_origin`).
fn offset_scale(p: Vec3) -> f32 {
    RAY_EPSILON * (1.0 + p.abs().max_element())
}

/// Which faces touch a face of a shape (the same one included) where one of the two declares
/// media, or (spheres) coincide with another sphere that way: per shape, per primitive (mesh
/// triangle; one for a sphere or disk), or an empty list for a shape none of whose faces touch;
/// no list at all when nothing touches.
pub fn touching_faces(shapes: &[Shape]) -> Vec<Vec<bool>> {
    let mut touching: Vec<Vec<bool>> = vec![Vec::new(); shapes.len()];
    if !shapes.iter().any(Shape::is_medium_transition) {
        return Vec::new();
    }
    let mut mark = |shape: u32, prim: u32| {
        let faces = &mut touching[shape as usize];
        if faces.is_empty() {
            let count = match &shapes[shape as usize].geometry {
                Geometry::Mesh(m) => m.indices.len(),
                Geometry::Sphere { .. } | Geometry::Disk { .. } => 1,
            };
            *faces = vec![false; count];
        }
        faces[prim as usize] = true;
    };
    let pieces = planar_pieces(shapes);
    let max_coord = pieces.iter().flat_map(|p| p.v).fold(0.0f32, |m, v| m.max(v.abs().max_element()));
    let tol = 2.0 * RAY_EPSILON * (1.0 + max_coord);
    let offset_cell = 64.0 * tol;
    // Boundary pieces, entered under both orientations of their plane.
    let mut table: HashMap<[i32; 4], Vec<u32>> = HashMap::new();
    for (i, p) in pieces.iter().enumerate() {
        if !shapes[p.shape as usize].is_medium_transition() {
            continue;
        }
        for n in [p.n, -p.n] {
            let key = [n.x / NORMAL_CELL, n.y / NORMAL_CELL, n.z / NORMAL_CELL, n.dot(p.v[0]) / offset_cell];
            let tols = [
                NORMAL_TOLERANCE / NORMAL_CELL,
                NORMAL_TOLERANCE / NORMAL_CELL,
                NORMAL_TOLERANCE / NORMAL_CELL,
                0.5,
            ];
            for cell in neighbour_cells(key, tols) {
                table.entry(cell).or_default().push(i as u32);
            }
        }
    }
    for (j, q) in pieces.iter().enumerate() {
        let key =
            [q.n.x / NORMAL_CELL, q.n.y / NORMAL_CELL, q.n.z / NORMAL_CELL, q.n.dot(q.v[0]) / offset_cell]
                .map(|x| x.floor() as i32);
        let Some(candidates) = table.get(&key) else { continue };
        for &i in candidates {
            let p = &pieces[i as usize];
            if i as usize != j && pieces_touch(p, q) {
                mark(p.shape, p.prim);
                mark(q.shape, q.prim);
            }
        }
    }
    for (i, j) in spheres_touching(shapes) {
        mark(i, 0);
        mark(j, 0);
    }
    if touching.iter().all(Vec::is_empty) {
        // Nothing touches: the scene tests one length instead of a shape's entry per hit.
        touching.clear();
    }
    touching
}

/// The cells of the hash whose key lies within `tol` (per coordinate) of `key`.
fn neighbour_cells(key: [f32; 4], tol: [f32; 4]) -> Vec<[i32; 4]> {
    let mut cells = vec![[0i32; 4]];
    for k in 0..4 {
        let lo = (key[k] - tol[k]).floor() as i32;
        let hi = (key[k] + tol[k]).floor() as i32;
        let mut next = Vec::with_capacity(cells.len() * 2);
        for c in &cells {
            for v in lo..=hi {
                let mut c = *c;
                c[k] = v;
                next.push(c);
            }
        }
        cells = next;
    }
    cells
}

/// Every triangle of every mesh, and each disk's bounding square as two triangles.
fn planar_pieces(shapes: &[Shape]) -> Vec<Piece> {
    let mut pieces = Vec::new();
    for (s, shape) in shapes.iter().enumerate() {
        match &shape.geometry {
            Geometry::Mesh(m) => {
                for i in 0..m.indices.len() {
                    let n = m.face_normal(i);
                    if n != Vec3::ZERO {
                        pieces.push(Piece { shape: s as u32, prim: i as u32, v: m.vertices(i), n });
                    }
                }
            }
            Geometry::Disk { to_world, .. } => {
                let c = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(x, y)| to_world.transform_point3(Vec3::new(x, y, 0.0)));
                for v in [[c[0], c[1], c[2]], [c[0], c[2], c[3]]] {
                    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
                    if n != Vec3::ZERO {
                        pieces.push(Piece { shape: s as u32, prim: 0, v, n });
                    }
                }
            }
            Geometry::Sphere { .. } => {}
        }
    }
    pieces
}

/// Two spheres of (nearly) the same centre and radius, one of them a medium boundary.
fn spheres_touching(shapes: &[Shape]) -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    let spheres: Vec<(usize, Vec3, f32)> = shapes
        .iter()
        .enumerate()
        .filter_map(|(i, s)| match s.geometry {
            Geometry::Sphere { center, radius, .. } => Some((i, center, radius)),
            _ => None,
        })
        .collect();
    for (a, &(i, ci, ri)) in spheres.iter().enumerate() {
        for &(j, cj, rj) in &spheres[a + 1..] {
            let tol = 2.0 * offset_scale(ci.abs().max(cj.abs()) + Vec3::splat(ri.max(rj)));
            let transition = shapes[i].is_medium_transition() || shapes[j].is_medium_transition();
            if transition && (ci - cj).length() + (ri - rj).abs() <= tol {
                pairs.push((i as u32, j as u32));
            }
        }
    }
    pairs
}

/// Every vertex of each piece within the offset distance (twice) of the other's plane, and
/// their projections overlapping with positive area.
fn pieces_touch(p: &Piece, q: &Piece) -> bool {
    let near_plane =
        |a: &Piece, b: &Piece| b.v.iter().all(|&v| (v - a.v[0]).dot(a.n).abs() <= 2.0 * offset_scale(v));
    if !near_plane(p, q) || !near_plane(q, p) {
        return false;
    }
    // Project onto the plane's two coordinates that keep the most area.
    let axis = p.n.abs();
    let drop = if axis.x >= axis.y && axis.x >= axis.z {
        0
    } else if axis.y >= axis.z {
        1
    } else {
        2
    };
    let flat = |v: Vec3| match drop {
        0 => Vec2::new(v.y, v.z),
        1 => Vec2::new(v.z, v.x),
        _ => Vec2::new(v.x, v.y),
    };
    let a = p.v.map(flat);
    let b = q.v.map(flat);
    let scale = p.v.iter().chain(&q.v).fold(0.0f32, |m, v| m.max(v.abs().max_element()));
    triangles_overlap_2d(a, b, 1e-6 * (1.0 + scale))
}

/// Separating-axis test of two 2D triangles: they overlap by more than `margin` along every
/// edge normal of either (a shared edge or vertex is not an overlap).
fn triangles_overlap_2d(a: [Vec2; 3], b: [Vec2; 3], margin: f32) -> bool {
    for tri in [a, b] {
        for k in 0..3 {
            let e = tri[(k + 1) % 3] - tri[k];
            let len = e.length();
            if len == 0.0 {
                return false;
            }
            let axis = Vec2::new(-e.y, e.x) / len;
            let range = |t: [Vec2; 3]| {
                t.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
                    let x = v.dot(axis);
                    (lo.min(x), hi.max(x))
                })
            };
            let (alo, ahi) = range(a);
            let (blo, bhi) = range(b);
            if ahi.min(bhi) - alo.max(blo) <= margin {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::shape::{cube_mesh, rectangle_mesh};
    use crate::texture::Texture;
    use glam::Mat4;
    use haze_core::Rgb;

    fn shape(geometry: Geometry, bsdf: Bsdf, interior: Option<u32>) -> Shape {
        Shape { name: "s".into(), geometry, bsdf, interior, exterior: None, emitter: None }
    }

    /// Per shape: some face touches.
    fn touching_shapes(shapes: &[Shape]) -> Vec<bool> {
        let faces = touching_faces(shapes);
        (0..shapes.len()).map(|s| faces.get(s).is_some_and(|f| f.iter().any(|&t| t))).collect()
    }

    fn diffuse() -> Bsdf {
        Bsdf::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }
    }

    /// A unit cube `[-1, 1]^3` lifted by `lift` (its bottom face at `y = -1 + lift`).
    fn fog_cube(lift: f32) -> Shape {
        shape(
            Geometry::Mesh(cube_mesh(&Mat4::from_translation(Vec3::new(0.0, lift, 0.0)), false)),
            Bsdf::Null,
            Some(0),
        )
    }

    /// The rectangle `[-4, 4]^2` in the plane `y = -1`, normal up.
    fn floor() -> Shape {
        let to_world = Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0))
            * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(4.0));
        shape(Geometry::Mesh(rectangle_mesh(&to_world, false)), diffuse(), None)
    }

    #[test]
    fn a_fog_cube_on_the_floor_touches_it_and_a_lifted_one_does_not() {
        assert_eq!(touching_shapes(&[fog_cube(0.0), floor()]), vec![true, true]);
        // Only the cube's two bottom triangles (normal -y), and both of the floor's.
        let cube = fog_cube(0.0);
        let Geometry::Mesh(m) = &cube.geometry else { unreachable!() };
        let bottom: Vec<bool> = (0..m.indices.len()).map(|i| m.face_normal(i).y < -0.5).collect();
        assert_eq!(bottom.iter().filter(|&&b| b).count(), 2);
        assert_eq!(touching_faces(&[cube.clone(), floor()]), vec![bottom, vec![true, true]]);
        assert_eq!(touching_shapes(&[fog_cube(1e-3), floor()]), vec![false, false]);
        assert_eq!(touching_shapes(&[fog_cube(-1e-3), floor()]), vec![false, false]);
        // Without media nothing is looked for: the tie between two opaque surfaces is not ours.
        let mut plain = fog_cube(0.0);
        plain.interior = None;
        assert_eq!(touching_shapes(&[plain, floor()]), vec![false, false]);
    }

    #[test]
    fn faces_that_only_share_an_edge_do_not_touch() {
        // A unit square in the floor's plane `y = -1` beside the cube, sharing the edge `x = 1`
        // of the cube's bottom face.
        let to_world = Mat4::from_translation(Vec3::new(2.0, -1.0, 0.0))
            * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        let beside = shape(Geometry::Mesh(rectangle_mesh(&to_world, false)), diffuse(), None);
        assert_eq!(touching_shapes(&[fog_cube(0.0), beside]), vec![false, false]);
        // The cube's own bottom triangles share an edge in one plane: not touching either.
        assert_eq!(touching_shapes(&[fog_cube(0.0)]), vec![false]);
    }

    #[test]
    fn coincident_meshes_and_spheres_touch() {
        let mut glass = fog_cube(0.0);
        glass.interior = None;
        glass.bsdf = Bsdf::Dielectric { eta: 1.5 };
        assert_eq!(touching_shapes(&[glass, fog_cube(0.0)]), vec![true, true]);
        let sphere = |r: f32, interior| {
            shape(
                Geometry::Sphere { center: Vec3::ONE, radius: r, flip_normals: false },
                Bsdf::Null,
                interior,
            )
        };
        assert_eq!(touching_shapes(&[sphere(1.0, Some(0)), sphere(1.0, None)]), vec![true, true]);
        assert_eq!(touching_shapes(&[sphere(1.0, Some(0)), sphere(1.01, None)]), vec![false, false]);
    }
}

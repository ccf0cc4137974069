//! Closed surfaces: which side of a shape is its inside, and whether a point lies inside it.
//!
//! A shadow ray that leaves a closed surface towards its inside and aims at a point outside it
//! must cross the surface again (the winding number of the surface about the ray's points goes
//! from at least 1 to 0, and it changes only where the ray crosses the surface). When that
//! surface stops shadow rays, the ray is blocked, whatever else the scene holds: next-event
//! estimation skips it untraced ([`crate::Scene::towards_sealed_inside`]).
//!
//! "Closed" here is checked on the mesh's topology after welding vertices at equal positions:
//! every edge is shared by exactly two triangles that run along it in opposite directions (a
//! consistently oriented closed surface), and every connected component encloses a volume of
//! the same sign (so the winding number is 1, not -1, just inside every face, and 0 far away).
//! A closed mesh that intersects itself in a way that wraps space negatively would pass these
//! checks and break the argument; scene meshes (spheres, glass objects, medium boundaries) do
//! not.

use super::{Geometry, TriangleMesh};
use glam::Vec3;

/// The sign `s` such that `s * n` points out of the enclosed volume for every geometric normal
/// `n` the shape's hits report (`TriangleMesh::face_normal`, the sphere's normal, both with
/// `flip_normals`), or `None` when the shape is not a closed surface (disks, open meshes, meshes
/// failing the checks of the module documentation).
pub fn outward_sign(geometry: &Geometry) -> Option<f32> {
    match geometry {
        Geometry::Sphere { radius, flip_normals, .. } => {
            (*radius > 0.0).then_some(if *flip_normals { -1.0 } else { 1.0 })
        }
        Geometry::Disk { .. } => None,
        Geometry::Mesh(m) => {
            let volume = closed_mesh_volume_sign(m)?;
            Some(if m.flip_normals { -volume } else { volume })
        }
    }
}

/// For a closed, consistently oriented mesh whose components all enclose volumes of one sign,
/// that sign (+1 when the winding normals `(p1 - p0) x (p2 - p0)` point outwards).
fn closed_mesh_volume_sign(m: &TriangleMesh) -> Option<f32> {
    if m.indices.is_empty() {
        return None;
    }
    // Weld: one id per distinct position (exact bits; -0.0 and 0.0 as one), by sorting.
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut order: Vec<u32> = (0..m.positions.len() as u32).collect();
    order.sort_unstable_by_key(|&v| key(m.positions[v as usize]));
    let mut welded = vec![0u32; m.positions.len()];
    let mut ids = 0u32;
    for (k, &v) in order.iter().enumerate() {
        if k > 0 && key(m.positions[v as usize]) != key(m.positions[order[k - 1] as usize]) {
            ids += 1;
        }
        welded[v as usize] = ids;
    }
    let tri = |i: usize| m.indices[i].map(|v| welded[v as usize]);
    // Directed edges `a -> b` as `a << 32 | b`: the mesh is closed and consistently oriented
    // when no directed edge appears twice and the sorted reversed edges are the same list.
    let mut edges: Vec<u64> = Vec::with_capacity(3 * m.indices.len());
    for i in 0..m.indices.len() {
        let [a, b, c] = tri(i).map(u64::from);
        if a == b || b == c || c == a {
            return None;
        }
        edges.extend([a << 32 | b, b << 32 | c, c << 32 | a]);
    }
    let mut reversed: Vec<u64> = edges.iter().map(|e| e.rotate_left(32)).collect();
    edges.sort_unstable();
    reversed.sort_unstable();
    if edges.windows(2).any(|w| w[0] == w[1]) || edges != reversed {
        return None;
    }
    // Components (union-find over welded vertices) and the signed volume of each,
    // V = sum over triangles of p0 . (p1 x p2) / 6 (divergence theorem), in f64.
    let mut parent: Vec<u32> = (0..=ids).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for i in 0..m.indices.len() {
        let [a, b, c] = tri(i);
        for (x, y) in [(a, b), (b, c)] {
            let (rx, ry) = (root(&mut parent, x), root(&mut parent, y));
            parent[rx as usize] = ry;
        }
    }
    // Per component root: its volume, and whether it has triangles at all (positions no
    // triangle uses are components of their own, with nothing to enclose).
    let mut volume = vec![(0.0f64, false); parent.len()];
    for i in 0..m.indices.len() {
        let [p0, p1, p2] = m.vertices(i).map(|p| p.as_dvec3());
        let v = &mut volume[root(&mut parent, tri(i)[0]) as usize];
        *v = (v.0 + p0.dot(p1.cross(p2)) / 6.0, true);
    }
    let volumes: Vec<f64> = volume.iter().filter(|v| v.1).map(|v| v.0).collect();
    if volumes.iter().all(|&v| v > 0.0) {
        Some(1.0)
    } else if volumes.iter().all(|&v| v < 0.0) {
        Some(-1.0)
    } else {
        None
    }
}

/// Whether `p` is inside the closed shape (see [`outward_sign`]), or `None` when that is not
/// certain: the shape is not closed, or `p` lies on or very near its surface. For meshes, the
/// generalised winding number (the solid angle the surface subtends at `p` over 4 pi, summed
/// exactly per triangle with Van Oosterom and Strackee's formula, 1983) is an integer away from
/// the surface: 0 outside, +-1 inside; anything else than a near-integer 0 or +-1 is `None`.
pub fn contains(geometry: &Geometry, p: Vec3) -> Option<bool> {
    outward_sign(geometry)?;
    contains_closed(geometry, p)
}

/// [`outward_sign`] when the shape is closed and every one of `points` is certainly outside it
/// ([`contains`]), else `None`: the closedness checked once for all points.
pub fn outward_sign_if_outside(geometry: &Geometry, points: &[Vec3]) -> Option<f32> {
    let sign = outward_sign(geometry)?;
    points.iter().all(|&p| contains_closed(geometry, p) == Some(false)).then_some(sign)
}

/// [`contains`] for a shape [`outward_sign`] accepted.
fn contains_closed(geometry: &Geometry, p: Vec3) -> Option<bool> {
    match geometry {
        Geometry::Sphere { center, radius, .. } => {
            let d = (p - *center).length();
            let margin = 1e-4 * radius;
            if d < radius - margin {
                Some(true)
            } else if d > radius + margin {
                Some(false)
            } else {
                None
            }
        }
        Geometry::Disk { .. } => None,
        Geometry::Mesh(m) => {
            // Outside the box of the triangles: outside (the common case, without the sum).
            let (lo, hi) = m
                .indices
                .iter()
                .flatten()
                .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &v| {
                    (lo.min(m.positions[v as usize]), hi.max(m.positions[v as usize]))
                });
            let margin = 1e-4 * (hi - lo).max_element();
            if p.cmplt(lo - margin).any() || p.cmpgt(hi + margin).any() {
                return Some(false);
            }
            let q = p.as_dvec3();
            let mut solid_angle = 0.0f64;
            for i in 0..m.indices.len() {
                let [a, b, c] = m.vertices(i).map(|v| v.as_dvec3() - q);
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                if la.min(lb).min(lc) <= 1e-9 * (1.0 + q.abs().max_element()) {
                    return None;
                }
                let num = a.dot(b.cross(c));
                let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
                solid_angle += 2.0 * num.atan2(den);
            }
            let w = solid_angle / (4.0 * std::f64::consts::PI);
            let nearest = w.round();
            if (w - nearest).abs() > 0.05 {
                return None;
            }
            match nearest as i64 {
                0 => Some(false),
                1 | -1 => Some(true),
                _ => None,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// A sphere of radius `radius` about `center` as a closed mesh (an octahedron refined twice,
    /// its vertices pushed onto the sphere), winding outwards; for tests.
    fn sphere_mesh(center: Vec3, radius: f32, flip: bool) -> TriangleMesh {
        let mut positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut indices: Vec<[u32; 3]> =
            vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        for _ in 0..2 {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut next = Vec::new();
            for [a, b, c] in indices {
                let mut m = |x: u32, y: u32| {
                    *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                        positions.push((positions[x as usize] + positions[y as usize]).normalize());
                        positions.len() as u32 - 1
                    })
                };
                let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
                next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            indices = next;
        }
        let positions = positions.into_iter().map(|p| center + p * radius).collect();
        TriangleMesh::new(positions, None, None, indices, flip)
    }

    fn mesh(m: TriangleMesh) -> Geometry {
        Geometry::Mesh(m)
    }

    /// A refined octahedron is closed with outward winding; flipped, its normals point in; its
    /// centre is inside, far points are outside, points on it are not decided.
    #[test]
    fn closed_mesh_sides_and_containment() {
        let c = Vec3::new(0.3, -0.2, 0.5);
        let g = mesh(sphere_mesh(c, 2.0, false));
        assert_eq!(outward_sign(&g), Some(1.0));
        assert_eq!(outward_sign(&mesh(sphere_mesh(c, 2.0, true))), Some(-1.0));
        let Geometry::Mesh(m) = &g else { unreachable!() };
        // The face normals point away from the centre.
        for i in 0..m.indices.len() {
            let [a, b, cc] = m.vertices(i);
            assert!(m.face_normal(i).dot((a + b + cc) / 3.0 - c) > 0.0);
        }
        assert_eq!(contains(&g, c), Some(true));
        assert_eq!(contains(&g, c + Vec3::new(1.5, 0.1, -0.2)), Some(true));
        assert_eq!(contains(&g, c + Vec3::new(3.0, 0.0, 0.0)), Some(false));
        assert_eq!(contains(&g, c + Vec3::new(-40.0, 7.0, 1.0)), Some(false));
        // A vertex of the mesh: on the surface, undecided.
        assert_eq!(contains(&g, m.positions[0]), None);
        // Reversed winding: still closed, inside and outside unchanged.
        let rev = TriangleMesh::new(
            m.positions.clone(),
            None,
            None,
            m.indices.iter().map(|&[a, b, c]| [a, c, b]).collect(),
            false,
        );
        assert_eq!(outward_sign(&mesh(rev.clone())), Some(-1.0));
        assert_eq!(contains(&mesh(rev), c), Some(true));
    }

    /// Open meshes, a face with mixed orientation, duplicated faces and degenerate triangles
    /// are not closed; duplicated vertices at equal positions (a uv seam) are welded.
    #[test]
    fn only_closed_consistent_meshes_qualify() {
        let Geometry::Mesh(m) = mesh(sphere_mesh(Vec3::ZERO, 1.0, false)) else { unreachable!() };
        let with = |indices: Vec<[u32; 3]>, positions: Vec<Vec3>| {
            outward_sign(&mesh(TriangleMesh::new(positions, None, None, indices, false)))
        };
        let mut open = m.indices.clone();
        open.pop();
        assert_eq!(with(open, m.positions.clone()), None);
        let mut mixed = m.indices.clone();
        mixed[3] = [mixed[3][0], mixed[3][2], mixed[3][1]];
        assert_eq!(with(mixed, m.positions.clone()), None);
        let mut doubled = m.indices.clone();
        doubled.extend(m.indices.iter().copied());
        assert_eq!(with(doubled, m.positions.clone()), None);
        let mut degenerate = m.indices.clone();
        degenerate.push([0, 0, 1]);
        assert_eq!(with(degenerate, m.positions.clone()), None);
        // Every triangle with its own three vertices (no shared indices at all): welded, closed.
        let positions: Vec<Vec3> =
            m.indices.iter().flat_map(|t| t.map(|v| m.positions[v as usize])).collect();
        let indices = (0..m.indices.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        assert_eq!(with(indices, positions), Some(1.0));
        // A position no triangle uses changes nothing.
        let mut extra = m.positions.clone();
        extra.push(Vec3::splat(9.0));
        assert_eq!(with(m.indices.clone(), extra), Some(1.0));
        // Two disjoint closed spheres, both outward: closed. One of them reversed (a hollow
        // shell's inner wall, or an inconsistent file): not accepted.
        let Geometry::Mesh(b) = mesh(sphere_mesh(Vec3::new(5.0, 0.0, 0.0), 1.0, false)) else {
            unreachable!()
        };
        let n = m.positions.len() as u32;
        let positions: Vec<Vec3> = m.positions.iter().chain(&b.positions).copied().collect();
        let two: Vec<[u32; 3]> =
            m.indices.iter().copied().chain(b.indices.iter().map(|t| t.map(|v| v + n))).collect();
        assert_eq!(with(two.clone(), positions.clone()), Some(1.0));
        let reversed: Vec<[u32; 3]> = m
            .indices
            .iter()
            .copied()
            .chain(b.indices.iter().map(|&[x, y, z]| [x + n, z + n, y + n]))
            .collect();
        assert_eq!(with(reversed, positions), None);
    }

    #[test]
    fn analytic_shapes() {
        let s = Geometry::Sphere { center: Vec3::ONE, radius: 2.0, flip_normals: false };
        assert_eq!(outward_sign(&s), Some(1.0));
        assert_eq!(
            outward_sign(&Geometry::Sphere { center: Vec3::ONE, radius: 2.0, flip_normals: true }),
            Some(-1.0)
        );
        assert_eq!(contains(&s, Vec3::ONE), Some(true));
        assert_eq!(contains(&s, Vec3::new(1.0, 3.0, 1.0)), None);
        assert_eq!(contains(&s, Vec3::new(1.0, 3.1, 1.0)), Some(false));
        let d = Geometry::Disk { to_world: glam::Mat4::IDENTITY, flip_normals: false };
        assert_eq!(outward_sign(&d), None);
        assert_eq!(contains(&d, Vec3::ZERO), None);
    }
}

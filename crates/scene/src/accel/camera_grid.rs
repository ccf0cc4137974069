//! Closest hits of camera rays from a grid over the film (docs/performance.md §3.4).
//!
//! Every camera ray leaves the pinhole, so the rays through one region of the film lie in one
//! pyramid with its apex at the pinhole. [`CameraGrid`] cuts the film into cells and keeps, per
//! cell, the BVH leaves with a triangle inside the cell's pyramid, sorted by a lower bound of
//! their distance from the pinhole. A camera ray then tests its cell's leaves in that order and
//! stops at the first leaf that starts beyond its closest hit so far: no node of the tree is
//! visited. On the Mitsuba 3 peer scenes (48x48 pixels, spheres of 5-12k triangles) a cell
//! holds about 12 leaves, of which a camera ray tests about 4 (docs/performance.md §3.4).
//!
//! The answer is the tree's: every leaf holding a triangle that a ray of the cell can meet is in
//! the cell's list (the pyramid is widened by a margin far above the rounding of the rays'
//! directions and origins), each triangle is tested with the same watertight test, and a leaf
//! is skipped only when no point of it lies closer than the hit already found. Only between two
//! triangles at exactly the same distance may the choice differ (the tree's traversal order
//! decides there, here the list order); either is a hit of the ray.
//!
//! The grid is a function of the scene alone (camera and geometry), built once (by the render
//! loop before its first pass, else by the first camera ray), so images do not depend on
//! threads, passes or timing.

use super::{wide::WideNode, Accel, LEAF, WIDTH};
use crate::camera::Camera;
use glam::{DMat3, DVec3, Mat3, Vec3};
use haze_core::Ray;
use rayon::prelude::*;

/// Most cells the grid has: cells are one pixel up to this many pixels, larger beyond (the
/// build visits the tree once per cell, about 2 us each on the peer scenes).
const MAX_CELLS: f64 = 65_536.0;

/// Most leaves a cell's rays are expected to test: a cell whose probe rays (its centre and four
/// points near its corners, traced through the tree at build) would test more on average is
/// left to the tree, which prunes by boxes where a list cannot (a dense mesh seen from afar, a
/// large cell). On the homogeneous peer scenes 8 of 2,304 cells exceed it (at the spheres'
/// silhouettes), on the heterogeneous ones none.
const MAX_TESTS: usize = 48;

/// Fewest nodes a closest-hit tree needs for a grid. In a smaller tree (rooms and boxes of a few
/// dozen triangles) a camera ray visits one or two nodes, and the grid's cell lookup cost about
/// what it saved: hg-box, bench-fog-shadow and bench-spot-beam (1-3 nodes) measured 3-7% slower
/// with a grid (docs/performance.md §3.4).
const MIN_NODES: usize = 16;

/// Longest list a cell keeps (memory: 8 bytes per entry).
const MAX_LIST: usize = 1024;

/// Film cells (in camera-space slopes `x / z`, `y / z`, the pinhole's film plane at depth 1,
/// `crate::camera::FilmPlane`) with their leaf lists.
#[derive(Clone, Debug)]
pub struct CameraGrid {
    /// The pinhole.
    apex: Vec3,
    /// World directions to camera space (the inverse of the camera's linear part).
    to_local: Mat3,
    /// Slope of the first cell's edge and the inverse cell size, per axis.
    origin: [f32; 2],
    inv_size: [f32; 2],
    cells: [u32; 2],
    /// Per cell, `(start, count)` in `entries`, or `count == u32::MAX` for a cell left to the
    /// tree.
    spans: Vec<[u32; 2]>,
    /// A leaf and a lower bound of the distance from the pinhole to its triangles in the cell.
    entries: Vec<(u32, f32)>,
    /// How far (world units) a ray's line may pass from the pinhole and still use the grid.
    tolerance: f32,
}

/// A row of cells while the grid is built: each cell's `(start, count)` within the row's
/// entries, and the entries.
type Row = (Vec<[u32; 2]>, Vec<(u32, f32)>);

/// A cell's pyramid: points `x` with `n . (x - apex) <= margin` for each plane normal `n`
/// (four sides and the plane through the apex facing backwards).
struct Pyramid {
    apex: DVec3,
    planes: [DVec3; 5],
    margin: f64,
}

impl Pyramid {
    /// True when the box lies wholly outside one plane.
    fn box_outside(&self, lo: DVec3, hi: DVec3) -> bool {
        let c = (lo + hi) * 0.5 - self.apex;
        let h = (hi - lo) * 0.5;
        self.planes.iter().any(|n| n.dot(c) - n.abs().dot(h) > self.margin)
    }

    /// True when the triangle lies wholly outside one plane.
    fn triangle_outside(&self, v: &[DVec3; 3]) -> bool {
        self.planes.iter().any(|n| v.iter().all(|p| n.dot(*p - self.apex) > self.margin))
    }
}

impl CameraGrid {
    /// The grid of `camera` over `accel`'s triangles; `None` when there are none or too few to
    /// gain from it ([`MIN_NODES`]).
    ///
    /// `parallel` builds its rows on rayon's pool. Not from a pool thread inside a one-time
    /// initialisation (`OnceLock`): while it waits for its rows, the thread may run another task
    /// that asks for the same grid, and would wait on itself.
    pub fn build(accel: &Accel, camera: &Camera, parallel: bool) -> Option<Self> {
        // Only a pinhole's rays share an apex (any other ray would miss the grid anyway).
        if !camera.is_pinhole() || accel.bvh.as_ref()?.closest.nodes.len() < MIN_NODES {
            return None;
        }
        Self::build_any(accel, camera, parallel)
    }

    /// [`Self::build`] for a tree of any size.
    fn build_any(accel: &Accel, camera: &Camera, parallel: bool) -> Option<Self> {
        let bvh = accel.bvh.as_ref()?;
        let m = camera.to_world.as_dmat4();
        let apex = m.transform_point3(DVec3::ZERO);
        let lin = DMat3::from_mat4(m);
        let to_local = lin.inverse();
        // A plane `n_local . x_local <= 0` in world space: `(M^-T n_local) . (x - apex) <= 0`.
        let to_world_normal = to_local.transpose();
        // The film in slopes `x / z`, `y / z` (the camera's projection, in f64): its corner
        // `(W, H)` has the least slopes (camera `+x` is left, `+y` up), `(0, 0)` the greatest.
        // Camera rays take their directions from the same formula in f32, ~1e-7 of the film
        // away, well within the cells' widening below.
        let film = camera.film_plane::<f64>();
        let origin = film.plane_point(camera.width as f64, camera.height as f64);
        let far = film.plane_point(0.0, 0.0);
        let pixels = camera.width as f64 * camera.height as f64;
        let cell_pixels = (pixels / MAX_CELLS).sqrt().max(1.0);
        let nx = (camera.width as f64 / cell_pixels).ceil().max(1.0) as u32;
        let ny = (camera.height as f64 / cell_pixels).ceil().max(1.0) as u32;
        let size = [(far[0] - origin[0]) / nx as f64, (far[1] - origin[1]) / ny as f64];
        let (lo, hi) = accel.bounds();
        let scale =
            apex.abs().max_element().max(lo.abs().max_element() as f64).max(hi.abs().max_element() as f64);
        // About 80 f32 spacings of the largest coordinate: the rounding of a camera ray's origin
        // (`apex + t_near d` in f32) and of the triangle test are a few.
        let margin = 1e-5 * (1.0 + scale);
        let triangle = |leaf: u32, lane: usize| {
            let t = accel.leaves[leaf as usize].packet.triangle(lane);
            [0, 1, 2].map(|j| Vec3::from(t.vertex(j)).as_dvec3())
        };
        // One row of cells: its spans (starts within the row's entries) and entries.
        let row = |cy: u32| {
            let mut spans = Vec::with_capacity(nx as usize);
            let mut entries: Vec<(u32, f32)> = Vec::new();
            let mut stack = Vec::new();
            let mut found: Vec<(u32, f32)> = Vec::new();
            for cx in 0..nx {
                // Widened by a thousandth of the cell and a millionth of the film, far above
                // the f32 rounding of a direction's slopes (`to_local * d`, ~1e-7 of the film).
                let bounds = |axis: usize, c: u32, half: f64| {
                    let a = origin[axis] + size[axis] * c as f64;
                    let e = 1e-3 * size[axis] + 1e-6 * half;
                    (a - e, a + size[axis] + e)
                };
                let (a0, a1) = bounds(0, cx, film.half_x);
                let (b0, b1) = bounds(1, cy, film.half_y);
                let plane = |n: DVec3| (to_world_normal * n).normalize();
                let pyramid = Pyramid {
                    apex,
                    planes: [
                        plane(DVec3::new(1.0, 0.0, -a1)),
                        plane(DVec3::new(-1.0, 0.0, a0)),
                        plane(DVec3::new(0.0, 1.0, -b1)),
                        plane(DVec3::new(0.0, -1.0, b0)),
                        plane(DVec3::new(0.0, 0.0, -1.0)),
                    ],
                    margin,
                };
                found.clear();
                stack.clear();
                stack.push(0u32);
                let mut full = false;
                'walk: while let Some(n) = stack.pop() {
                    let node: &WideNode = &bvh.closest.nodes[n as usize];
                    for c in 0..WIDTH {
                        let Some((blo, bhi)) = node.child_bounds(c) else { continue };
                        if pyramid.box_outside(blo.as_dvec3(), bhi.as_dvec3()) {
                            continue;
                        }
                        let child = node.children[c];
                        if child & LEAF == 0 {
                            stack.push(child);
                            continue;
                        }
                        let leaf = child & !LEAF;
                        let count = accel.leaves[leaf as usize].packet.count() as usize;
                        // The nearest point of the box around the leaf's triangles inside the
                        // pyramid, less the margin.
                        let near = (0..count)
                            .map(|lane| triangle(leaf, lane))
                            .filter(|v| !pyramid.triangle_outside(v))
                            .map(|v| {
                                let blo = v[0].min(v[1]).min(v[2]);
                                let bhi = v[0].max(v[1]).max(v[2]);
                                (apex.clamp(blo, bhi) - apex).length()
                            })
                            .fold(f64::INFINITY, f64::min);
                        if near.is_finite() {
                            if found.len() == MAX_LIST {
                                full = true;
                                break 'walk;
                            }
                            let bound = ((near - 2.0 * margin).max(0.0) * (1.0 - 1e-6)) as f32;
                            found.push((leaf, bound));
                        }
                    }
                }
                found.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
                // How many leaves a probe ray from the pinhole through `(u, v)` (fractions of
                // the cell) would test: those starting before its hit.
                let tests = |u: f64, v: f64| {
                    let slope = DVec3::new(a0 + (a1 - a0) * u, b0 + (b1 - b0) * v, 1.0);
                    let d = (lin * slope).normalize().as_vec3();
                    let hit = accel.intersect_preliminary(&Ray::new(apex.as_vec3(), d));
                    let reach = hit.map_or(f32::INFINITY, |h| h.t());
                    found.partition_point(|e| e.1 <= reach)
                };
                let probes = [(0.5, 0.5), (0.1, 0.1), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)];
                if full || probes.iter().map(|&(u, v)| tests(u, v)).sum::<usize>() > MAX_TESTS * probes.len()
                {
                    spans.push([0, u32::MAX]);
                    continue;
                }
                spans.push([entries.len() as u32, found.len() as u32]);
                entries.extend_from_slice(&found);
            }
            (spans, entries)
        };
        let rows: Vec<Row> =
            if parallel { (0..ny).into_par_iter().map(row).collect() } else { (0..ny).map(row).collect() };
        let mut spans = Vec::with_capacity((nx * ny) as usize);
        let mut entries = Vec::with_capacity(rows.iter().map(|r| r.1.len()).sum());
        for (row_spans, row_entries) in rows {
            let base = entries.len() as u32;
            spans.extend(row_spans.into_iter().map(|[start, count]| [start + base, count]));
            entries.extend(row_entries);
        }
        Some(CameraGrid {
            apex: apex.as_vec3(),
            to_local: to_local.as_mat3(),
            origin: origin.map(|o| o as f32),
            inv_size: size.map(|s| (1.0 / s) as f32),
            cells: [nx, ny],
            spans,
            entries,
            tolerance: (0.25 * margin) as f32,
        })
    }

    /// The list of the cell `ray` goes through, with the distance from the pinhole to the ray's
    /// origin; `None` when the ray's line misses the pinhole by more than the grid allows,
    /// starts behind it, leaves the film's pyramid, or its cell is left to the tree.
    #[inline]
    pub(super) fn list(&self, ray: &Ray) -> Option<(&[(u32, f32)], f32)> {
        let rel = ray.o - self.apex;
        let along = rel.dot(ray.d);
        let tol = self.tolerance;
        if !(along >= -tol && rel.cross(ray.d).length_squared() <= tol * tol) {
            return None;
        }
        let local = self.to_local * ray.d;
        if local.z <= 0.0 {
            return None;
        }
        let inv_z = 1.0 / local.z;
        let u = (local.x * inv_z - self.origin[0]) * self.inv_size[0];
        let v = (local.y * inv_z - self.origin[1]) * self.inv_size[1];
        // Negative and NaN slopes fail too (`as u32` saturates them to 0, so test first).
        if !(u >= 0.0 && v >= 0.0) {
            return None;
        }
        let (cx, cy) = (u as u32, v as u32);
        if cx >= self.cells[0] || cy >= self.cells[1] {
            return None;
        }
        let [start, count] = self.spans[(cy * self.cells[0] + cx) as usize];
        if count == u32::MAX {
            return None;
        }
        // `|rel| <= |along| + |rel x d|`.
        Some((&self.entries[start as usize..(start + count) as usize], along.abs() + tol))
    }

    /// Cells, cells left to the tree, and list entries (for tests and reports).
    pub fn counts(&self) -> (usize, usize, usize) {
        let fallback = self.spans.iter().filter(|s| s[1] == u32::MAX).count();
        (self.spans.len(), fallback, self.entries.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::PreliminaryHit;
    use crate::bsdf::Bsdf;
    use crate::camera::PixelFilter;
    use crate::shape::{cube_mesh, Geometry, Shape, TriangleMesh};
    use glam::{Mat4, Vec4};
    use haze_core::Sampler;

    fn shape(geometry: Geometry) -> Shape {
        Shape { name: "s".into(), geometry, bsdf: Bsdf::Null, interior: None, exterior: None, emitter: None }
    }

    /// Mitsuba's `lookat` (camera space: `+x` left, `+y` up, `+z` forward), times `scale`.
    fn look_at(origin: Vec3, target: Vec3, up: Vec3, scale: Vec3) -> Mat4 {
        let dir = (target - origin).normalize();
        let left = up.cross(dir).normalize();
        let up = dir.cross(left);
        Mat4::from_cols(left.extend(0.0), up.extend(0.0), dir.extend(0.0), origin.extend(1.0))
            * Mat4::from_scale(scale)
    }

    /// A latitude-longitude sphere of `4 n^2` triangles (those at the poles degenerate).
    fn sphere(center: Vec3, radius: f32, n: u32) -> Geometry {
        let mut positions = Vec::new();
        for i in 0..=n {
            for j in 0..=2 * n {
                let (theta, phi) =
                    (std::f32::consts::PI * i as f32 / n as f32, std::f32::consts::PI * j as f32 / n as f32);
                positions.push(
                    center
                        + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()),
                );
            }
        }
        let at = |i: u32, j: u32| i * (2 * n + 1) + j;
        let mut indices = Vec::new();
        for i in 0..n {
            for j in 0..2 * n {
                indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        Geometry::Mesh(TriangleMesh::new(positions, None, None, indices, false))
    }

    /// `count` random triangles of about `size` in a cube of side `scale`.
    fn soup(s: &mut Sampler, count: usize, scale: f32, size: f32) -> Geometry {
        let mut positions = Vec::new();
        for _ in 0..count {
            let c = (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5) * scale;
            for _ in 0..3 {
                positions.push(c + size * Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5));
            }
        }
        let indices = (0..count as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        Geometry::Mesh(TriangleMesh::new(positions, None, None, indices, false))
    }

    fn camera(to_world: Mat4, fov: f32, film: (u32, u32), filter: PixelFilter) -> Camera {
        Camera { near_clip: 0.05, filter, ..Camera::pinhole(to_world, fov, film) }
    }

    /// The closest hit as `(t bits, shape, primitive)`.
    fn key(accel: &Accel, shapes: &[Shape], h: Option<PreliminaryHit>) -> Option<(u32, u32, u32)> {
        h.map(|h| {
            let si = accel.interaction(shapes, &h);
            (h.t().to_bits(), si.shape, si.prim)
        })
    }

    /// Camera rays through random film positions (the camera's own filter) get the tree's
    /// closest hit from the grid, bit for bit, also cut short at random distances; returns how
    /// many the grid answered (not left to the tree).
    fn agree(shapes: &[Shape], cam: &Camera, rays: usize, seed: u64) -> usize {
        let accel = Accel::build(shapes);
        let grid = CameraGrid::build_any(&accel, cam, true).expect("the scene has triangles");
        // Rows built on the pool or one after the other: the same grid.
        let serial = CameraGrid::build_any(&accel, cam, false).unwrap();
        assert!(grid.spans == serial.spans && grid.entries == serial.entries);
        let generator = cam.ray_generator();
        let mut s = Sampler::new(seed, 0, 0);
        let mut answered = 0;
        for i in 0..rays {
            let x = (s.next_1d() * cam.width as f32) as u32;
            let y = (s.next_1d() * cam.height as f32) as u32;
            let ray = generator.generate(cam.sample_film_position(x, y, &mut s));
            let ray = if i % 3 == 2 { Ray { t_max: ray.t_max * s.next_1d().powi(4), ..ray } } else { ray };
            answered += usize::from(grid.list(&ray).is_some());
            let tree = key(&accel, shapes, accel.intersect_preliminary(&ray));
            let from_grid = key(&accel, shapes, accel.intersect_camera(&grid, &ray));
            // Two triangles at exactly the same distance may be chosen either way.
            let tie = matches!((tree, from_grid), (Some(a), Some(b)) if a.0 == b.0);
            assert!(tree == from_grid || tie, "ray {i} {ray:?}: tree {tree:?}, grid {from_grid:?}");
        }
        answered
    }

    /// Spheres seen from outside, a closed room seen from inside (rays along its edges and
    /// corners), a soup of random triangles, an analytic sphere among meshes; cameras rotated,
    /// mirrored (`scale x = -1`) and stretched, wide and narrow, with the box and the gaussian
    /// filter (whose film positions reach past the pixel).
    #[test]
    fn camera_rays_get_the_trees_answers() {
        let mut s = Sampler::from_seed(5);
        let spheres =
            vec![shape(sphere(Vec3::ZERO, 1.0, 48)), shape(sphere(Vec3::new(0.8, 0.3, 0.9), 0.3, 24))];
        let room = vec![shape(Geometry::Mesh(cube_mesh(&Mat4::from_scale(Vec3::splat(2.0)), true)))];
        let soup = vec![shape(soup(&mut s, 3000, 6.0, 1.0))];
        let mut mixed = spheres.clone();
        mixed.push(shape(Geometry::Sphere {
            center: Vec3::new(-0.9, 0.2, 1.2),
            radius: 0.25,
            flip_normals: false,
        }));
        let outside = look_at(Vec3::new(0.3, 0.8, 4.0), Vec3::ZERO, Vec3::Y, Vec3::ONE);
        let tilted = look_at(
            Vec3::new(-3.0, 2.5, 1.0),
            Vec3::new(0.2, -0.1, 0.0),
            Vec3::new(0.3, 1.0, 0.1),
            Vec3::ONE,
        );
        let mirrored = look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, Vec3::new(-1.0, 1.0, 1.0));
        let stretched = look_at(Vec3::new(2.0, 1.0, 3.0), Vec3::ZERO, Vec3::Y, Vec3::new(1.0, 2.0, 1.5));
        let inside = look_at(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0), Vec3::Y, Vec3::ONE);
        let gaussian = PixelFilter::Gaussian { stddev: 0.5 };
        let cases = [
            (&spheres, camera(outside, 40.0, (48, 48), PixelFilter::Box)),
            (&spheres, camera(tilted, 70.0, (31, 17), gaussian)),
            (&spheres, camera(mirrored, 30.0, (20, 24), PixelFilter::Box)),
            (&spheres, camera(stretched, 50.0, (16, 16), PixelFilter::Tent { radius: 1.0 })),
            (&room, camera(inside, 100.0, (24, 24), PixelFilter::Box)),
            (
                &room,
                camera(
                    look_at(Vec3::new(1.5, -1.0, 0.3), Vec3::new(-2.0, 2.0, -2.0), Vec3::Y, Vec3::ONE),
                    90.0,
                    (9, 13),
                    gaussian,
                ),
            ),
            (
                &soup,
                camera(
                    look_at(Vec3::new(0.0, 0.0, 8.0), Vec3::ZERO, Vec3::Y, Vec3::ONE),
                    45.0,
                    (64, 48),
                    PixelFilter::Box,
                ),
            ),
            (
                &soup,
                camera(
                    look_at(Vec3::new(0.5, 0.2, 0.1), Vec3::new(3.0, 0.0, 0.0), Vec3::Y, Vec3::ONE),
                    60.0,
                    (40, 40),
                    PixelFilter::Box,
                ),
            ),
            (&mixed, camera(outside, 40.0, (32, 32), gaussian)),
        ];
        for (k, (shapes, cam)) in cases.iter().enumerate() {
            let rays = 6000;
            let answered = agree(shapes, cam, rays, k as u64);
            // The grid, not the tree, answered most of them (the soup seen from inside it has
            // crowded cells left to the tree).
            assert!(answered > rays / 2, "case {k}: the grid answered {answered} of {rays}");
        }
    }

    /// A 40-degree box-filtered camera on the `z` axis at `distance`, looking at the origin, and
    /// its grid over `accel`.
    fn on_axis(accel: &Accel, distance: f32, size: (u32, u32)) -> (Camera, CameraGrid) {
        let to_world = look_at(Vec3::new(0.0, 0.0, distance), Vec3::ZERO, Vec3::Y, Vec3::ONE);
        let cam = camera(to_world, 40.0, size, PixelFilter::Box);
        let grid = CameraGrid::build_any(accel, &cam, false).unwrap();
        (cam, grid)
    }

    /// A ray whose line misses the pinhole, one starting behind it, and one leaving the film's
    /// pyramid are left to the tree.
    #[test]
    fn other_rays_are_left_to_the_tree() {
        let shapes = vec![shape(sphere(Vec3::ZERO, 1.0, 16))];
        let accel = Accel::build(&shapes);
        let (cam, grid) = on_axis(&accel, 4.0, (8, 8));
        let ray = cam.generate_ray(glam::Vec2::new(4.2, 3.7));
        assert!(grid.list(&ray).is_some());
        let side = ray.d.cross(Vec3::Y).normalize();
        assert!(grid.list(&Ray { o: ray.o + 1e-3 * side, ..ray }).is_none());
        assert!(grid.list(&Ray { o: cam.position() - 0.1 * ray.d, ..ray }).is_none());
        let outside = Vec4::new(0.9, 0.0, 1.0, 0.0);
        let d = (cam.to_world * outside).truncate().normalize();
        assert!(grid.list(&Ray { o: cam.position() + 0.05 * d, d, t_max: 10.0 }).is_none());
        assert!(grid.list(&Ray { o: cam.position() - 0.05 * ray.d, d: -ray.d, t_max: 10.0 }).is_none());
    }

    /// A cell whose rays would test too many leaves is left to the tree; a scene without
    /// triangles has no grid, nor one whose tree is smaller than [`MIN_NODES`].
    #[test]
    fn crowded_cells_and_empty_scenes() {
        let mut s = Sampler::from_seed(3);
        // Dust: rays pass between thousands of tiny triangles and test every leaf in front.
        let shapes = vec![shape(soup(&mut s, 4000, 4.0, 0.01))];
        let accel = Accel::build(&shapes);
        let (cam, grid) = on_axis(&accel, 9.0, (3, 2));
        let (cells, crowded, _) = grid.counts();
        assert_eq!((cells, crowded), (6, 6));
        let ray = cam.generate_ray(glam::Vec2::new(1.5, 1.0));
        assert!(grid.list(&ray).is_none());
        let none = vec![shape(Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false })];
        assert!(CameraGrid::build_any(&Accel::build(&none), &cam, false).is_none());
        // A room of 12 triangles is one node: no grid.
        let room = vec![shape(Geometry::Mesh(cube_mesh(&Mat4::IDENTITY, true)))];
        assert!(CameraGrid::build(&Accel::build(&room), &cam, true).is_none());
        assert!(CameraGrid::build_any(&Accel::build(&room), &cam, true).is_some());
    }
}

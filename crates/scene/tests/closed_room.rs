//! No path leaves a closed triangle room (issue 16, "the leak").
//!
//! Random walks bounce inside closed mesh rooms the way the integrators do (diffuse bounces from
//! the offset origin `offset_origin(p, n, d)`, and scattering at points of a medium, which may
//! lie arbitrarily close to a wall, edge or corner) and count every ray that finds no wall. It
//! must be zero. Before the fix, the axis-aligned cube room leaked about one ray in 10^5: the
//! BVH's flat node boxes (a face of an axis-aligned cube has zero thickness) were missed by rays
//! through the cube's edges, and boxes left before `t = 1e-4` (obvhs's fixed traversal `tmin`)
//! were culled, which loses walls right at a corner.

use glam::Vec3;
use haze_core::ray::offset_origin;
use haze_core::sampling::{sample_cosine_hemisphere, sample_uniform_sphere};
use haze_core::{Frame, Ray, Sampler};
use haze_scene::{load_str, LoadOptions, Scene};
use std::path::Path;

fn room(transform: &str) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
            <sensor type="perspective"/>
            <shape type="cube">
                <boolean name="flip_normals" value="true"/>
                <transform name="to_world">{transform}</transform>
            </shape>
        </scene>"#
    );
    load_str(&xml, Path::new("room.xml"), Path::new("."), &LoadOptions::default()).unwrap()
}

/// Walks `paths` random paths of `bounces` bounces each from `start`; returns the number of rays
/// that found no wall or a wall from outside (each such path restarts from `start`) and the
/// number of rays traced. Half the bounces are diffuse reflections at the wall; the others are
/// "medium" events at a point before the wall, from `1e-5 (1 + |p|)` (about 20 f32 spacings,
/// and inside obvhs's box `tmin` of `1e-4`) to 1 away from its plane, biased towards the wall
/// so that scattering points come very close to walls, edges and corners. (Closer still,
/// rounding may put the point on or past the wall, where neither side is right.) A medium event
/// is followed by a reflection, so that the next point is not close to two walls by chance.
fn walk(scene: &Scene, start: Vec3, paths: u32, bounces: u32, seed: u64) -> (u64, u64) {
    let mut s = Sampler::from_seed(seed);
    let (mut escaped, mut traced) = (0u64, 0u64);
    for _ in 0..paths {
        let mut ray = Ray::new(start, sample_uniform_sphere(s.next_2d()));
        let mut after_medium = false;
        for _ in 0..bounces {
            traced += 1;
            let Some(h) = scene.intersect(&ray).filter(|h| h.n.dot(ray.d) < 0.0) else {
                escaped += 1;
                break;
            };
            if !after_medium && s.next_1d() < 0.5 {
                let min = 1e-5 * (1.0 + h.p.abs().max_element());
                let gap = min * (1.0 / min).powf(s.next_1d());
                let back = (gap / -h.n.dot(ray.d)).min(h.t);
                ray = Ray::new(ray.at(h.t - back), sample_uniform_sphere(s.next_2d()));
                after_medium = true;
            } else {
                let d = Frame::from_normal(h.n).to_world(sample_cosine_hemisphere(s.next_2d()));
                ray = Ray::new(offset_origin(h.p, h.n, d), d);
                after_medium = false;
            }
        }
    }
    (escaped, traced)
}

fn assert_closed(transform: &str, start: Vec3, seed: u64) {
    let scene = room(transform);
    let (escaped, traced) = walk(&scene, start, 2_000, 1_000, seed);
    assert_eq!(escaped, 0, "{escaped} of {traced} rays left the closed room `{transform}`");
}

/// The room of `leak_closed_cube_room.xml`: faces on the axes, so each face's BVH box is flat.
#[test]
fn axis_aligned_cube_room_holds_every_path() {
    assert_closed(r#"<scale x="3" y="2" z="6"/><translate y="2"/>"#, Vec3::new(0.0, 1.0, 5.0), 1);
}

/// `leak_closed_cube_room_rotated.xml`'s room: no flat boxes, corners off the axes.
#[test]
fn rotated_cube_room_holds_every_path() {
    assert_closed(
        r#"<scale x="3" y="2" z="6"/><rotate x="1" y="1" z="0.3" angle="17"/><translate y="2"/>"#,
        Vec3::new(0.0, 1.0, 5.0),
        2,
    );
}

/// A room far from the origin (ray origins and walls with large coordinates).
#[test]
fn distant_cube_room_holds_every_path() {
    assert_closed(
        r#"<scale x="3" y="2" z="6"/><translate x="1000" y="-3000" z="2000"/>"#,
        Vec3::new(1000.0, -3000.0, 2001.0),
        3,
    );
}

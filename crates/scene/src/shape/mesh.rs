//! Triangle meshes in world space.

use glam::{Vec2, Vec3};

/// Indexed triangle mesh, positions already in world space.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (world space), if the file had them.
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Mitsuba's `flip_normals`: swaps inside and outside.
    pub flip_normals: bool,
}

impl TriangleMesh {
    pub fn new(
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        indices: Vec<[u32; 3]>,
        flip_normals: bool,
    ) -> Self {
        TriangleMesh { positions, normals, uvs, indices, flip_normals }
    }

    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        let t = self.indices[i];
        [self.positions[t[0] as usize], self.positions[t[1] as usize], self.positions[t[2] as usize]]
    }

    /// Geometric normal `normalize((p1 - p0) x (p2 - p0))`, negated with `flip_normals`.
    pub fn face_normal(&self, i: usize) -> Vec3 {
        let [p0, p1, p2] = self.vertices(i);
        let n = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        if self.flip_normals {
            -n
        } else {
            n
        }
    }

    pub fn triangle_area(&self, i: usize) -> f32 {
        let [p0, p1, p2] = self.vertices(i);
        0.5 * (p1 - p0).cross(p2 - p0).length()
    }
}

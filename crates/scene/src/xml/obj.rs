//! Wavefront OBJ meshes (`<shape type="obj">`), read with `tobj`.

use crate::shape::TriangleMesh;
use glam::{Vec2, Vec3};
use std::io::BufReader;
use std::path::Path;

/// Reads an OBJ file into one mesh in object space: polygons are triangulated (as a fan), all
/// objects and groups are merged, points and lines are ignored, and materials are not read
/// (a missing `.mtl` file is no error). Normals and texture coordinates are kept only if every
/// vertex has them.
pub(super) fn load(path: &Path) -> Result<TriangleMesh, String> {
    let file = super::ply::open_mesh_file(path)?;
    let options =
        tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let (models, _) = tobj::load_obj_buf(&mut BufReader::new(file), &options, |_| Ok(Default::default()))
        .map_err(|e| format!("invalid OBJ: {e}"))?;

    let mut mesh = TriangleMesh::default();
    let mut normals = Some(Vec::new());
    let mut uvs = Some(Vec::new());
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let n = m.positions.len() / 3;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        if m.normals.len() != 3 * n {
            normals = None;
        }
        if let Some(normals) = normals.as_mut() {
            normals.extend(m.normals.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        }
        if m.texcoords.len() != 2 * n {
            uvs = None;
        }
        if let Some(uvs) = uvs.as_mut() {
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        }
        for t in m.indices.chunks_exact(3) {
            mesh.indices.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    mesh.normals = normals.filter(|n| !n.is_empty());
    mesh.uvs = uvs.filter(|u| !u.is_empty());
    Ok(mesh)
}

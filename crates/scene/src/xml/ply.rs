//! Stanford PLY meshes (`<shape type="ply">`), ASCII or binary, read with `ply-rs-bw`.

use crate::shape::TriangleMesh;
use glam::{Vec2, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

/// Names of texture coordinate pairs, as Mitsuba 3 accepts them.
const UV_NAMES: &[(&str, &str)] =
    &[("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

/// Reads a PLY file into a mesh in object space. Vertex positions `x`, `y`, `z` of any numeric
/// type (float or double, ...); optional normals `nx`, `ny`, `nz` and texture coordinates
/// (`u`/`v`, `s`/`t`, ...); faces as index lists named `vertex_indices` or `vertex_index`,
/// polygons triangulated as a fan.
pub(super) fn load(path: &Path) -> Result<TriangleMesh, String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut BufReader::new(file))
        .map_err(|e| format!("invalid PLY: {e}"))?;
    let vertices = ply.payload.get("vertex").ok_or("invalid PLY: no 'vertex' element")?;
    let faces = ply.payload.get("face").ok_or("invalid PLY: no 'face' element")?;

    let positions = vertices
        .iter()
        .enumerate()
        .map(|(i, v)| vec3(v, ["x", "y", "z"]).ok_or(format!("invalid PLY: vertex {i} has no x, y, z")))
        .collect::<Result<Vec<Vec3>, String>>()?;
    let normals: Option<Vec<Vec3>> = vertices.iter().map(|v| vec3(v, ["nx", "ny", "nz"])).collect();
    let uvs = UV_NAMES.iter().find_map(|(u, v)| {
        vertices.iter().map(|e| Some(Vec2::new(scalar(e, u)?, scalar(e, v)?))).collect::<Option<Vec<Vec2>>>()
    });

    let mut indices = Vec::with_capacity(faces.len());
    for (i, face) in faces.iter().enumerate() {
        let list = face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
            .and_then(Property::to_u32_list)
            .ok_or(format!("invalid PLY: face {i} has no vertex_indices list"))?;
        if list.len() < 3 {
            return Err(format!("invalid PLY: face {i} has {} vertices", list.len()));
        }
        for k in 1..list.len() - 1 {
            indices.push([list[0], list[k], list[k + 1]]);
        }
    }
    Ok(TriangleMesh::new(
        positions,
        normals.filter(|n| !n.is_empty()),
        uvs.filter(|u| !u.is_empty()),
        indices,
        false,
    ))
}

fn scalar(e: &DefaultElement, key: &str) -> Option<f32> {
    e.get(key)?.to_f32_lossy()
}

fn vec3(e: &DefaultElement, keys: [&str; 3]) -> Option<Vec3> {
    Some(Vec3::new(scalar(e, keys[0])?, scalar(e, keys[1])?, scalar(e, keys[2])?))
}

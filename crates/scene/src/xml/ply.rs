//! Stanford PLY meshes (`<shape type="ply">`), ASCII or binary, read with `ply-rs-bw`.

use crate::shape::TriangleMesh;
use glam::{Vec2, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

/// Names of texture coordinate pairs, as Mitsuba 3 accepts them.
const UV_NAMES: &[(&str, &str)] =
    &[("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

/// Reads a PLY file into a mesh in object space. Vertex positions `x`, `y`, `z` of any numeric
/// type (float or double, ...); optional normals `nx`, `ny`, `nz` and texture coordinates
/// (`u`/`v`, `s`/`t`, ...); faces as index lists named `vertex_indices` or `vertex_index`,
/// polygons triangulated as a fan.
pub(super) fn load(path: &Path) -> Result<TriangleMesh, String> {
    let file = open_mesh_file(path)?;
    let size = file.get_ref().metadata().map_err(|e| e.to_string())?.len();
    let mut reader = BufReader::new(file);
    check_ply_header(&mut reader, size)?;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| format!("invalid PLY: {}", one_line(&e.to_string())))?;
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

/// Largest mesh file haze reads.
pub(super) const MAX_MESH_FILE_BYTES: u64 = 2 << 30;

/// Opens a mesh file for reading: a regular file (not a device such as `/dev/zero` or a pipe)
/// of at most [`MAX_MESH_FILE_BYTES`], read through a limit so that a file growing while it is
/// read cannot exhaust memory either.
pub(super) fn open_mesh_file(path: &Path) -> Result<std::io::Take<File>, String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let meta = file.metadata().map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > MAX_MESH_FILE_BYTES {
        return Err(format!(
            "the file is {} bytes; haze reads mesh files of at most {MAX_MESH_FILE_BYTES} bytes",
            meta.len()
        ));
    }
    Ok(file.take(MAX_MESH_FILE_BYTES))
}

/// Reads the PLY header ahead of the parser (without consuming it) and refuses element counts
/// the file cannot hold (each element takes at least one byte), which would otherwise make
/// the parser reserve memory for them.
fn check_ply_header(reader: &mut BufReader<std::io::Take<File>>, size: u64) -> Result<(), String> {
    use std::io::BufRead;
    let head = reader.fill_buf().map_err(|e| e.to_string())?;
    let text = String::from_utf8_lossy(&head[..head.len().min(64 << 10)]);
    for line in text.lines().take_while(|l| l.trim() != "end_header") {
        let words: Vec<&str> = line.split_whitespace().collect();
        if let ["element", name, count] = words[..] {
            let count: u64 =
                count.parse().map_err(|_| format!("invalid PLY: bad count in '{}'", one_line(line)))?;
            if count > size {
                return Err(format!(
                    "invalid PLY: the header declares {count} '{name}' elements, more than the file's {size} bytes can hold"
                ));
            }
        }
    }
    Ok(())
}

/// A parser message on one line (ply-rs's can span several, with a debug dump).
fn one_line(s: &str) -> String {
    let s = s.split_whitespace().collect::<Vec<_>>().join(" ");
    if s.chars().count() > 300 {
        let cut = s.char_indices().nth(300).map_or(s.len(), |(i, _)| i);
        format!("{}...", &s[..cut])
    } else {
        s
    }
}

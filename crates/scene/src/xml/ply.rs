//! Stanford PLY meshes (`<shape type="ply">`), ASCII or binary, read with `ply-rs-bw`, with
//! their other vertex and face properties as Mitsuba 3's mesh attributes.

use crate::bitmap::srgb_to_linear;
use crate::mesh_attribute::AttributeArray;
use crate::shape::TriangleMesh;
use glam::{Vec2, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, KeyMap, Property, PropertyDef};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

/// Names of texture coordinate pairs, as Mitsuba 3 accepts them.
const UV_NAMES: &[(&str, &str)] =
    &[("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

/// Reads a PLY file into a mesh in object space. Vertex positions `x`, `y`, `z` of any numeric
/// type (float or double, ...); optional normals `nx`, `ny`, `nz` and texture coordinates
/// (`u`/`v`, `s`/`t`, ...); faces as index lists named `vertex_indices` or `vertex_index`,
/// polygons triangulated as a fan. The other properties become attributes ([`attributes`]); a
/// face attribute has one row per triangle (a polygon's row repeated for each of its
/// triangles; Mitsuba 3 reads triangles only).
pub(super) fn load(path: &Path) -> Result<(TriangleMesh, Vec<AttributeArray>), String> {
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

    let uv_names = UV_NAMES
        .iter()
        .find(|(u, v)| vertices.first().is_some_and(|e| e.contains_key(*u) && e.contains_key(*v)));
    let mut reserved = vec!["x", "y", "z", "nx", "ny", "nz"];
    reserved.extend(uv_names.iter().flat_map(|(u, v)| [*u, *v]));
    let element_def = |name: &str| ply.header.elements.get(name).map(|e| &e.properties);
    let mut attrs =
        element_def("vertex").map_or(Vec::new(), |d| attributes("vertex_", d, vertices, &reserved));
    let mut face_attrs = element_def("face")
        .map_or(Vec::new(), |d| attributes("face_", d, faces, &["vertex_indices", "vertex_index"]));

    let mut indices = Vec::with_capacity(faces.len());
    let mut face_of_triangle = Vec::with_capacity(faces.len());
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
            face_of_triangle.push(i);
        }
    }
    if face_of_triangle.len() != faces.len() {
        for a in &mut face_attrs {
            let dim = a.dim;
            a.values =
                face_of_triangle.iter().flat_map(|&f| a.values[f * dim..(f + 1) * dim].to_vec()).collect();
        }
    }
    attrs.append(&mut face_attrs);
    let mesh = TriangleMesh::new(
        positions,
        normals.filter(|n| !n.is_empty()),
        uvs.filter(|u| !u.is_empty()),
        indices,
        false,
    );
    Ok((mesh, attrs))
}

/// The attributes of one PLY element (`prefix` is `vertex_` or `face_`), grouped as Mitsuba
/// 3.9.1's PLY loader groups them (`find_other_fields` in its `ply.h`), skipping `reserved`:
/// - `r`, `g`, `b` (or `red`, `green`, `blue`), and `a` (or `alpha`) if present, give
///   `{prefix}color` with 3 (or 4) channels;
/// - consecutive properties `{name}_{c}` with the suffixes `x y z w`, `r g b a`, `0 1 2 3` or
///   `1 2 3 4`, in that order, give `{prefix}{name}` (`{prefix}{name}_color` for `r g b a`) if
///   there are 1 or 3 of them; other properties are ignored (Mitsuba warns).
///
/// Values as Mitsuba 3.9.1 reads them (measured with its `attribute_buffer`): floats and
/// `uchar`s as they are (a `uchar` 128 stays 128), the other integer types divided by their
/// largest value and then decoded from sRGB (its `Normalized | Gamma` struct fields; `short`
/// 100 gives `srgb_to_linear(100 / 32767)`).
fn attributes(
    prefix: &str,
    defs: &KeyMap<PropertyDef>,
    rows: &[DefaultElement],
    reserved: &[&str],
) -> Vec<AttributeArray> {
    let names: Vec<&str> = defs.keys().map(String::as_str).filter(|n| !reserved.contains(n)).collect();
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    let has = |n: &str| names.contains(&n);
    let colour = if has("r") && has("g") && has("b") {
        Some(["r", "g", "b", "a"])
    } else if has("red") && has("green") && has("blue") {
        Some(["red", "green", "blue", "alpha"])
    } else {
        None
    };
    if let Some(c) = colour {
        let n = if has(c[3]) { 4 } else { 3 };
        groups.push((format!("{prefix}color"), c[..n].to_vec()));
    }
    const SUFFIXES: [&str; 4] = ["xyzw", "rgba", "0123", "1234"];
    let mut seen: Vec<&str> = Vec::new();
    // The attribute being read: its name before `_`, its suffix family, its properties.
    let mut current: Open = None;
    type Open<'a> = Option<(&'a str, usize, Vec<&'a str>)>;
    fn flush<'a>(prefix: &str, current: &mut Open<'a>, groups: &mut Vec<(String, Vec<&'a str>)>) {
        if let Some((stem, family, fields)) = current.take() {
            if matches!(fields.len(), 1 | 3) {
                let tail = if family == 1 { "_color" } else { "" };
                groups.push((format!("{prefix}{stem}{tail}"), fields));
            }
        }
    }
    for &name in &names {
        if matches!(name, "r" | "g" | "b" | "a") || colour.is_some_and(|c| c.contains(&name)) {
            continue;
        }
        let Some((stem, suffix)) = name.rsplit_once('_') else {
            flush(prefix, &mut current, &mut groups);
            continue;
        };
        let mut chars = suffix.chars();
        let (Some(c), None) = (chars.next(), chars.next()) else {
            flush(prefix, &mut current, &mut groups);
            continue;
        };
        if current.as_ref().is_some_and(|(s, _, _)| *s != stem) {
            flush(prefix, &mut current, &mut groups);
        }
        match &mut current {
            Some((_, family, fields)) => {
                let next = SUFFIXES[*family].chars().nth(fields.len());
                if next == Some(c) {
                    fields.push(name);
                } else {
                    // An out-of-order suffix: Mitsuba drops the whole attribute.
                    current = None;
                    seen.push(stem);
                }
            }
            None if seen.contains(&stem) => {}
            None => {
                if let Some(family) = SUFFIXES.iter().position(|s| s.starts_with(c)) {
                    seen.push(stem);
                    current = Some((stem, family, vec![name]));
                }
            }
        }
    }
    flush(prefix, &mut current, &mut groups);
    groups
        .into_iter()
        .map(|(name, fields)| AttributeArray {
            name,
            dim: fields.len(),
            values: rows
                .iter()
                .flat_map(|r| fields.iter().map(|f| r.get(*f).map_or(0.0, attribute_value)))
                .collect(),
        })
        .collect()
}

/// A PLY number as Mitsuba 3.9.1 stores it in an attribute (see [`attributes`]).
fn attribute_value(p: &Property) -> f32 {
    let normalized = |v: f64, max: f64| srgb_to_linear((v / max) as f32);
    match *p {
        Property::UChar(v) => f32::from(v),
        Property::Char(v) => normalized(v.into(), i8::MAX.into()),
        Property::Short(v) => normalized(v.into(), i16::MAX.into()),
        Property::UShort(v) => normalized(v.into(), u16::MAX.into()),
        Property::Int(v) => normalized(v.into(), i32::MAX.into()),
        Property::UInt(v) => normalized(v.into(), u32::MAX.into()),
        Property::Float(v) => v,
        Property::Double(v) => v as f32,
        _ => 0.0,
    }
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

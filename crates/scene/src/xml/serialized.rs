//! Mitsuba's `.serialized` meshes (`<shape type="serialized">`), format versions 3 and 4 (what
//! Mitsuba 0.5 to 3.x write and public scenes hold), as Mitsuba 3's `serialized` plugin
//! documents them (`src/shapes/serialized.cpp`):
//!
//! Little endian. Each mesh: `u16` magic `0x041C`, `u16` version (3 or 4), then one zlib
//! stream of: `u32` flags (`0x0001` vertex normals, `0x0002` texture coordinates, `0x0008`
//! vertex colours, `0x2000` double precision, else single), version 4 only a NUL-terminated
//! name, `u64` vertex count `V`, `u64` triangle count `F`, `3V` positions, `3V` normals (if
//! flagged), `2V` texture coordinates (if flagged), `3V` colours (if flagged, skipped), `3F`
//! `u32` vertex indices. Meshes are concatenated; the file ends with the offset of every mesh
//! (`u64` in version 4, `u32` in version 3) and the `u32` mesh count, which `shape_index`
//! selects through.

use crate::shape::TriangleMesh;
use flate2::read::ZlibDecoder;
use glam::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Most vertices or triangles of one mesh haze reads (each index fits a `u32`; beyond this
/// the arrays alone would take tens of GB).
const MAX_ELEMENTS: u64 = 1 << 30;

/// Reads mesh `shape_index` of the `.serialized` file `path` in object space.
pub(super) fn load(path: &Path, shape_index: u32) -> Result<TriangleMesh, String> {
    let mut bytes = Vec::new();
    super::ply::open_mesh_file(path)?.read_to_end(&mut bytes).map_err(|e| e.to_string())?;
    parse(&bytes, shape_index)
}

/// [`load`] of the file's bytes.
pub(super) fn parse(bytes: &[u8], shape_index: u32) -> Result<TriangleMesh, String> {
    let version = header(bytes, 0)?;
    let offset = if shape_index == 0 { 0 } else { mesh_offset(bytes, version, shape_index)? };
    let version = header(bytes, offset)?;
    let mut z = ZlibDecoder::new(&bytes[offset + 4..]);
    let mut r = Reader { z: &mut z };
    let flags = r.u32()?;
    if version == 4 {
        // The mesh's name, NUL-terminated (not used).
        let mut len = 0;
        while r.u8()? != 0 {
            len += 1;
            if len > 1 << 16 {
                return Err("the mesh name does not end".into());
            }
        }
    }
    let vertex_count = r.u64()?;
    let face_count = r.u64()?;
    if vertex_count > MAX_ELEMENTS || face_count > MAX_ELEMENTS {
        return Err(format!(
            "{vertex_count} vertices and {face_count} triangles: haze reads meshes of at most {MAX_ELEMENTS} of each"
        ));
    }
    if face_count == 0 {
        return Err("the mesh has no triangles".into());
    }
    let (v, f) = (vertex_count as usize, face_count as usize);
    let double = flags & DOUBLE_PRECISION != 0;
    let positions = r.floats(3 * v, double)?;
    let normals = if flags & HAS_NORMALS != 0 { Some(r.floats(3 * v, double)?) } else { None };
    let uvs = if flags & HAS_TEXCOORDS != 0 { Some(r.floats(2 * v, double)?) } else { None };
    if flags & HAS_COLORS != 0 {
        r.floats(3 * v, double)?; // vertex colours: haze has no use for them (nor has Mitsuba 3)
    }
    let raw = r.bytes(12 * f)?;
    let indices = raw
        .chunks_exact(12)
        .map(|t| {
            std::array::from_fn(|k| u32::from_le_bytes(t[4 * k..4 * k + 4].try_into().unwrap_or([0; 4])))
        })
        .collect();
    let vec3s = |a: Vec<f32>| a.chunks_exact(3).map(Vec3::from_slice).collect::<Vec<Vec3>>();
    Ok(TriangleMesh::new(
        vec3s(positions),
        normals.map(vec3s),
        uvs.map(|a| a.chunks_exact(2).map(Vec2::from_slice).collect()),
        indices,
        false,
    ))
}

/// The version of the mesh header at `offset` (3 or 4).
fn header(bytes: &[u8], offset: usize) -> Result<u16, String> {
    let h = bytes.get(offset..offset + 4).ok_or("the file ends inside a mesh header")?;
    let magic = u16::from_le_bytes([h[0], h[1]]);
    let version = u16::from_le_bytes([h[2], h[3]]);
    if magic != MAGIC {
        return Err(format!(
            "not a Mitsuba .serialized mesh (magic number {magic:#06x}, expected {MAGIC:#06x})"
        ));
    }
    match version {
        3 | 4 => Ok(version),
        _ => Err(format!("unsupported .serialized version {version} (haze reads versions 3 and 4)")),
    }
}

/// The file offset of mesh `index`, from the dictionary at the end of the file.
fn mesh_offset(bytes: &[u8], version: u16, index: u32) -> Result<usize, String> {
    let n = bytes.len();
    let tail =
        |at: usize, len: usize| bytes.get(at..at + len).ok_or("the file's mesh dictionary is truncated");
    let count = u32::from_le_bytes(
        tail(n.checked_sub(4).ok_or("the file is empty")?, 4)?.try_into().unwrap_or([0; 4]),
    );
    if index >= count {
        return Err(format!("shape_index {index} is out of range: the file holds {count} meshes"));
    }
    let rest = (count - index) as usize;
    let offset = if version >= 4 {
        let at = n.checked_sub(4 + 8 * rest).ok_or("the file's mesh dictionary is truncated")?;
        u64::from_le_bytes(tail(at, 8)?.try_into().unwrap_or([0; 8]))
    } else {
        let at = n.checked_sub(4 * (rest + 1)).ok_or("the file's mesh dictionary is truncated")?;
        u64::from(u32::from_le_bytes(tail(at, 4)?.try_into().unwrap_or([0; 4])))
    };
    usize::try_from(offset)
        .ok()
        .filter(|&o| o < n)
        .ok_or(format!("mesh {index} starts past the end of the file"))
}

/// Little-endian values from the decompressed stream; a stream that ends early is an error.
struct Reader<'a, R: Read> {
    z: &'a mut R,
}

impl<R: Read> Reader<'_, R> {
    /// Exactly `n` bytes. The buffer grows with what arrives (a header announcing more than
    /// the stream holds allocates no more than the stream gives).
    fn bytes(&mut self, n: usize) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        (&mut *self.z)
            .take(n as u64)
            .read_to_end(&mut out)
            .map_err(|e| format!("corrupt compressed data: {e}"))?;
        if out.len() != n {
            return Err("the compressed mesh data ends early".into());
        }
        Ok(out)
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.bytes(1)?[0])
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.bytes(4)?.try_into().unwrap_or([0; 4])))
    }

    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.bytes(8)?.try_into().unwrap_or([0; 8])))
    }

    /// `n` floats, stored as `f64` when `double`, else `f32`.
    fn floats(&mut self, n: usize, double: bool) -> Result<Vec<f32>, String> {
        Ok(if double {
            self.bytes(8 * n)?
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f32)
                .collect()
        } else {
            self.bytes(4 * n)?
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().unwrap_or([0; 4])))
                .collect()
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use flate2::write::ZlibEncoder;
    use std::io::Write;

    /// One mesh in Mitsuba's format, written from its documentation: version 3 or 4, with
    /// optional normals and uvs, single or double precision.
    pub(crate) struct MeshRecord<'a> {
        pub positions: &'a [[f64; 3]],
        pub normals: Option<&'a [[f64; 3]]>,
        pub uvs: Option<&'a [[f64; 2]]>,
        pub colors: bool,
        pub triangles: &'a [[u32; 3]],
        pub double: bool,
    }

    /// A whole file of `meshes`, with the end-of-file dictionary.
    pub(crate) fn write_serialized(version: u16, meshes: &[MeshRecord]) -> Vec<u8> {
        let mut file = Vec::new();
        let mut offsets = Vec::new();
        for m in meshes {
            offsets.push(file.len() as u64);
            file.extend_from_slice(&MAGIC.to_le_bytes());
            file.extend_from_slice(&version.to_le_bytes());
            let mut body = Vec::new();
            let flag = |on: bool, bit: u32| if on { bit } else { 0 };
            let flags = flag(m.normals.is_some(), HAS_NORMALS)
                | flag(m.uvs.is_some(), HAS_TEXCOORDS)
                | flag(m.colors, HAS_COLORS)
                | flag(m.double, DOUBLE_PRECISION)
                | flag(!m.double, 0x1000);
            body.extend_from_slice(&flags.to_le_bytes());
            if version == 4 {
                body.extend_from_slice(b"mesh name\0");
            }
            body.extend_from_slice(&(m.positions.len() as u64).to_le_bytes());
            body.extend_from_slice(&(m.triangles.len() as u64).to_le_bytes());
            let mut put = |xs: &[f64]| {
                for &x in xs {
                    if m.double {
                        body.extend_from_slice(&x.to_le_bytes());
                    } else {
                        body.extend_from_slice(&(x as f32).to_le_bytes());
                    }
                }
            };
            put(m.positions.as_flattened());
            if let Some(n) = m.normals {
                put(n.as_flattened());
            }
            if let Some(uv) = m.uvs {
                put(uv.as_flattened());
            }
            if m.colors {
                put(&vec![0.5; 3 * m.positions.len()]);
            }
            for t in m.triangles {
                for i in t {
                    body.extend_from_slice(&i.to_le_bytes());
                }
            }
            let mut z = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&body).unwrap();
            file.extend_from_slice(&z.finish().unwrap());
        }
        for o in &offsets {
            if version == 4 {
                file.extend_from_slice(&o.to_le_bytes());
            } else {
                file.extend_from_slice(&(*o as u32).to_le_bytes());
            }
        }
        file.extend_from_slice(&(meshes.len() as u32).to_le_bytes());
        file
    }

    const QUAD: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    const TRIS: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    #[test]
    fn reads_every_field_of_both_versions_and_precisions() {
        let normals = [[0.0, 0.0, 1.0]; 4];
        let uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.25, 0.75]];
        let tri = [[2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 0.0, 1.0]];
        for version in [3, 4] {
            for double in [false, true] {
                let quad = MeshRecord {
                    positions: &QUAD,
                    normals: Some(&normals),
                    uvs: Some(&uvs),
                    colors: true,
                    triangles: &TRIS,
                    double,
                };
                let second = MeshRecord {
                    positions: &tri,
                    normals: None,
                    uvs: None,
                    colors: false,
                    triangles: &[[0, 1, 2]],
                    double,
                };
                let file = write_serialized(version, &[quad, second]);
                let m = parse(&file, 0).unwrap();
                assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
                assert_eq!(m.indices, TRIS.to_vec());
                assert_eq!(m.normals.as_ref().unwrap()[3], Vec3::Z);
                assert_eq!(m.uvs.as_ref().unwrap()[3], Vec2::new(0.25, 0.75));
                let m = parse(&file, 1).unwrap();
                assert_eq!((m.positions.len(), m.indices.len(), m.normals, m.uvs), (3, 1, None, None));
                assert_eq!(m.positions[2], Vec3::new(2.0, 0.0, 1.0), "version {version}, double {double}");
                let e = parse(&file, 2).unwrap_err();
                assert!(e.contains("shape_index 2 is out of range: the file holds 2 meshes"), "{e}");
            }
        }
    }

    /// Through the loader: `shape_index`, `to_world`, `face_normals`, and errors naming the
    /// element.
    #[test]
    fn the_shape_plugin_selects_transforms_and_reports() {
        let dir = std::env::temp_dir().join(format!("haze-serialized-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let normals = [[0.0, 0.0, 1.0]; 4];
        let tri = [[2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 0.0, 1.0]];
        let quad = MeshRecord {
            positions: &QUAD,
            normals: Some(&normals),
            uvs: None,
            colors: false,
            triangles: &TRIS,
            double: false,
        };
        let second = MeshRecord {
            positions: &tri,
            normals: None,
            uvs: None,
            colors: false,
            triangles: &[[0, 1, 2]],
            double: true,
        };
        std::fs::write(dir.join("two.serialized"), write_serialized(4, &[quad, second])).unwrap();
        let load = |shape: &str| {
            let xml = format!(r#"<scene version="3.0.0"><sensor type="perspective"/>{shape}</scene>"#);
            crate::xml::load_str(&xml, &dir.join("s.xml"), &dir, &Default::default())
        };
        let load_err = |shape: &str| match load(shape) {
            Ok(_) => panic!("{shape} loaded"),
            Err(e) => e,
        };
        let s = load(
            r#"<shape type="serialized"><string name="filename" value="two.serialized"/>
               <integer name="shape_index" value="1"/><transform name="to_world"><translate x="1"/></transform></shape>"#,
        )
        .unwrap();
        let crate::Geometry::Mesh(m) = &s.shapes[0].geometry else { panic!("a mesh") };
        assert_eq!(m.positions[1], Vec3::new(4.0, 0.0, 0.0));
        assert_eq!(s.shapes[0].name, "serialized \"two.serialized\"");
        let s = load(
            r#"<shape type="serialized"><string name="filename" value="two.serialized"/>
               <boolean name="face_normals" value="true"/><boolean name="flip_normals" value="true"/></shape>"#,
        )
        .unwrap();
        let crate::Geometry::Mesh(m) = &s.shapes[0].geometry else { panic!("a mesh") };
        assert_eq!((m.normals.is_none(), m.flip_normals, m.indices.len()), (true, true, 2));
        let s = load(r#"<shape type="serialized"><string name="filename" value="two.serialized"/></shape>"#)
            .unwrap();
        let crate::Geometry::Mesh(m) = &s.shapes[0].geometry else { panic!("a mesh") };
        assert!(m.normals.is_some(), "vertex normals kept by default");
        let e = load_err(
            r#"<shape type="serialized"><string name="filename" value="two.serialized"/><integer name="shape_index" value="-1"/></shape>"#,
        );
        assert!(e.message.contains("'shape_index' must be >= 0, got -1"), "{e}");
        let e = load_err(
            r#"<shape type="serialized"><string name="filename" value="two.serialized"/><integer name="shape_index" value="5"/></shape>"#,
        );
        assert!(e.message.contains("shape_index 5 is out of range: the file holds 2 meshes"), "{e}");
        assert_eq!(e.element, "<shape type=\"serialized\">");
        let e = load_err(
            r#"<shape type="serialized"><string name="filename" value="two.serialized"/><boolean name="flip_tex_coords" value="true"/></shape>"#,
        );
        assert!(e.message.contains("unused parameter 'flip_tex_coords'"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn damaged_files_are_errors() {
        let m = MeshRecord {
            positions: &QUAD,
            normals: None,
            uvs: None,
            colors: false,
            triangles: &TRIS,
            double: false,
        };
        let file = write_serialized(4, &[m]);
        let e = |bytes: &[u8], index| parse(bytes, index).unwrap_err();
        assert!(
            e(&file[..file.len() / 2], 0).contains("ends early")
                || e(&file[..file.len() / 2], 0).contains("corrupt")
        );
        assert!(e(b"PK\x03\x04....", 0).contains("not a Mitsuba .serialized mesh"));
        let mut v5 = file.clone();
        v5[2] = 5;
        assert!(e(&v5, 0).contains("unsupported .serialized version 5"));
        assert!(e(&file[..3], 0).contains("ends inside a mesh header"));
        let mut bad_offset = file.clone();
        let n = bad_offset.len();
        bad_offset[n - 4..].copy_from_slice(&3u32.to_le_bytes());
        bad_offset[n - 12..n - 4].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(parse(&bad_offset, 0).is_ok(), "mesh 0 is found without the dictionary");
        assert!(e(&bad_offset, 2).contains("past the end"), "{}", e(&bad_offset, 2));
        // A header announcing 2^40 vertices is refused before anything is allocated.
        let mut body = Vec::new();
        body.extend_from_slice(&0x1000u32.to_le_bytes());
        body.extend_from_slice(&(1u64 << 40).to_le_bytes());
        body.extend_from_slice(&1u64.to_le_bytes());
        let mut z = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&body).unwrap();
        let mut huge = vec![0x1C, 0x04, 3, 0];
        huge.extend_from_slice(&z.finish().unwrap());
        assert!(e(&huge, 0).contains("haze reads meshes of at most"));
    }
}

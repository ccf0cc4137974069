//! OpenVDB `.vdb` float grids for `gridvolume` (haze's extension of Mitsuba 3; issue 15), read
//! through the `vdb-rs` crate (0.6.0 with haze's patch, `vendor/vdb-rs/PATCHES.md`) and densified
//! into a [`Grid`], so the lookups, the bounding box and the majorant grid are those of a `.vol`
//! grid. Grids saved as 16-bit half floats are float grids like the others.
//!
//! How a VDB grid becomes a medium (what a Blender, Houdini or EmberGen user exporting smoke
//! expects; `docs/openvdb.md` says it for users):
//! - OpenVDB puts the centre of voxel `(i, j, k)` at world `translation + voxel_size * (i, j, k)`
//!   (its linear transforms `UniformScaleMap`, `ScaleTranslateMap`, `UniformScaleTranslateMap`);
//!   haze uses that world, then the element's `to_world`.
//! - The active voxels and active tiles hold the density; everything else is the background,
//!   which must be 0 (a fog volume). The dense grid is the box of the active voxels padded by
//!   one voxel of background on every side, cell centres at the voxel centres. With the padding,
//!   trilinear lookups fade to 0 over the voxel around the active ones exactly as OpenVDB's
//!   `BoxSampler` does, and the medium's box (the padded box, where haze clips a heterogeneous
//!   medium) holds everything a lookup can see; `wrap_mode` then changes nothing, so it is
//!   refused for `.vdb` files, as is `use_grid_bbox` (the file's transform places the grid).
//!
//! What `vdb-rs` 0.6 does not do, and how haze copes:
//! - it allocated lengths read from the file before reading them (a corrupt length aborted the
//!   process) and misread half-float grids: haze builds a patched copy, `vendor/vdb-rs`, which
//!   checks every length against the bytes left and the node's size (errors
//!   `ParseError::PastEnd`/`BadLength`, mapped in [`guarded`]) and reads half floats as
//!   OpenVDB writes them; `crates/scene/tests/vdb_hostile.rs` fuzzes the reader with corrupt
//!   files;
//! - it panics on some inputs (a transform map it does not know, e.g. the `AffineMap` of a
//!   rotated grid; multi-buffer trees; very old files) and mis-checks the magic number, so
//!   [`read_vdb`] checks the header itself and runs the crate inside `catch_unwind` (with a
//!   panic hook that keeps those panics quiet): such files are errors, not crashes;
//! - it ignores tiles at the root level and the root's background value, so haze checks the
//!   inactive values it can see (they must be 0) and that the active voxels it found span the
//!   bounding box the file records;
//! - it trusts the root nodes' origins, which a corrupt file can make overflow the i32 voxel
//!   coordinates or repeat: haze checks them before walking the tree ([`check_roots`]).

use crate::volume::Grid;
use glam::{Affine3A, DVec3, Mat3A, Vec3};
use std::io::Cursor;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use vdb_rs::{MetadataValue, Node, VdbLevel, VdbReader};

/// The bytes an OpenVDB file starts with: the int64 `OPENVDB_MAGIC` (0x56444220), little endian.
const MAGIC: [u8; 8] = [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0];

/// The oldest file format haze reads: 222 (OpenVDB 3.0, node-mask compression), from which on
/// internal nodes store every tile value (older files store them compressed, which `vdb-rs`
/// 0.6 does not always expand).
const MIN_FILE_VERSION: u32 = 222;

/// Largest `.vdb` file haze reads, and largest dense grid (in cells) it makes of one: 2 GiB of
/// float32, as for `.vol` files.
pub const MAX_VDB_FILE_BYTES: u64 = 2 << 30;
pub const MAX_DENSE_CELLS: u64 = (2 << 30) / 4;

/// Most memory the tree `vdb-rs` builds from a grid may take, its nodes expanded (masks and every
/// value: ~16x what the file stores for nodes of inactive background, vendor/vdb-rs/PATCHES.md),
/// counted before each node is allocated: twice the largest dense grid, so that a hostile file
/// of 2 GiB cannot make the reader ask for ~32 GiB.
pub const MAX_VDB_TREE_BYTES: u64 = 2 * 4 * MAX_DENSE_CELLS;

/// A `.vdb` grid read into a dense grid.
#[derive(Clone, Debug)]
pub struct VdbGrid {
    /// The padded dense grid (1 channel); its `bbox` is the world box of `to_world`.
    pub grid: Grid,
    /// The grid's local unit cube -> the VDB's world (before the element's `to_world`).
    pub to_world: Affine3A,
    /// The VDB index of dense cell `(0, 0, 0)`: cell `c` is voxel `c + index_origin`.
    pub index_origin: [i32; 3],
}

impl VdbGrid {
    /// The VDB voxel index of dense cell `cell` (for messages).
    pub fn voxel(&self, cell: [u32; 3]) -> [i64; 3] {
        std::array::from_fn(|k| cell[k] as i64 + self.index_origin[k] as i64)
    }
}

/// Why a `.vdb` file could not be read.
#[derive(Clone, Debug, PartialEq)]
pub enum VdbError {
    /// The file has no float grid of the asked name, or the grid is not usable as a density
    /// (the message is about the `grid` parameter).
    Grid(String),
    /// The file itself is bad (the message is about the file).
    File(String),
}

/// Reads the float grid `name` of the OpenVDB file `path` (see the module comment for the
/// mapping). Errors say what is wrong; the caller adds the scene file, line and element.
pub fn read_vdb(path: &Path, name: &str) -> Result<VdbGrid, VdbError> {
    let bytes = crate::volume::read_volume_file(path, MAX_VDB_FILE_BYTES, ".vdb").map_err(VdbError::File)?;
    parse_vdb(&bytes, name)
}

/// The panic message of a caught panic.
fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown failure".into())
}

thread_local! {
    /// True while this thread runs a call into `vdb-rs` under [`guarded`].
    static IN_VDB_RS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Installs (once) a panic hook that keeps quiet about panics inside [`guarded`], which become
/// load errors, and passes every other panic to the hook it replaces: without it, a user would
/// see vdb-rs's "thread panicked at ..." before the clean error.
fn quiet_vdb_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_VDB_RS.with(|f| f.get()) {
                previous(info);
            }
        }));
    });
}

/// Runs `f` (a call into `vdb-rs`), turning its errors and panics into messages.
fn guarded<T>(what: &str, f: impl FnOnce() -> Result<T, vdb_rs::ParseError>) -> Result<T, VdbError> {
    quiet_vdb_panics();
    IN_VDB_RS.with(|flag| flag.set(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    IN_VDB_RS.with(|flag| flag.set(false));
    match result {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(vdb_rs::ParseError::IoError(e))) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            Err(VdbError::File(format!("truncated .vdb file: it ends in the middle of {what}")))
        }
        // A length read from the file that runs past its end (vendor/vdb-rs/PATCHES.md): the
        // file is cut short, or the length is corrupt; which, the reader cannot tell.
        Ok(Err(e @ vdb_rs::ParseError::PastEnd { .. })) => {
            Err(VdbError::File(format!("truncated .vdb file, or a corrupt length in it ({what}): {e}")))
        }
        Ok(Err(e @ vdb_rs::ParseError::BadLength { .. })) => {
            Err(VdbError::File(format!("corrupt .vdb file ({what}): {e}")))
        }
        Ok(Err(vdb_rs::ParseError::TreeTooLarge { budget })) => Err(VdbError::File(format!(
            "{what} is too large for haze: its tree, every node expanded as the reader holds it, would take \
             more than {:.1} GiB of memory (a corrupt file, or a grid beyond what haze renders densely)",
            budget as f64 / (1u64 << 30) as f64
        ))),
        Ok(Err(e)) => Err(VdbError::File(format!("unreadable .vdb file ({what}): {e}"))),
        // vdb-rs panics on what it does not support (see the module comment).
        Err(p) => Err(VdbError::File(format!(
            "unsupported or corrupt .vdb file ({what}): {}",
            panic_message(p.as_ref())
        ))),
    }
}

/// Parses the bytes of a `.vdb` file; see [`read_vdb`].
pub fn parse_vdb(bytes: &[u8], name: &str) -> Result<VdbGrid, VdbError> {
    parse_vdb_within(bytes, name, MAX_VDB_TREE_BYTES)
}

/// [`parse_vdb`] with the tree's memory budget given ([`MAX_VDB_TREE_BYTES`] there).
fn parse_vdb_within(bytes: &[u8], name: &str, tree_budget: u64) -> Result<VdbGrid, VdbError> {
    let file_err = |m: String| VdbError::File(m);
    if bytes.len() < 12 {
        return Err(file_err(format!("truncated .vdb header: {} bytes", bytes.len())));
    }
    if bytes[..8] != MAGIC {
        return Err(file_err(
            "not an OpenVDB file: it does not start with the OpenVDB magic number (the bytes ' BDV' and four zeros)"
                .into(),
        ));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
    if version < MIN_FILE_VERSION {
        return Err(file_err(format!(
            "OpenVDB file format {version} is older than haze reads ({MIN_FILE_VERSION}, OpenVDB 3.0 and later): \
             re-save the file with a current OpenVDB"
        )));
    }
    let mut reader = guarded("the file header and grid descriptors", || VdbReader::new(Cursor::new(bytes)))?;
    let mut names: Vec<(String, String)> =
        reader.grid_descriptors.values().map(|d| (d.name.clone(), d.grid_type.clone())).collect();
    names.sort();
    let Some(desc) = reader.grid_descriptors.get(name).cloned() else {
        let list = names.iter().map(|(n, t)| format!("'{n}' ({})", value_type(t))).collect::<Vec<_>>();
        return Err(VdbError::Grid(if list.is_empty() {
            format!("no grid named '{name}': the file has no grids")
        } else {
            format!("no grid named '{name}': the file has {}", list.join(", "))
        }));
    };
    // Float grids, also those saved as half floats (type names `Tree_float_5_4_3` and
    // `Tree_float_5_4_3_HalfFloat`); vdb-rs reads both as f32 (half floats: with haze's patch,
    // vendor/vdb-rs/PATCHES.md).
    if !desc.grid_type.starts_with("Tree_float_") {
        return Err(VdbError::Grid(format!(
            "grid '{name}' holds {} values ({}); haze reads float grids",
            value_type(&desc.grid_type),
            desc.grid_type
        )));
    }
    // Exactly those two: the suffix decides how the values are stored.
    if !matches!(desc.grid_type.as_str(), "Tree_float_5_4_3" | "Tree_float_5_4_3_HalfFloat") {
        return Err(VdbError::Grid(format!(
            "grid '{name}' is a float grid of tree type {}, which haze does not read (it reads \
             Tree_float_5_4_3, saved as full or half floats)",
            desc.grid_type
        )));
    }
    if !desc.instance_parent.is_empty() {
        return Err(VdbError::Grid(format!(
            "grid '{name}' is an instance of grid '{}' (shares its tree); haze does not read instanced grids",
            desc.instance_parent
        )));
    }
    if matches!(desc.meta_data.0.get("class"), Some(MetadataValue::String(c)) if c == "level set") {
        return Err(VdbError::Grid(format!(
            "grid '{name}' is a level set (signed distances), not a fog volume of densities: convert it to a \
             fog volume first (e.g. Houdini's or Blender's 'convert to fog volume')"
        )));
    }
    // Every grid must end within the file (a file cut short anywhere is refused, even in a
    // grid not asked for: it is a damaged copy).
    let len = bytes.len() as u64;
    for d in reader.grid_descriptors.values() {
        let end = d.end_pos.max(d.block_pos).max(d.grid_pos);
        if end > len {
            return Err(file_err(format!(
                "truncated .vdb file: grid '{}' ends at byte {end}, the file has {len}",
                d.name
            )));
        }
    }
    reader.tree_budget = tree_budget;
    let grid = guarded(&format!("grid '{name}'"), || reader.read_grid::<f32>(name))?;
    densify(&grid, &desc.meta_data, name)
}

/// `float` for `Tree_float_5_4_3`, else the type name as it is.
fn value_type(grid_type: &str) -> &str {
    grid_type.strip_prefix("Tree_").and_then(|t| t.split('_').next()).unwrap_or(grid_type)
}

/// The voxels of one entry of vdb-rs's iterator: a voxel, or a tile of 8^3 or 128^3 voxels.
fn extent(level: VdbLevel) -> i64 {
    match level {
        VdbLevel::Voxel => 1,
        VdbLevel::Node3 => 8,
        VdbLevel::Node4 => 128,
    }
}

fn densify(grid: &vdb_rs::Grid<f32>, meta: &vdb_rs::Metadata, name: &str) -> Result<VdbGrid, VdbError> {
    let grid_err = |m: String| VdbError::Grid(format!("grid '{name}': {m}"));
    check_roots(grid).map_err(|m| VdbError::File(format!("corrupt .vdb file (grid '{name}'): {m}")))?;
    check_inactive(grid).map_err(grid_err)?;
    // The active bounding box (inclusive voxel indices).
    let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
    for (p, _, level) in grid.iter() {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] as i64);
            hi[k] = hi[k].max(p[k] as i64 + extent(level) - 1);
        }
    }
    if lo[0] > hi[0] {
        return Err(grid_err("the grid has no active voxels (an empty medium)".into()));
    }
    // OpenVDB records the active box at write time; vdb-rs drops tiles at the root level, so
    // a box larger than the voxels read means lost data.
    if let (Some(MetadataValue::Vec3i(a)), Some(MetadataValue::Vec3i(b))) =
        (meta.0.get("file_bbox_min"), meta.0.get("file_bbox_max"))
    {
        let (a, b) = (a.to_array().map(i64::from), b.to_array().map(i64::from));
        if a != lo || b != hi {
            return Err(grid_err(format!(
                "the file records active voxels in {a:?} - {b:?}, haze read {lo:?} - {hi:?} (tiles at the root \
                 level, which vdb-rs does not read?)"
            )));
        }
    }
    // Padded by one voxel of background per side.
    let res: [u64; 3] = std::array::from_fn(|k| (hi[k] - lo[k] + 3) as u64);
    let cells = res[0].saturating_mul(res[1]).saturating_mul(res[2]);
    if cells > MAX_DENSE_CELLS {
        return Err(grid_err(format!(
            "its active voxels span {} x {} x {} cells with the padding, more than the {MAX_DENSE_CELLS} haze \
             makes a dense grid of",
            res[0], res[1], res[2]
        )));
    }
    let origin = [lo[0] - 1, lo[1] - 1, lo[2] - 1];
    let mut data = vec![0f32; cells as usize];
    for (p, v, level) in grid.iter() {
        let n = extent(level);
        let p = [p[0] as i64, p[1] as i64, p[2] as i64];
        for z in p[2]..p[2] + n {
            for y in p[1]..p[1] + n {
                let row = (((z - origin[2]) as u64 * res[1] + (y - origin[1]) as u64) * res[0]) as usize;
                for x in p[0]..p[0] + n {
                    data[row + (x - origin[0]) as usize] = v;
                }
            }
        }
    }
    let (scale, translation) = match &grid.transform {
        vdb_rs::Map::UniformScaleMap { scale_values, .. } => (scale_values.to_array(), [0.0; 3]),
        vdb_rs::Map::ScaleTranslateMap { scale_values, translation, .. } => {
            (scale_values.to_array(), translation.to_array())
        }
    };
    let (scale, translation) = (DVec3::from_array(scale), DVec3::from_array(translation));
    if !(scale.is_finite() && translation.is_finite() && scale.abs().min_element() > 0.0) {
        return Err(grid_err(format!("invalid transform: voxel size {scale}, translation {translation}")));
    }
    // The unit cube -> index space [lo - 3/2, hi + 3/2] (cell centres at voxel indices), then
    // index -> world: world = translation + voxel_size * index.
    let res_f = DVec3::new(res[0] as f64, res[1] as f64, res[2] as f64);
    let corner = DVec3::new(origin[0] as f64, origin[1] as f64, origin[2] as f64) - 0.5;
    let to_world = Affine3A {
        matrix3: Mat3A::from_diagonal((scale * res_f).as_vec3()),
        translation: (translation + scale * corner).as_vec3().into(),
    };
    let (a, b) = (to_world.transform_point3(Vec3::ZERO), to_world.transform_point3(Vec3::ONE));
    let res32 = res.map(|r| r as u32);
    Ok(VdbGrid {
        grid: Grid { res: res32, channels: 1, data, bbox: (a.min(b), a.max(b)) },
        to_world,
        index_origin: origin.map(|o| o as i32),
    })
}

/// The root nodes' origins, before anything walks the tree: OpenVDB's root node keys its
/// children (4096^3 voxels each) by their origin, a multiple of 4096 on each axis, each origin
/// once. A corrupt file can break both, and vdb-rs does not check: an origin near `i32::MAX`
/// overflows its voxel coordinates (origin + offset, up to 4095), and a repeated origin makes
/// the same voxels be filled again for every copy.
fn check_roots(grid: &vdb_rs::Grid<f32>) -> Result<(), String> {
    let mut seen = std::collections::HashSet::new();
    for n5 in &grid.tree.root_nodes {
        let o = n5.origin.to_array();
        if o.iter().any(|c| c % 4096 != 0) {
            return Err(format!("a root node's origin {o:?} is not a multiple of 4096"));
        }
        if !seen.insert(o) {
            return Err(format!("two root nodes at {o:?}"));
        }
    }
    Ok(())
}

/// Inactive values must be 0 (the background of a fog volume): vdb-rs drops the background
/// value, and haze reads everything but the active voxels and tiles as 0.
fn check_inactive(grid: &vdb_rs::Grid<f32>) -> Result<(), String> {
    // vdb-rs's coordinates are glam 0.24 vectors: taken apart as arrays.
    let bad = |at: [i32; 3], v: f32| {
        Err(format!(
            "inactive value {v} at voxel ({}, {}, {}): haze reads fog volumes, whose inactive voxels and \
             background are 0",
            at[0], at[1], at[2]
        ))
    };
    for n5 in &grid.tree.root_nodes {
        for i in 0..n5.data.len().min(n5.child_mask.len()) {
            if !n5.child_mask[i] && !n5.value_mask[i] && n5.data[i] != 0.0 {
                return bad(n5.offset_to_global_coord(vdb_rs::Index(i as u32)).0.to_array(), n5.data[i]);
            }
        }
        for n4 in n5.nodes.values() {
            for i in 0..n4.data.len().min(n4.child_mask.len()) {
                if !n4.child_mask[i] && !n4.value_mask[i] && n4.data[i] != 0.0 {
                    return bad(n4.offset_to_global_coord(vdb_rs::Index(i as u32)).0.to_array(), n4.data[i]);
                }
            }
            for n3 in n4.nodes.values() {
                for i in 0..n3.buffer.len().min(n3.value_mask.len()) {
                    if !n3.value_mask[i] && n3.buffer[i] != 0.0 {
                        return bad(
                            n3.offset_to_global_coord(vdb_rs::Index(i as u32)).0.to_array(),
                            n3.buffer[i],
                        );
                    }
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn smoke() -> Vec<u8> {
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/vdb/smoke.vdb")).unwrap()
    }

    /// What the tree of `smoke.vdb` takes expanded, by the charge of haze's vdb-rs patch: per
    /// internal node two masks and one f32 per entry, per leaf one mask and 512 f32.
    fn expanded_tree_bytes(bytes: &[u8]) -> u64 {
        let mut reader = VdbReader::new(Cursor::new(bytes)).unwrap();
        let grid = reader.read_grid::<f32>("density").unwrap();
        let node = |log2: u32, masks: u64| {
            let n = 1u64 << (3 * log2);
            masks * n / 8 + 4 * n
        };
        let mut total = 0;
        for n5 in &grid.tree.root_nodes {
            total += node(5, 2);
            for n4 in n5.nodes.values() {
                total += node(4, 2) + node(3, 1) * n4.nodes.len() as u64;
            }
        }
        total
    }

    /// The budget holds exactly: the whole expanded tree fits in its own size and not in one
    /// byte less, and the refusal names the grid and says why.
    #[test]
    fn a_tree_beyond_the_budget_is_refused_before_it_is_built() {
        let bytes = smoke();
        let need = expanded_tree_bytes(&bytes);
        // Expanded, the tree is several times the file (what the budget is for).
        assert!(need > 4 * bytes.len() as u64, "{need} bytes from a file of {}", bytes.len());
        assert!(parse_vdb_within(&bytes, "density", need).is_ok());
        assert!(parse_vdb(&bytes, "density").is_ok());
        match parse_vdb_within(&bytes, "density", need - 1) {
            Err(VdbError::File(m)) => assert!(
                m.contains("grid 'density' is too large for haze") && m.contains("GiB of memory"),
                "{m}"
            ),
            other => panic!("{other:?}"),
        }
    }
}

//! Volumes: spatially varying quantities of a `heterogeneous` medium. Mitsuba 3 plugins
//! `gridvolume` (a voxel grid from a binary `.vol` file) and `constvolume`.
//!
//! Semantics follow Mitsuba 3 (`src/volumes/grid.cpp`, `src/render/volume.cpp`,
//! `include/mitsuba/render/volumegrid.h`, and Dr.Jit's `Texture::eval`), because scenes and
//! references come from it (`docs/theory.md` §12.1):
//! - a volume maps world points to its local unit cube by the inverse of `to_world`
//!   (with `use_grid_bbox`, then by the file's bounding box to `[0, 1]^3`);
//! - its bounding box is the world axis-aligned box of `to_world` applied to the unit cube;
//! - a grid of `res` cells per axis has cell `i`'s value at local `(i + 1/2) / res` (cell
//!   centres); trilinear filtering reads the 8 cells around `u res - 1/2`, nearest the cell
//!   `floor(u res)`; cell indices outside `[0, res)` are wrapped by `wrap_mode` (clamp to the
//!   edge, repeat, or mirror with the edge cell repeated);
//! - a `constvolume` has the same value everywhere (its `to_world` only sets its bounding box).
//!
//! haze renders in RGB, like Mitsuba's `*_rgb` variants: a 1-channel grid is grey, a
//! 3-channel grid is RGB, and `raw` changes nothing (it only disables spectral upsampling).

use glam::{Affine3A, Vec3};
use haze_core::Rgb;
use std::path::Path;
use std::sync::Arc;

/// How a grid interpolates between cell centres (`filter_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Trilinear,
    Nearest,
}

/// How cell indices outside the grid are mapped into it (`wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Clamp,
    Repeat,
    Mirror,
}

impl Wrap {
    /// Dr.Jit's `tex_wrap`: clamp to `[0, n)`; repeat by the Euclidean remainder; mirror with
    /// period `2n` and the edge cell repeated (`-1 -> 0`, `n -> n - 1`).
    #[inline]
    pub fn apply(self, i: i32, n: i32) -> i32 {
        match self {
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Mirror => {
                let q = i.rem_euclid(2 * n);
                if q < n {
                    q
                } else {
                    2 * n - 1 - q
                }
            }
        }
    }
}

/// A voxel grid as stored in a `.vol` file: `res = [x, y, z]` cells, `channels` (1 or 3) floats
/// per cell, cell `(x, y, z)` channel `c` at `data[((z * res_y + y) * res_x + x) * channels + c]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub res: [u32; 3],
    pub channels: u32,
    pub data: Vec<f32>,
    /// The bounding box stored in the file (used with `use_grid_bbox`).
    pub bbox: (Vec3, Vec3),
}

/// Largest `.vol` file haze reads (as for mesh files, `docs/robustness.md`).
pub const MAX_VOLUME_FILE_BYTES: u64 = 2 << 30;

/// Size of a `.vol` header in bytes.
pub const VOL_HEADER_BYTES: usize = 48;

/// The bytes of the volume file `path` (`kind`, e.g. ".vol", names it in messages): a regular
/// file (not a device such as `/dev/zero` or a pipe) of at most `limit` bytes, read through that
/// limit so that a file growing while it is read cannot exhaust memory either.
pub(crate) fn read_volume_file(path: &Path, limit: u64, kind: &str) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read: {e}"))?;
    let meta = file.metadata().map_err(|e| format!("cannot read: {e}"))?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > limit {
        return Err(format!(
            "the file is {} bytes; haze reads {kind} files of at most {limit} bytes",
            meta.len()
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit).read_to_end(&mut bytes).map_err(|e| format!("cannot read: {e}"))?;
    Ok(bytes)
}

impl Grid {
    /// A grid whose cell `(x, y, z)` channel `c` holds `f(x, y, z, c)`, in the `.vol` order
    /// (x fastest, then y, then z; channels interleaved).
    pub fn from_fn(
        res: [u32; 3],
        channels: u32,
        bbox: (Vec3, Vec3),
        f: impl Fn(u32, u32, u32, u32) -> f32,
    ) -> Grid {
        let mut data = Vec::with_capacity((res[0] * res[1] * res[2] * channels) as usize);
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    for c in 0..channels {
                        data.push(f(x, y, z, c));
                    }
                }
            }
        }
        Grid { res, channels, data, bbox }
    }

    /// Reads a Mitsuba `.vol` file (format version 3, encoding 1 = float32, little endian;
    /// `docs/mitsuba-compat.md` has the layout). Errors name the file and what is wrong.
    /// At most [`MAX_VOLUME_FILE_BYTES`] are read ([`read_volume_file`]); messages do not name
    /// the file (the caller does, with the scene element).
    pub fn read_vol(path: &Path) -> Result<Grid, String> {
        let bytes = read_volume_file(path, MAX_VOLUME_FILE_BYTES, ".vol")?;
        Grid::parse_vol(&bytes)
    }

    /// Parses the bytes of a `.vol` file; see [`Grid::read_vol`].
    pub fn parse_vol(bytes: &[u8]) -> Result<Grid, String> {
        if bytes.len() < VOL_HEADER_BYTES {
            return Err(format!(
                "truncated .vol header: {} bytes, a header has {VOL_HEADER_BYTES}",
                bytes.len()
            ));
        }
        if &bytes[0..3] != b"VOL" {
            return Err("not a .vol file: it does not start with the bytes 'VOL'".into());
        }
        if bytes[3] != 3 {
            return Err(format!("unsupported .vol version {} (only version 3 exists)", bytes[3]));
        }
        let int = |at: usize| i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let encoding = int(4);
        if encoding != 1 {
            return Err(format!("unsupported .vol encoding {encoding} (only 1, float32, is supported)"));
        }
        let (rx, ry, rz) = (int(8), int(12), int(16));
        if rx <= 0 || ry <= 0 || rz <= 0 {
            return Err(format!(
                "invalid .vol resolution {rx} x {ry} x {rz}: every axis needs at least one cell"
            ));
        }
        let channels = int(20);
        if channels != 1 && channels != 3 {
            return Err(format!(
                "unsupported .vol channel count {channels} (haze reads 1 or 3 channels; Mitsuba's 6-channel \
                 grids are for microflake phase functions)"
            ));
        }
        let bbox = (Vec3::new(float(24), float(28), float(32)), Vec3::new(float(36), float(40), float(44)));
        // In u128: four i32 factors cannot overflow it.
        let count = (rx as u128) * (ry as u128) * (rz as u128) * channels as u128;
        let expected = VOL_HEADER_BYTES as u128 + 4 * count;
        if (bytes.len() as u128) < expected {
            return Err(format!(
                "truncated .vol file: the header announces {rx} x {ry} x {rz} cells x {channels} channel(s) \
                 = {expected} bytes, the file has {}",
                bytes.len()
            ));
        }
        if (bytes.len() as u128) > expected {
            return Err(format!(
                "the .vol file has {} bytes after the {rx} x {ry} x {rz} x {channels} floats its header announces \
                 (wrong resolution or channel count in the header?)",
                bytes.len() as u128 - expected
            ));
        }
        let data = bytes[VOL_HEADER_BYTES..]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        Ok(Grid { res: [rx as u32, ry as u32, rz as u32], channels: channels as u32, data, bbox })
    }

    /// Encodes the grid as a `.vol` file (tests and the demo-scene generator's checks).
    pub fn to_vol_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(VOL_HEADER_BYTES + 4 * self.data.len());
        out.extend_from_slice(b"VOL");
        out.push(3);
        for v in [1, self.res[0] as i32, self.res[1] as i32, self.res[2] as i32, self.channels as i32] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for v in self.bbox.0.to_array().into_iter().chain(self.bbox.1.to_array()) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for v in &self.data {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// The first value outside `[lo, hi]` (or NaN), as `(cell, channel, value)`.
    pub fn first_outside(&self, lo: f32, hi: f32) -> Option<([u32; 3], u32, f32)> {
        let i = self.data.iter().position(|v| !(*v >= lo && *v <= hi))?;
        let c = self.channels as usize;
        let cell = i / c;
        let (rx, ry) = (self.res[0] as usize, self.res[1] as usize);
        Some((
            [(cell % rx) as u32, ((cell / rx) % ry) as u32, (cell / (rx * ry)) as u32],
            (i % c) as u32,
            self.data[i],
        ))
    }

    #[inline]
    fn cell(&self, x: i32, y: i32, z: i32) -> Rgb {
        let i = ((z as usize * self.res[1] as usize + y as usize) * self.res[0] as usize + x as usize)
            * self.channels as usize;
        if self.channels == 1 {
            Rgb::splat(self.data[i])
        } else {
            Rgb([self.data[i], self.data[i + 1], self.data[i + 2]])
        }
    }
}

/// What a volume holds.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeData {
    Const(Rgb),
    Grid { grid: Arc<Grid>, filter: Filter, wrap: Wrap },
}

/// A volume: its data, the world-to-local map and its world bounding box.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub data: VolumeData,
    /// World point -> local unit-cube coordinates.
    pub to_local: Affine3A,
    /// World axis-aligned bounding box of the local unit cube (Mitsuba's `Volume::update_bbox`).
    pub bbox: (Vec3, Vec3),
}

impl Volume {
    /// A volume with local-to-world map `to_world` (must be invertible).
    pub fn new(data: VolumeData, to_world: Affine3A) -> Volume {
        let to_local = to_world.inverse();
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for i in 0..8 {
            let c = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
            let w = to_world.transform_point3(c);
            lo = lo.min(w);
            hi = hi.max(w);
        }
        Volume { data, to_local, bbox: (lo, hi) }
    }

    /// A constant volume over the unit cube: what Mitsuba 3's `props.get_volume` makes of a
    /// plain float or RGB.
    pub fn constant(value: Rgb) -> Volume {
        Volume::new(VolumeData::Const(value), Affine3A::IDENTITY)
    }

    /// The value at world point `p`.
    #[inline]
    pub fn eval(&self, p: Vec3) -> Rgb {
        match &self.data {
            VolumeData::Const(v) => *v,
            VolumeData::Grid { grid, filter, wrap } => {
                eval_grid(grid, *filter, *wrap, self.to_local.transform_point3(p))
            }
        }
    }

    /// Per-channel maximum over the whole volume.
    pub fn max(&self) -> Rgb {
        match &self.data {
            VolumeData::Const(v) => *v,
            VolumeData::Grid { grid, .. } => {
                let c = grid.channels as usize;
                let mut m = [f32::NEG_INFINITY; 3];
                for cell in grid.data.chunks_exact(c) {
                    for k in 0..3 {
                        m[k] = m[k].max(cell[k.min(c - 1)]);
                    }
                }
                Rgb(m)
            }
        }
    }

    /// A per-channel upper bound of [`Volume::eval`] over the world box `[lo, hi]`: the
    /// maximum over every cell a lookup in it can read (trilinear weights are convex, so the
    /// interpolated value never exceeds the largest cell it reads).
    pub fn max_over_box(&self, lo: Vec3, hi: Vec3) -> Rgb {
        let VolumeData::Grid { grid, filter, wrap } = &self.data else {
            return self.max();
        };
        // Local box of the world box: the bounds of its transformed corners (affine map).
        let (mut llo, mut lhi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let l = self.to_local.transform_point3(c);
            llo = llo.min(l);
            lhi = lhi.max(l);
        }
        let axes: [Vec<i32>; 3] = std::array::from_fn(|k| {
            let n = grid.res[k] as i32;
            let (a, b) = match filter {
                Filter::Trilinear => {
                    ((llo[k] * n as f32 - 0.5).floor() as i64, (lhi[k] * n as f32 - 0.5).floor() as i64 + 1)
                }
                Filter::Nearest => ((llo[k] * n as f32).floor() as i64, (lhi[k] * n as f32).floor() as i64),
            };
            // One cell of margin against rounding of the corners' transform.
            let (a, b) = (a - 1, b + 1);
            if b - a + 1 >= 2 * n as i64 {
                return (0..n).collect();
            }
            let mut seen = vec![false; n as usize];
            for i in a..=b {
                seen[wrap.apply(i.clamp(i32::MIN as i64 / 4, i32::MAX as i64 / 4) as i32, n) as usize] = true;
            }
            (0..n).filter(|&i| seen[i as usize]).collect()
        });
        let mut m = Rgb::splat(0.0);
        for &z in &axes[2] {
            for &y in &axes[1] {
                for &x in &axes[0] {
                    m = m.max(grid.cell(x, y, z));
                }
            }
        }
        m
    }
}

/// Dr.Jit's `tex_eval` on a grid at local point `u` (`docs/theory.md` §12.1, (T26)).
#[inline]
fn eval_grid(grid: &Grid, filter: Filter, wrap: Wrap, u: Vec3) -> Rgb {
    let n = [grid.res[0] as i32, grid.res[1] as i32, grid.res[2] as i32];
    match filter {
        Filter::Nearest => {
            let i: [i32; 3] = std::array::from_fn(|k| wrap.apply(floor_i32(u[k] * n[k] as f32), n[k]));
            grid.cell(i[0], i[1], i[2])
        }
        Filter::Trilinear => {
            let mut i0 = [0i32; 3];
            let mut i1 = [0i32; 3];
            let mut w1 = [0f32; 3];
            for k in 0..3 {
                let x = u[k] * n[k] as f32 - 0.5;
                let f = x.floor();
                let fi = floor_i32(x);
                w1[k] = x - f;
                i0[k] = wrap.apply(fi, n[k]);
                i1[k] = wrap.apply(fi.saturating_add(1), n[k]);
            }
            let lerp = |a: Rgb, b: Rgb, t: f32| a * (1.0 - t) + b * t;
            let c00 = lerp(grid.cell(i0[0], i0[1], i0[2]), grid.cell(i1[0], i0[1], i0[2]), w1[0]);
            let c10 = lerp(grid.cell(i0[0], i1[1], i0[2]), grid.cell(i1[0], i1[1], i0[2]), w1[0]);
            let c01 = lerp(grid.cell(i0[0], i0[1], i1[2]), grid.cell(i1[0], i0[1], i1[2]), w1[0]);
            let c11 = lerp(grid.cell(i0[0], i1[1], i1[2]), grid.cell(i1[0], i1[1], i1[2]), w1[0]);
            lerp(lerp(c00, c10, w1[1]), lerp(c01, c11, w1[1]), w1[2])
        }
    }
}

/// `floor(x)` as an integer, saturating far outside the grid (and 0 for NaN, which the
/// renderer never passes: points come from finite rays).
#[inline]
fn floor_i32(x: f32) -> i32 {
    x.floor().clamp(-1.0e9, 1.0e9) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(res: [u32; 3], channels: u32, f: impl Fn(u32, u32, u32, u32) -> f32) -> Grid {
        Grid::from_fn(res, channels, (Vec3::ZERO, Vec3::ONE), f)
    }

    fn volume(g: Grid, filter: Filter, wrap: Wrap) -> Volume {
        Volume::new(VolumeData::Grid { grid: Arc::new(g), filter, wrap }, Affine3A::IDENTITY)
    }

    #[test]
    fn wrap_modes_match_drjit() {
        let n = 4;
        let clamp: Vec<i32> = (-3..8).map(|i| Wrap::Clamp.apply(i, n)).collect();
        assert_eq!(clamp, [0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3]);
        let repeat: Vec<i32> = (-3..8).map(|i| Wrap::Repeat.apply(i, n)).collect();
        assert_eq!(repeat, [1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3]);
        let mirror: Vec<i32> = (-3..8).map(|i| Wrap::Mirror.apply(i, n)).collect();
        assert_eq!(mirror, [2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0]);
    }

    /// Cell values sit at cell centres: a grid with value `x` in cell `x` reads `x` at
    /// `(x + 1/2) / res`, halfway values between centres, and clamps to the edge cells.
    #[test]
    fn trilinear_reads_cell_centres_and_clamps() {
        let v = volume(grid([4, 2, 3], 1, |x, _, _, _| x as f32), Filter::Trilinear, Wrap::Clamp);
        for x in 0..4 {
            let p = Vec3::new((x as f32 + 0.5) / 4.0, 0.3, 0.6);
            assert!((v.eval(p)[0] - x as f32).abs() < 1e-6);
        }
        assert!((v.eval(Vec3::new(0.25, 0.5, 0.5))[0] - 0.5).abs() < 1e-6);
        assert_eq!(v.eval(Vec3::new(0.05, 0.5, 0.5))[0], 0.0);
        assert_eq!(v.eval(Vec3::new(-3.0, 0.5, 0.5))[0], 0.0);
        assert_eq!(v.eval(Vec3::new(7.0, 0.5, 0.5))[0], 3.0);
        let n = volume(grid([4, 2, 3], 1, |x, _, _, _| x as f32), Filter::Nearest, Wrap::Clamp);
        assert_eq!(n.eval(Vec3::new(0.49, 0.5, 0.5))[0], 1.0);
        assert_eq!(n.eval(Vec3::new(0.51, 0.5, 0.5))[0], 2.0);
        let r = volume(grid([4, 2, 3], 1, |x, _, _, _| x as f32), Filter::Nearest, Wrap::Repeat);
        assert_eq!(r.eval(Vec3::new(1.1, 0.5, 0.5))[0], 0.0);
    }

    #[test]
    fn three_channels_and_transform() {
        let g = grid([2, 2, 2], 3, |x, y, z, c| (x + 2 * y + 4 * z) as f32 + 10.0 * c as f32);
        let to_world = Affine3A::from_translation(Vec3::splat(-0.5)) * Affine3A::from_scale(Vec3::splat(1.5));
        let v = Volume::new(
            VolumeData::Grid { grid: Arc::new(g), filter: Filter::Nearest, wrap: Wrap::Clamp },
            to_world,
        );
        assert!(
            (v.bbox.0 - Vec3::splat(-0.5)).length() < 1e-6 && (v.bbox.1 - Vec3::splat(1.0)).length() < 1e-6
        );
        // World (0.9, -0.4, 0.9) -> local (0.933, 0.067, 0.933): cell (1, 0, 1).
        assert_eq!(v.eval(Vec3::new(0.9, -0.4, 0.9)), Rgb([5.0, 15.0, 25.0]));
        assert_eq!(v.max(), Rgb([7.0, 17.0, 27.0]));
    }

    /// The box bound holds for every lookup inside the box (random boxes and points), and is
    /// tighter than the global maximum for a small box.
    #[test]
    fn box_maximum_bounds_every_lookup() {
        let g = grid([7, 5, 6], 1, |x, y, z, _| ((x * 7 + y * 3 + z * 5) % 11) as f32);
        let mut s = haze_core::Sampler::from_seed(3);
        for (filter, wrap) in [
            (Filter::Trilinear, Wrap::Clamp),
            (Filter::Trilinear, Wrap::Repeat),
            (Filter::Nearest, Wrap::Mirror),
            (Filter::Trilinear, Wrap::Mirror),
        ] {
            let v = volume(g.clone(), filter, wrap);
            for _ in 0..200 {
                let a = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 1.6 - 0.3;
                let b = a + Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.3;
                let m = v.max_over_box(a, b);
                for _ in 0..50 {
                    let t = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
                    let p = a + (b - a) * t;
                    assert!(v.eval(p)[0] <= m[0], "{filter:?} {wrap:?}: {} > {} at {p}", v.eval(p)[0], m[0]);
                }
            }
        }
        let v = volume(grid([7, 5, 6], 1, |x, y, z, _| (x + y + z) as f32), Filter::Nearest, Wrap::Clamp);
        assert_eq!(v.max_over_box(Vec3::splat(0.0), Vec3::splat(0.05))[0], 3.0);
        assert_eq!(v.max()[0], 15.0);
    }

    #[test]
    fn vol_round_trip_and_header_errors() {
        let g = grid([3, 2, 1], 3, |x, y, _, c| (x + y + c) as f32);
        let bytes = g.to_vol_bytes();
        assert_eq!(Grid::parse_vol(&bytes).unwrap(), g);
        let err = |b: &[u8]| Grid::parse_vol(b).unwrap_err();
        assert!(err(&bytes[..20]).contains("truncated .vol header"));
        assert!(err(&bytes[..bytes.len() - 4]).contains("truncated .vol file"));
        let mut long = bytes.clone();
        long.extend_from_slice(&[0; 4]);
        assert!(err(&long).contains("bytes after"));
        let mut magic = bytes.clone();
        magic[0] = b'X';
        assert!(err(&magic).contains("does not start with the bytes 'VOL'"));
        let mut version = bytes.clone();
        version[3] = 2;
        assert!(err(&version).contains("version 2"));
        let mut enc = bytes.clone();
        enc[4] = 2;
        assert!(err(&enc).contains("encoding 2"));
        let mut huge = bytes.clone();
        for at in [8, 12, 16] {
            huge[at..at + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        }
        assert!(err(&huge).contains("truncated .vol file"));
        let mut res = bytes.clone();
        res[8..12].copy_from_slice(&0i32.to_le_bytes());
        assert!(err(&res).contains("resolution 0 x 2 x 1"));
        let mut ch = bytes.clone();
        ch[20..24].copy_from_slice(&6i32.to_le_bytes());
        assert!(err(&ch).contains("channel count 6"));
        let mut neg = g.clone();
        neg.data[7] = -1.0;
        assert_eq!(neg.first_outside(0.0, f32::INFINITY), Some(([2, 0, 0], 1, -1.0)));
        neg.data[7] = f32::NAN;
        assert!(neg.first_outside(0.0, f32::INFINITY).is_some());
    }
}

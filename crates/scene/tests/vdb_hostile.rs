//! Hostile bytes in `.vdb` files (issue 15): a deterministic fuzz test. Seeded mutations of the
//! committed test grids (`tests/data/vdb/`: random byte changes, 4- and 8-byte words overwritten
//! with huge values, above all in the fields that hold lengths, and truncations) are loaded
//! through the `gridvolume` path of a scene, and each must load or fail with a one-line error
//! that names the scene file, the line, the element and the grid file: never a panic, never an
//! abort. An abort (a failed allocation of a length read from the file, which the unpatched
//! vdb-rs 0.6.0 makes: `vendor/vdb-rs/PATCHES.md`) kills this test binary, so the test fails.
//! Its own binary, so an abort takes no other test with it.

use haze_core::Sampler;
use haze_scene::{load_str, LoadOptions};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    haze_testkit::data::repo_root().join("tests/data/vdb").join(name)
}

/// Where the length fields of a `.vdb` file probably are: a u32 in 1..=256 followed by that
/// many printable bytes (the length of a name, a type or a string value), and an i64 in
/// 16..=file length (the byte count of a compressed block, or a grid's offsets).
fn length_fields(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut at = Vec::new();
    for p in 0..bytes.len().saturating_sub(8) {
        let n = u32::from_le_bytes(bytes[p..p + 4].try_into().unwrap()) as usize;
        if (1..=256).contains(&n)
            && p + 4 + n <= bytes.len()
            && bytes[p + 4..p + 4 + n].iter().all(|b| b.is_ascii_graphic() || *b == b' ')
        {
            at.push((p, 4));
        }
        let n = i64::from_le_bytes(bytes[p..p + 8].try_into().unwrap());
        if (16..=bytes.len() as i64).contains(&n) {
            at.push((p, 8));
        }
    }
    at
}

/// Huge or negative values for a 4- or 8-byte field.
const HUGE_32: [u32; 5] = [u32::MAX, 0x7fff_ffff, 0x8000_0000, 0x4000_0000, 0x0100_0000];
const HUGE_64: [i64; 8] = [i64::MAX, i64::MIN, 1 << 40, -(1 << 40), 1 << 33, -(1 << 33), 1 << 62, -3];

/// One seeded mutation of `good`, and what it did (for the failure message).
fn mutate(good: &[u8], fields: &[(usize, usize)], s: &mut Sampler) -> (Vec<u8>, String) {
    let mut b = good.to_vec();
    let mut pick = |n: usize| (s.next_u32() as usize) % n;
    let kind = pick(5);
    let what = match kind {
        // Random bytes: one to four of them anywhere after the header checks haze makes itself.
        0 => {
            let n = 1 + pick(4);
            let mut at = Vec::new();
            for _ in 0..n {
                let p = 12 + pick(b.len() - 12);
                b[p] = pick(256) as u8;
                at.push(p);
            }
            format!("bytes {at:?} changed")
        }
        // A 4-byte word anywhere.
        1 => {
            let p = pick(b.len() - 4);
            let v = HUGE_32[pick(HUGE_32.len())];
            b[p..p + 4].copy_from_slice(&v.to_le_bytes());
            format!("u32 at {p} set to {v}")
        }
        // An 8-byte word anywhere.
        2 => {
            let p = pick(b.len() - 8);
            let v = HUGE_64[pick(HUGE_64.len())];
            b[p..p + 8].copy_from_slice(&v.to_le_bytes());
            format!("i64 at {p} set to {v}")
        }
        // A length field.
        3 => {
            let (p, w) = fields[pick(fields.len())];
            if w == 4 {
                let v = HUGE_32[pick(HUGE_32.len())];
                b[p..p + 4].copy_from_slice(&v.to_le_bytes());
                format!("length u32 at {p} set to {v}")
            } else {
                let v = HUGE_64[pick(HUGE_64.len())];
                b[p..p + 8].copy_from_slice(&v.to_le_bytes());
                format!("length i64 at {p} set to {v}")
            }
        }
        // Truncated, after a changed byte half of the time.
        _ => {
            let cut = 12 + pick(b.len() - 12);
            let mut what = format!("cut at {cut}");
            if cut > 12 && pick(2) == 0 {
                let p = 12 + pick(cut - 12);
                b[p] ^= 1 + pick(255) as u8;
                what += &format!(", byte {p} changed");
            }
            b.truncate(cut);
            what
        }
    };
    (b, what)
}

#[test]
fn mutated_vdb_files_load_or_fail_cleanly() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("haze-vdb-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let grid = dir.join("grid.vdb");
    let scene = dir.join("scene.xml");
    // The grid file's parameter is on line 5.
    let xml = "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><film type=\"hdrfilm\">\
               <integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/></film></sensor>\n\
               <medium id=\"smoke\" type=\"heterogeneous\">\n<volume name=\"sigma_t\" type=\"gridvolume\">\n\
               <string name=\"filename\" value=\"grid.vdb\"/>\n</volume>\n</medium>\n\
               <shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"smoke\"/></shape>\n</scene>\n";
    let mut s = Sampler::from_seed(0x15_f022);
    let (mut loaded, mut failed) = (0, 0);
    // Float grids with two grids in the file, half floats (with an empty leaf), active tiles,
    // and a grid too sparse to densify (two voxels 4000 apart).
    for file in ["smoke.vdb", "half.vdb", "tiles.vdb", "sparse.vdb"] {
        let good = std::fs::read(data(file)).unwrap();
        let fields = length_fields(&good);
        assert!(fields.len() > 10, "{file}: {} length fields found", fields.len());
        for i in 0..80 {
            let (bytes, what) = mutate(&good, &fields, &mut s);
            std::fs::write(&grid, &bytes).unwrap();
            match load_str(xml, &scene, &dir, &LoadOptions::default()) {
                Ok(_) => loaded += 1,
                Err(e) => {
                    failed += 1;
                    let msg = e.to_string();
                    let clean = msg.starts_with(&format!("{}:5:", scene.display()))
                        && msg.contains("<string name=\"filename\">")
                        && msg.contains("grid.vdb")
                        && !msg.contains('\n');
                    assert!(clean, "{file} mutation {i} ({what}): not a clean error: {msg}");
                }
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    eprintln!("{loaded} mutations loaded, {failed} failed cleanly");
    // The mutations reach the reader: most of them break the file.
    assert!(failed > (loaded + failed) / 2, "only {failed} of {} mutations failed", loaded + failed);
}

//! Bounded fuzzing of the scene loader (issue 16): mutants of the scenes in `scenes/` and the
//! validation scenes must load or fail with an error, never panic (an abort or a stack
//! overflow would kill the test process, failing it too), each within a time bound.
//!
//! A fixed number of cases with a fixed seed runs in the normal suite in a few seconds; run
//! more by hand with `HAZE_FUZZ_CASES=100000 HAZE_FUZZ_SEED=7 cargo test -p haze-scene --test
//! fuzz --release`. A failing mutant is written to the temporary folder for reproduction.

use haze_core::Sampler;
use haze_scene::{load_str, LoadOptions};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const REPO: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// Scene files to mutate: `scenes/*.xml`, the validation scenes (wherever the checkout keeps
/// them), and the bad-scene corpus.
fn seeds() -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    for dir in ["scenes", "tests/data/validation/scenes", "../shared/validation/scenes", "tests/bad-scenes"] {
        let Ok(entries) = std::fs::read_dir(Path::new(REPO).join(dir)) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.extension().is_some_and(|x| x == "xml") {
                // Valid scenes ten times as often: their mutants reach deeper into the loader.
                let weight = if dir == "tests/bad-scenes" { 1 } else { 10 };
                files.extend(std::iter::repeat_n(p, weight));
            }
        }
    }
    files.sort();
    files.into_iter().filter_map(|p| std::fs::read_to_string(&p).ok().map(|s| (p, s))).collect()
}

/// Values that broke haze once, or might: non-finite and huge numbers, fractions where
/// integers go, lists of the wrong length, substitutions, empty and very long strings.
const HOSTILE: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e39",
    "3.4e38",
    "1e30",
    "-1e30",
    "1e-30",
    "1e-45",
    "0",
    "-0",
    "-1",
    "2147483648",
    "-2147483649",
    "99999999999999999999",
    "45.7",
    "",
    " ",
    "x",
    "$",
    "$nope",
    "1, 2",
    "1 2 3 4",
    "0, 0, 0",
    "nan, 0, 0",
    "1e20, 1e20, 1e20",
    "1 0 0 0 0 1 0 0 0 0 1 0 1 1 1 1",
    "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1",
    "/dev/zero",
    "..",
    "true",
    "ggx",
    "400:1, 300:2",
    "&amp;",
    "\u{1F600}",
];

fn pick<'a, T>(s: &mut Sampler, items: &'a [T]) -> &'a T {
    &items[((s.next_1d() * items.len() as f32) as usize).min(items.len() - 1)]
}

/// Byte offsets of every `value="` / `x="` ... attribute value (start, end) in `xml`.
fn attribute_values(xml: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = xml[from..].find("=\"") {
        let start = from + i + 2;
        let Some(len) = xml[start..].find('"') else { break };
        out.push((start, start + len));
        from = start + len + 1;
    }
    out
}

fn mutate(xml: &str, s: &mut Sampler) -> String {
    let lines: Vec<&str> = xml.lines().collect();
    let line = |s: &mut Sampler| ((s.next_1d() * lines.len() as f32) as usize).min(lines.len().max(1) - 1);
    match (s.next_1d() * 7.0) as u32 {
        // An attribute value replaced by a hostile one (most often: the richest mutation).
        0..=2 => {
            let values = attribute_values(xml);
            if values.is_empty() {
                return xml.to_string();
            }
            let (a, b) = *pick(s, &values);
            let v: String =
                if s.next_1d() < 0.05 { "9".repeat(100_000) } else { pick(s, HOSTILE).to_string() };
            format!("{}{}{}", &xml[..a], v, &xml[b..])
        }
        // A line deleted, duplicated, or two lines swapped.
        3 => {
            let k = line(s);
            lines.iter().enumerate().filter(|&(i, _)| i != k).map(|(_, l)| *l).collect::<Vec<_>>().join("\n")
        }
        4 => {
            let k = line(s);
            let mut v = lines.clone();
            if !v.is_empty() {
                v.insert(k, lines[k]);
            }
            v.join("\n")
        }
        5 => {
            let (i, j) = (line(s), line(s));
            let mut v = lines.clone();
            if !v.is_empty() {
                v.swap(i, j);
            }
            v.join("\n")
        }
        // Bytes: one replaced by a random ASCII character, or the file cut short.
        _ => {
            let mut bytes = xml.as_bytes().to_vec();
            if bytes.is_empty() {
                return String::new();
            }
            let k = ((s.next_1d() * bytes.len() as f32) as usize).min(bytes.len() - 1);
            if s.next_1d() < 0.5 {
                bytes[k] = b' ' + (s.next_1d() * 95.0) as u8;
            } else {
                bytes.truncate(k);
            }
            String::from_utf8_lossy(&bytes).into_owned()
        }
    }
}

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn mutated_scenes_load_or_fail_cleanly() {
    let seeds = seeds();
    assert!(seeds.len() >= 50, "only {} scenes to mutate", seeds.len());
    let cases = env_u64("HAZE_FUZZ_CASES", 3000);
    let seed = env_u64("HAZE_FUZZ_SEED", 16);
    let mut s = Sampler::from_seed(seed);
    let (mut loaded, mut refused) = (0u64, 0u64);
    let start = Instant::now();
    for case in 0..cases {
        let (path, xml) = pick(&mut s, &seeds);
        let mut mutant = mutate(xml, &mut s);
        // Sometimes two mutations at once.
        if s.next_1d() < 0.3 {
            mutant = mutate(&mutant, &mut s);
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let t = Instant::now();
        let result = std::panic::catch_unwind(|| load_str(&mutant, path, dir, &LoadOptions::default()));
        let took = t.elapsed();
        let keep = |why: &str| {
            let file = std::env::temp_dir().join(format!("haze-fuzz-{seed}-{case}.xml"));
            std::fs::write(&file, &mutant).unwrap();
            panic!("case {case} (from {}): {why}; the mutant is in {}", path.display(), file.display());
        };
        match result {
            Err(_) => keep("the loader panicked"),
            Ok(Ok(_)) => loaded += 1,
            Ok(Err(e)) => {
                let m = e.to_string();
                if m.contains('\n') || m.len() > 2000 {
                    keep(&format!("the message is not one short line ({} bytes)", m.len()));
                }
                refused += 1;
            }
        }
        if took > Duration::from_secs(5) {
            keep(&format!("loading took {took:?}"));
        }
    }
    eprintln!("{cases} mutants in {:?}: {loaded} loaded, {refused} refused", start.elapsed());
    assert!(loaded > 0 && refused > 0);
}

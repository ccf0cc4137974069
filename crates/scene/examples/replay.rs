//! SCRATCH: replay logged rays (9 f32: o, d, t_max, depth, path) through intersect_preliminary.
use glam::Vec3;
use haze_core::Ray;
use haze_scene::xml::{load_file, LoadOptions};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let scene = load_file(args[1].as_ref(), &LoadOptions::default())?;
    let bytes = std::fs::read(&args[2])?;
    let f: Vec<f32> = bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    let rays: Vec<Ray> = f
        .chunks_exact(9)
        .map(|r| Ray { t_max: r[6], ..Ray::new(Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5])) })
        .collect();
    let mode = std::env::var("SPLIT").unwrap_or_default();
    let rays: Vec<Ray> = rays
        .into_iter()
        .filter(|r| match mode.as_str() {
            "hit" => scene.intersect_preliminary(r).is_some(),
            "miss" => scene.intersect_preliminary(r).is_none(),
            _ => true,
        })
        .collect();
    let repeat: usize = std::env::var("REPEAT").ok().map_or(1, |s| s.parse().unwrap());
    let rays: Vec<Ray> = rays.iter().flat_map(|r| std::iter::repeat_n(*r, repeat)).collect();
    let reps: usize = args.get(3).map_or(15, |s| s.parse().unwrap());
    let mut best = f64::INFINITY;
    let mut hits = 0;
    let mut tsum = 0.0f64;
    for _ in 0..reps {
        let t0 = Instant::now();
        hits = 0;
        tsum = 0.0;
        for r in &rays {
            if let Some(h) = scene.intersect_preliminary(r) {
                hits += 1;
                tsum += h.t() as f64;
            }
        }
        best = best.min(t0.elapsed().as_secs_f64());
    }
    println!(
        "{} rays, {:.1} ns/ray, hits {hits}, tsum {tsum:.3}",
        rays.len(),
        best * 1e9 / rays.len() as f64
    );
    Ok(())
}

//! Ray-query throughput of a scene's acceleration structure, without shading: closest hits
//! (`intersect`) and shadow segments (`shadow_hits`) from seeded random points in the scene's
//! bounds, and shadow segments from the closest hits' points (rays leaving a surface, as in
//! next-event estimation at a surface) to the same random points. For measuring traversal
//! changes (docs/performance.md §1.4), not a test.
//!
//!     cargo run --release -p haze-lab --example accel_bench -- SCENE.xml [RAYS]

use glam::Vec3;
use haze_core::ray::offset_origin;
use haze_core::{sampling::sample_uniform_sphere, Ray, Sampler};
use haze_scene::accel::{ShadowHit, ShadowQuery, MAX_SHADOW_HITS};
use haze_scene::xml::{load_file, LoadOptions};
use std::time::Instant;

/// Seconds this thread has run on a CPU (Linux `schedstat`, nanoseconds), so that other
/// processes on a shared machine do not count; wall time where it is unavailable.
fn cpu_seconds(wall: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(wall.elapsed().as_secs_f64(), |ns| ns as f64 * 1e-9)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else { return Err("usage: accel_bench SCENE.xml [RAYS]".into()) };
    let rays: usize = args.get(2).map_or(Ok(1_000_000), |s| s.parse())?;
    let start = Instant::now();
    let scene = load_file(path.as_ref(), &LoadOptions::default())?;
    eprintln!("loaded in {:.3} s", start.elapsed().as_secs_f64());
    let (lo, hi) = scene.bounds();
    let point = |s: &mut Sampler| lo + (hi - lo) * Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
    let mut s = Sampler::from_seed(7);
    let queries: Vec<(Vec3, Vec3, Vec3)> =
        (0..rays).map(|_| (point(&mut s), sample_uniform_sphere(s.next_2d()), point(&mut s))).collect();

    let t0 = cpu_seconds(start);
    let mut hits = 0usize;
    let mut surface = Vec::new();
    for &(o, d, p) in &queries {
        if let Some(h) = scene.intersect(&Ray::new(o, d)) {
            hits += 1;
            surface.push((h.p, h.n, p));
        }
    }
    let closest = cpu_seconds(start) - t0;

    let t0 = cpu_seconds(start);
    let mut blocked = 0usize;
    let mut buf = [ShadowHit::default(); MAX_SHADOW_HITS];
    for &(o, _, p) in &queries {
        let v = p - o;
        let len = v.length();
        let ray = Ray { t_max: len * (1.0 - 1e-4), ..Ray::new(o, v / len) };
        blocked += matches!(scene.shadow_hits(&ray, &mut buf), ShadowQuery::Blocked) as usize;
    }
    let shadow = cpu_seconds(start) - t0;

    let t0 = cpu_seconds(start);
    let mut surface_blocked = 0usize;
    for &(p, n, target) in &surface {
        let v = target - p;
        let d = v.normalize();
        let o = offset_origin(p, n, d);
        let ray = Ray { t_max: (target - o).length() * (1.0 - 1e-4), ..Ray::new(o, d) };
        surface_blocked += matches!(scene.shadow_hits(&ray, &mut buf), ShadowQuery::Blocked) as usize;
    }
    let from_surface = cpu_seconds(start) - t0;
    println!(
        "closest: {:.1} ns/ray ({hits} hits); shadow: {:.1} ns/ray ({blocked} blocked); \
         shadow from the hits: {:.1} ns/ray ({surface_blocked} blocked)",
        closest * 1e9 / rays as f64,
        shadow * 1e9 / rays as f64,
        from_surface * 1e9 / surface.len().max(1) as f64
    );
    Ok(())
}

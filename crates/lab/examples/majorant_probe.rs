//! Majorant grid against one global majorant (issue 15, `docs/performance.md` §4.5): for each
//! heterogeneous medium of each scene, the mean majorant optical depth `int sigma_maj dt` (the
//! expected number of density lookups of delta and ratio tracking) along random rays through the
//! medium's box, then volpath's render time at equal spp with each.
//!
//! `cargo run --release -p haze-lab --example majorant_probe -- SCENE.xml... [--spp N]`

use haze_core::{Rgb, Sampler};
use haze_render::progressive::{render_volpath, RenderSettings};
use haze_scene::hetero::{Heterogeneous, MajorantGrid};
use haze_scene::{load_file, LoadOptions, MediumKind, Scene};
use std::sync::Arc;

fn use_global_majorant(s: &mut Scene) {
    for m in &mut s.media {
        if let MediumKind::Grid(h) = &mut m.kind {
            let majorants = MajorantGrid::build(&h.sigma_t, h.scale, [1; 3]);
            *h = Arc::new(Heterogeneous { majorants, ..(**h).clone() });
        }
    }
}

/// Mean over random chords of the box of `int sigma_maj dt` (largest channel) and of the true
/// optical depth (quadrature), for the medium's majorants.
fn lookups_per_ray(h: &Heterogeneous) -> (f64, f64) {
    let (lo, hi) = h.sigma_t.bbox;
    let mut s = Sampler::from_seed(1);
    let (mut maj, mut tau) = (0.0f64, 0.0f64);
    let n = 2000;
    for _ in 0..n {
        let a = lo + (hi - lo) * glam::Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let b = lo + (hi - lo) * glam::Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let d = (b - a).normalize();
        let far = (hi - lo).length() * 2.0;
        let o = a - d * far;
        maj += h
            .majorants
            .segments(o, d, 0.0, 2.0 * far)
            .map(|g| (g.t1 - g.t0) as f64 * g.sigma_maj.max_component() as f64)
            .sum::<f64>();
        tau += h.optical_depth(o, d, 0.0, 2.0 * far, 4000).max_component() as f64;
    }
    (maj / n as f64, tau / n as f64)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spp: u32 = args.iter().position(|a| a == "--spp").map_or(64, |i| args[i + 1].parse().unwrap());
    let scenes: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|(i, a)| a.ends_with(".xml") && (*i == 0 || args[i - 1] != "--spp"))
        .map(|(_, a)| a)
        .collect();
    println!("| scene | majorant | mean int sigma_maj dt per chord | mean optical depth | volpath time at {spp} spp (s) | image mean |");
    println!("|---|---|---|---|---|---|");
    for path in scenes {
        let grid = load_file(path.as_ref(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let mut global = load_file(path.as_ref(), &LoadOptions::default()).unwrap();
        use_global_majorant(&mut global);
        let name = std::path::Path::new(path).file_stem().unwrap().to_string_lossy().to_string();
        for (label, scene) in [("grid", &grid), ("global", &global)] {
            let Some(h) = scene.media.iter().find_map(|m| m.as_grid().cloned()) else { continue };
            let r = h.majorants.res;
            let label = format!("{label} {}x{}x{}", r[0], r[1], r[2]);
            let (maj, tau) = lookups_per_ray(&h);
            let settings = RenderSettings { spp, seed: 0, spp_per_pass: spp, ..Default::default() };
            let out = render_volpath(scene, &settings);
            let mean: Rgb = out.film.mean(None).chunks_exact(3).map(|c| Rgb([c[0], c[1], c[2]])).sum::<Rgb>()
                / (out.film.mean(None).len() / 3) as f32;
            println!(
                "| {name} | {label} | {maj:.3} | {tau:.3} | {:.2} | {:.4} |",
                out.elapsed.as_secs_f64(),
                mean.mean()
            );
        }
    }
}

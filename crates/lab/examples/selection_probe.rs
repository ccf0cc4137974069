//! How much variance the stochastic cut's light selection adds, per scene (docs/lightcuts.md,
//! "Choosing the importance"; `haze_lab::selection`).
//!
//! ```text
//! cargo run --release -p haze-lab --example selection_probe -- SCENE.xml... \
//!     [--vrls 1000] [--every 150] [--width 96] [--spp 2] [--share 0.1]
//! ```
//!
//! Renders each scene with `vrl_lightcuts` (k = 1, `--vrls` per pass, one spp per pass) at
//! `--width` pixels across (height from the scene's aspect), probes one camera segment in
//! `--every`, and prints one table row per scene: the relative variance `V` of one sampled light
//! for the tree's descent, for power-proportional and for leaf-importance-proportional
//! probabilities, averaged over the probed segments weighted by their squared sum (the share of
//! the image's variance), and its median. `--share` sets the descent's power share `a`.

use haze_engine::options::MethodKind;
use haze_lab::selection::{SelectionProbe, SelectionRecord};
use haze_lab::setup;
use haze_manylight::integrators::Observed;
use haze_render::progressive::{render, RenderSettings};
use std::sync::atomic::AtomicBool;

fn main() {
    let (mut scenes, mut vrls, mut every, mut width, mut spp) = (Vec::new(), 1000u64, 150u64, 96u32, 2u32);
    let mut share = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| -> u64 {
            let v = args.next().unwrap_or_else(|| fail(&format!("{name} needs a value")));
            v.parse().unwrap_or_else(|_| fail(&format!("{name}: not a positive integer: {v}")))
        };
        match a.as_str() {
            "--vrls" => vrls = value("--vrls"),
            "--every" => every = value("--every").max(1),
            "--width" => width = value("--width").max(1) as u32,
            "--spp" => spp = value("--spp").max(1) as u32,
            "--share" => {
                let v = args.next().unwrap_or_else(|| fail("--share needs a value"));
                share = match v.parse::<f32>() {
                    Ok(a) if a > 0.0 && a <= 1.0 => Some(a),
                    _ => fail(&format!("--share: not in (0, 1]: {v}")),
                };
            }
            _ if a.starts_with("--") => fail(&format!("unknown option {a}")),
            _ => scenes.push(a),
        }
    }
    if scenes.is_empty() {
        fail("usage: selection_probe SCENE.xml... [--vrls N] [--every N] [--width W] [--spp N] [--share A]");
    }
    println!("| scene | segments | tree (k = 1) | power only | leaves | tree, median | joint, tree | joint, all lights |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for path in scenes {
        let mut scene =
            setup::load_scene(std::path::Path::new(&path), &[]).unwrap_or_else(|e| fail(&format!("{e:#}")));
        let aspect = scene.camera.height as f32 / scene.camera.width as f32;
        scene.camera.width = width;
        scene.camera.height = ((width as f32 * aspect).round() as u32).max(1);
        // The power share is the probe's own knob, not an option of haze render.
        let vrls = vrls.to_string();
        let mut options = setup::options(MethodKind::VrlLightcuts, &[("vrls", &vrls)])
            .unwrap_or_else(|e| fail(&format!("{e:#}")));
        if let Some(a) = share {
            options.method.lightcuts.stochastic.settings.power_share = a;
        }
        let integrator =
            setup::vrl_lightcuts(&scene, &options).unwrap_or_else(|e| fail(&format!("{path}: {e:#}")));
        let settings = RenderSettings {
            spp,
            seed: 0,
            spp_per_pass: 1,
            components: false,
            time_limit: None,
            first_pass: 0,
            sampler: Default::default(),
        };
        let probe = SelectionProbe::new(every);
        let observed = Observed { integrator: &integrator, observer: &probe };
        render(&scene, &observed, &settings, &AtomicBool::new(false), |_| {});
        let records = probe.take_records();
        let weighted = |f: fn(&SelectionRecord) -> f64| {
            let w: f64 = records.iter().map(|r| r.sum * r.sum).sum();
            records.iter().map(|r| f(r) * r.sum * r.sum).sum::<f64>() / w
        };
        let mut tree: Vec<f64> = records.iter().map(|r| r.tree).collect();
        tree.sort_by(f64::total_cmp);
        let median = tree.get(tree.len() / 2).copied().unwrap_or(f64::NAN);
        let name = std::path::Path::new(&path).file_stem().map(|s| s.to_string_lossy().into_owned());
        println!(
            "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} |",
            name.unwrap_or(path.clone()),
            records.len(),
            weighted(|r| r.tree),
            weighted(|r| r.power),
            weighted(|r| r.leaves),
            median,
            weighted(|r| r.joint_tree),
            weighted(|r| r.joint_all),
        );
    }
}

fn fail(msg: &str) -> ! {
    eprintln!("selection_probe: {msg}");
    std::process::exit(2)
}

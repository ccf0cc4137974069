use haze_manylight::integrators::{LightBudget, LightcutsIntegrator, ManyLightSettings, VrlIntegrator, Vrls, Vpls};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, RenderSettings};
use haze_render::{Component, Integrator, VolPath};
use haze_scene::{load_file, LoadOptions};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

fn run<I: Integrator>(name: &str, scene: &haze_scene::Scene, i: &I, spp: u32, sppp: u32) {
    let t = Instant::now();
    let s = RenderSettings { spp, seed: 3, spp_per_pass: sppp, components: true, ..Default::default() };
    let out = render(scene, i, &s, &AtomicBool::new(false), |_| {});
    let secs = t.elapsed().as_secs_f64();
    let mut line = format!("{name:>14} {secs:6.2}s inv {} |", out.invalid_samples);
    for c in Component::ALL {
        let m = out.film.image_mean(Some(c));
        let var: f64 = out.film.sample_variance(Some(c)).iter().map(|v| *v as f64).sum::<f64>()
            / out.film.sample_variance(Some(c)).len() as f64;
        // variance of the mean per pixel times seconds: efficiency (lower is better)
        let eff = var / out.film.samples as f64 * secs;
        line += &format!(" {} mean {:.4} var*s {:.2e} |", c.name(), (m[0] + m[1] + m[2]) / 3.0, eff);
    }
    println!("{line}");
}

#[test]
#[ignore]
fn plume() {
    let opts = LoadOptions { defines: vec![("res".into(), "32".into()), ("res_y".into(), "40".into())] };
    let scene = load_file(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/smoke-plume.xml")), &opts).unwrap();
    let ml = ManyLightSettings { budget: LightBudget::Vrls(1000), trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth) };
    run("volpath", &scene, &VolPath::from_spec(&scene.integrator), 512, 64);
    run("vrl", &scene, &VrlIntegrator::new(&scene, ml.clone(), 1).unwrap(), 16, 1);
    run("vrl_lc", &scene, &LightcutsIntegrator::<Vrls>::new(&scene, ml.clone(), Default::default(), 1).unwrap(), 256, 16);
    run("vpl_lc", &scene, &LightcutsIntegrator::<Vpls>::new(&scene, ml.clone(), Default::default(), 1).unwrap(), 256, 16);
}

//! Shared by the tests that compare the many-light integrators with `volpath` image against
//! image (`integrators.rs`, `sky_sun.rs`): renders split into passes, the per-pixel z-test with
//! the image-mean z from the per-pass spread, the paired z of two renders with the same seeds,
//! and the whole comparison of `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts` with `volpath`.
//!
//! Each many-light pass traces a fresh, independently seeded set of light paths, so the
//! per-pixel sample variance over passes is an honest variance of the pass estimate (pixels of
//! one pass are correlated with each other, not across passes). Statistic as in
//! `haze-render/tests/validation.rs`: per channel-pixel z with pooled variances, at most 1% of
//! channel-pixels beyond the Sidak threshold, and the image-mean z-score within 5 — where the
//! variance of a many-light image mean comes from the spread of the per-pass image means,
//! because all pixels of one pass share its lights and are correlated.
#![allow(dead_code)]

use haze_core::SamplerSpec;
use haze_manylight::integrators::{
    LightBudget, ManyLightSettings, PathTracedMedia, VplIntegrator, VrlIntegrator,
};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, RenderSettings};
use haze_render::{Component, Film, Integrator, VolPath};
use haze_scene::Scene;
use haze_testkit::ztest::{pool_variance, z_test, ZTestReport};
use std::sync::atomic::AtomicBool;

/// A render split into passes: the accumulated film and the image mean of each pass per
/// component (volpath's pixels are independent, so one pass of many samples per pixel suffices).
pub struct Passes {
    pub film: Film,
    pub pass_means: Vec<[[f64; 3]; 4]>,
}

pub fn render_passes<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    passes: u32,
    spp_per_pass: u32,
    seed: u64,
) -> Passes {
    render_passes_with(scene, integrator, passes, spp_per_pass, seed, SamplerSpec::default())
}

/// [`render_passes`] with the sample generator `sampler` (pass `k`'s samples are the pattern's
/// indices `k spp_per_pass ..`, as in a progressive render).
pub fn render_passes_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    passes: u32,
    spp_per_pass: u32,
    seed: u64,
    sampler: SamplerSpec,
) -> Passes {
    let mut total: Option<Film> = None;
    let mut pass_means = Vec::new();
    for k in 0..passes {
        let settings = RenderSettings {
            spp: spp_per_pass,
            seed,
            spp_per_pass,
            components: true,
            time_limit: None,
            first_pass: k,
            sampler,
        };
        let out = render(scene, integrator, &settings, &AtomicBool::new(false), |_| {});
        assert_eq!(out.invalid_samples, 0);
        pass_means.push(Component::ALL.map(|c| out.film.image_mean(Some(c))));
        match &mut total {
            Some(t) => t.merge(&out.film),
            None => total = Some(out.film),
        }
    }
    Passes { film: total.expect("at least one pass"), pass_means }
}

impl Passes {
    /// Mean and variance of the mean of the image mean of `comp` (`None`: all components
    /// summed), channel-averaged, over passes.
    pub fn mean_and_variance(&self, comp: Option<Component>) -> (f64, f64) {
        let comps = comp.map_or(Component::ALL.to_vec(), |c| vec![c]);
        let xs: Vec<f64> = self
            .pass_means
            .iter()
            .map(|m| comps.iter().map(|&c| m[c as usize].iter().sum::<f64>() / 3.0).sum::<f64>())
            .collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
        (mean, var / n)
    }
}

/// Per-pixel z-test of `a` against `b` and the image-mean z-score from per-pass spreads.
pub fn compare(a: &Passes, b: &Passes, comp: Component) -> (ZTestReport, f64) {
    let (w, h) = (a.film.width as usize, a.film.height as usize);
    let var_of = |f: &Film| -> Vec<f32> {
        pool_variance(&f.sample_variance(Some(comp)), w, h, 3).iter().map(|v| v / f.samples as f32).collect()
    };
    let pixels =
        z_test(&a.film.mean(Some(comp)), &var_of(&a.film), &b.film.mean(Some(comp)), &var_of(&b.film), 0.01);
    let ((ma, va), (mb, vb)) = (a.mean_and_variance(Some(comp)), b.mean_and_variance(Some(comp)));
    let mean_z = if va + vb > 0.0 { (ma - mb) / (va + vb).sqrt() } else { 0.0 };
    (pixels, mean_z)
}

/// z-score of the mean of the per-pass differences of `comp`'s image means of two renders
/// with the same seeds (paired: the light paths of a pass are the same in both, so their noise
/// cancels in the difference).
pub fn paired_z(a: &Passes, b: &Passes, comp: Component) -> f64 {
    let c = comp as usize;
    let d: Vec<f64> = a
        .pass_means
        .iter()
        .zip(&b.pass_means)
        .map(|(x, y)| (x[c].iter().sum::<f64>() - y[c].iter().sum::<f64>()) / 3.0)
        .collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    if var > 0.0 {
        mean / (var / n).sqrt()
    } else {
        0.0
    }
}

/// Prints one comparison and records it in `failures` when more than `max_failed` of the
/// channel-pixels fail the z-test or the image mean is more than 5 standard errors off.
pub fn judge(failures: &mut Vec<String>, what: &str, r: &ZTestReport, mean_z: f64, max_failed: f64) {
    println!("{what}: {r}; per-pass image-mean z = {mean_z:.2}");
    if r.failed_fraction() > max_failed || mean_z.abs() > 5.0 {
        failures.push(format!("{what}: {r}; image-mean z = {mean_z:.2}"));
    }
}

/// A negative control's verdict: true if `wrong` fails the z-test of [`judge`] (more than 1% of
/// the channel-pixels, or an image mean more than 5 standard errors off) against `reference` in
/// any component; every component's line is printed, prefixed with `what`.
pub fn caught_in_any_component(wrong: &Passes, reference: &Passes, what: &str) -> bool {
    let mut caught = false;
    for comp in Component::ALL {
        let (r, mean_z) = compare(wrong, reference, comp);
        println!("{what}, {}: {r}; image-mean z = {mean_z:.2}", comp.name());
        caught |= r.failed_fraction() > 0.01 || mean_z.abs() > 5.0;
    }
    caught
}

/// `paths` light paths per pass, gathering in every medium (`PathTracedMedia::None`): the tests
/// built on it check the gather's estimators, heterogeneous ones included; the hand-off to
/// volpath has tests of its own (`tests/integrators.rs`, `path_traced_media_*`).
pub fn settings(scene: &Scene, paths: u64) -> ManyLightSettings {
    ManyLightSettings {
        budget: LightBudget::Paths(paths),
        trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth),
        caustic_paths: None,
        compensated_clamp: None,
        path_traced_media: PathTracedMedia::None,
    }
}

/// `volpath`'s reference for [`check_against_volpath`]: 16 passes of 256 spp.
pub fn volpath_reference(scene: &Scene) -> Passes {
    render_passes(scene, &VolPath::from_spec(&scene.integrator), 16, 256, 11)
}

/// Renders `scene` with `volpath` (the reference, 16 passes of 256 spp), `vrl`, `vpl` and, with
/// `lightcuts`, `vrl_lightcuts` and `vpl_lightcuts` (`passes` passes of 1 spp, `paths` light
/// paths each), and checks every component of each against the reference with `judge` (at most
/// 1% of the channel-pixels failing the z-test); its lines start with `label`. Returns the
/// reference.
pub fn check_against_volpath(scene: &Scene, label: &str, paths: u64, passes: u32, lightcuts: bool) -> Passes {
    let reference = volpath_reference(scene);
    check_methods_against(scene, &reference, label, paths, passes, lightcuts);
    reference
}

/// The many-light half of [`check_against_volpath`], against a given `volpath` reference.
pub fn check_methods_against(
    scene: &Scene,
    reference: &Passes,
    label: &str,
    paths: u64,
    passes: u32,
    lightcuts: bool,
) {
    check_methods_with(scene, reference, label, &settings(scene, paths), passes, lightcuts);
}

/// [`check_methods_against`] with the many-light settings `ml`.
pub fn check_methods_with(
    scene: &Scene,
    reference: &Passes,
    label: &str,
    ml: &ManyLightSettings,
    passes: u32,
    lightcuts: bool,
) {
    let vrl = render_passes(scene, &VrlIntegrator::exhaustive(scene, ml.clone(), 1).unwrap(), passes, 1, 1);
    let vpl = render_passes(scene, &VplIntegrator::exhaustive(scene, ml.clone(), 2).unwrap(), passes, 1, 2);
    let mut methods = vec![("vrl", vrl), ("vpl", vpl)];
    if lightcuts {
        let (vrl_lc, vpl_lc) = lightcut_renders_with(
            scene,
            ml,
            passes,
            haze_manylight::integrators::StochasticCut::default(),
            [5, 6],
        );
        methods.extend([("vrl_lightcuts", vrl_lc), ("vpl_lightcuts", vpl_lc)]);
    }
    let mut failures = Vec::new();
    for (method, f) in &methods {
        for comp in Component::ALL {
            let (r, mean_z) = compare(f, reference, comp);
            judge(&mut failures, &format!("{label}{method} {}", comp.name()), &r, mean_z, 0.01);
        }
    }
    assert!(failures.is_empty(), "{label}\n{}", failures.join("\n"));
}

/// `vrl_lightcuts` and `vpl_lightcuts` with the settings `lc`, `passes` passes of 1 spp and
/// `paths` light paths each, with the seeds `seeds` (the integrator's and the render's).
pub fn lightcut_renders(
    scene: &Scene,
    paths: u64,
    passes: u32,
    lc: impl haze_manylight::integrators::CutStrategy,
    seeds: [u64; 2],
) -> (Passes, Passes) {
    lightcut_renders_with(scene, &settings(scene, paths), passes, lc, seeds)
}

/// [`lightcut_renders`] with the many-light settings `ml`.
pub fn lightcut_renders_with<S: haze_manylight::integrators::CutStrategy>(
    scene: &Scene,
    ml: &ManyLightSettings,
    passes: u32,
    lc: S,
    seeds: [u64; 2],
) -> (Passes, Passes) {
    use haze_manylight::integrators::{LightcutsIntegrator, Vpls, Vrls};
    let a = render_passes(
        scene,
        &LightcutsIntegrator::<Vrls, S>::new(scene, ml.clone(), lc.clone(), seeds[0]).unwrap(),
        passes,
        1,
        seeds[0],
    );
    let b = render_passes(
        scene,
        &LightcutsIntegrator::<Vpls, S>::new(scene, ml.clone(), lc, seeds[1]).unwrap(),
        passes,
        1,
        seeds[1],
    );
    (a, b)
}

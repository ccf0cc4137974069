//! The stochastic lightcut (`tree::stochastic`) on random trees and camera segments:
//!
//! - every light is below exactly one cut node, the probabilities below each cut node sum to 1,
//!   and every light with power has a positive probability (randomized property test, segments
//!   through the light cloud included);
//! - the descent's empirical distribution matches the computed probabilities (chi-square);
//! - the estimate is unbiased: per camera segment, the mean over many independent cuts agrees
//!   with the brute-force sum over every VRL (z-test), for k = 1 (the default), 4 and 16; the same
//!   test with the probability of one child misstated by a factor 1.1 must fail.

use glam::Vec3;
use haze_core::rng::mix64;
use haze_core::{Phase, Rgb, Sampler};
use haze_manylight::tree::build::{build_agglomerative, build_median_split, BuildSettings};
use haze_manylight::tree::importance::ImportanceContext;
use haze_manylight::tree::lights::LightSummary;
use haze_manylight::tree::stochastic::{
    light_probabilities, sample_light, select_cut, stochastic_cut, SampleNode, SampleTree, StochasticScratch,
    StochasticSettings,
};
use haze_manylight::vrl::{sample_vrl_contribution, Segment, Vrl, VrlMedium};
use haze_testkit::chi2::chi2_test;
use haze_testkit::ztest::sidak_threshold;

const MEDIUM: VrlMedium =
    VrlMedium { sigma_s: Rgb([0.4, 0.5, 0.6]), sigma_t: Rgb([0.5, 0.6, 0.8]), phase: Phase::Isotropic };

/// `n` VRLs in a 10-unit cube, lengths up to 3, fluxes over four decades; every 17th has zero
/// flux (it must never matter).
fn random_vrls(n: usize, seed: u64) -> Vec<Vrl> {
    let mut s = Sampler::from_seed(seed);
    (0..n)
        .map(|i| {
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
            let d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let len = 3.0 * s.next_1d() + 1e-3;
            let w = if i % 17 == 5 { 0.0 } else { 10f32.powf(4.0 * s.next_1d() - 2.0) };
            let flux = Rgb([w, w * (0.5 + s.next_1d()), w * (0.5 + s.next_1d())]);
            Vrl::attenuated(Segment::new(o, d, len), flux, 0)
        })
        .collect()
}

fn tree_of(vrls: &[Vrl], median: bool, seed: u64) -> SampleTree {
    let summaries: Vec<LightSummary> = vrls.iter().map(|v| LightSummary::vrl(v, &MEDIUM)).collect();
    let tree = if median {
        build_median_split(&summaries, seed)
    } else {
        build_agglomerative(&summaries, &BuildSettings { group_size: 64, seed, ..Default::default() })
    };
    tree.check(&summaries).expect("tree invariants");
    SampleTree::new(&tree)
}

/// A camera segment: half of them start inside the cloud and cross it.
fn random_segment(s: &mut Sampler, k: usize) -> Segment {
    let o = if k % 2 == 0 {
        Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0
    } else {
        Vec3::new(-5.0, 5.0 * s.next_1d(), 15.0 * s.next_1d())
    };
    let target = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
    let len = (target - o).length().max(0.5) * (0.5 + s.next_1d());
    Segment::new(o, (target - o).normalize_or(Vec3::X), len)
}

fn leaves_below(tree: &SampleTree, node: u32, out: &mut Vec<u32>) {
    let n = tree.node(node);
    if n.is_leaf() {
        out.push(n.light());
    } else {
        for c in n.children() {
            leaves_below(tree, c, out);
        }
    }
}

#[test]
fn cut_partitions_lights_and_probabilities_sum_to_one() {
    let mut s = Sampler::from_seed(3);
    let mut checked = 0usize;
    for trial in 0..24 {
        let n = [1usize, 2, 7, 64, 300, 1000][trial % 6];
        let vrls = random_vrls(n, trial as u64);
        let tree = tree_of(&vrls, trial % 4 == 3, trial as u64);
        for k in 0..6 {
            let seg = random_segment(&mut s, k);
            let ctx = ImportanceContext::new(seg, &MEDIUM);
            let importance = |node: &SampleNode| ctx.importance(node);
            for cut_size in [1u32, 4, 16, 5000] {
                let mut scratch = StochasticScratch::default();
                let cut = select_cut(&tree, &importance, cut_size, &mut scratch).to_vec();
                assert_eq!(cut.len(), (cut_size as usize).min(n), "cut size");
                let mut seen = vec![0u32; n];
                for &c in &cut {
                    let mut below = Vec::new();
                    leaves_below(&tree, c, &mut below);
                    for &l in &below {
                        seen[l as usize] += 1;
                    }
                    let probs = light_probabilities(&tree, c, &importance, 0.1);
                    assert_eq!(probs.len(), below.len());
                    let total: f64 = probs.iter().map(|p| p.1).sum();
                    assert!((total - 1.0).abs() < 1e-5, "probabilities sum to {total}");
                    for &(light, p) in &probs {
                        let has_power = vrls[light as usize].flux.max_component() > 0.0;
                        assert!(!has_power || p > 0.0, "light {light} with power has probability {p}");
                        checked += 1;
                    }
                }
                assert!(seen.iter().all(|&k| k == 1), "every light below exactly one cut node");
            }
        }
    }
    assert!(checked > 100_000, "{checked}");
}

#[test]
fn descent_matches_its_probabilities() {
    let mut s = Sampler::from_seed(8);
    for trial in 0..6 {
        let vrls = random_vrls(200, 100 + trial);
        let tree = tree_of(&vrls, trial % 2 == 1, trial);
        let seg = random_segment(&mut s, trial as usize);
        let ctx = ImportanceContext::new(seg, &MEDIUM);
        let importance = |node: &SampleNode| ctx.importance(node);
        let start = 0;
        let probs = light_probabilities(&tree, start, &importance, 0.1);
        let n = 200_000;
        let mut observed = vec![0.0f64; vrls.len()];
        let mut rng = mix64(trial + 77);
        for _ in 0..n {
            let (light, p) = sample_light(&tree, start, &importance, 0.1, &mut rng);
            let expected = probs.iter().find(|q| q.0 == light).unwrap().1;
            assert!((p as f64 / expected - 1.0).abs() < 1e-4, "reported {p} vs computed {expected}");
            observed[light as usize] += 1.0;
        }
        let mut expected = vec![0.0f64; vrls.len()];
        for (l, p) in probs {
            expected[l as usize] = p * n as f64;
        }
        let r = chi2_test(&observed, &expected);
        println!("trial {trial}: {r}");
        assert!(r.passed(0.01 / 6.0), "{r}");
    }
}

/// Brute-force sum over every VRL and one stochastic-cut estimate of the contribution to `seg`
/// (no occlusion; connection transmittance of the homogeneous medium). `misstate` multiplies
/// the probability the estimate divides by for lights under the root's left child.
fn estimates(
    tree: &SampleTree,
    vrls: &[Vrl],
    seg: &Segment,
    settings: &StochasticSettings,
    key: u64,
    misstate: Option<&[bool]>,
) -> (f64, f64) {
    let connect = |y: Vec3, x: Vec3| MEDIUM.sigma_t.exp_neg((x - y).length());
    let uniforms = |light: u32| {
        let h = mix64(key ^ mix64(light as u64 + 1));
        glam::Vec2::new(
            (h >> 40) as f32 / (1u64 << 24) as f32,
            ((h >> 8) & 0xff_ffff) as f32 / (1u64 << 24) as f32,
        )
    };
    let contribution = |l: u32| {
        sample_vrl_contribution(seg, &MEDIUM, &vrls[l as usize], &MEDIUM, uniforms(l), connect).mean() as f64
    };
    let brute: f64 = (0..vrls.len() as u32).map(contribution).sum();
    let ctx = ImportanceContext::new(*seg, &MEDIUM);
    let importance = |node: &SampleNode| ctx.importance(node);
    let mut scratch = StochasticScratch::default();
    let mut est = 0.0f64;
    stochastic_cut(tree, &importance, settings, key ^ 0xabc, &mut scratch, |light, prob| {
        let wrong = misstate.is_some_and(|m| m[light as usize]);
        let prob = if wrong { prob as f64 * 1.1 } else { prob as f64 };
        est += contribution(light) / prob;
    });
    (brute, est)
}

/// Per camera segment, the mean difference between a stochastic estimate and the brute-force
/// sum with the same per-light random numbers (so only the light selection's noise remains;
/// under the null hypothesis its expectation is 0), over `trials` independent keys, z-tested
/// with a Sidak threshold over the segments; returns the number of segments failing and the
/// largest |z|.
fn unbiasedness(settings: StochasticSettings, misstate: bool) -> (usize, f64) {
    let vrls = random_vrls(400, 42);
    let tree = tree_of(&vrls, false, 42);
    let left = {
        let mut below = Vec::new();
        leaves_below(&tree, tree.node(0).children()[0], &mut below);
        let mut m = vec![false; vrls.len()];
        for l in below {
            m[l as usize] = true;
        }
        m
    };
    let mut s = Sampler::from_seed(1234);
    let segments = 12;
    let trials = 2000;
    let threshold = sidak_threshold(0.01, segments);
    let (mut failed, mut worst) = (0, 0.0f64);
    for k in 0..segments {
        let seg = random_segment(&mut s, k);
        let (mut sum, mut sum2, mut brute_sum) = (0.0, 0.0, 0.0);
        for t in 0..trials {
            let key = mix64((k * trials + t) as u64 ^ 0x5151);
            let (brute, est) = estimates(&tree, &vrls, &seg, &settings, key, misstate.then_some(&left[..]));
            let d = est - brute;
            sum += d;
            sum2 += d * d;
            brute_sum += brute;
        }
        let n = trials as f64;
        let mean = sum / n;
        let var = (sum2 / n - mean * mean) / (n - 1.0);
        let z = mean / var.sqrt().max(1e-30);
        println!(
            "k = {}, segment {k}: brute {:.5e}, stochastic - brute {mean:.3e}, z = {z:.2}",
            settings.cut_size,
            brute_sum / n
        );
        worst = worst.max(z.abs());
        if z.abs() > threshold {
            failed += 1;
        }
    }
    (failed, worst)
}

#[test]
fn stochastic_cut_is_unbiased() {
    for cut_size in [1, 4, 16] {
        let settings = StochasticSettings { cut_size, ..Default::default() };
        let (failed, worst) = unbiasedness(settings, false);
        assert_eq!(failed, 0, "k = {cut_size}: {failed} segments fail, max |z| {worst:.2}");
    }
}

/// The negative control: lights under one child of the root divided by 1.1 times their real
/// probability (a 10% error in one child's probability) must be detected.
#[test]
fn misstated_child_probability_fails() {
    let settings = StochasticSettings { cut_size: 16, ..Default::default() };
    let (failed, worst) = unbiasedness(settings, true);
    assert!(failed >= 6, "only {failed} of 12 segments detect the wrong probability (max |z| {worst:.2})");
}

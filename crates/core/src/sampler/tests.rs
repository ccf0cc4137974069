//! The generators' promises: Mitsuba 3.9's sample-count rounding, one point per stratum in the
//! projections each one stratifies, the (0,2)-net property of `ldsampler`, uniform values over
//! pixels (chi-square), and `independent` streams unchanged.

use super::*;
use crate::Sampler;
use haze_testkit::chi2::chi2_test;

/// Samples `0..count` of pixel `pixel`, each `draws` values: `draw(sampler)` per dimension.
fn samples<T>(
    spec: &SamplerSpec,
    pixel: u64,
    first: u64,
    count: u64,
    mut draw: impl FnMut(&mut Sampler) -> T,
) -> Vec<T> {
    let mut s = Sampler::for_pixel(spec, 9, pixel, 0);
    (first..first + count)
        .map(|i| {
            s.start_sample(i);
            draw(&mut s)
        })
        .collect()
}

/// Each of `cells` cells, from `cell(value)`, holds exactly one of `values`.
fn one_per_cell<T: Copy + std::fmt::Debug>(values: &[T], cells: u32, cell: impl Fn(T) -> u32, what: &str) {
    let mut seen = vec![None; cells as usize];
    for &v in values {
        let c = cell(v);
        assert!(c < cells, "{what}: {v:?} outside the cells");
        if let Some(other) = seen[c as usize] {
            panic!("{what}: {v:?} and {other:?} share cell {c} of {cells}");
        }
        seen[c as usize] = Some(v);
    }
    assert_eq!(values.len(), cells as usize, "{what}");
}

fn interval(x: f32, n: u32) -> u32 {
    assert!((0.0..1.0).contains(&x), "{x} outside [0, 1)");
    (x as f64 * n as f64) as u32
}

#[test]
fn sample_counts_round_as_mitsuba_3_9() {
    // Mitsuba 3.9.1 (scalar_rgb): mi.load_dict({'type': t, 'sample_count': n}).sample_count().
    let asked = [1, 2, 4, 5, 10, 16, 17, 30, 64, 100];
    let table: [(SamplerKind, [u32; 10]); 5] = [
        (SamplerKind::Independent, [1, 2, 4, 5, 10, 16, 17, 30, 64, 100]),
        (SamplerKind::Stratified, [1, 4, 4, 9, 16, 16, 25, 36, 64, 100]),
        (SamplerKind::Multijitter, [1, 2, 4, 6, 12, 16, 20, 30, 64, 100]),
        (SamplerKind::Orthogonal, [4, 4, 4, 9, 25, 25, 25, 49, 121, 121]),
        (SamplerKind::LdSampler, [4, 4, 4, 16, 16, 16, 64, 64, 64, 256]),
    ];
    for (kind, want) in table {
        let got: Vec<u32> = asked.iter().map(|&n| kind.round_sample_count(n)).collect();
        assert_eq!(got, want, "{kind}");
    }
    for kind in SamplerKind::ALL {
        assert_eq!(SamplerKind::from_name(kind.name()), Some(kind));
    }
    assert_eq!(SamplerKind::from_name("sobol"), None);
}

#[test]
fn independent_streams_are_the_plain_streams() {
    let spec = SamplerSpec::independent(16);
    let mut a = Sampler::for_pixel(&spec, 3, 77, 5);
    let mut b = Sampler::new(3, 77, 5);
    for i in 0..100 {
        a.start_sample(i / 7);
        assert_eq!(a.next_1d().to_bits(), b.next_1d().to_bits());
        assert_eq!(a.next_2d(), b.next_2d());
        assert_eq!(a.next_u32(), b.next_u32());
    }
}

#[test]
fn stratified_puts_one_sample_per_stratum() {
    for n in [1, 4, 9, 16, 25, 64] {
        let spec = SamplerSpec::new(SamplerKind::Stratified, n);
        let r = (n as f64).sqrt() as u32;
        for pixel in [0, 1, 12345] {
            // Two rounds, each a stratified set of its own.
            for first in [0, n as u64] {
                let pts = samples(&spec, pixel, first, n as u64, |s| {
                    (s.next_2d(), s.next_1d(), s.next_2d(), s.next_1d())
                });
                for (what, v) in [
                    ("dim 0", pts.iter().map(|p| p.0).collect::<Vec<_>>()),
                    ("dim 2", pts.iter().map(|p| p.2).collect()),
                ] {
                    one_per_cell(
                        &v,
                        r * r,
                        |p| interval(p.x, r) + r * interval(p.y, r),
                        &format!("n {n} {what}"),
                    );
                }
                for (what, v) in [
                    ("dim 1", pts.iter().map(|p| p.1).collect::<Vec<_>>()),
                    ("dim 3", pts.iter().map(|p| p.3).collect()),
                ] {
                    one_per_cell(&v, n, |x| interval(x, n), &format!("n {n} {what}"));
                }
            }
        }
    }
}

#[test]
fn multijitter_is_a_grid_and_n_rooks() {
    for n in [2, 6, 12, 16, 20, 30, 64] {
        let spec = SamplerSpec::new(SamplerKind::Multijitter, n);
        let (rx, ry) = spec.resolution();
        assert_eq!(rx * ry, n);
        for first in [0, 3 * n as u64] {
            let pts = samples(&spec, 42, first, n as u64, |s| (s.next_1d(), s.next_2d(), s.next_2d()));
            let one_d: Vec<f32> = pts.iter().map(|p| p.0).collect();
            one_per_cell(&one_d, n, |x| interval(x, n), &format!("n {n} 1D"));
            for (what, v) in [
                ("dim 1", pts.iter().map(|p| p.1).collect::<Vec<_>>()),
                ("dim 2", pts.iter().map(|p| p.2).collect()),
            ] {
                let what = format!("n {n} {what}");
                one_per_cell(&v, rx * ry, |p| interval(p.x, rx) + rx * interval(p.y, ry), &what);
                one_per_cell(&v, n, |p| interval(p.x, n), &format!("{what} x"));
                one_per_cell(&v, n, |p| interval(p.y, n), &format!("{what} y"));
            }
        }
    }
}

#[test]
fn orthogonal_stratifies_every_pair_of_its_p_plus_1_dimensions() {
    for p in [2u32, 3, 5, 7] {
        let n = p * p;
        let spec = SamplerSpec::new(SamplerKind::Orthogonal, n);
        assert_eq!(spec.sample_count(), n);
        for first in [0, n as u64] {
            let dims = (p + 1) as usize;
            let pts =
                samples(&spec, 5, first, n as u64, |s| (0..dims).map(|_| s.next_1d()).collect::<Vec<f32>>());
            for j in 0..dims {
                let col: Vec<f32> = pts.iter().map(|v| v[j]).collect();
                one_per_cell(&col, n, |x| interval(x, n), &format!("p {p} dim {j}"));
                for k in j + 1..dims {
                    let pair: Vec<(f32, f32)> = pts.iter().map(|v| (v[j], v[k])).collect();
                    one_per_cell(
                        &pair,
                        n,
                        |(a, b)| interval(a, p) + p * interval(b, p),
                        &format!("p {p} dims {j}, {k}"),
                    );
                }
            }
        }
        // next_2d is two dimensions.
        let pts = samples(&spec, 5, 0, n as u64, |s| {
            let a = s.next_2d();
            (a, s.next_1d())
        });
        let third: Vec<f32> = pts.iter().map(|v| v.1).collect();
        one_per_cell(&third, n, |x| interval(x, n), "dimension after a 2D draw");
    }
}

/// Every elementary interval `[a 2^-k, (a + 1) 2^-k) x [b 2^-(m-k), (b + 1) 2^-(m-k))` of area
/// `2^-m` holds exactly one of the `2^m` points.
fn assert_02_net(pts: &[(f32, f32)], what: &str) {
    let m = pts.len().trailing_zeros();
    assert_eq!(1 << m, pts.len());
    for k in 0..=m {
        let (nx, ny) = (1u32 << k, 1u32 << (m - k));
        one_per_cell(
            pts,
            1 << m,
            |(x, y)| interval(x, nx) + nx * interval(y, ny),
            &format!("{what}, {nx} x {ny}"),
        );
    }
}

#[test]
fn ldsampler_rounds_are_02_nets() {
    for n in [4, 16, 64, 256] {
        let spec = SamplerSpec::new(SamplerKind::LdSampler, n);
        for pixel in [0, 99] {
            // Rounds 0 and 1, each a net; together the sequence's first 2n points, a net too.
            let pts = samples(&spec, pixel, 0, 2 * n as u64, |s| {
                let a = s.next_2d();
                (s.next_1d(), (a.x, a.y), s.next_2d())
            });
            for (lo, hi) in [(0, n), (n, 2 * n), (0, 2 * n)] {
                let block = &pts[lo as usize..hi as usize];
                let what = format!("n {n} pixel {pixel} samples {lo}..{hi}");
                assert_02_net(&block.iter().map(|p| p.1).collect::<Vec<_>>(), &format!("{what} dim 0"));
                assert_02_net(
                    &block.iter().map(|p| (p.2.x, p.2.y)).collect::<Vec<_>>(),
                    &format!("{what} dim 2"),
                );
                let one_d: Vec<f32> = block.iter().map(|p| p.0).collect();
                one_per_cell(&one_d, hi - lo, |x| interval(x, hi - lo), &format!("{what} dim 1"));
            }
        }
    }
}

/// A dimension's value at a fixed sample index, over many pixels (each its own randomisation),
/// is uniform: chi-square over 16 x 16 cells in 2D and 64 intervals in 1D.
#[test]
fn values_are_uniform_over_pixels() {
    let pixels = 25_600u64;
    for kind in SamplerKind::ALL {
        for jitter in [true, false] {
            if !jitter && matches!(kind, SamplerKind::Independent | SamplerKind::LdSampler) {
                continue;
            }
            let mut spec = SamplerSpec::new(kind, 16);
            spec.jitter = jitter;
            // Without jitter the values sit at the centres of the n intervals: count per interval.
            let cells_1d = if jitter { 64 } else { spec.sample_count() as usize };
            let (mut c2, mut c1) = (vec![0.0f64; 256], vec![0.0f64; cells_1d]);
            for pixel in 0..pixels {
                let mut s = Sampler::for_pixel(&spec, 1, pixel, 0);
                s.start_sample(pixel % 37);
                s.next_2d();
                let u = s.next_2d();
                let x = s.next_1d();
                c2[(interval(u.x, 16) + 16 * interval(u.y, 16)) as usize] += 1.0;
                c1[interval(x, cells_1d as u32) as usize] += 1.0;
            }
            let r1 = chi2_test(&c1, &vec![pixels as f64 / cells_1d as f64; cells_1d]);
            assert!(r1.passed(1e-3), "{kind} jitter {jitter} 1D: {r1}");
            if jitter {
                let r2 = chi2_test(&c2, &vec![pixels as f64 / 256.0; 256]);
                assert!(r2.passed(1e-3), "{kind} 2D: {r2}");
            }
        }
    }
}

/// A sample's values depend on its index, not on the samples drawn before it.
#[test]
fn a_sample_depends_only_on_its_index() {
    for kind in SamplerKind::ALL.into_iter().skip(1) {
        let spec = SamplerSpec::new(kind, 16);
        let in_order = samples(&spec, 7, 0, 40, |s| (s.next_2d(), s.next_1d()));
        for i in [0u64, 13, 39] {
            // Jitter comes from the pixel's stream: a fresh sampler at sample i differs only there.
            let mut spec_nj = spec;
            spec_nj.jitter = false;
            let mut a = Sampler::for_pixel(&spec_nj, 9, 7, 0);
            let mut b = Sampler::for_pixel(&spec_nj, 9, 7, 3);
            a.start_sample(i);
            b.next_2d();
            b.start_sample(i);
            assert_eq!((a.next_2d(), a.next_1d()), (b.next_2d(), b.next_1d()), "{kind} sample {i}");
        }
        assert!(in_order
            .iter()
            .all(|(u, x)| (0.0..1.0).contains(&u.x) && (0.0..1.0).contains(&u.y) && (0.0..1.0).contains(x)));
    }
}

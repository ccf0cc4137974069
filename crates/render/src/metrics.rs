//! Image error metrics against a reference, as used in equal-time comparisons (`haze compare`).
//!
//! Images are row-major linear RGB (`[r, g, b]` per pixel, as `Film::mean` returns them). Every
//! metric averages over all pixels and all three channels, or only over the pixels whose entry in
//! the optional `mask` (one `bool` per pixel) is `true`. Sums are taken in `f64`.
//!
//! Preconditions (checked with `assert!`, the caller validates user images first):
//! `approx.len() == reference.len()`, a multiple of 3, and `mask.len() == reference.len() / 3`.

/// Guard added to the denominators of [`rel_mse`] and [`mean_abs_rel_error`] so that black or
/// nearly black reference pixels do not dominate: the usual value (e.g. Rousselle et al. 2011,
/// Vibert et al. 2019), for images whose interesting radiance is of order 0.1 to 10.
pub const REL_GUARD: f64 = 1e-2;

/// All four metrics of one image against a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub rmse: f64,
    pub rel_mse: f64,
    pub smape: f64,
    pub mare: f64,
}

impl Metrics {
    /// Computes every metric of `approx` against `reference` (see the module preconditions).
    pub fn compute(approx: &[f32], reference: &[f32], mask: Option<&[bool]>) -> Metrics {
        Metrics {
            rmse: rmse(approx, reference, mask),
            rel_mse: rel_mse(approx, reference, mask),
            smape: smape(approx, reference, mask),
            mare: mean_abs_rel_error(approx, reference, mask),
        }
    }
}

/// Root mean squared error: `sqrt( mean_{pixels p, channels c} (a_pc - r_pc)^2 )`, in the
/// images' radiance units. Fireflies weigh heavily.
pub fn rmse(approx: &[f32], reference: &[f32], mask: Option<&[bool]>) -> f64 {
    mean_over(approx, reference, mask, |a, r| Some((a - r) * (a - r))).sqrt()
}

/// Relative mean squared error: `mean_{p,c} (a - r)^2 / (r^2 + g)` with the guard
/// `g = REL_GUARD = 1e-2`. Dimensionless.
pub fn rel_mse(approx: &[f32], reference: &[f32], mask: Option<&[bool]>) -> f64 {
    mean_over(approx, reference, mask, |a, r| Some((a - r) * (a - r) / (r * r + REL_GUARD)))
}

/// Symmetric mean absolute percentage error, in percent, with the convention
/// `100 * mean_{p,c} |a - r| / (|a| + |r|)` (range 0 to 100; some authors use 200 and a
/// half-sum denominator, which doubles the numbers). Entries (pixel, channel) where both `a`
/// and `r` are 0 are skipped: they are exact, and the ratio is undefined there. Robust to
/// fireflies, since each entry contributes at most 100.
pub fn smape(approx: &[f32], reference: &[f32], mask: Option<&[bool]>) -> f64 {
    100.0
        * mean_over(approx, reference, mask, |a, r| {
            let d = a.abs() + r.abs();
            (d > 0.0).then(|| (a - r).abs() / d)
        })
}

/// Mean absolute relative error: `mean_{p,c} |a - r| / (|r| + g)` with the guard
/// `g = REL_GUARD = 1e-2`. Dimensionless.
pub fn mean_abs_rel_error(approx: &[f32], reference: &[f32], mask: Option<&[bool]>) -> f64 {
    mean_over(approx, reference, mask, |a, r| Some((a - r).abs() / (r.abs() + REL_GUARD)))
}

/// Per-pixel relative error `mean_c |a - r| / (|r| + g)` (the per-pixel term of
/// [`mean_abs_rel_error`]), for false-colour error maps. One value per pixel.
pub fn per_pixel_rel_error(approx: &[f32], reference: &[f32]) -> Vec<f32> {
    check_sizes(approx, reference, None);
    approx
        .chunks_exact(3)
        .zip(reference.chunks_exact(3))
        .map(|(a, r)| {
            let s: f64 =
                (0..3).map(|c| (a[c] as f64 - r[c] as f64).abs() / ((r[c] as f64).abs() + REL_GUARD)).sum();
            (s / 3.0) as f32
        })
        .collect()
}

fn check_sizes(approx: &[f32], reference: &[f32], mask: Option<&[bool]>) {
    assert_eq!(approx.len(), reference.len(), "metrics: images of different sizes");
    assert_eq!(reference.len() % 3, 0, "metrics: RGB images have 3 floats per pixel");
    if let Some(m) = mask {
        assert_eq!(m.len() * 3, reference.len(), "metrics: the mask needs one entry per pixel");
    }
}

/// Mean of `term(a, r)` over the (pixel, channel) entries selected by `mask` for which `term`
/// is `Some`; 0 if there are none.
fn mean_over(
    approx: &[f32],
    reference: &[f32],
    mask: Option<&[bool]>,
    term: impl Fn(f64, f64) -> Option<f64>,
) -> f64 {
    check_sizes(approx, reference, mask);
    let (mut sum, mut n) = (0.0f64, 0u64);
    for (p, (a, r)) in approx.chunks_exact(3).zip(reference.chunks_exact(3)).enumerate() {
        if mask.is_some_and(|m| !m[p]) {
            continue;
        }
        for c in 0..3 {
            if let Some(t) = term(a[c] as f64, r[c] as f64) {
                sum += t;
                n += 1;
            }
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close_to(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol * b.abs().max(1.0), "{a} != {b}");
    }

    fn close(a: f64, b: f64) {
        close_to(a, b, 1e-9);
    }

    // Two pixels: reference (1,1,1) (0,0,0); approx (2,1,1) (0,0,0.5).
    const R: [f32; 6] = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    const A: [f32; 6] = [2.0, 1.0, 1.0, 0.0, 0.0, 0.5];

    #[test]
    fn identical_images_have_zero_error() {
        let m = Metrics::compute(&R, &R, None);
        assert_eq!(m, Metrics { rmse: 0.0, rel_mse: 0.0, smape: 0.0, mare: 0.0 });
    }

    #[test]
    fn rmse_by_hand() {
        // squared errors 1, 0, 0, 0, 0, 0.25 over 6 entries.
        close(rmse(&A, &R, None), (1.25f64 / 6.0).sqrt());
    }

    #[test]
    fn rel_mse_by_hand() {
        // 1/(1+0.01) + 0.25/(0+0.01), over 6.
        close(rel_mse(&A, &R, None), (1.0 / 1.01 + 0.25 / 0.01) / 6.0);
    }

    #[test]
    fn smape_skips_entries_where_both_are_zero() {
        // Entries: |2-1|/3, 0, 0 | skipped, skipped, |0.5-0|/0.5 = 1 -> 4 entries.
        close(smape(&A, &R, None), 100.0 * (1.0 / 3.0 + 1.0) / 4.0);
        // Only zeros: nothing to average.
        assert_eq!(smape(&[0.0; 3], &[0.0; 3], None), 0.0);
    }

    #[test]
    fn smape_is_at_most_100_and_symmetric() {
        let a = [5.0, 0.0, 1e6];
        let r = [0.0, 3.0, 1.0];
        let s = smape(&a, &r, None);
        assert!(s <= 100.0 && s > 99.0, "{s}");
        close(s, smape(&r, &a, None));
    }

    #[test]
    fn mean_abs_rel_error_by_hand() {
        // 1/(1+0.01) + 0.5/(0+0.01), over 6.
        close(mean_abs_rel_error(&A, &R, None), (1.0 / 1.01 + 0.5 / 0.01) / 6.0);
    }

    #[test]
    fn mask_selects_pixels() {
        let only_first = [true, false];
        close(rmse(&A, &R, Some(&only_first)), (1.0f64 / 3.0).sqrt());
        close(smape(&A, &R, Some(&only_first)), 100.0 / 9.0);
        let none = [false, false];
        assert_eq!(rmse(&A, &R, Some(&none)), 0.0);
    }

    #[test]
    fn per_pixel_rel_error_by_hand() {
        let e = per_pixel_rel_error(&A, &R);
        assert_eq!(e.len(), 2);
        // f32 output: compare to single precision.
        close_to(e[0] as f64, 1.0 / 1.01 / 3.0, 1e-6);
        close_to(e[1] as f64, 50.0 / 3.0, 1e-6);
        // Its mean is the mean absolute relative error.
        close_to((e[0] as f64 + e[1] as f64) / 2.0, mean_abs_rel_error(&A, &R, None), 1e-6);
    }

    #[test]
    #[should_panic(expected = "different sizes")]
    fn different_sizes_panic() {
        rmse(&A, &R[..3], None);
    }
}

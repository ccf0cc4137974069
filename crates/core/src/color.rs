//! Colour: CIE 1931 colour matching, and the conversion of a sampled spectrum to linear sRGB
//! the way Mitsuba 3's RGB variants do when they read a `<spectrum>` given as
//! wavelength:value pairs.
//!
//! Mitsuba 3 (`spectrum_list_to_srgb`): the piecewise-linear spectrum (zero outside its first and
//! last wavelength) is integrated against the CIE 1931 2-degree matching functions with a
//! 1000-point rule over 360..830 nm; the matching functions are the 5 nm table, linearly
//! interpolated and divided by the integral of y-bar as Mitsuba states it (106.7502593994...);
//! reflectances are weighted by the D65 illuminant (normalised to unit luminance) so that a
//! constant 1 gives white, emission spectra are not. XYZ goes to linear sRGB (Rec. 709
//! primaries, D65 white) with the usual matrix; negative results clamp to 0 and bounded
//! (reflectance) results to 1.
//!
//! Data: CIE 1931 2-degree standard observer and CIE standard illuminant D65, 360..830 nm in
//! 5 nm steps (CIE 015 tables).

/// First and last wavelength of the tables, in nm.
pub const CIE_MIN: f32 = 360.0;
pub const CIE_MAX: f32 = 830.0;
const CIE_SAMPLES: usize = 95;
/// `1 / integral of y-bar`, as Mitsuba 3 states it (`MI_CIE_Y_NORMALIZATION`).
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// `1 / integral of y-bar * D65 * CIE_Y_NORMALIZATION` (unit luminance for D65).
const CIE_D65_NORMALIZATION: f64 = 1.0 / 98.997_417_518_762_55;

/// The CIE 1931 matching functions `(x-bar, y-bar, z-bar)` at `lambda` nm, linearly
/// interpolated, zero outside `[CIE_MIN, CIE_MAX]`, and divided by the integral of y-bar.
pub fn cie1931_xyz(lambda: f32) -> [f64; 3] {
    let Some((i, t)) = table_position(lambda) else { return [0.0; 3] };
    let (a, b) = (CIE_1931_XYZ[i], CIE_1931_XYZ[(i + 1).min(CIE_SAMPLES - 1)]);
    std::array::from_fn(|k| (a[k] as f64 * (1.0 - t) + b[k] as f64 * t) * CIE_Y_NORMALIZATION)
}

/// The D65 illuminant at `lambda` nm, scaled to unit luminance; zero outside the table.
pub fn cie_d65(lambda: f32) -> f64 {
    let Some((i, t)) = table_position(lambda) else { return 0.0 };
    let (a, b) = (CIE_D65[i] as f64, CIE_D65[(i + 1).min(CIE_SAMPLES - 1)] as f64);
    (a * (1.0 - t) + b * t) * CIE_D65_NORMALIZATION
}

fn table_position(lambda: f32) -> Option<(usize, f64)> {
    if !(CIE_MIN..=CIE_MAX).contains(&lambda) {
        return None;
    }
    let x = (lambda as f64 - CIE_MIN as f64) / 5.0;
    let i = (x.floor() as usize).min(CIE_SAMPLES - 2);
    Some((i, x - i as f64))
}

/// CIE XYZ to linear sRGB (Rec. 709 primaries, D65 white).
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] =
        [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556], [0.055648, -0.204043, 1.057311]];
    std::array::from_fn(|r| M[r][0] * xyz[0] + M[r][1] * xyz[1] + M[r][2] * xyz[2])
}

/// What a spectrum describes, which decides how Mitsuba 3 converts it to RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumKind {
    /// Emitted radiance or intensity: no illuminant weighting, unbounded.
    Emission,
    /// A reflectance or albedo: weighted by D65 (so that 1 is white) and clamped to `[0, 1]`.
    Reflectance,
    /// Any other unbounded quantity (e.g. extinction): weighted by D65, not clamped above.
    Unbounded,
}

/// Linear sRGB of the piecewise-linear spectrum through `(wavelengths[i], values[i])`
/// (wavelengths in nm, strictly increasing, at least two), zero outside its range; see the
/// module documentation for the rule.
pub fn spectrum_to_linear_srgb(wavelengths: &[f32], values: &[f32], kind: SpectrumKind) -> [f32; 3] {
    assert!(wavelengths.len() >= 2 && wavelengths.len() == values.len());
    const STEPS: usize = 1000;
    let (first, last) = (wavelengths[0], wavelengths[wavelengths.len() - 1]);
    let mut xyz = [0.0f64; 3];
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f32 / (STEPS - 1) as f32) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        let j = wavelengths.partition_point(|&x| x <= w).clamp(1, wavelengths.len() - 1) - 1;
        let (w0, w1) = (wavelengths[j] as f64, wavelengths[j + 1] as f64);
        let (v0, v1) = (values[j] as f64, values[j + 1] as f64);
        let v = ((w as f64 - w1) * v0 + (w0 - w as f64) * v1) / (w0 - w1);
        let illuminant = if kind == SpectrumKind::Emission { 1.0 } else { cie_d65(w) };
        let cmf = cie1931_xyz(w);
        for k in 0..3 {
            xyz[k] += cmf[k] * v * illuminant;
        }
    }
    let dw = (CIE_MAX - CIE_MIN) as f64 / STEPS as f64;
    let rgb = xyz_to_linear_srgb(xyz.map(|c| c * dw));
    let upper = if kind == SpectrumKind::Reflectance { 1.0 } else { f64::INFINITY };
    rgb.map(|c| c.clamp(0.0, upper) as f32)
}

// The tables (generated; 95 rows, 360..830 nm in 5 nm steps).
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const CIE_1931_XYZ: [[f32; 3]; CIE_SAMPLES] = [
    [0.00012989999999999996, 3.917e-06, 0.0006060999999999996],
    [0.00023209999999999992, 6.9650000000000045e-06, 0.0010859999999999997],
    [0.00041489999999999984, 1.238999999999999e-05, 0.0019459999999999996],
    [0.0007416, 2.202e-05, 0.0034860000000000013],
    [0.0013679999999999996, 3.8999999999999986e-05, 0.006450001000000006],
    [0.0022360000000000023, 6.399999999999986e-05, 0.01054998999999999],
    [0.004243000000000001, 0.00011999999999999996, 0.02005001],
    [0.007649999999999997, 0.00021700000000000012, 0.03621000000000005],
    [0.01431000000000001, 0.0003960000000000002, 0.06785000999999995],
    [0.023190000000000054, 0.00064, 0.11020000000000003],
    [0.04351000000000001, 0.0012100000000000012, 0.20739999999999992],
    [0.07762999999999998, 0.0021800000000000014, 0.3712999999999997],
    [0.13437999999999997, 0.003999999999999999, 0.6456000000000005],
    [0.2147699999999999, 0.007299999999999998, 1.039050099999999],
    [0.2838999999999999, 0.01160000000000001, 1.385599999999999],
    [0.32849999999999974, 0.01684, 1.6229599999999993],
    [0.34828000000000003, 0.023000000000000007, 1.74706],
    [0.34806000000000004, 0.029800000000000007, 1.7825999999999984],
    [0.33619999999999955, 0.038, 1.7721099999999994],
    [0.3187, 0.047999999999999994, 1.7441000000000002],
    [0.29080000000000045, 0.06000000000000007, 1.6692000000000002],
    [0.25109999999999993, 0.0739, 1.528099999999999],
    [0.19535999999999984, 0.09098000000000005, 1.2876400000000008],
    [0.1421000000000001, 0.11259999999999994, 1.0418999999999994],
    [0.09564000000000003, 0.13902000000000012, 0.8129500999999997],
    [0.05795000999999997, 0.1692999999999998, 0.6162000000000006],
    [0.03201000000000001, 0.2080200000000003, 0.4651799999999995],
    [0.014700000000000013, 0.2586, 0.3533],
    [0.004899999999999991, 0.3230000000000002, 0.27200000000000024],
    [0.0023999999999999994, 0.4072999999999996, 0.21229999999999993],
    [0.009299999999999992, 0.5029999999999993, 0.15819999999999984],
    [0.029099999999999987, 0.6081999999999996, 0.11169999999999998],
    [0.06327, 0.7100000000000011, 0.07824998999999999],
    [0.10960000000000004, 0.7931999999999996, 0.057250010000000094],
    [0.16549999999999998, 0.862, 0.04215999999999998],
    [0.22574989999999995, 0.9148501, 0.029839999999999988],
    [0.29040000000000016, 0.9540000000000008, 0.02029999999999997],
    [0.35969999999999985, 0.9803000000000001, 0.013400000000000002],
    [0.43344989999999994, 0.9949500999999998, 0.008749999000000007],
    [0.5120500999999997, 1.0, 0.005749998999999996],
    [0.5945000000000003, 0.9949999999999998, 0.0039000000000000003],
    [0.6783999999999999, 0.9785999999999992, 0.002749999000000002],
    [0.7621000000000006, 0.9519999999999996, 0.0021000000000000016],
    [0.8425000000000007, 0.9153999999999994, 0.0018000000000000021],
    [0.9162999999999994, 0.870000000000001, 0.0016500009999999988],
    [0.9785999999999999, 0.8162999999999996, 0.0013999999999999996],
    [1.0262999999999995, 0.7570000000000003, 0.0010999999999999994],
    [1.0566999999999995, 0.6948999999999996, 0.000999999999999999],
    [1.0621999999999998, 0.6310000000000002, 0.0007999999999999991],
    [1.045599999999998, 0.5668, 0.0006000000000000005],
    [1.0025999999999997, 0.5029999999999999, 0.0003399999999999997],
    [0.9383999999999995, 0.44120000000000004, 0.0002400000000000002],
    [0.8544498999999998, 0.38099999999999984, 0.0001899999999999999],
    [0.7514000000000005, 0.3210000000000003, 0.00010000000000000003],
    [0.6423999999999992, 0.2650000000000002, 4.999999000000001e-05],
    [0.5418999999999992, 0.21699999999999997, 2.999999999999997e-05],
    [0.4479000000000001, 0.17499999999999988, 2.0000000000000005e-05],
    [0.3607999999999996, 0.1382000000000001, 9.999999999999999e-06],
    [0.28349999999999986, 0.10699999999999996, -1.9058241313221758e-21],
    [0.2187, 0.08160000000000002, 0.0],
    [0.16489999999999996, 0.060999999999999985, 0.0],
    [0.12120000000000003, 0.04458000000000006, 0.0],
    [0.08739999999999999, 0.032000000000000035, 0.0],
    [0.06360000000000007, 0.023199999999999964, 0.0],
    [0.04676999999999999, 0.016999999999999998, 0.0],
    [0.032899999999999964, 0.01191999999999998, 0.0],
    [0.02269999999999998, 0.008209999999999997, 0.0],
    [0.015840000000000014, 0.005722999999999998, 0.0],
    [0.011359160000000002, 0.004101999999999994, 0.0],
    [0.00811091600000002, 0.002929, 0.0],
    [0.005790345999999993, 0.002090999999999997, 0.0],
    [0.004109457000000005, 0.0014839999999999981, 0.0],
    [0.0028993270000000015, 0.0010469999999999998, 0.0],
    [0.002049189999999999, 0.0007400000000000007, 0.0],
    [0.001439971, 0.0005200000000000003, 0.0],
    [0.0009999492999999999, 0.00036109999999999945, 0.0],
    [0.0006900785999999999, 0.00024920000000000004, 0.0],
    [0.0004760213, 0.00017189999999999981, 0.0],
    [0.0003323010999999997, 0.00011999999999999994, 0.0],
    [0.0002348260999999999, 8.479999999999996e-05, 0.0],
    [0.00016615049999999985, 5.9999999999999954e-05, 0.0],
    [0.00011741300000000005, 4.2400000000000055e-05, 0.0],
    [8.307527000000009e-05, 2.9999999999999997e-05, 0.0],
    [5.870652e-05, 2.1199999999999997e-05, 0.0],
    [4.1509940000000044e-05, 1.4990000000000004e-05, 0.0],
    [2.935325999999998e-05, 1.0599999999999995e-05, 0.0],
    [2.067382999999998e-05, 7.465699999999997e-06, 0.0],
    [1.4559770000000004e-05, 5.257800000000001e-06, 0.0],
    [1.0253979999999997e-05, 3.7029000000000014e-06, 0.0],
    [7.221456000000013e-06, 2.6078000000000003e-06, 0.0],
    [5.085868000000002e-06, 1.8366000000000029e-06, 0.0],
    [3.5816519999999944e-06, 1.2934000000000006e-06, 0.0],
    [2.522524999999999e-06, 9.1093e-07, 0.0],
    [1.7765089999999997e-06, 6.415299999999999e-07, 0.0],
    [1.2511409999999992e-06, 4.518099999999998e-07, 0.0],
];
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const CIE_D65: [f32; CIE_SAMPLES] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015,
    82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736,
    104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296,
    104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939,
    83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281,
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.5927, 55.0054, 46.4182, 56.6118,
    66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The triple docs/mitsuba-compat.md and the peer README quote for Mitsuba 3's RGB variants.
    #[test]
    fn emission_spectrum_matches_mitsuba() {
        let rgb = spectrum_to_linear_srgb(
            &[400.0, 500.0, 600.0, 700.0],
            &[0.0, 0.3, 0.8, 1.1],
            SpectrumKind::Emission,
        );
        let expected = [1.12687, 0.488194, 0.0880343];
        for k in 0..3 {
            assert!((rgb[k] - expected[k]).abs() < 2e-5 * expected[k].max(1.0), "{rgb:?}");
        }
    }

    #[test]
    fn constant_reflectance_is_white() {
        let rgb = spectrum_to_linear_srgb(&[CIE_MIN, CIE_MAX], &[1.0, 1.0], SpectrumKind::Reflectance);
        for c in rgb {
            assert!((c - 1.0).abs() < 0.01, "{rgb:?}");
        }
    }

    #[test]
    fn y_bar_integrates_to_one() {
        let y: f64 = (0..=470).map(|i| cie1931_xyz(CIE_MIN + i as f32)[1]).sum();
        assert!((y - 1.0).abs() < 0.01, "{y}");
    }
}

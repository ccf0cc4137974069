//! What `haze compare` measured of each method: made by `compare.rs`, shown by its table and by
//! the HTML report (`report.rs`), which needs no more of the method than its label.

use haze_render::metrics::Metrics;
use std::fmt;

/// The error of a method's image at one moment of its run.
#[derive(Clone, Copy, Debug)]
pub struct CurvePoint {
    pub seconds: f64,
    pub metrics: Metrics,
}

/// How a method is named in tables, plots and file names.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodLabel {
    /// The method spec as the user writes it, e.g. `vrl_lightcuts:100000,epsilon=0.01`.
    pub text: String,
    /// A file-name-safe form of `text`.
    pub file_stem: String,
    /// Virtual lights per pass, if the method has any.
    pub lights: Option<u64>,
}

impl MethodLabel {
    pub fn file_stem(&self) -> String {
        self.file_stem.clone()
    }

    pub fn light_count(&self) -> Option<u64> {
        self.lights
    }
}

impl fmt::Display for MethodLabel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// What one method produced in its time budget.
pub struct MethodResult {
    pub spec: MethodLabel,
    pub seconds: f64,
    pub passes: u32,
    pub metrics: Metrics,
    pub mean_cut: Option<f64>,
    /// Row-major linear RGB.
    pub image: Vec<f32>,
    /// Error at the end of passes (geometrically spaced), for the convergence plot.
    pub curve: Vec<CurvePoint>,
}

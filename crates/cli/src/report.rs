//! The static HTML report of `haze compare --report DIR`: the reference and every method side by
//! side (tone-mapped PNGs), false-colour maps of the per-pixel relative error with a colour bar,
//! 4x zoomed crops of the image centre, the results table, and log-log convergence plots (error
//! vs time, sampled at the end of passes) drawn with plotters as SVG. No server or script needed.

use crate::results::{CurvePoint, MethodResult};
use anyhow::{anyhow, Context, Result};
use haze_render::image_io::RgbImage;
use haze_render::metrics::{per_pixel_rel_error, REL_GUARD};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Relative error shown at the top of the colour scale (larger errors saturate).
const ERROR_SCALE_MAX: f32 = 1.0;
/// Line colours of the plots (Tableau 10, readable on white).
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];
/// Base of a log axis from `lo` to `hi`: 10, or 2 when the range holds less than a decade (see
/// `Report::plot`).
fn log_base(lo: f64, hi: f64) -> f64 {
    if hi < 8.0 * lo {
        2.0
    } else {
        10.0
    }
}

/// Magnification of the crops.
const ZOOM: usize = 4;

/// Marks the page once loaded: `data-images` on `<body>` is `ok` or the list of images that did
/// not load, so a headless browser (`scripts/report-screenshot.sh`) can check the page and not
/// only take a picture of it.
const IMAGE_CHECK: &str = "<script>window.addEventListener('load', () => {\n\
  const bad = [...document.images].filter(i => !i.complete || i.naturalWidth === 0).map(i => i.getAttribute('src'));\n\
  document.body.dataset.images = bad.length ? 'missing: ' + bad.join(' ') : 'ok';\n});</script>\n";

pub struct Report<'a> {
    pub scene: &'a Path,
    pub width: usize,
    pub height: usize,
    /// Seconds per method.
    pub budget: f64,
    pub reference: &'a [f32],
    pub results: &'a [MethodResult],
    pub exposure: f32,
}

/// Viridis, sampled at 0, 1/4, ..., 1 (sRGB 8-bit), linearly interpolated.
fn viridis(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f32;
    let mut out = [0u8; 3];
    for c in 0..3 {
        out[c] = (STOPS[i][c] * (1.0 - f) + STOPS[i + 1][c] * f).round() as u8;
    }
    out
}

fn write_rgb8(path: &Path, width: usize, height: usize, data: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(width as u32, height as u32, data)
        .ok_or_else(|| anyhow!("{}: wrong buffer size", path.display()))?;
    img.save(path).with_context(|| format!("writing {}", path.display()))
}

/// The square crop at the image centre, a quarter of the smaller side (at least 1 pixel).
fn crop_window(width: usize, height: usize) -> (usize, usize, usize) {
    let size = (width.min(height) / 4).max(1);
    ((width - size) / 2, (height - size) / 2, size)
}

/// The crop of `data` (row-major RGB) magnified `ZOOM` times by pixel replication.
fn zoomed_crop(data: &[f32], width: usize, (x0, y0, size): (usize, usize, usize)) -> RgbImage {
    let n = size * ZOOM;
    let mut out = Vec::with_capacity(n * n * 3);
    for y in 0..n {
        for x in 0..n {
            let i = ((y0 + y / ZOOM) * width + x0 + x / ZOOM) * 3;
            out.extend_from_slice(&data[i..i + 3]);
        }
    }
    RgbImage::new(n, n, out)
}

impl Report<'_> {
    /// Writes `dir/index.html` and its images; returns the page's path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let (w, h) = (self.width, self.height);
        let crop = crop_window(w, h);
        let write_png = |name: &str, img: &RgbImage| -> Result<()> {
            let p = dir.join(name);
            img.write_png(&p, self.exposure).with_context(|| format!("writing {}", p.display()))
        };
        write_png("reference.png", &RgbImage::new(w, h, self.reference.to_vec()))?;
        write_png("reference_crop.png", &zoomed_crop(self.reference, w, crop))?;
        for r in self.results {
            let stem = r.spec.file_stem();
            write_png(&format!("{stem}.png"), &RgbImage::new(w, h, r.image.clone()))?;
            write_png(&format!("{stem}_crop.png"), &zoomed_crop(&r.image, w, crop))?;
            let err = per_pixel_rel_error(&r.image, self.reference);
            let rgb = err.iter().flat_map(|e| viridis(e / ERROR_SCALE_MAX)).collect();
            write_rgb8(&dir.join(format!("{stem}_error.png")), w, h, rgb)?;
        }
        let bar: Vec<u8> = (0..16).flat_map(|_| (0..256).flat_map(|x| viridis(x as f32 / 255.0))).collect();
        write_rgb8(&dir.join("colorbar.png"), 256, 16, bar)?;
        self.plot(&dir.join("convergence_rmse.svg"), "RMSE", |m| m.metrics.rmse)?;
        self.plot(&dir.join("convergence_smape.svg"), "SMAPE (%)", |m| m.metrics.smape)?;
        let index = dir.join("index.html");
        std::fs::write(&index, self.html(crop)).with_context(|| format!("writing {}", index.display()))?;
        Ok(index)
    }

    /// Log-log plot of `metric` against time, one line per method.
    fn plot(&self, path: &Path, label: &str, metric: impl Fn(&CurvePoint) -> f64) -> Result<()> {
        let series: Vec<(String, Vec<(f64, f64)>)> = self
            .results
            .iter()
            .map(|r| (r.spec.to_string(), r.curve.iter().map(|p| (p.seconds, metric(p))).collect()))
            .collect();
        log_log_plot(path, &format!("{label} vs time (log-log)"), "time (s)", label, &series)
    }

    fn html(&self, (cx, cy, cs): (usize, usize, usize)) -> String {
        let scene = esc(&self.scene.display().to_string());
        let mut s = String::new();
        let _ = write!(
            s,
            r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>haze compare: {scene}</title>
<style>
body {{ font-family: sans-serif; margin: 20px; color: #222; }}
.row {{ display: flex; flex-wrap: wrap; gap: 12px; }}
figure {{ margin: 0; }}
figcaption {{ font-size: 13px; text-align: center; }}
img.pix {{ image-rendering: pixelated; }}
table {{ border-collapse: collapse; margin: 12px 0; }}
td, th {{ border: 1px solid #bbb; padding: 3px 8px; text-align: right; }}
td:first-child, th:first-child {{ text-align: left; }}
.bar {{ display: flex; align-items: center; gap: 8px; font-size: 13px; }}
</style></head><body>
<h1>haze compare: {scene}</h1>
<p>{w}x{h} pixels, {budget} s per method (light tracing and tree builds included), run one after another on all cores.</p>
"#,
            w = self.width,
            h = self.height,
            budget = self.budget,
        );
        s += "<h2>Results</h2>\n<table><tr><th>method</th><th>lights</th><th>time (s)</th><th>passes</th>\
              <th>RMSE</th><th>SMAPE (%)</th><th>relMSE</th><th>MARE</th><th>mean cut size</th></tr>\n";
        for r in self.results {
            let lights = r.spec.light_count().map_or("-".to_string(), |n| n.to_string());
            let cut = r.mean_cut.map_or("-".to_string(), |c| format!("{c:.1}"));
            let m = &r.metrics;
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td>{lights}</td><td>{:.2}</td><td>{}</td><td>{:.4}</td><td>{:.2}</td><td>{:.4}</td><td>{:.4}</td><td>{cut}</td></tr>",
                esc(&r.spec.to_string()),
                r.seconds,
                r.passes,
                m.rmse,
                m.smape,
                m.rel_mse,
                m.mare
            );
        }
        s += "</table>\n<p>SMAPE = 100 mean |a-r|/(|a|+|r|) over pixels and channels, entries where both are 0 \
              skipped; relMSE = mean (a-r)^2/(r^2+0.01); MARE = mean |a-r|/(|r|+0.01).</p>\n";
        // Small images are shown magnified (pixel replication) to at least 256 pixels wide.
        let shown = self.width * (256 / self.width.max(1)).max(1);
        let crop_shown = cs * ZOOM * (128 / (cs * ZOOM)).max(1);
        let fig = |src: &str, cap: &str, class: &str| {
            // Crops are shown at least 128 pixels wide.
            let width = if class == "pix" { crop_shown } else { shown };
            format!(
                "<figure><img class=\"pix\" width=\"{width}\" src=\"{src}\" alt=\"{cap}\"><figcaption>{cap}</figcaption></figure>\n"
            )
        };
        s += "<h2>Images</h2>\n<div class=\"row\">\n";
        s += &fig("reference.png", "reference", "");
        for r in self.results {
            s += &fig(&format!("{}.png", r.spec.file_stem()), &esc(&r.spec.to_string()), "");
        }
        let _ = write!(
            s,
            "</div>\n<h2>Relative error |a-r|/(|r|+{REL_GUARD}), mean over channels</h2>\n<div class=\"bar\">0 \
             <img src=\"colorbar.png\" width=\"256\" height=\"16\" alt=\"colour bar\"> &ge; {ERROR_SCALE_MAX}</div>\n<div class=\"row\">\n"
        );
        for r in self.results {
            s += &fig(&format!("{}_error.png", r.spec.file_stem()), &esc(&r.spec.to_string()), "");
        }
        let _ = write!(
            s,
            "</div>\n<h2>Crops ({cs}x{cs} pixels at ({cx}, {cy}), {ZOOM}x)</h2>\n<div class=\"row\">\n"
        );
        s += &fig("reference_crop.png", "reference", "pix");
        for r in self.results {
            s += &fig(&format!("{}_crop.png", r.spec.file_stem()), &esc(&r.spec.to_string()), "pix");
        }
        s += &format!(
            "</div>\n<h2>Convergence</h2>\n<p>Error of the image so far, sampled at the end of passes.</p>\n\
              <div class=\"row\">\n<img src=\"convergence_rmse.svg\" alt=\"RMSE vs time\">\n\
              <img src=\"convergence_smape.svg\" alt=\"SMAPE vs time\">\n</div>\n{IMAGE_CHECK}</body></html>\n"
        );
        s
    }
}

/// RMSE against the number of lights per pass, one line per method family (`vrl`,
/// `vrl_lightcuts`, ...), for results of one method at several light counts (`haze compare
/// --lights-plot`). Methods without a light count (volpath) are left out.
pub fn lights_plot(path: &Path, results: &[MethodResult], budget: f64) -> Result<()> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in results {
        let Some(lights) = r.spec.light_count() else { continue };
        let name = r.spec.to_string();
        let family = name.split(':').next().unwrap_or(&name).to_string();
        let point = (lights as f64, r.metrics.rmse);
        match series.iter_mut().find(|(f, _)| *f == family) {
            Some((_, pts)) => pts.push(point),
            None => series.push((family, vec![point])),
        }
    }
    for (_, pts) in &mut series {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let title = format!("RMSE vs lights per pass, {budget} s each (log-log)");
    log_log_plot(path, &title, "lights per pass", "RMSE", &series)
}

/// A log-log line plot (SVG) of named series; points that are not positive and finite are left out.
/// plotters labels a log axis at the powers of its base inside the range only: an axis spanning
/// less than a decade would have no labels in base 10, so it uses base 2 (`log_base`).
fn log_log_plot(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<()> {
    let pts: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|(_, p)| {
            p.iter().copied().filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()).collect()
        })
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts.iter().flatten() {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.1, 1.0, 0.1, 1.0);
    }
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(path, (640, 420)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (x0 * 0.8..x1 * 1.25).log_scale().base(log_base(x0, x1)),
                (y0 * 0.8..y1 * 1.25).log_scale().base(log_base(y0, y1)),
            )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&|v| significant(*v))
            .y_label_formatter(&|v| significant(*v))
            .draw()?;
        for (i, ((name, _), p)) in series.iter().zip(&pts).enumerate() {
            let color = PALETTE[i % PALETTE.len()].to_rgba();
            chart
                .draw_series(LineSeries::new(p.iter().copied(), color.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            chart.draw_series(p.iter().map(|&xy| Circle::new(xy, 3, color.filled())))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| anyhow!("drawing {}: {e}", path.display()))
}

/// A tick label with 3 significant digits (log axes make values like 0.30000000000000004).
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_have_three_significant_digits() {
        assert_eq!(significant(0.30000000000000004), "0.300");
        assert_eq!(significant(12.5), "12.5");
        assert_eq!(significant(2000.0), "2000");
    }

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(7.0), viridis(1.0));
        assert_eq!(viridis(-1.0), viridis(0.0));
    }

    #[test]
    fn crops_replicate_pixels() {
        // 4x4 image whose pixel value is its index; centre crop of 1 pixel at (1, 1)... (size 1).
        let data: Vec<f32> = (0..16).flat_map(|i| [i as f32; 3]).collect();
        let win = crop_window(4, 4);
        assert_eq!(win, (1, 1, 1));
        let c = zoomed_crop(&data, 4, win);
        assert_eq!((c.width, c.height), (ZOOM, ZOOM));
        assert!(c.data.iter().all(|&v| v == 5.0));
    }
}

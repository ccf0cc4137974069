//! `haze render --cut-image`: a heat map per pixel of what explains the cut.
//!
//! - `--cut bound`: the mean lightcut size; colour scale linear from 0 (black) to `--max-cut`
//!   (pale yellow), through the "inferno" colours.
//! - `--cut stochastic` (fixed size): the largest cut node's share of the cut's importance,
//!   from 0 to 1: near 1 where one cluster carries the estimate (its sample's noise is the
//!   pixel's noise), near `1/k` where the light spreads over the whole cut.
//!
//! Scales are fixed so that maps of different runs compare; pixels whose camera path meets no
//! medium are 0. Below the map a legend strip shows the scale with white ticks at every
//! quarter; the scale is also printed to stderr.

use anyhow::{Context, Result};
use haze_engine::methods::Method;
use haze_engine::options::{Options, TreeCut};
use haze_scene::Scene;
use std::path::Path;

/// Inferno colour map, sampled at five points (matplotlib's `inferno` at 0, 1/4, 1/2, 3/4, 1).
const INFERNO: [[f32; 3]; 5] =
    [[0.0, 0.0, 4.0], [87.0, 16.0, 110.0], [188.0, 55.0, 84.0], [249.0, 142.0, 9.0], [252.0, 255.0, 164.0]];

/// sRGB bytes of the colour map at `t` in [0, 1].
pub fn colour(t: f32) -> [u8; 3] {
    let x = t.clamp(0.0, 1.0) * (INFERNO.len() - 1) as f32;
    let i = (x as usize).min(INFERNO.len() - 2);
    let f = x - i as f32;
    std::array::from_fn(|c| (INFERNO[i][c] * (1.0 - f) + INFERNO[i + 1][c] * f + 0.5) as u8)
}

/// Height of the legend strip below a map of `height` rows.
pub fn legend_height(height: usize) -> usize {
    (height / 8).max(4)
}

/// Renders one extra pass at 1 spp (pass 0, the same seed: the lights and cuts of the image's
/// first pass) with `method`'s lightcuts integrator, recording the mean cut size per camera
/// segment of each pixel, and writes the heat map to `path`.
pub fn write(method: &Method, scene: &Scene, options: &Options, path: &Path) -> Result<()> {
    let sizes = method.cut_sizes(scene, options.seed, options.sampler_for(scene))?;
    let max_cut = options.method.lightcuts.bound.cut.max_cut;
    let stochastic = method.tree_cut() == Some(TreeCut::Stochastic);
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let scale = if stochastic { 1.0 } else { max_cut.max(1) as f32 };
    let lh = legend_height(h);
    let mut bytes = Vec::with_capacity(w * (h + lh) * 3);
    for &s in &sizes {
        bytes.extend(colour(s / scale));
    }
    for y in 0..lh {
        for x in 0..w {
            let t = x as f32 / (w - 1).max(1) as f32;
            // White ticks at 0, 1/4, 1/2, 3/4 and 1 of the scale, in the strip's top half.
            let tick = (0..=4).any(|k| x == k * (w - 1) / 4) && y < lh / 2;
            bytes.extend(if tick { [255, 255, 255] } else { colour(t) });
        }
    }
    image::save_buffer(path, &bytes, w as u32, (h + lh) as u32, image::ColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))?;
    let mean = sizes.iter().map(|&s| s as f64).sum::<f64>() / sizes.len().max(1) as f64;
    let max = sizes.iter().copied().fold(0.0f32, f32::max);
    let what = if stochastic {
        "largest cut node's share of the stochastic cut's importance per pixel"
    } else {
        "mean cut size per pixel"
    };
    eprintln!(
        "wrote {} ({what}, 1 spp: colour scale 0 to {scale} linear, legend strip of {lh} rows below with ticks at every {}; image mean {mean:.3}, max {max:.3})",
        path.display(),
        scale / 4.0
    );
    Ok(())
}

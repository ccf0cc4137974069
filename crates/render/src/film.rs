//! Film: per-pixel accumulation of sample sums and squared sums, for the mean image and the
//! variance of that mean (used by the statistical tests and `--variance-out`).

use crate::components::{Component, PathRadiance};
use haze_core::Rgb;

/// Layers stored per pixel: the full image, then optionally the four components.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// 1 (full image only) or 5 (full image + components).
    layers: usize,
    /// Per pixel: for each layer, 3 sums then 3 squared sums (f64: millions of samples).
    data: Vec<f64>,
    /// Samples accumulated per pixel (the same for every pixel).
    pub samples: u64,
}

impl Film {
    pub fn new(width: u32, height: u32, components: bool) -> Self {
        let layers = if components { 5 } else { 1 };
        Film {
            width,
            height,
            layers,
            data: vec![0.0; width as usize * height as usize * layers * 6],
            samples: 0,
        }
    }

    pub fn has_components(&self) -> bool {
        self.layers == 5
    }

    /// Values per pixel in the raw buffer (for splitting it into rows).
    pub fn stride(&self) -> usize {
        self.layers * 6
    }

    /// Rebuilds a film from the raw buffer of [`Self::data`] (e.g. sent by another process):
    /// row-major pixels of [`Self::stride`] values each (per layer 3 sums, then 3 squared sums).
    pub fn from_raw(
        width: u32,
        height: u32,
        components: bool,
        data: Vec<f64>,
        samples: u64,
    ) -> Result<Self, String> {
        let film = Film { width, height, layers: if components { 5 } else { 1 }, data, samples };
        let expected = width as usize * height as usize * film.stride();
        if film.data.len() != expected {
            return Err(format!(
                "a {width}x{height} film{} holds {expected} values, got {}",
                if components { " with components" } else { "" },
                film.data.len()
            ));
        }
        Ok(film)
    }

    /// The raw accumulation buffer (see [`Self::from_raw`]).
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// The raw accumulation buffer, for parallel per-row updates.
    pub fn data_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// Adds one sample to a pixel's slot of the raw buffer.
    #[inline]
    pub fn add_sample(slot: &mut [f64], r: &PathRadiance) {
        let layers = slot.len() / 6;
        let mut put = |layer: usize, v: Rgb| {
            let base = layer * 6;
            for c in 0..3 {
                let x = v[c] as f64;
                slot[base + c] += x;
                slot[base + 3 + c] += x * x;
            }
        };
        put(0, r.total());
        if layers == 5 {
            for comp in Component::ALL {
                put(1 + comp as usize, r.get(comp));
            }
        }
    }

    fn layer_index(&self, comp: Option<Component>) -> usize {
        match comp {
            None => 0,
            Some(c) => {
                assert!(self.has_components(), "film was created without components");
                1 + c as usize
            }
        }
    }

    /// Mean image (row-major RGB) of the full image (`None`) or a component.
    pub fn mean(&self, comp: Option<Component>) -> Vec<f32> {
        let layer = self.layer_index(comp);
        let n = self.samples.max(1) as f64;
        let stride = self.stride();
        self.data.chunks(stride).flat_map(|px| (0..3).map(move |c| (px[layer * 6 + c] / n) as f32)).collect()
    }

    /// Variance of the per-pixel mean: the unbiased sample variance of one sample divided by the
    /// sample count.
    pub fn variance_of_mean(&self, comp: Option<Component>) -> Vec<f32> {
        self.sample_variance(comp).into_iter().map(|v| v / self.samples.max(1) as f32).collect()
    }

    /// Unbiased variance of a single sample, per pixel and channel (Mitsuba's `_var` images).
    pub fn sample_variance(&self, comp: Option<Component>) -> Vec<f32> {
        let layer = self.layer_index(comp);
        let n = self.samples as f64;
        let stride = self.stride();
        self.data
            .chunks(stride)
            .flat_map(|px| {
                (0..3).map(move |c| {
                    if n < 2.0 {
                        return 0.0;
                    }
                    let s = px[layer * 6 + c];
                    let s2 = px[layer * 6 + 3 + c];
                    (((s2 - s * s / n) / (n - 1.0)).max(0.0)) as f32
                })
            })
            .collect()
    }
}

impl Film {
    /// Adds the samples of `other` (same size and layers), e.g. a render of other passes.
    pub fn merge(&mut self, other: &Film) {
        assert!(self.width == other.width && self.height == other.height && self.layers == other.layers);
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += *b;
        }
        self.samples += other.samples;
    }

    /// Mean over all pixels of the full image (`None`) or a component, per channel.
    pub fn image_mean(&self, comp: Option<Component>) -> [f64; 3] {
        let m = self.mean(comp);
        let n = (m.len() / 3).max(1) as f64;
        let mut out = [0.0; 3];
        for px in m.chunks(3) {
            for c in 0..3 {
                out[c] += px[c] as f64 / n;
            }
        }
        out
    }

    /// Multiplies every accumulated sample by `s` (tests of normalisation use it to fake an error).
    pub fn scale(&mut self, s: f64) {
        let stride = self.stride();
        for px in self.data.chunks_mut(stride) {
            for layer in px.chunks_mut(6) {
                for c in 0..3 {
                    layer[c] *= s;
                    layer[3 + c] *= s * s;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_buffer_round_trips_and_sizes_are_checked() {
        let mut film = Film::new(3, 2, true);
        let mut r = PathRadiance::default();
        r.add(Component::Single, Rgb([1.0, 2.0, 3.0]));
        Film::add_sample(&mut film.data_mut()[..30], &r);
        film.samples = 1;
        let back = Film::from_raw(3, 2, true, film.data().to_vec(), 1).unwrap();
        assert_eq!(back.mean(Some(Component::Single)), film.mean(Some(Component::Single)));
        assert_eq!(back.mean(None)[..3], [1.0, 2.0, 3.0]);
        assert!(Film::from_raw(3, 2, false, film.data().to_vec(), 1).is_err());
    }
}

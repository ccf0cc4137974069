//! Reading and writing images: linear float RGB OpenEXR (`exr` crate) and tone-mapped sRGB PNG
//! (`image` crate).

use std::path::Path;

/// A linear RGB float image, row-major, 3 values per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error("refusing to write {path}: pixel ({x}, {y}) is not finite ({value})")]
    NotFinite { path: String, x: usize, y: usize, value: f32 },
}

impl RgbImage {
    pub fn new(width: usize, height: usize, data: Vec<f32>) -> Self {
        assert_eq!(data.len(), width * height * 3);
        RgbImage { width, height, data }
    }

    pub fn pixel(&self, x: usize, y: usize) -> [f32; 3] {
        let i = (y * self.width + x) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    fn check_finite(&self, path: &Path) -> Result<(), ImageError> {
        if let Some(i) = self.data.iter().position(|v| !v.is_finite()) {
            let p = i / 3;
            return Err(ImageError::NotFinite {
                path: path.display().to_string(),
                x: p % self.width,
                y: p / self.width,
                value: self.data[i],
            });
        }
        Ok(())
    }

    /// Writes a linear RGB 32-bit float EXR. Refuses images with NaN or Inf.
    ///
    /// Tiles in increasing order (`LineOrder::Increasing`): the `exr` crate compresses tiles on
    /// several threads and, with its default unspecified order, stores them in the order they
    /// finish, so the same image gave files that differed in their bytes (never in their
    /// pixels) from run to run. In order, one seed gives one file.
    pub fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        use exr::prelude::*;
        self.check_finite(path)?;
        let channels = SpecificChannels::rgb(|Vec2(x, y)| {
            let p = self.pixel(x, y);
            (p[0], p[1], p[2])
        });
        let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
        Image::from_encoded_channels((self.width, self.height), encoding, channels)
            .write()
            .to_file(path)
            .map_err(|e| ImageError::Io { path: path.display().to_string(), message: e.to_string() })
    }

    /// Writes an 8-bit sRGB PNG: linear values times `2^exposure`, clamped to `[0, 1]`, sRGB curve.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageError> {
        self.check_finite(path)?;
        let scale = exposure.exp2();
        let bytes: Vec<u8> =
            self.data.iter().map(|&v| (linear_to_srgb(v * scale) * 255.0 + 0.5) as u8).collect();
        image::save_buffer(path, &bytes, self.width as u32, self.height as u32, image::ColorType::Rgb8)
            .map_err(|e| ImageError::Io { path: path.display().to_string(), message: e.to_string() })
    }

    /// Reads the first RGB(A) layer of an EXR file (alpha dropped).
    pub fn read_exr(path: &Path) -> Result<Self, ImageError> {
        use exr::prelude::*;
        let image = read_first_rgba_layer_from_file(
            path,
            |res, _| RgbImage {
                width: res.width(),
                height: res.height(),
                data: vec![0.0; res.width() * res.height() * 3],
            },
            |img: &mut RgbImage, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let i = (pos.y() * img.width + pos.x()) * 3;
                img.data[i] = r;
                img.data[i + 1] = g;
                img.data[i + 2] = b;
            },
        )
        .map_err(|e| ImageError::Io { path: path.display().to_string(), message: e.to_string() })?;
        Ok(image.layer_data.channel_data.pixels)
    }
}

/// sRGB opto-electronic transfer function (IEC 61966-2-1), input clamped to `[0, 1]`.
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_and_nan_refused() {
        let dir = std::env::temp_dir().join(format!("haze-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = RgbImage::new(3, 2, (0..18).map(|i| i as f32 * 0.25).collect());
        let p = dir.join("a.exr");
        img.write_exr(&p).unwrap();
        assert_eq!(RgbImage::read_exr(&p).unwrap(), img);
        img.write_png(&dir.join("a.png"), 0.0).unwrap();
        let mut bad = img.clone();
        bad.data[4] = f32::NAN;
        let err = bad.write_exr(&dir.join("b.exr")).unwrap_err().to_string();
        assert!(err.contains("pixel (1, 0) is not finite"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Tiles are stored in increasing order, so writing the same image again gives the same
    /// bytes (an image of many tiles, which the `exr` crate compresses in parallel).
    #[test]
    fn exr_files_are_reproducible() {
        let dir = std::env::temp_dir().join(format!("haze-io-order-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (w, h) = (300, 200);
        let img = RgbImage::new(w, h, (0..w * h * 3).map(|i| ((i * 7919) % 1000) as f32 * 1e-3).collect());
        let first = dir.join("first.exr");
        img.write_exr(&first).unwrap();
        let meta = exr::meta::MetaData::read_from_file(&first, false).unwrap();
        assert_eq!(meta.headers[0].line_order, exr::meta::attribute::LineOrder::Increasing);
        let bytes = std::fs::read(&first).unwrap();
        for i in 0..5 {
            let again = dir.join(format!("again{i}.exr"));
            img.write_exr(&again).unwrap();
            assert!(std::fs::read(&again).unwrap() == bytes, "rewrite {i} differs");
        }
        assert_eq!(RgbImage::read_exr(&first).unwrap(), img);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn srgb_curve_endpoints() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.18) - 0.4613).abs() < 1e-3);
    }
}

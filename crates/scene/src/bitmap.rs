//! Mitsuba 3's `bitmap` texture: an image looked up by surface `uv`, with its filter and wrap
//! modes (`src/textures/bitmap.cpp` and Dr.Jit's `Texture` lookups).
//!
//! Conventions, as Mitsuba 3: `uv = to_uv(surface uv)`; texel `(x, y)` (row `y = 0` is the
//! image's top row) has its centre at `((x + 1/2) / width, (y + 1/2) / height)`. `bilinear`
//! interpolates the four texels around `uv * size - 1/2`; `nearest` takes texel
//! `floor(uv * size)`. Indices outside the image wrap: `repeat` (modulo the size), `mirror`
//! (reflected at each edge, period twice the size), `clamp` (to the edge texel).
//! 8- and 16-bit images (PNG, JPEG, BMP) are sRGB-encoded and decoded to linear at load unless
//! `raw` (Mitsuba 3's RGB variants; OpenEXR and Radiance HDR images are linear already).

use glam::{Affine2, Vec2};
use haze_core::Rgb;
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterType {
    Bilinear,
    Nearest,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrapMode {
    Repeat,
    Mirror,
    Clamp,
}

impl FilterType {
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "bilinear" => Some(FilterType::Bilinear),
            "nearest" => Some(FilterType::Nearest),
            _ => None,
        }
    }
}

impl WrapMode {
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "repeat" => Some(WrapMode::Repeat),
            "mirror" => Some(WrapMode::Mirror),
            "clamp" => Some(WrapMode::Clamp),
            _ => None,
        }
    }

    /// Texel index `i` (any integer) wrapped into `0..n`.
    fn wrap(self, i: i64, n: usize) -> usize {
        let n = n as i64;
        let w = match self {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        };
        w as usize
    }
}

/// A bitmap texture: linear RGB texels, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    pub width: usize,
    pub height: usize,
    texels: Vec<Rgb>,
    pub filter: FilterType,
    pub wrap: WrapMode,
    pub to_uv: Affine2,
    mean: Rgb,
    range: (f32, f32),
}

impl Bitmap {
    /// A bitmap of `width * height` linear RGB texels, row by row from the top.
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<Rgb>,
        filter: FilterType,
        wrap: WrapMode,
        to_uv: Affine2,
    ) -> Result<Self, String> {
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(format!(
                "a {width}x{height} image needs {} texels, got {}",
                width * height,
                texels.len()
            ));
        }
        if let Some(i) = texels.iter().position(|t| !t.0.iter().all(|c| c.is_finite())) {
            return Err(format!("texel ({}, {}) is not a finite number", i % width, i / width));
        }
        let sum = texels.iter().fold([0.0f64; 3], |a, t| std::array::from_fn(|c| a[c] + f64::from(t.0[c])));
        let n = texels.len() as f64;
        let mean = Rgb::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32);
        let range = texels.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), t| {
            (lo.min(t.min_component()), hi.max(t.max_component()))
        });
        Ok(Bitmap { width, height, texels, filter, wrap, to_uv, mean, range })
    }

    /// Reads `path`: PNG, JPEG or BMP (8 or 16 bits; sRGB-decoded unless `raw`), OpenEXR or
    /// Radiance HDR (linear). Grey images give grey texels; alpha is dropped.
    pub fn load(
        path: &Path,
        raw: bool,
        filter: FilterType,
        wrap: WrapMode,
        to_uv: Affine2,
    ) -> Result<Self, String> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let (w, h, rgb, encoded) = match ext.as_str() {
            "exr" => {
                let (w, h, rgb) = crate::envmap::read_exr(path)?;
                (w, h, rgb, false)
            }
            "hdr" | "rgbe" => {
                let (w, h, rgb) = crate::envmap::read_hdr(path)?;
                (w, h, rgb, false)
            }
            "png" | "jpg" | "jpeg" | "bmp" => {
                let img = image::open(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
                let rgb = img.into_rgb32f();
                (rgb.width() as usize, rgb.height() as usize, rgb.into_raw(), true)
            }
            _ => {
                return Err(format!(
                    "unsupported image format '{}' (haze reads .png, .jpg, .bmp, .exr and .hdr)",
                    path.display()
                ))
            }
        };
        let decode = |v: f32| if encoded && !raw { srgb_to_linear(v) } else { v };
        let texels =
            rgb.chunks_exact(3).map(|c| Rgb::new(decode(c[0]), decode(c[1]), decode(c[2]))).collect();
        Self::new(w, h, texels, filter, wrap, to_uv)
    }

    fn texel(&self, x: i64, y: i64) -> Rgb {
        self.texels[self.wrap.wrap(y, self.height) * self.width + self.wrap.wrap(x, self.width)]
    }

    /// The value at surface coordinates `uv` (before `to_uv`).
    pub fn eval(&self, uv: Vec2) -> Rgb {
        let p = self.to_uv.transform_point2(uv) * Vec2::new(self.width as f32, self.height as f32);
        if !p.is_finite() {
            return Rgb::ZERO;
        }
        match self.filter {
            FilterType::Nearest => self.texel(p.x.floor() as i64, p.y.floor() as i64),
            FilterType::Bilinear => {
                let q = p - Vec2::splat(0.5);
                let (x0, y0) = (q.x.floor(), q.y.floor());
                let (fx, fy) = (q.x - x0, q.y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
                let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }

    /// The gradient with respect to `uv` of the luminance of [`Self::eval`] (Mitsuba's
    /// `eval_1_grad`, which bump maps read): zero for `nearest`; for `bilinear`, with `(x, y)`
    /// the texel-space position and `f` the luminance of the four texels around it,
    /// `df/dx = (f10 - f00)(1 - fy) + (f11 - f01) fy`, `df/dy = (f01 - f00)(1 - fx) + (f11 - f10) fx`,
    /// scaled by the resolution and carried back through `to_uv` (the transpose of its linear
    /// part).
    pub fn eval_1_grad(&self, uv: Vec2) -> Vec2 {
        let res = Vec2::new(self.width as f32, self.height as f32);
        let p = self.to_uv.transform_point2(uv) * res;
        if !p.is_finite() || self.filter == FilterType::Nearest {
            return Vec2::ZERO;
        }
        let q = p - Vec2::splat(0.5);
        let (x0, y0) = (q.x.floor(), q.y.floor());
        let (fx, fy) = (q.x - x0, q.y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let f = |x, y| self.texel(x, y).luminance();
        let (f00, f10, f01, f11) = (f(x0, y0), f(x0 + 1, y0), f(x0, y0 + 1), f(x0 + 1, y0 + 1));
        let d = Vec2::new(
            (f10 - f00) * (1.0 - fy) + (f11 - f01) * fy,
            (f01 - f00) * (1.0 - fx) + (f11 - f10) * fx,
        );
        self.to_uv.matrix2.transpose() * (d * res)
    }

    /// The mean of the texels (Mitsuba's `Texture::mean`).
    pub fn mean(&self) -> Rgb {
        self.mean
    }

    /// Smallest and largest channel value of any texel (interpolation stays within them).
    pub fn range(&self) -> (f32, f32) {
        self.range
    }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1), for 8- and 16-bit images.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(filter: FilterType, wrap: WrapMode) -> Bitmap {
        // 2x2: top row 0, 1; bottom row 2, 3 (grey).
        let t = [0.0, 1.0, 2.0, 3.0].map(Rgb::splat).to_vec();
        Bitmap::new(2, 2, t, filter, wrap, Affine2::IDENTITY).unwrap()
    }

    #[test]
    fn nearest_lookups_and_wrap_modes() {
        let b = image(FilterType::Nearest, WrapMode::Repeat);
        assert_eq!(b.eval(Vec2::new(0.25, 0.25)), Rgb::splat(0.0), "row 0 is the top row at v < 1/2");
        assert_eq!(b.eval(Vec2::new(0.75, 0.25)), Rgb::splat(1.0));
        assert_eq!(b.eval(Vec2::new(0.25, 0.75)), Rgb::splat(2.0));
        assert_eq!(b.eval(Vec2::new(1.25, -0.25)), Rgb::splat(2.0), "repeat");
        let m = image(FilterType::Nearest, WrapMode::Mirror);
        assert_eq!(
            m.eval(Vec2::new(1.25, 0.25)),
            Rgb::splat(1.0),
            "mirror: just past the right edge is the edge texel"
        );
        assert_eq!(m.eval(Vec2::new(1.75, 0.25)), Rgb::splat(0.0));
        assert_eq!(m.eval(Vec2::new(-0.25, 0.25)), Rgb::splat(0.0));
        let c = image(FilterType::Nearest, WrapMode::Clamp);
        assert_eq!(c.eval(Vec2::new(7.0, 9.0)), Rgb::splat(3.0));
        assert_eq!(c.eval(Vec2::new(-7.0, -9.0)), Rgb::splat(0.0));
    }

    #[test]
    fn bilinear_interpolates_between_texel_centres() {
        let b = image(FilterType::Bilinear, WrapMode::Clamp);
        assert_eq!(b.eval(Vec2::new(0.25, 0.25)), Rgb::splat(0.0), "a texel centre");
        assert!((b.eval(Vec2::new(0.5, 0.5))[0] - 1.5).abs() < 1e-6, "the middle: mean of four");
        assert!((b.eval(Vec2::new(0.5, 0.25))[0] - 0.5).abs() < 1e-6);
        assert_eq!(b.eval(Vec2::new(0.0, 0.0)), Rgb::splat(0.0), "clamp at the corner");
        let r = image(FilterType::Bilinear, WrapMode::Repeat);
        // At u = 0 the left neighbour is the last column: halfway between 0 and 1.
        assert!((r.eval(Vec2::new(0.0, 0.25))[0] - 0.5).abs() < 1e-6);
        assert_eq!(b.mean(), Rgb::splat(1.5));
        assert_eq!(b.range(), (0.0, 3.0));
    }

    #[test]
    fn to_uv_applies_before_the_lookup() {
        let t = [0.0, 1.0, 2.0, 3.0].map(Rgb::splat).to_vec();
        let scale = Affine2::from_scale(Vec2::splat(2.0));
        let b = Bitmap::new(2, 2, t, FilterType::Nearest, WrapMode::Repeat, scale).unwrap();
        assert_eq!(b.eval(Vec2::new(0.375, 0.125)), Rgb::splat(1.0));
        assert_eq!(b.eval(Vec2::new(0.625, 0.125)), Rgb::splat(0.0), "the second tile");
    }

    #[test]
    fn srgb_decoding_matches_the_standard() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-9);
    }

    /// An 8-bit PNG is sRGB-decoded unless `raw`; the image's top row is `v` near 0.
    #[test]
    fn png_files_are_decoded_unless_raw() {
        let dir = std::env::temp_dir().join(format!("haze-bitmap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        let img = image::RgbImage::from_fn(2, 1, |x, _| {
            if x == 0 {
                image::Rgb([128, 0, 255])
            } else {
                image::Rgb([255; 3])
            }
        });
        img.save(&path).unwrap();
        // The same pixels as JPEG (lossy: only roughly) and BMP (exactly).
        img.save(dir.join("t.bmp")).unwrap();
        let bmp =
            Bitmap::load(&dir.join("t.bmp"), false, FilterType::Nearest, WrapMode::Repeat, Affine2::IDENTITY)
                .unwrap();
        assert_eq!(
            bmp.eval(Vec2::new(0.25, 0.5)),
            Bitmap::load(&path, false, FilterType::Nearest, WrapMode::Repeat, Affine2::IDENTITY)
                .unwrap()
                .eval(Vec2::new(0.25, 0.5))
        );
        image::RgbImage::from_pixel(8, 8, image::Rgb([200, 100, 50])).save(dir.join("t.jpg")).unwrap();
        let jpg =
            Bitmap::load(&dir.join("t.jpg"), false, FilterType::Nearest, WrapMode::Repeat, Affine2::IDENTITY)
                .unwrap();
        let v = jpg.eval(Vec2::splat(0.5));
        assert!(
            (v[0] - srgb_to_linear(200.0 / 255.0)).abs() < 0.02
                && (v[2] - srgb_to_linear(50.0 / 255.0)).abs() < 0.02,
            "{v:?}"
        );
        let b = Bitmap::load(&path, false, FilterType::Nearest, WrapMode::Repeat, Affine2::IDENTITY).unwrap();
        let v = b.eval(Vec2::new(0.25, 0.5));
        assert!(
            (v[0] - srgb_to_linear(128.0 / 255.0)).abs() < 1e-6 && v[1] == 0.0 && (v[2] - 1.0).abs() < 1e-6,
            "{v:?}"
        );
        let raw =
            Bitmap::load(&path, true, FilterType::Nearest, WrapMode::Repeat, Affine2::IDENTITY).unwrap();
        assert!((raw.eval(Vec2::new(0.25, 0.5))[0] - 128.0 / 255.0).abs() < 1e-6);
        let e =
            Bitmap::load(&dir.join("t.tga"), false, FilterType::Nearest, WrapMode::Repeat, Affine2::IDENTITY)
                .unwrap_err();
        assert!(e.contains("unsupported image format"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

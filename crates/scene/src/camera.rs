//! Perspective pinhole camera (Mitsuba 3 plugin `perspective`) and the film's reconstruction
//! filter (`rfilter`: `box`, `tent`, `gaussian`).

use crate::medium::MediumId;
use glam::{Mat4, Vec2, Vec3};
use haze_core::{Ray, Sampler};

/// Pinhole camera. Camera space follows Mitsuba: looking down `+z`, `+y` up, `+x` to the
/// *left* (so `lookat` builds `to_world` with columns `(left, up, dir, origin)`). Film pixel
/// `(0, 0)` is the top-left corner of the image.
#[derive(Clone, Debug)]
pub struct Camera {
    pub to_world: Mat4,
    /// Full horizontal field of view in degrees (the loader resolves `fov_axis` to this).
    pub fov_x_deg: f32,
    pub near_clip: f32,
    pub far_clip: f32,
    /// Medium the camera sits in (`<ref id=".."/>` inside the sensor).
    pub medium: Option<MediumId>,
    pub width: u32,
    pub height: u32,
    /// Reconstruction filter of the film.
    pub filter: PixelFilter,
}

/// A film's reconstruction filter, separable in x and y, as Mitsuba 3's `rfilter` plugins
/// (1D profiles, `x` in pixels from the pixel centre):
/// - `box`: constant on `[-1/2, 1/2]`;
/// - `tent`: `max(0, 1 - |x| / radius)`, Mitsuba's default radius 1;
/// - `gaussian`: `max(0, exp(-x^2 / (2 s^2)) - exp(-r^2 / (2 s^2)))` with `r = 4 s`, Mitsuba's
///   default `s = 0.5`.
///
/// Mitsuba 3 splats each sample into every pixel within the filter radius with weight
/// `f(dx) f(dy)` and divides by the summed weights; in the limit a pixel is the filter-weighted
/// mean of the radiance over the film around it (only samples on the film contribute). haze
/// estimates the same mean by *filter importance sampling*: each pixel draws its film positions
/// from the normalised filter restricted to the film (rejection per axis), with weight 1. It is
/// a different estimator of the same image (the noise differs, the expectation does not), and
/// it keeps each pixel's samples its own, so the parallel loop stays deterministic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PixelFilter {
    Box,
    Tent { radius: f32 },
    Gaussian { stddev: f32 },
}

impl PixelFilter {
    /// Mitsuba 3's default filter of `hdrfilm`.
    pub const MITSUBA_DEFAULT: PixelFilter = PixelFilter::Gaussian { stddev: 0.5 };

    /// Half-width of the support, in pixels.
    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box => 0.5,
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Gaussian { stddev } => 4.0 * stddev,
        }
    }

    /// The unnormalised 1D profile at `x` pixels from the centre.
    pub fn eval(&self, x: f32) -> f32 {
        match *self {
            PixelFilter::Box => (x.abs() <= 0.5) as u32 as f32,
            PixelFilter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            PixelFilter::Gaussian { stddev } => {
                let alpha = -0.5 / (stddev * stddev);
                let r = 4.0 * stddev;
                ((alpha * x * x).exp() - (alpha * r * r).exp()).max(0.0)
            }
        }
    }

    /// An offset from the pixel centre distributed as the normalised profile restricted to
    /// `[lo, hi]` (the film around the pixel; `lo < 0 < hi`).
    fn sample_1d(&self, sampler: &mut Sampler, lo: f32, hi: f32) -> f32 {
        // Rejection keeps the draw exact; the acceptance rate is at least about 1/4 (a corner
        // pixel keeps half of each axis), so 64 tries fail with negligible probability.
        for _ in 0..64 {
            let x = match *self {
                PixelFilter::Box => sampler.next_1d() - 0.5,
                PixelFilter::Tent { radius } => {
                    let u = sampler.next_1d();
                    if u < 0.5 {
                        radius * ((2.0 * u).sqrt() - 1.0)
                    } else {
                        radius * (1.0 - (2.0 - 2.0 * u).sqrt())
                    }
                }
                PixelFilter::Gaussian { stddev } => {
                    // A normal draw (Box-Muller), then acceptance with probability
                    // f(x) / exp(-x^2 / 2s^2) = 1 - bias / exp(-x^2 / 2s^2), which removes the
                    // constant the truncated profile subtracts.
                    let u = sampler.next_2d();
                    let x =
                        stddev * (-2.0 * (1.0 - u.x).ln()).sqrt() * (2.0 * std::f32::consts::PI * u.y).cos();
                    let g = (-0.5 * x * x / (stddev * stddev)).exp();
                    if sampler.next_1d() * g >= self.eval(x) {
                        continue;
                    }
                    x
                }
            };
            if x >= lo && x <= hi {
                return x;
            }
        }
        0.0
    }
}

impl Camera {
    /// A film position (pixel units) for a sample of pixel `(x, y)`, drawn from the
    /// reconstruction filter around the pixel centre (see [`PixelFilter`]). For `box` this is
    /// `(x, y) + sampler.next_2d()`, the uniform position in the pixel.
    pub fn sample_film_position(&self, x: u32, y: u32, sampler: &mut Sampler) -> Vec2 {
        let corner = Vec2::new(x as f32, y as f32);
        if self.filter == PixelFilter::Box {
            return corner + sampler.next_2d();
        }
        let c = corner + Vec2::splat(0.5);
        let dx = self.filter.sample_1d(sampler, -c.x, self.width as f32 - c.x);
        let dy = self.filter.sample_1d(sampler, -c.y, self.height as f32 - c.y);
        c + Vec2::new(dx, dy)
    }
}

impl Camera {
    /// Primary ray through the film position `p` in pixel units (`[0, width) x [0, height)`).
    /// The ray starts at the near clip plane and ends at the far clip plane, as in Mitsuba.
    pub fn generate_ray(&self, p: Vec2) -> Ray {
        self.ray_generator().generate(p)
    }

    /// [`Self::generate_ray`] with the per-camera constants (a `tan`, the origin) computed once,
    /// for the render loop: the same rays bit for bit.
    pub fn ray_generator(&self) -> RayGenerator<'_> {
        let tan_x = (0.5 * self.fov_x_deg.to_radians()).tan();
        RayGenerator {
            cam: self,
            tan_x,
            tan_y: tan_x * self.height as f32 / self.width as f32,
            o: self.to_world.transform_point3(Vec3::ZERO),
        }
    }

    pub fn position(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }
}

/// Primary rays of a camera (see [`Camera::ray_generator`]).
pub struct RayGenerator<'a> {
    cam: &'a Camera,
    tan_x: f32,
    tan_y: f32,
    o: Vec3,
}

impl RayGenerator<'_> {
    #[inline]
    pub fn generate(&self, p: Vec2) -> Ray {
        let cam = self.cam;
        let sx = 1.0 - 2.0 * p.x / cam.width as f32;
        let sy = 1.0 - 2.0 * p.y / cam.height as f32;
        let local = Vec3::new(sx * self.tan_x, sy * self.tan_y, 1.0);
        let inv_len = 1.0 / local.length();
        let d_local = local * inv_len;
        let d = cam.to_world.transform_vector3(d_local).normalize();
        // Near/far clips are distances along the camera's z axis.
        let t_near = cam.near_clip / d_local.z;
        let t_far = cam.far_clip / d_local.z;
        Ray { o: self.o + d * t_near, d, t_max: t_far - t_near }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Film positions follow the normalised filter profile: chi-square of a histogram of offsets
    /// for a pixel far from the film's edges, and offsets stay on the film at a corner.
    #[test]
    fn film_positions_follow_the_filter() {
        for filter in [PixelFilter::Tent { radius: 1.0 }, PixelFilter::Gaussian { stddev: 0.5 }] {
            let camera = Camera {
                to_world: Mat4::IDENTITY,
                fov_x_deg: 40.0,
                near_clip: 0.01,
                far_clip: 100.0,
                medium: None,
                width: 20,
                height: 20,
                filter,
            };
            let r = filter.radius();
            let mut sampler = Sampler::from_seed(5);
            let mut xs = Vec::new();
            for _ in 0..100_000 {
                let p = camera.sample_film_position(10, 10, &mut sampler);
                xs.push(p.x - 10.5);
                let q = camera.sample_film_position(0, 19, &mut sampler);
                assert!(q.x >= 0.0 && q.y <= 20.0 && (q - Vec2::new(0.5, 19.5)).abs().max_element() <= r);
            }
            let bins = 40;
            let mut observed = vec![0.0f64; bins];
            for x in &xs {
                let b = ((x + r) / (2.0 * r) * bins as f32) as usize;
                observed[b.min(bins - 1)] += 1.0;
            }
            let fine = 4000;
            let dens: Vec<f64> = (0..fine)
                .map(|i| filter.eval(-r + 2.0 * r * (i as f32 + 0.5) / fine as f32) as f64)
                .collect();
            let total: f64 = dens.iter().sum();
            let expected: Vec<f64> = (0..bins)
                .map(|b| {
                    dens[b * fine / bins..(b + 1) * fine / bins].iter().sum::<f64>() / total * xs.len() as f64
                })
                .collect();
            let res = haze_testkit::chi2::chi2_test(&observed, &expected);
            assert!(res.passed(0.01), "{filter:?}: {res}");
        }
    }
}

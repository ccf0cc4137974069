//! The camera (Mitsuba 3 sensors `perspective`, `thinlens`, `orthographic`) and the film's
//! reconstruction filter (`rfilter`: `box`, `tent`, `gaussian`).

use crate::medium::MediumId;
use glam::{Mat4, Vec2, Vec3};
use haze_core::sampling::sample_uniform_disk_concentric;
use haze_core::{Ray, Sampler};
use std::ops::{Add, Div, Mul, Sub};

/// The camera. Camera space follows Mitsuba: looking down `+z`, `+y` up, `+x` to the
/// *left* (so `lookat` builds `to_world` with columns `(left, up, dir, origin)`). Film pixel
/// `(0, 0)` is the top-left corner of the image.
#[derive(Clone, Debug)]
pub struct Camera {
    pub to_world: Mat4,
    /// How film positions become rays: a pinhole (`perspective`), a thin lens or parallel rays.
    pub projection: Projection,
    /// Full horizontal field of view in degrees (the loader resolves `fov_axis` to this); not
    /// used by [`Projection::Orthographic`].
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

/// The projection of a [`Camera`], as Mitsuba 3's sensor plugins generate their rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// `perspective`: every ray through the pinhole at the camera-space origin.
    Pinhole,
    /// `thinlens`: rays from a point of a disk of radius `aperture_radius` in the camera's
    /// `z = 0` plane, through the point of the plane `z = focus_distance` that the pinhole ray
    /// of the same film position reaches (Mitsuba 3's `thinlens.cpp`): in focus there.
    ThinLens { aperture_radius: f32, focus_distance: f32 },
    /// `orthographic`: parallel rays along camera `+z` from the film rectangle
    /// `[-1, 1] x [-1/aspect, 1/aspect]` (`aspect = width / height`) on the near clip plane,
    /// which `to_world`'s scale sizes (Mitsuba 3's `orthographic_projection`).
    Orthographic,
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
    /// Mitsuba 3's default `near_clip` of every sensor.
    pub const DEFAULT_NEAR_CLIP: f32 = 0.01;
    /// Mitsuba 3's default `far_clip` of every sensor.
    pub const DEFAULT_FAR_CLIP: f32 = 10000.0;

    /// A `perspective` camera with the full horizontal field of view `fov_x_deg` and a
    /// `width x height` film: Mitsuba 3's default clip planes, a `box` filter (a sample's film
    /// position is uniform in its pixel), in vacuum. For scenes built in code (tests,
    /// examples), which change any other field with struct update syntax:
    ///
    /// ```
    /// # use glam::Mat4;
    /// # use haze_scene::Camera;
    /// let camera = Camera { medium: Some(0), ..Camera::pinhole(Mat4::IDENTITY, 30.0, (4, 4)) };
    /// assert!(camera.is_pinhole() && camera.medium == Some(0));
    /// ```
    pub fn pinhole(to_world: Mat4, fov_x_deg: f32, (width, height): (u32, u32)) -> Camera {
        Camera {
            to_world,
            projection: Projection::Pinhole,
            fov_x_deg,
            near_clip: Self::DEFAULT_NEAR_CLIP,
            far_clip: Self::DEFAULT_FAR_CLIP,
            medium: None,
            width,
            height,
            filter: PixelFilter::Box,
        }
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
    /// Primary ray through the film position `p` in pixel units (`[0, width) x [0, height)`),
    /// through the centre of a thin lens. The ray starts at the near clip plane and ends at the
    /// far clip plane, as in Mitsuba.
    pub fn generate_ray(&self, p: Vec2) -> Ray {
        self.ray_generator().generate(p)
    }

    /// [`Self::generate_ray`] with the per-camera constants (a `tan`, the origin) computed once,
    /// for the render loop: the same rays bit for bit.
    pub fn ray_generator(&self) -> RayGenerator<'_> {
        RayGenerator { cam: self, film: self.film_plane(), o: self.to_world.transform_point3(Vec3::ZERO) }
    }

    /// The film's rectangle in camera space ([`FilmPlane`]), in `f32` (the rays) or `f64` (the
    /// camera grid): the pinhole's slopes `(tan(fov_x / 2), tan(fov_x / 2) H / W)` for
    /// `perspective` and `thinlens`, the near plane's half extents `(1, H / W)` for
    /// `orthographic`.
    pub fn film_plane<F: FilmFloat>(&self) -> FilmPlane<F> {
        let (width, height) = (F::from_u32(self.width), F::from_u32(self.height));
        let aspect_inv = height / width;
        let half_x = match self.projection {
            Projection::Orthographic => F::ONE,
            _ => half_slope(self.fov_x_deg),
        };
        FilmPlane { half_x, half_y: half_x * aspect_inv, width, height }
    }

    pub fn position(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }

    /// True for a `perspective` camera, whose rays all pass through [`Self::position`].
    pub fn is_pinhole(&self) -> bool {
        self.projection == Projection::Pinhole
    }

    /// The Mitsuba 3 plugin name of the projection (for messages).
    pub fn plugin_name(&self) -> &'static str {
        match self.projection {
            Projection::Pinhole => "perspective",
            Projection::ThinLens { .. } => "thinlens",
            Projection::Orthographic => "orthographic",
        }
    }
}

impl Camera {
    /// The pinhole's projection of world points onto the film, the inverse of
    /// [`Self::ray_generator`] (the same slopes); `None` for other projections, whose rays do
    /// not meet in one point.
    pub fn film_projector(&self) -> Option<FilmProjector<'_>> {
        if !self.is_pinhole() {
            return None;
        }
        let RayGenerator { film, o, .. } = self.ray_generator();
        Some(FilmProjector {
            cam: self,
            o,
            to_camera: self.to_world.inverse(),
            film,
            pixel_density: (self.width * self.height) as f32 / (4.0 * film.half_x * film.half_y),
        })
    }
}

/// Where a world point lands on a pinhole camera's film ([`FilmProjector::project`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmPoint {
    /// Film position in pixel units, `[0, width) x [0, height)`.
    pub px: f32,
    pub py: f32,
    /// `(W H / A) / cos^3 θ`, with `A = 4 half_x half_y` the film's area at distance 1
    /// ([`FilmPlane`]) and θ the angle from the optical axis (cos θ from camera space, so any
    /// scale of `to_world` drops out): the factor by which a light tracer's splat at this
    /// point, of radiance arriving at the pinhole per unit solid angle, becomes a pixel value
    /// (`crate`'s users: the caustic paths, `haze_manylight::splat`).
    pub density: f32,
    /// The fraction of the way from the pinhole to the point where camera rays start (the near
    /// clip plane): only what lies beyond it is seen.
    pub near: f32,
}

/// A pinhole camera's projection with its constants computed once ([`Camera::film_projector`]).
pub struct FilmProjector<'a> {
    cam: &'a Camera,
    /// The pinhole.
    pub o: Vec3,
    to_camera: Mat4,
    film: FilmPlane<f32>,
    /// `W H / A`: pixels per unit area of the image plane at distance 1.
    pixel_density: f32,
}

impl FilmProjector<'_> {
    /// The film point of world point `p`, or `None` outside the film or the clip planes: the
    /// film position of its camera-space point `q` ([`FilmPlane::film_position`]), inverting
    /// [`RayGenerator::generate_through`].
    pub fn project(&self, p: Vec3) -> Option<FilmPoint> {
        let cam = self.cam;
        let q = self.to_camera.transform_point3(p);
        if !(q.z >= cam.near_clip && q.z <= cam.far_clip) {
            return None;
        }
        let [px, py] = self.film.film_position(q.x, q.y, q.z);
        if !(px >= 0.0 && px < cam.width as f32 && py >= 0.0 && py < cam.height as f32) {
            return None;
        }
        let cos = q.z / q.length();
        Some(FilmPoint { px, py, density: self.pixel_density / (cos * cos * cos), near: cam.near_clip / q.z })
    }
}

/// The float types [`FilmPlane`]'s formulas are written for, once: `f32` for the camera's rays
/// and the caustic paths' splats, `f64` for the camera grid's conservative pyramids
/// (`accel/camera_grid.rs`).
pub trait FilmFloat:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    const ONE: Self;
    const TWO: Self;
    const HALF: Self;
    fn from_f32(x: f32) -> Self;
    fn from_u32(x: u32) -> Self;
    fn tan(self) -> Self;
    fn to_radians(self) -> Self;
}

macro_rules! film_float {
    ($t:ty) => {
        impl FilmFloat for $t {
            const ONE: $t = 1.0;
            const TWO: $t = 2.0;
            const HALF: $t = 0.5;
            #[inline]
            fn from_f32(x: f32) -> $t {
                x as $t
            }
            #[inline]
            fn from_u32(x: u32) -> $t {
                x as $t
            }
            #[inline]
            fn tan(self) -> $t {
                <$t>::tan(self)
            }
            #[inline]
            fn to_radians(self) -> $t {
                <$t>::to_radians(self)
            }
        }
    };
}
film_float!(f32);
film_float!(f64);

/// The film as a rectangle in a camera-space plane: the one definition of where a film
/// position goes ([`Camera::film_plane`]). Film position `p` (pixels, `[0, W] x [0, H]`,
/// `(0, 0)` the top-left corner) is the plane point
///
/// ```text
///   (s.x half_x, s.y half_y),   s = (1 - 2 p.x / W, 1 - 2 p.y / H)
/// ```
///
/// (`s` in `[-1, 1]^2`; camera `+x` is left and `+y` up, hence the signs). For the pinhole
/// (`perspective`, and `thinlens` through its lens centre) the plane is `z = 1`, so the plane
/// point `(x, y)` is the camera-space direction `(x, y, 1)` of the ray through `p`, and the
/// half extents are the slopes of the film's edges,
///
/// ```text
///   half_x = tan(fov_x / 2),   half_y = half_x H / W .
/// ```
///
/// For `orthographic` the plane is the near clip plane and the half extents are `(1, H / W)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmPlane<F> {
    pub half_x: F,
    pub half_y: F,
    width: F,
    height: F,
}

impl<F: FilmFloat> FilmPlane<F> {
    /// The plane point of film position `(px, py)` (see [`FilmPlane`]).
    #[inline]
    pub fn plane_point(&self, px: F, py: F) -> [F; 2] {
        let sx = F::ONE - F::TWO * px / self.width;
        let sy = F::ONE - F::TWO * py / self.height;
        [sx * self.half_x, sy * self.half_y]
    }

    /// The film position of the camera-space point `(x, y, z)` (`z > 0`) seen from the pinhole,
    /// the inverse of [`Self::plane_point`] on the plane `z = 1`:
    /// `s = (x / (z half_x), y / (z half_y))`, `p = ((1 - s.x) W / 2, (1 - s.y) H / 2)`.
    #[inline]
    pub fn film_position(&self, x: F, y: F, z: F) -> [F; 2] {
        let (sx, sy) = (x / (z * self.half_x), y / (z * self.half_y));
        [(F::ONE - sx) * F::HALF * self.width, (F::ONE - sy) * F::HALF * self.height]
    }
}

/// `tan(fov_x / 2)` for a horizontal field of view in degrees: the slope of the film's side
/// edges of a pinhole ([`FilmPlane`]'s `half_x`), and of a projector's image
/// (`crate::projector`).
#[inline]
pub fn half_slope<F: FilmFloat>(fov_x_deg: f32) -> F {
    (F::HALF * F::from_f32(fov_x_deg).to_radians()).tan()
}

/// Primary rays of a camera (see [`Camera::ray_generator`]).
pub struct RayGenerator<'a> {
    cam: &'a Camera,
    film: FilmPlane<f32>,
    o: Vec3,
}

impl RayGenerator<'_> {
    /// The ray through film position `p` and the centre of the lens.
    #[inline]
    pub fn generate(&self, p: Vec2) -> Ray {
        self.generate_through(p, Vec2::ZERO)
    }

    /// A camera sample's ray: through film position `p` and, for a thin lens, a lens point drawn
    /// from `sampler` (one 2D sample, after the film position's; other cameras draw nothing, so
    /// their sample streams are those of a pinhole).
    #[inline]
    pub fn sample(&self, p: Vec2, sampler: &mut Sampler) -> Ray {
        match self.cam.projection {
            Projection::ThinLens { aperture_radius, .. } => {
                self.generate_through(p, aperture_radius * sample_uniform_disk_concentric(sampler.next_2d()))
            }
            _ => self.generate(p),
        }
    }

    /// The ray through film position `p` and the camera-space lens point `(lens, 0)`.
    ///
    /// With `(x, y)` the film position's point of the film plane ([`FilmPlane::plane_point`]):
    /// - pinhole: direction `(x, y, 1)` from the origin;
    /// - thin lens: from `(lens, 0)` towards `focus_distance (x, y, 1)`;
    /// - orthographic: along `+z` from `(x, y, near_clip)`.
    ///
    /// Perspective rays start where they cross the near clip plane `z = near_clip` and end at
    /// `z = far_clip` (camera-space depths); orthographic ones run `far_clip - near_clip` in
    /// world units, as Mitsuba's, even when `to_world` scales `z`.
    #[inline]
    pub fn generate_through(&self, p: Vec2, lens: Vec2) -> Ray {
        let cam = self.cam;
        let [x, y] = self.film.plane_point(p.x, p.y);
        let local = Vec3::new(x, y, 1.0);
        let (o, d_local) = match cam.projection {
            Projection::Pinhole => (self.o, local * (1.0 / local.length())),
            Projection::ThinLens { focus_distance, .. } => {
                let from = Vec3::new(lens.x, lens.y, 0.0);
                ((cam.to_world.transform_point3(from)), (local * focus_distance - from).normalize())
            }
            Projection::Orthographic => {
                let o = cam.to_world.transform_point3(Vec3::new(local.x, local.y, cam.near_clip));
                let d = cam.to_world.transform_vector3(Vec3::Z).normalize();
                return Ray { o, d, t_max: cam.far_clip - cam.near_clip };
            }
        };
        let d = cam.to_world.transform_vector3(d_local).normalize();
        // Near/far clips are distances along the camera's z axis.
        let t_near = cam.near_clip / d_local.z;
        let t_far = cam.far_clip / d_local.z;
        Ray { o: o + d * t_near, d, t_max: t_far - t_near }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(projection: Projection, to_world: Mat4, near_clip: f32) -> Camera {
        Camera {
            projection,
            near_clip,
            far_clip: if near_clip == 1.0 { 100.0 } else { 10000.0 },
            ..Camera::pinhole(to_world, 40.0, (200, 120))
        }
    }

    fn assert_ray(r: &Ray, o: [f32; 3], d: [f32; 3], t_max: f32) {
        let near = |a: Vec3, b: [f32; 3]| (a - Vec3::from(b)).abs().max_element() < 2e-5;
        assert!(near(r.o, o) && near(r.d, d), "ray {r:?}, Mitsuba o {o:?} d {d:?}");
        assert!((r.t_max - t_max).abs() < 1e-4 * t_max, "t_max {} vs Mitsuba {t_max}", r.t_max);
    }

    /// Rays of a 200x120 film against Mitsuba 3.9.1's (`scalar_rgb`, `Sensor::sample_ray` with
    /// the same position sample, `(x / W, y / H)`, and aperture sample).
    #[test]
    fn rays_match_mitsuba() {
        let px = |u: f32, v: f32| Vec2::new(u * 200.0, v * 120.0);
        // `orthographic`, near 1, far 100, to_world scale(1.5, 1.5, 1).
        let ortho = camera(Projection::Orthographic, Mat4::from_scale(Vec3::new(1.5, 1.5, 1.0)), 1.0);
        let g = ortho.ray_generator();
        assert_ray(&g.generate(px(0.0, 0.0)), [1.5, 0.9, 1.0], [0.0, 0.0, 1.0], 99.0);
        assert_ray(&g.generate(px(1.0, 1.0)), [-1.5, -0.9, 1.0], [0.0, 0.0, 1.0], 99.0);
        assert_ray(&g.generate(px(0.25, 0.75)), [0.75, -0.45, 1.0], [0.0, 0.0, 1.0], 99.0);
        // `thinlens`, fov 40, aperture_radius 0.2, focus_distance default (far_clip) or 3.
        let lens = |focus_distance| {
            camera(Projection::ThinLens { aperture_radius: 0.2, focus_distance }, Mat4::IDENTITY, 0.01)
        };
        let draw = |cam: &Camera, p: Vec2, u: Vec2| {
            let Projection::ThinLens { aperture_radius, .. } = cam.projection else { unreachable!() };
            cam.ray_generator().generate_through(p, aperture_radius * sample_uniform_disk_concentric(u))
        };
        let far = lens(10000.0);
        let r = draw(&far, px(0.5, 0.5), Vec2::new(1.0, 0.5));
        assert_ray(&r, [0.2, 0.0, 0.01], [-1.99702e-05, 0.0, 1.0], 9999.99);
        let r = draw(&far, px(0.1, 0.3), Vec2::new(0.2, 0.9));
        assert_ray(&r, [-0.0859794, 0.133909, 0.01], [0.278596, 0.0835635, 0.956766], 10451.864);
        let r = draw(&lens(3.0), px(0.1, 0.3), Vec2::new(0.2, 0.9));
        assert_ray(&r, [-0.0856832, 0.133465, 0.01], [0.305216, 0.0409178, 0.951403], 10510.777);
    }

    /// The film plane's two directions are inverses, its `f32` and `f64` forms agree to the
    /// rounding of `f32` (the camera grid widens its cells by 1e-6 of the film for this), and a
    /// pinhole ray's direction projects back onto its film position.
    #[test]
    fn film_plane_round_trips() {
        let cam = camera(Projection::Pinhole, Mat4::from_rotation_y(0.3), 0.01);
        let (f, g) = (cam.film_plane::<f32>(), cam.film_plane::<f64>());
        let projector = cam.film_projector().unwrap();
        let mut sampler = Sampler::from_seed(7);
        for _ in 0..1000 {
            let p = Vec2::new(sampler.next_1d() * 200.0, sampler.next_1d() * 120.0);
            let [x, y] = f.plane_point(p.x, p.y);
            let [xd, yd] = g.plane_point(p.x as f64, p.y as f64);
            assert!((x as f64 - xd).abs() <= 1e-6 * g.half_x && (y as f64 - yd).abs() <= 1e-6 * g.half_y);
            let [px, py] = g.film_position(xd * 2.5, yd * 2.5, 2.5);
            assert!((px - p.x as f64).abs() < 1e-9 && (py - p.y as f64).abs() < 1e-9, "{px} {py} vs {p}");
            let ray = cam.generate_ray(p);
            let back = projector.project(ray.o + ray.d).unwrap();
            assert!((back.px - p.x).abs() < 1e-3 && (back.py - p.y).abs() < 1e-3, "{back:?} vs {p}");
        }
    }

    /// Every ray of a thin lens through the same film position meets at the focal plane, and
    /// the lens points cover the aperture disk.
    #[test]
    fn thin_lens_rays_focus() {
        let to_world = Mat4::from_rotation_y(0.7) * Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let cam = camera(Projection::ThinLens { aperture_radius: 0.5, focus_distance: 4.0 }, to_world, 0.01);
        let g = cam.ray_generator();
        let p = Vec2::new(37.3, 81.9);
        let pinhole = g.generate(p);
        let to_cam = cam.to_world.inverse();
        let at_focus = |r: &Ray| {
            let (o, d) = (to_cam.transform_point3(r.o), to_cam.transform_vector3(r.d));
            o + d * ((4.0 - o.z) / d.z)
        };
        let focus = at_focus(&pinhole);
        let mut sampler = Sampler::from_seed(3);
        let mut widest = 0.0f32;
        for _ in 0..1000 {
            let r = g.sample(p, &mut sampler);
            assert!((at_focus(&r) - focus).length() < 1e-4, "{} vs {focus}", at_focus(&r));
            let o = to_cam.transform_point3(r.o);
            let lens = o - to_cam.transform_vector3(r.d) * (o.z / to_cam.transform_vector3(r.d).z);
            assert!(lens.truncate().length() <= 0.5 + 1e-4);
            widest = widest.max(lens.truncate().length());
        }
        assert!(widest > 0.48, "{widest}");
    }

    /// Film positions follow the normalised filter profile: chi-square of a histogram of offsets
    /// for a pixel far from the film's edges, and offsets stay on the film at a corner.
    #[test]
    fn film_positions_follow_the_filter() {
        for filter in [PixelFilter::Tent { radius: 1.0 }, PixelFilter::Gaussian { stddev: 0.5 }] {
            let camera =
                Camera { far_clip: 100.0, filter, ..Camera::pinhole(Mat4::IDENTITY, 40.0, (20, 20)) };
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

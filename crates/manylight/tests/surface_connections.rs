//! The surface connections of `docs/theory.md` §5.1-5.3 against references computed
//! independently in `f64`: VRL -> surface point and surface VPL -> camera segment against
//! adaptive quadrature of their integrals (T12a), (T12c); surface VPLs -> surface point against
//! the closed-form form factor of a disk. Each with negative controls (a missing `1/pi`, a wrong
//! cosine), which must fail the same check.
//!
//! `cargo test -p haze-manylight --test surface_connections -- --nocapture` prints the tables.

mod vrl_support;

use haze_core::{Frame, Rgb, Sampler, Vec3};
use haze_manylight::vpl::{point_light_to_point, sample_point_light_to_segment, SurfaceVpl};
use haze_manylight::vrl::surface::sample_vrl_to_point;
use haze_manylight::vrl::{Segment, Vrl, VrlMedium};
use haze_scene::{Bsdf, Texture};
use vrl_support::*;

/// How a receiver's or light's cosine lobe is (mis)computed by the estimator under test.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Lobe {
    Right,
    /// `rho` instead of `rho / pi`.
    NoInvPi,
    /// No cosine factor.
    NoCosine,
}

/// A Lambertian lobe of albedo `rho` about the normal `n`, towards the unit direction `d`.
fn lambert(rho: Rgb, n: Vec3, d: Vec3, lobe: Lobe) -> Rgb {
    let cos = n.dot(d);
    if cos <= 0.0 {
        return Rgb::ZERO;
    }
    match lobe {
        Lobe::Right => rho * (cos / std::f32::consts::PI),
        Lobe::NoInvPi => rho * cos,
        Lobe::NoCosine => rho * (1.0 / std::f32::consts::PI),
    }
}

fn lambert64(rho: Rgb, n: Vec3, d: [f64; 3]) -> Rgb64 {
    let cos = (n.x as f64 * d[0] + n.y as f64 * d[1] + n.z as f64 * d[2]).max(0.0);
    rgb64(rho).map(|r| r * cos / std::f64::consts::PI)
}

/// A segment-to-point connection case: its estimate with a (mis)computed lobe, and the
/// reference.
trait Case {
    fn estimate(&self, lobe: Lobe) -> McResult;
    fn reference(&self) -> Rgb64;
}

/// Checks every case against its reference, and that the check fails both negative controls:
/// a missing `1/pi` and a missing cosine at the diffuse end `at` ("receiver", "VPL").
fn check_with_controls<C: Case>(title: &str, cases: &[(&str, C)], at: &str) {
    let rows = |lobe: Lobe| -> Vec<_> {
        cases.iter().map(|(name, c)| check(name, &c.estimate(lobe), c.reference())).collect()
    };
    let (right, no_pi, no_cos) = (rows(Lobe::Right), rows(Lobe::NoInvPi), rows(Lobe::NoCosine));
    let (pi_what, cos_what) = (format!("a missing 1/pi at the {at}"), format!("a missing {at} cosine"));
    report_controls(title, &right, &[(&no_pi, &pi_what), (&no_cos, &cos_what)]);
}

/// (T12a) and (T12c) are one integral over the segment `seg` (`y_t = o + t d`), lit or
/// gathered in `medium` (HG `g`, transmittance `exp(-sigma_t t)` from the segment's start),
/// exchanging light with the diffuse point `p` (normal `n_p`, albedo `rho`) through a
/// connection of extinction `sigma_conn`, with `n = (p - y_t) / w`:
/// `Int_0^len flux exp(-sigma_t t) sigma_s f_hg(n . d) exp(-sigma_conn w) rho/pi max(0, -n . n_p) / w^2 dt`
/// (`docs/theory.md` §5.1, §5.2).
struct Exchange<'a> {
    seg: &'a Segment,
    medium: &'a VrlMedium,
    g: f32,
    flux: Rgb,
    p: Vec3,
    n_p: Vec3,
    rho: Rgb,
    sigma_conn: Rgb,
}

impl Exchange<'_> {
    /// The integral by adaptive quadrature over `t`, in `f64`, split at the foot of `p`.
    fn quadrature(&self) -> Rgb64 {
        let (o, d) = (d64(self.seg.o), d64(self.seg.d));
        let p = d64(self.p);
        let foot: f64 = (0..3).map(|i| (p[i] - o[i]) * d[i]).sum();
        let len = self.seg.len as f64;
        let flux = rgb64(self.flux);
        let (st, ss, sc) = (rgb64(self.medium.sigma_t), rgb64(self.medium.sigma_s), rgb64(self.sigma_conn));
        let breaks: Vec<f64> = [foot].into_iter().filter(|f| *f > 0.0 && *f < len).collect();
        integrate(
            |t| {
                let y: [f64; 3] = std::array::from_fn(|i| o[i] + t * d[i]);
                let r: [f64; 3] = std::array::from_fn(|i| p[i] - y[i]);
                let w2: f64 = r.iter().map(|c| c * c).sum();
                let w = w2.sqrt();
                let n: [f64; 3] = r.map(|c| c / w);
                let cos: f64 = (0..3).map(|i| n[i] * d[i]).sum();
                let phase = hg64(cos, self.g as f64);
                let lobe = lambert64(self.rho, self.n_p, n.map(|c| -c));
                std::array::from_fn(|c| {
                    flux[c] * (-st[c] * t).exp() * ss[c] * phase * (-sc[c] * w).exp() * lobe[c] / w2
                })
            },
            0.0,
            len,
            &breaks,
            1e-9,
        )
    }
}

struct VrlCase {
    vrl: Vrl,
    medium: VrlMedium,
    g: f32,
    x: Vec3,
    n_x: Vec3,
    rho: Rgb,
    sigma_conn: Rgb,
}

impl VrlCase {
    /// A VRL through the origin along a random direction; the receiver at distance `h` from its
    /// line (foot at `foot`), its normal tilted towards the line.
    fn new(h: f32, foot: f32, len: f32, g: f32, seed: u64) -> Self {
        let mut s = Sampler::from_seed(seed);
        let q = random_rotation(&mut s);
        let d = (q * Vec3::Z).normalize();
        let side = (q * Vec3::X).normalize();
        let x = d * foot + side * h;
        let n_x = (-side + d * (s.next_1d() - 0.5) + (q * Vec3::Y) * (s.next_1d() - 0.5)).normalize();
        let sigma_s = random_rgb(&mut s, 0.2, 1.2);
        let medium =
            VrlMedium { sigma_s, sigma_t: sigma_s + random_rgb(&mut s, 0.0, 0.5), phase: phase_of(g) };
        let vrl = Vrl::attenuated(Segment::new(Vec3::ZERO, d, len), random_rgb(&mut s, 0.5, 2.0), 0);
        VrlCase {
            vrl,
            medium,
            g,
            x,
            n_x,
            rho: random_rgb(&mut s, 0.3, 0.9),
            sigma_conn: random_rgb(&mut s, 0.1, 0.8),
        }
    }
}

impl Case for VrlCase {
    fn estimate(&self, lobe: Lobe) -> McResult {
        let sigma = self.sigma_conn;
        monte_carlo(
            |s| {
                sample_vrl_to_point(
                    self.x,
                    |d| lambert(self.rho, self.n_x, d, lobe),
                    &self.vrl,
                    &self.medium,
                    s.next_1d(),
                    |a, b| sigma.exp_neg((a - b).length()),
                )
            },
            7,
            1e-3,
            2_000_000,
        )
    }

    /// (T12a) by adaptive quadrature over `v`, in `f64`.
    fn reference(&self) -> Rgb64 {
        Exchange {
            seg: &self.vrl.seg,
            medium: &self.medium,
            g: self.g,
            flux: self.vrl.flux,
            p: self.x,
            n_p: self.n_x,
            rho: self.rho,
            sigma_conn: self.sigma_conn,
        }
        .quadrature()
    }
}

#[test]
fn vrl_to_surface_point_matches_quadrature() {
    let cases = [
        ("near, foot inside", VrlCase::new(0.05, 0.7, 1.5, 0.0, 1)),
        ("far", VrlCase::new(2.0, 0.3, 1.0, 0.6, 2)),
        ("foot before start", VrlCase::new(0.2, -0.5, 2.0, -0.4, 3)),
        ("foot past end, hg 0.8", VrlCase::new(0.1, 1.4, 1.0, 0.8, 4)),
    ];
    check_with_controls("VRL -> surface point (T12b) against quadrature of (T12a)", &cases, "receiver");
}

struct SegCase {
    cam: Segment,
    cam_medium: VrlMedium,
    g: f32,
    vpl: SurfaceVpl,
    rho: Rgb,
    sigma_conn: Rgb,
}

impl SegCase {
    /// A camera segment along a random direction; a diffuse surface VPL at distance `h` from
    /// its line (foot at `foot`), its normal towards the segment.
    fn new(h: f32, foot: f32, len: f32, g: f32, seed: u64) -> Self {
        let mut s = Sampler::from_seed(seed);
        let q = random_rotation(&mut s);
        let d = (q * Vec3::Z).normalize();
        let side = (q * Vec3::X).normalize();
        let p = d * foot + side * h;
        // Towards the segment's middle, tilted at random: the VPL lights all of the segment.
        let to_mid = (d * (0.5 * len) - p).normalize();
        let n = (to_mid + 0.3 * (q * Vec3::Y) * (s.next_1d() - 0.5)).normalize();
        let frame = Frame::from_normal(n);
        let w_prev = Vec3::new(0.3, -0.2, 0.9).normalize();
        let vpl = SurfaceVpl {
            events: 0,
            p,
            n,
            frame,
            w_prev,
            flux: random_rgb(&mut s, 0.5, 2.0),
            shape: 0,
            tex: Default::default(),
            medium: None,
        };
        let sigma_s = random_rgb(&mut s, 0.2, 1.2);
        let cam_medium =
            VrlMedium { sigma_s, sigma_t: sigma_s + random_rgb(&mut s, 0.0, 0.5), phase: phase_of(g) };
        let cam = Segment::new(Vec3::ZERO, d, len);
        SegCase {
            cam,
            cam_medium,
            g,
            vpl,
            rho: random_rgb(&mut s, 0.3, 0.9),
            sigma_conn: random_rgb(&mut s, 0.1, 0.8),
        }
    }
}

impl Case for SegCase {
    fn estimate(&self, lobe: Lobe) -> McResult {
        let sigma = self.sigma_conn;
        let bsdf = Bsdf::Diffuse { reflectance: Texture::Constant(self.rho) };
        let n = self.vpl.n;
        monte_carlo(
            |s| {
                sample_point_light_to_segment(
                    &self.cam,
                    &self.cam_medium,
                    self.vpl.p,
                    |w| match lobe {
                        Lobe::Right => self.vpl.intensity(&bsdf, w),
                        _ => self.vpl.flux * lambert(self.rho, n, w, lobe),
                    },
                    s.next_1d(),
                    None,
                    |a, b| sigma.exp_neg((a - b).length()),
                )
            },
            9,
            1e-3,
            2_000_000,
        )
    }

    /// (T12c)'s integral by adaptive quadrature over `u`, in `f64`, with the diffuse intensity
    /// `Phi rho / pi cos_p`.
    fn reference(&self) -> Rgb64 {
        Exchange {
            seg: &self.cam,
            medium: &self.cam_medium,
            g: self.g,
            flux: self.vpl.flux,
            p: self.vpl.p,
            n_p: self.vpl.n,
            rho: self.rho,
            sigma_conn: self.sigma_conn,
        }
        .quadrature()
    }
}

#[test]
fn surface_vpl_to_camera_segment_matches_quadrature() {
    let cases = [
        ("near, foot inside", SegCase::new(0.05, 0.7, 1.5, 0.0, 11)),
        ("far", SegCase::new(2.0, 0.3, 1.0, 0.6, 12)),
        ("foot before start", SegCase::new(0.2, -0.5, 2.0, -0.4, 13)),
        ("foot past end, hg 0.8", SegCase::new(0.1, 1.4, 1.0, 0.8, 14)),
    ];
    check_with_controls("surface VPL -> camera segment (T12c) against quadrature", &cases, "VPL");
}

/// Surface VPLs spread uniformly over a disk of radius `r` (a Lambertian emitter of total flux
/// `Phi`: diffuse VPLs of albedo 1) light a diffuse point on the disk's axis at height `h`,
/// facing it. The outgoing radiance is `rho/pi E` with `E = (Phi / (pi r^2)) r^2 / (h^2 + r^2)`
/// (the differential-area-to-coaxial-disk form factor). The mean of (T12d) over VPL positions
/// must match it.
#[test]
fn surface_vpls_to_surface_point_match_the_disk_form_factor() {
    let (r, h) = (0.8f32, 0.5f32);
    let phi = Rgb::new(1.0, 2.0, 3.0);
    let rho_x = Rgb::new(0.7, 0.5, 0.3);
    let x = Vec3::new(0.0, 0.0, h);
    let n_x = -Vec3::Z;
    let white = Bsdf::Diffuse { reflectance: Texture::Constant(Rgb::ONE) };
    let frame = Frame::from_normal(Vec3::Z);
    let run = |lobe: Lobe| {
        monte_carlo(
            |s| {
                let u = s.next_2d();
                let (rad, ang) = (r * u.x.sqrt(), std::f32::consts::TAU * u.y);
                let p = Vec3::new(rad * ang.cos(), rad * ang.sin(), 0.0);
                let vpl = SurfaceVpl {
                    events: 0,
                    p,
                    n: Vec3::Z,
                    frame,
                    w_prev: Vec3::new(0.2, 0.1, 0.97).normalize(),
                    flux: phi,
                    shape: 0,
                    tex: Default::default(),
                    medium: None,
                };
                point_light_to_point(
                    x,
                    |d| lambert(rho_x, n_x, d, lobe),
                    p,
                    |w| vpl.intensity(&white, w),
                    None,
                    |_, _| Rgb::ONE,
                )
            },
            21,
            1e-3,
            4_000_000,
        )
    };
    let (r, h) = (r as f64, h as f64);
    let reference = rgb64(rho_x)
        .map(|c| c / std::f64::consts::PI * (1.0 / std::f64::consts::PI) * r * r / (h * h + r * r))
        .iter()
        .zip(rgb64(phi))
        .map(|(a, b)| a * b / (r * r))
        .collect::<Vec<_>>();
    let reference = [reference[0], reference[1], reference[2]];
    let ok = [check("disk", &run(Lobe::Right), reference)];
    let no_pi = [check("disk, receiver without 1/pi", &run(Lobe::NoInvPi), reference)];
    let no_cos = [check("disk, receiver without cosine", &run(Lobe::NoCosine), reference)];
    report_controls(
        "surface VPLs -> surface point (T12d) against the disk form factor",
        &ok,
        &[(&no_pi, "a missing 1/pi at the receiver"), (&no_cos, "a missing receiver cosine")],
    );
}

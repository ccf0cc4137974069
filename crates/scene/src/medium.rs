//! Participating media, one interface for Mitsuba 3's `homogeneous` and `heterogeneous` plugins
//! (the grid medium's coefficients, majorant grid and trackers live in [`crate::hetero`]).
//!
//! As pbrt-v4's `Medium` does, every medium describes itself along a ray by *majorant
//! segments* (pieces of the ray with a per-channel upper bound of `sigma_t`,
//! [`Medium::majorant_segments`]): a homogeneous medium is one segment whose majorant is its
//! `sigma_t`, a grid medium one segment per majorant cell its DDA crosses. Free flights are
//! sampled by one routine for every walker ([`Medium::begin_flight`], [`Medium::end_flight`]):
//! closed form in a homogeneous medium, delta tracking in a grid. What a grid medium is not,
//! a constant `sigma_t` and albedo, cannot be read from it: [`Medium::homogeneous`] is `None`
//! there, and the bounds the many-light methods' importances and bound cuts use are named as
//! bounds ([`Medium::majorant`], [`Medium::albedo_bound`]).

pub use crate::flight::{Flight, FlightStart};
use crate::hetero::{Heterogeneous, MajorantIter, MajorantSegment};
use glam::Vec3;
use haze_core::transmittance::{free_flight_at, free_flight_distance, FreeFlight};
use haze_core::{Phase, Rgb, Sampler};
use std::sync::Arc;

/// Index of a medium in [`crate::Scene::media`].
pub type MediumId = u32;

/// A medium: its name, phase function and coefficients.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The XML `id`, for messages.
    pub name: String,
    pub phase: Phase,
    pub kind: MediumKind,
}

/// How a medium's coefficients vary in space.
#[derive(Clone, Debug, PartialEq)]
pub enum MediumKind {
    /// Constant coefficients.
    Homogeneous(Homogeneous),
    /// Coefficients from volumes, clipped to the `sigma_t` volume's box (Mitsuba 3's
    /// `heterogeneous`, `docs/theory.md` §12).
    Grid(Arc<Heterogeneous>),
}

/// A homogeneous medium's extinction `sigma_t` and single-scattering albedo, both RGB, already
/// multiplied by Mitsuba's `scale`; `sigma_s = albedo sigma_t`, `sigma_a = sigma_t - sigma_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    pub sigma_t: Rgb,
    pub albedo: Rgb,
}

impl Homogeneous {
    pub fn sigma_s(&self) -> Rgb {
        self.sigma_t * self.albedo
    }
}

/// [`Medium::majorant_segments`]: one segment or a grid's cells.
pub enum MajorantSegments<'a> {
    One(Option<MajorantSegment>),
    Grid(MajorantIter<'a>),
}

impl Iterator for MajorantSegments<'_> {
    type Item = MajorantSegment;
    fn next(&mut self) -> Option<MajorantSegment> {
        match self {
            MajorantSegments::One(seg) => seg.take(),
            MajorantSegments::Grid(it) => it.next(),
        }
    }
}

impl Medium {
    pub fn homogeneous(name: String, sigma_t: Rgb, albedo: Rgb, phase: Phase) -> Medium {
        Medium { name, phase, kind: MediumKind::Homogeneous(Homogeneous { sigma_t, albedo }) }
    }

    pub fn grid(name: String, grid: Arc<Heterogeneous>, phase: Phase) -> Medium {
        Medium { name, phase, kind: MediumKind::Grid(grid) }
    }

    /// The constant coefficients of a homogeneous medium; `None` for a grid.
    #[inline]
    pub fn as_homogeneous(&self) -> Option<&Homogeneous> {
        match &self.kind {
            MediumKind::Homogeneous(h) => Some(h),
            MediumKind::Grid(_) => None,
        }
    }

    /// A grid medium's coefficients; `None` for a homogeneous one.
    #[inline]
    pub fn as_grid(&self) -> Option<&Heterogeneous> {
        match &self.kind {
            MediumKind::Grid(g) => Some(g),
            MediumKind::Homogeneous(_) => None,
        }
    }

    pub fn is_homogeneous(&self) -> bool {
        matches!(self.kind, MediumKind::Homogeneous(_))
    }

    /// A per-channel upper bound of `sigma_t` everywhere: `sigma_t` itself when homogeneous, the
    /// largest majorant cell of a grid.
    pub fn majorant(&self) -> Rgb {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.sigma_t,
            MediumKind::Grid(g) => g.global_majorant(),
        }
    }

    /// A per-channel upper bound of the albedo: the albedo itself when homogeneous, the albedo
    /// volume's maximum for a grid.
    pub fn albedo_bound(&self) -> Rgb {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.albedo,
            MediumKind::Grid(g) => g.albedo.max(),
        }
    }

    /// The mean of the majorant over the medium: `sigma_t` itself when homogeneous, the mean of a
    /// grid's majorant cells (the homogeneous proxy the many-light methods' importances use,
    /// `docs/theory.md` §12.5).
    pub fn mean_majorant(&self) -> Rgb {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.sigma_t,
            MediumKind::Grid(g) => g.mean_majorant(),
        }
    }

    /// `(sigma_t, sigma_s)` at the point `p`: the constants of a homogeneous medium; a grid's
    /// volumes at `p`, zero outside the `sigma_t` volume's box (`Heterogeneous::coefficients`).
    #[inline]
    pub fn coefficients(&self, p: Vec3) -> (Rgb, Rgb) {
        match &self.kind {
            MediumKind::Homogeneous(h) => (h.sigma_t, h.sigma_s()),
            MediumKind::Grid(g) => g.coefficients(p),
        }
    }

    /// Whether the medium can scatter light anywhere (`majorant * albedo_bound` not black): a
    /// purely absorbing medium only attenuates.
    pub fn scatters(&self) -> bool {
        !(self.majorant() * self.albedo_bound()).is_black()
    }

    /// The ray `o + t d` over `[t0, t1]` as majorant segments (pbrt-v4's `SampleRay`): one
    /// segment with `sigma_maj = sigma_t` in a homogeneous medium (none if `t1 <= t0`), the
    /// majorant grid's cells in a grid medium (only those inside its box).
    pub fn majorant_segments(&self, o: Vec3, d: Vec3, t0: f32, t1: f32) -> MajorantSegments<'_> {
        match &self.kind {
            MediumKind::Homogeneous(h) => {
                MajorantSegments::One((t1 > t0).then_some(MajorantSegment { t0, t1, sigma_maj: h.sigma_t }))
            }
            MediumKind::Grid(g) => MajorantSegments::Grid(g.majorants.segments(o, d, t0, t1)),
        }
    }

    /// The first half of a free flight, before the surface is known: a homogeneous medium
    /// draws its distance now (one number from `sampler`, `-ln(1 - u) / sigma_t[hero]`), a grid
    /// medium nothing.
    #[inline]
    pub fn begin_flight(&self, hero: usize, sampler: &mut Sampler) -> FlightStart {
        match &self.kind {
            MediumKind::Homogeneous(h) => {
                FlightStart::Drawn(free_flight_distance(h.sigma_t, hero, sampler.next_1d()))
            }
            MediumKind::Grid(_) => FlightStart::Tracked,
        }
    }

    /// The free flight along `o + t d` up to the surface at `t_surface` begun by
    /// [`Self::begin_flight`]: in a homogeneous medium a collision at the drawn distance if it
    /// comes first, with the closed-form weights (`haze_core::transmittance::free_flight_at`);
    /// in a grid medium delta tracking against the majorant grid (`docs/theory.md` §12.3,
    /// (T29)).
    #[inline]
    pub fn end_flight(
        &self,
        start: FlightStart,
        o: Vec3,
        d: Vec3,
        t_surface: f32,
        hero: usize,
        sampler: &mut Sampler,
    ) -> Flight {
        match (&self.kind, start) {
            (MediumKind::Homogeneous(h), FlightStart::Drawn(t)) => {
                match free_flight_at(h.sigma_t, t_surface, hero, t) {
                    FreeFlight::Interaction { t, weight, ratio } => {
                        Flight::Scatter { t, weight, sigma_s: h.sigma_s(), ratio }
                    }
                    FreeFlight::Pass { weight, ratio } => Flight::Pass { weight, ratio },
                }
            }
            (MediumKind::Grid(g), _) => {
                // A copy of the ray for the out-of-line tracking, which takes `o` and `d` by
                // address: passed the caller's own, LLVM keeps every walker's ray in memory
                // through its whole walk, homogeneous media included (+0.75% instructions on
                // volpath's bench-fog-shadow, docs/performance.md §3.6).
                let (o, d) = std::hint::black_box((o, d));
                g.sample_free_flight(o, d, t_surface, hero, sampler)
            }
            (MediumKind::Homogeneous(_), FlightStart::Tracked) => {
                unreachable!("a homogeneous medium's flight begins with a drawn distance")
            }
        }
    }

    /// The transmittance along `o + t d` over `[t0, t1]`: `exp(-sigma_t (t1 - t0))` in a
    /// homogeneous medium (no number drawn), a ratio-tracking estimate against the majorant grid
    /// in a grid medium (numbers from `sampler`; (T30), `docs/theory.md` §12.4).
    #[inline]
    pub fn transmittance(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, sampler: &mut Sampler) -> Rgb {
        match &self.kind {
            MediumKind::Homogeneous(h) => haze_core::transmittance::transmittance(h.sigma_t, t1 - t0),
            MediumKind::Grid(g) => g.transmittance(o, d, t0, t1, sampler),
        }
    }

    /// The optical depth `sigma_t len` of a leg of length `len`, where the medium gives it in
    /// closed form: a homogeneous medium and a finite `len`. `None` where the transmittance
    /// must be estimated ([`Self::transmittance`]: a grid) or is a limit (an infinite leg: 0 or
    /// 1 per channel). Shadow rays sum it over the legs they cross and take one `exp` at the
    /// end (Beer–Lambert: `T(a) T(b) = exp(-(tau_a + tau_b))`).
    #[inline]
    pub fn optical_depth(&self, len: f32) -> Option<Rgb> {
        match &self.kind {
            MediumKind::Homogeneous(h) if len.is_finite() => Some(h.sigma_t * len),
            _ => None,
        }
    }

    /// The part of `o + t d` over `[t0, t1]` where the medium may interact: all of it in a
    /// homogeneous medium (`None` if empty), in a grid medium the span of the majorant cells
    /// with a positive majorant (`Heterogeneous::clip`; the medium is empty elsewhere, (T27),
    /// (T28)).
    #[inline]
    pub fn support(&self, o: Vec3, d: Vec3, t0: f32, t1: f32) -> Option<(f32, f32)> {
        match &self.kind {
            MediumKind::Homogeneous(_) => (t1 > t0).then_some((t0, t1)),
            MediumKind::Grid(g) => g.clip(o, d, t0, t1),
        }
    }

    /// [`Self::begin_flight`] and [`Self::end_flight`] at once, for a walker that knows its
    /// surface first.
    pub fn sample_flight(
        &self,
        o: Vec3,
        d: Vec3,
        t_surface: f32,
        hero: usize,
        sampler: &mut Sampler,
    ) -> Flight {
        let start = self.begin_flight(hero, sampler);
        self.end_flight(start, o, d, t_surface, hero, sampler)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hetero::MajorantGrid;
    use crate::volume::Volume;

    fn homogeneous(sigma_t: Rgb, albedo: Rgb) -> Medium {
        Medium::homogeneous("m".into(), sigma_t, albedo, Phase::Isotropic)
    }

    /// A grid medium whose `sigma_t` and albedo volumes are constant over the unit cube.
    fn constant_grid(sigma_t: Rgb, albedo: Rgb) -> Medium {
        let (st, al) = (Volume::constant(sigma_t), Volume::constant(albedo));
        let majorants = MajorantGrid::build(&st, 1.0, [4, 4, 4]);
        Medium::grid(
            "g".into(),
            Arc::new(Heterogeneous { sigma_t: st, albedo: al, scale: 1.0, majorants }),
            Phase::Isotropic,
        )
    }

    /// Per channel, the MIS estimates `weight / mean(ratio)` of passing and of scattering
    /// (times `sigma_s`) over a random hero reproduce `exp(-sigma_t L)` and
    /// `albedo (1 - exp(-sigma_t L))` within 4 standard errors, for a homogeneous medium and
    /// for a constant grid medium alike (one interface, one estimate).
    #[test]
    fn flights_reproduce_beer_lambert_in_both_kinds() {
        let sigma_t = Rgb::new(0.5, 1.5, 3.0);
        let albedo = Rgb::new(0.9, 0.5, 0.2);
        let len = 0.8;
        for medium in [homogeneous(sigma_t, albedo), constant_grid(sigma_t, albedo)] {
            let (o, d) = (Vec3::new(0.1, 0.5, 0.5), Vec3::X);
            let n = 200_000;
            let mut s = Sampler::new(7, 1, 0);
            let (mut pass, mut pass2, mut scat, mut scat2) = ([0f64; 3], [0f64; 3], [0f64; 3], [0f64; 3]);
            for _ in 0..n {
                let hero = haze_core::transmittance::hero_channel(s.next_1d());
                match medium.sample_flight(o, d, len, hero, &mut s) {
                    Flight::Pass { weight, ratio } => {
                        let v = weight * (1.0 / ratio.mean());
                        for c in 0..3 {
                            pass[c] += v[c] as f64;
                            pass2[c] += (v[c] as f64).powi(2);
                        }
                    }
                    Flight::Scatter { t, weight, sigma_s, ratio } => {
                        assert!(t > 0.0 && t < len);
                        // The scattered energy over the segment: sigma_s T / p, and for the
                        // homogeneous medium the weight excludes sigma_s (T / p = 1 / sigma_t).
                        let v = weight * sigma_s * (1.0 / ratio.mean());
                        for c in 0..3 {
                            scat[c] += v[c] as f64;
                            scat2[c] += (v[c] as f64).powi(2);
                        }
                    }
                }
            }
            let nf = n as f64;
            for c in 0..3 {
                let tr = (-(sigma_t[c] as f64) * len as f64).exp();
                let (m, v) = (pass[c] / nf, pass2[c] / nf - (pass[c] / nf).powi(2));
                assert!(
                    (m - tr).abs() < 4.0 * (v / nf).sqrt() + 1e-6,
                    "{}: pass {c}: {m} vs {tr}",
                    medium.name
                );
                let want = albedo[c] as f64 * (1.0 - tr);
                let (m, v) = (scat[c] / nf, scat2[c] / nf - (scat[c] / nf).powi(2));
                assert!(
                    (m - want).abs() < 4.0 * (v / nf).sqrt() + 1e-6,
                    "{}: scatter {c}: {m} vs {want}",
                    medium.name
                );
            }
        }
    }

    /// `transmittance` is Beer-Lambert over `[t0, t1]` in both kinds (a constant grid's ratio
    /// tracking is exact), and `support` is the whole interval in a homogeneous medium, the
    /// part inside the box in a grid.
    #[test]
    fn transmittance_and_support_in_both_kinds() {
        let sigma_t = Rgb::new(0.5, 1.5, 3.0);
        let (o, d) = (Vec3::new(0.1, 0.5, 0.5), Vec3::X);
        let mut s = Sampler::new(3, 0, 0);
        for medium in [homogeneous(sigma_t, Rgb::ONE), constant_grid(sigma_t, Rgb::ONE)] {
            let tr = medium.transmittance(o, d, 0.2, 0.7, &mut s);
            for c in 0..3 {
                let want = (-sigma_t[c] * 0.5).exp();
                assert!((tr[c] - want).abs() < 1e-5 * want, "{}: {c}: {} vs {want}", medium.name, tr[c]);
            }
            assert_eq!(medium.support(o, d, 0.3, 0.3), None, "{}: empty interval", medium.name);
        }
        assert_eq!(homogeneous(sigma_t, Rgb::ONE).support(o, d, 0.0, 5.0), Some((0.0, 5.0)));
        let (a, b) = constant_grid(sigma_t, Rgb::ONE).support(o, d, 0.0, 5.0).expect("crosses the box");
        assert!(a.abs() < 1e-6 && (b - 0.9).abs() < 1e-5, "grid support [{a}, {b}], box [0, 0.9]");
    }

    /// The point and closed-form queries: a homogeneous medium's constants and optical depth
    /// `sigma_t len` (none for an infinite leg); a grid's coefficients inside its box, zero
    /// outside it, and no closed form; the mean majorant of each.
    #[test]
    fn coefficients_and_optical_depth_in_both_kinds() {
        let (sigma_t, albedo) = (Rgb::new(0.5, 1.5, 3.0), Rgb::new(0.2, 0.5, 0.9));
        let h = homogeneous(sigma_t, albedo);
        assert_eq!(h.coefficients(Vec3::splat(7.0)), (sigma_t, sigma_t * albedo));
        assert_eq!(h.optical_depth(2.0), Some(Rgb::new(1.0, 3.0, 6.0)));
        assert_eq!(h.optical_depth(f32::INFINITY), None);
        assert_eq!(h.mean_majorant(), sigma_t);

        let g = constant_grid(sigma_t, albedo);
        let (t, s) = g.coefficients(Vec3::splat(0.5));
        for c in 0..3 {
            assert!(
                (t[c] - sigma_t[c]).abs() < 1e-6 && (s[c] - sigma_t[c] * albedo[c]).abs() < 1e-6,
                "{t:?} {s:?}"
            );
            assert!(g.mean_majorant()[c] >= sigma_t[c] * (1.0 - 1e-6), "{:?}", g.mean_majorant());
        }
        assert_eq!(g.coefficients(Vec3::splat(1.5)), (Rgb::ZERO, Rgb::ZERO));
        assert_eq!(g.optical_depth(2.0), None);
    }

    /// The bounds: exact for a homogeneous medium, above every coefficient of a grid.
    #[test]
    fn bounds_and_segments() {
        let h = homogeneous(Rgb::new(1.0, 2.0, 3.0), Rgb::splat(0.5));
        assert_eq!(h.majorant(), Rgb::new(1.0, 2.0, 3.0));
        assert_eq!(h.albedo_bound(), Rgb::splat(0.5));
        assert!(h.scatters());
        let segs: Vec<_> = h.majorant_segments(Vec3::ZERO, Vec3::X, 0.5, 2.0).collect();
        assert_eq!(segs, vec![MajorantSegment { t0: 0.5, t1: 2.0, sigma_maj: Rgb::new(1.0, 2.0, 3.0) }]);
        assert_eq!(h.majorant_segments(Vec3::ZERO, Vec3::X, 2.0, 2.0).count(), 0);
        assert!(!homogeneous(Rgb::ONE, Rgb::ZERO).scatters());

        let g = constant_grid(Rgb::new(1.0, 2.0, 3.0), Rgb::splat(0.25));
        assert!(g.as_homogeneous().is_none() && g.as_grid().is_some());
        let m = g.majorant();
        assert!((0..3).all(|c| m[c] >= [1.0, 2.0, 3.0][c]), "{m}");
        assert_eq!(g.albedo_bound(), Rgb::splat(0.25));
        // A ray through the unit cube along x from outside: segments tile [1, 2] only.
        let segs: Vec<_> = g.majorant_segments(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 0.0, 5.0).collect();
        assert!(!segs.is_empty());
        assert!((segs[0].t0 - 1.0).abs() < 1e-5 && (segs.last().unwrap().t1 - 2.0).abs() < 1e-5);
        for w in segs.windows(2) {
            assert!((w[0].t1 - w[1].t0).abs() < 1e-5);
        }
    }
}

//! Per-emitter sampling data that the [`Scene`](crate::Scene) builds once and `lights.rs` reads
//! when it samples emitters.

use crate::emitter::Emitter;
use crate::shape::{AreaSampler, Shape};
use glam::Vec3;
use haze_core::PI;

/// A sphere that holds all of the scene's finite geometry: the light of emitters at infinity
/// enters the scene through it (`docs/theory.md` §13).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Default for BoundingSphere {
    /// The unit sphere at the origin.
    fn default() -> Self {
        BoundingSphere { center: Vec3::ZERO, radius: 1.0 }
    }
}

impl BoundingSphere {
    /// The sphere around the box `(lo, hi)`, widened by 1% (and at least 1e-3) so that no
    /// geometry lies on it; the unit sphere at the origin for an empty or non-finite box.
    pub fn around(lo: Vec3, hi: Vec3) -> Self {
        if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
            return BoundingSphere::default();
        }
        let center = 0.5 * (lo + hi);
        let r = 0.5 * (hi - lo).length();
        BoundingSphere { center, radius: (r * 1.01).max(r + 1e-3) }
    }
}

/// Per-emitter data needed to sample it (area tables of area lights, the choice of emitter for
/// light paths).
#[derive(Clone, Debug, Default)]
pub struct EmitterTables {
    pub area: Vec<Option<AreaSampler>>,
    /// Some emitter is an environment map ([`Scene::prefetch_emitter_sample`](crate::Scene::prefetch_emitter_sample) has work).
    pub has_envmap: bool,
    /// The sphere through which light from infinity enters ([`BoundingSphere::around`] the
    /// scene's geometry).
    pub sphere: BoundingSphere,
    /// The sphere around the scattering media that light paths from infinity also aim at,
    /// when they are bounded and small against `sphere` ([`crate::media_bounds::media_sphere`],
    /// `docs/theory.md` §13, (T38b)).
    pub media: Option<BoundingSphere>,
    /// Probability that a light path starts at each emitter: proportional to its emitted power
    /// ([`emitted_power`]), so that every light path carries about the same flux whatever the
    /// mix of emitters (a bright sun and a dim sky, a lamp and a large sky); cumulative in
    /// `emission_cdf`. Next-event estimation keeps the uniform choice (`lights.rs`), which the
    /// MIS weights of volpath's escaping rays assume.
    pub emission_pmf: Vec<f32>,
    pub emission_cdf: Vec<f32>,
}

impl EmitterTables {
    pub fn new(emitters: &[Emitter], shapes: &[Shape], sphere: BoundingSphere) -> Self {
        let area: Vec<Option<AreaSampler>> = emitters
            .iter()
            .map(|e| match e {
                Emitter::Area { shape, .. } => Some(AreaSampler::new(&shapes[*shape as usize])),
                _ => None,
            })
            .collect();
        let has_envmap = emitters.iter().any(|e| matches!(e, Emitter::EnvMap(_)));
        let power: Vec<f64> =
            emitters.iter().zip(&area).map(|(e, a)| emitted_power(e, a.as_ref(), sphere) as f64).collect();
        let total: f64 = power.iter().sum();
        let emission_pmf: Vec<f32> = if total > 0.0 && total.is_finite() {
            power.iter().map(|p| (p / total) as f32).collect()
        } else {
            vec![1.0 / emitters.len().max(1) as f32; emitters.len()]
        };
        let mut acc = 0.0f64;
        let emission_cdf = emission_pmf
            .iter()
            .map(|p| {
                acc += *p as f64;
                acc as f32
            })
            .collect();
        EmitterTables { area, has_envmap, sphere, media: None, emission_pmf, emission_cdf }
    }

    /// The emitter that `u` chooses for a light path, and the probability of that choice.
    pub fn select_for_emission(&self, u: f32) -> Option<(usize, f32)> {
        let n = self.emission_cdf.len();
        if n == 0 {
            return None;
        }
        let total = self.emission_cdf[n - 1];
        let i = self.emission_cdf.partition_point(|&c| c <= u * total).min(n - 1);
        let p = self.emission_pmf[i];
        (p > 0.0).then_some((i, p))
    }
}

/// The mean over the RGB channels of the power an emitter sends into the scene, in watts:
/// `4 pi I` (point), `2 pi (1 - cos cutoff) I` (spot, an upper bound: the falloff is left
/// out), `pi A L` (area, one-sided; a textured radiance by its mean over uv, Mitsuba's `Texture::mean`, exact when the uv map preserves area ratios), `pi s mean(E) A_image` (projector: [`crate::projector::Projector::power`]), and for emitters at infinity the flux through the disk of
/// the bounding sphere, `pi r^2 E` (directional) and `pi r^2 Int L dw` (constant, envmap).
/// Only ratios matter (the light paths' emitter choice).
pub fn emitted_power(e: &Emitter, area: Option<&AreaSampler>, sphere: BoundingSphere) -> f32 {
    let disk = PI * sphere.radius * sphere.radius;
    match e {
        Emitter::Point { intensity, .. } => 4.0 * PI * intensity.mean(),
        Emitter::Spot { intensity, cos_cutoff, texture, .. } => {
            // The texture's largest value keeps the bound (its mean over the cone is not at hand).
            let tex = texture.as_ref().map_or(1.0, |t| t.range().1);
            2.0 * PI * (1.0 - cos_cutoff) * intensity.mean() * tex
        }
        Emitter::Projector(p) => p.power(),
        Emitter::Area { radiance, .. } => PI * area.map_or(0.0, |a| a.area) * radiance.mean().mean(),
        Emitter::Constant { radiance } => disk * 4.0 * PI * radiance.mean(),
        Emitter::EnvMap(map) => disk * map.radiance_integral().mean(),
        Emitter::Directional { irradiance, .. } => disk * irradiance.mean(),
    }
}

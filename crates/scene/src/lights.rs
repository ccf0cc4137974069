//! Sampling emitters from a reference point (next-event estimation) and evaluating the pdf of
//! hitting them by chance, for multiple importance sampling.
//!
//! Emitters are chosen uniformly (probability `1/N`), as Mitsuba 3 does by default; the pdfs
//! returned here include that selection probability. Solid-angle pdfs are per steradian at the
//! reference point.

use crate::emitter::Emitter;
use crate::emitter_tables::BoundingSphere;
use crate::medium::MediumId;
use crate::scene::Scene;
use crate::texture::TexPoint;
use glam::{Vec2, Vec3};
use haze_core::sampling::{sample_uniform_sphere, uniform_sphere_pdf};
use haze_core::Rgb;

/// A sampled direction towards an emitter.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    /// Unit direction from the reference point towards the emitter.
    pub wi: Vec3,
    /// Distance to the sampled point (infinite for `constant`).
    pub dist: f32,
    /// Radiance arriving from the emitter along `-wi` before attenuation by media; for point and
    /// spot lights the intensity times `1/dist^2`.
    pub radiance: Rgb,
    /// Solid-angle pdf including the selection probability; for delta lights, the selection
    /// probability alone.
    pub pdf: f32,
    pub is_delta: bool,
    pub emitter: u32,
}

impl Scene {
    /// Samples a direction from `p` towards a uniformly chosen emitter. `None` if the sample
    /// carries no energy (back side of an area light, outside a spot's cone).
    pub fn sample_emitter_direction(&self, p: Vec3, u_select: f32, u: Vec2) -> Option<EmitterSample> {
        self.sample_emitter_direction_if(p, u_select, u, |_| true)
    }

    /// The emitter `u_select` chooses (uniformly) and the probability of that choice.
    #[inline]
    fn select_emitter(&self, u_select: f32) -> Option<(usize, f32)> {
        let n = self.emitters.len();
        (n > 0).then(|| (((u_select * n as f32) as usize).min(n - 1), 1.0 / n as f32))
    }

    /// A hint, no effect on results: prefetches the cache lines that
    /// [`Self::sample_emitter_direction`] will read first when it is called with the random
    /// numbers `sampler` gives next (`next_1d`, then `next_2d`), for an environment map (its
    /// large tables are the misses; other emitters read little). `sampler` is not advanced: a
    /// copy draws the numbers. Worth it only where those are the next-event estimation's numbers
    /// and a ray traversal follows before it (volpath, docs/performance.md §4.1).
    #[inline]
    pub fn prefetch_emitter_sample(&self, sampler: &haze_core::Sampler) {
        if !self.emitter_tables.has_envmap {
            return;
        }
        let mut peek = sampler.clone();
        let u_select = peek.next_1d();
        if let Some((idx, _)) = self.select_emitter(u_select) {
            if let Emitter::EnvMap(map) = &self.emitters[idx] {
                map.prefetch(peek.next_2d());
            }
        }
    }

    /// [`Self::sample_emitter_direction`] for a caller whose estimate is zero in the directions
    /// `accept` refuses: an environment map then skips reading the pdf and radiance of such a
    /// direction (`EnvMap::sample_if`); other emitters ignore `accept` (their lookups are cheap).
    /// The same random numbers are used either way, and an accepted sample is the same.
    #[inline]
    pub fn sample_emitter_direction_if(
        &self,
        p: Vec3,
        u_select: f32,
        u: Vec2,
        accept: impl Fn(Vec3) -> bool,
    ) -> Option<EmitterSample> {
        let (idx, sel) = self.select_emitter(u_select)?;
        self.sample_direction_of(idx, sel, p, u, accept)
    }

    /// The direction sample of [`Self::sample_emitter_direction_if`] from the emitter `idx`,
    /// chosen with probability `sel` (the pdf includes it; `sel = 1` for a sample of this
    /// emitter alone, as single scattering from emitters at infinity takes one per emitter).
    #[inline]
    pub fn sample_direction_of(
        &self,
        idx: usize,
        sel: f32,
        p: Vec3,
        u: Vec2,
        accept: impl Fn(Vec3) -> bool,
    ) -> Option<EmitterSample> {
        match &self.emitters[idx] {
            Emitter::Point { position, intensity } => {
                let v = *position - p;
                let d2 = v.length_squared();
                let dist = d2.sqrt();
                Some(EmitterSample {
                    wi: v / dist,
                    dist,
                    radiance: *intensity / d2,
                    pdf: sel,
                    is_delta: true,
                    emitter: idx as u32,
                })
            }
            Emitter::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
                to_local,
                cos_cutoff,
                cos_beam,
                texture,
            } => {
                let pos = to_world.transform_point3(Vec3::ZERO);
                let v = pos - p;
                let d2 = v.length_squared();
                let dist = d2.sqrt();
                let wi = v / dist;
                let local = to_local.transform_vector3(-wi).normalize();
                let f = Emitter::spot_falloff_cos(*cutoff_angle, *beam_width, *cos_cutoff, *cos_beam, local);
                (f > 0.0).then(|| EmitterSample {
                    wi,
                    dist,
                    radiance: *intensity * Emitter::spot_texture(texture, *cutoff_angle, local) * (f / d2),
                    pdf: sel,
                    is_delta: true,
                    emitter: idx as u32,
                })
            }
            Emitter::Projector(proj) => {
                let pos = proj.position();
                let v = pos - p;
                let d2 = v.length_squared();
                let dist = d2.sqrt();
                let wi = v / dist;
                let intensity = proj.intensity(proj.to_local.transform_vector3(-wi).normalize());
                (!intensity.is_black()).then(|| EmitterSample {
                    wi,
                    dist,
                    radiance: intensity / d2,
                    pdf: sel,
                    is_delta: true,
                    emitter: idx as u32,
                })
            }
            Emitter::Area { shape, radiance } => {
                let sh = &self.shapes[*shape as usize];
                let table = self.emitter_tables.area[idx].as_ref()?;
                let s = table.sample(sh, u);
                let v = s.p - p;
                let d2 = v.length_squared();
                let dist = d2.sqrt();
                let wi = v / dist;
                let cos_l = -wi.dot(s.n);
                if cos_l <= 0.0 || d2 == 0.0 {
                    return None;
                }
                Some(EmitterSample {
                    wi,
                    dist,
                    radiance: radiance.eval(s.tex),
                    pdf: sel * s.pdf * d2 / cos_l,
                    is_delta: false,
                    emitter: idx as u32,
                })
            }
            Emitter::Constant { radiance } => Some(EmitterSample {
                wi: sample_uniform_sphere(u),
                dist: f32::INFINITY,
                radiance: *radiance,
                pdf: sel * uniform_sphere_pdf(),
                is_delta: false,
                emitter: idx as u32,
            }),
            Emitter::EnvMap(map) => map.sample_if(u, accept).map(|s| EmitterSample {
                wi: s.d,
                dist: f32::INFINITY,
                radiance: s.radiance,
                pdf: sel * s.pdf,
                is_delta: false,
                emitter: idx as u32,
            }),
            // The irradiance plays the part of a point light's `I / dist^2`.
            Emitter::Directional { d, irradiance } => Some(EmitterSample {
                wi: -*d,
                dist: f32::INFINITY,
                radiance: *irradiance,
                pdf: sel,
                is_delta: true,
                emitter: idx as u32,
            }),
        }
    }

    /// Pdf (per steradian at `p_ref`, selection included) that [`Self::sample_emitter_direction`]
    /// picks the point `p_light` with normal `n_light` on the area emitter `emitter`.
    pub fn area_emitter_pdf(&self, emitter: u32, p_ref: Vec3, p_light: Vec3, n_light: Vec3) -> f32 {
        let Some(table) = self.emitter_tables.area[emitter as usize].as_ref() else { return 0.0 };
        let v = p_light - p_ref;
        let d2 = v.length_squared();
        let cos_l = (-v.normalize().dot(n_light)).abs();
        if cos_l == 0.0 {
            return 0.0;
        }
        d2 / (cos_l * table.area * self.emitters.len() as f32)
    }

    /// Pdf (per steradian, selection included) that [`Self::sample_emitter_direction`]
    /// returns the unit direction `d` from any environment emitter (`constant`, `envmap`).
    pub fn environment_pdf(&self, d: Vec3) -> f32 {
        self.environment_emission(d).map(|(_, pdf)| pdf).sum()
    }

    /// Radiance arriving from infinity along the unit direction `d` of an escaping ray: the
    /// sum over the environment emitters.
    pub fn environment_radiance(&self, d: Vec3) -> Rgb {
        self.environment_emission(d).map(|(le, _)| le).sum()
    }

    /// For each environment emitter, the radiance from the unit direction `d` and the pdf
    /// (per steradian, selection included) that next-event estimation samples `d` from that
    /// emitter. An escaping path MIS-weights each term with its own pdf, matching the weights
    /// next-event estimation gives the same emitter.
    pub fn environment_emission(&self, d: Vec3) -> impl Iterator<Item = (Rgb, f32)> + '_ {
        let sel = 1.0 / self.emitters.len().max(1) as f32;
        self.emitters.iter().filter_map(move |e| match e {
            Emitter::Constant { radiance } => Some((*radiance, sel * uniform_sphere_pdf())),
            Emitter::EnvMap(map) => {
                let (le, pdf) = map.eval_pdf(d);
                Some((le, sel * pdf))
            }
            _ => None,
        })
    }

    /// Radiance leaving an area-emitting shape at a point with normal `n` and texture point
    /// `at` (`SurfaceInteraction::tex` of a hit, `SurfaceSample::tex` of a sampled point) in
    /// direction `w` (unit, pointing away from the surface), and the emitter's index. `None`
    /// on the back side.
    pub fn area_radiance(&self, shape: u32, n: Vec3, at: TexPoint, w: Vec3) -> Option<(u32, Rgb)> {
        let e = self.shapes[shape as usize].emitter?;
        match &self.emitters[e as usize] {
            Emitter::Area { radiance, .. } if n.dot(w) > 0.0 => Some((e, radiance.eval(at))),
            _ => None,
        }
    }
}

/// A sampled emission: where light leaves an emitter, in which direction, and with what weight.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub p: Vec3,
    /// Unit direction of the emitted light.
    pub d: Vec3,
    /// Surface normal at `p` for area lights (to offset the ray origin), `None` for point lights.
    pub n: Option<Vec3>,
    /// `L_e cos / (p_select p_pos p_dir)`: the emitted power per sample, in watts.
    pub weight: Rgb,
    pub emitter: u32,
}

/// Why an emitter cannot start light paths.
#[derive(Clone, Debug, PartialEq)]
pub enum EmissionError {
    NoEmitters,
}

impl std::fmt::Display for EmissionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EmissionError::NoEmitters => write!(f, "the scene has no emitters to trace light from"),
        }
    }
}

impl std::error::Error for EmissionError {}

impl Scene {
    /// Checks that light paths can start: the scene has an emitter. Every kind starts light
    /// paths (emitters at infinity from a disk outside the scene, [`Self::sample_infinite_emission`];
    /// heterogeneous media are fine: `docs/theory.md` §12.5).
    pub fn check_emission(&self) -> Result<(), EmissionError> {
        if self.emitters.is_empty() {
            return Err(EmissionError::NoEmitters);
        }
        Ok(())
    }

    /// The uniform-area sampler of area emitter `emitter` (`None` for other kinds).
    pub fn area_sampler(&self, emitter: u32) -> Option<&crate::shape::AreaSampler> {
        self.emitter_tables.area.get(emitter as usize)?.as_ref()
    }

    /// Samples the start of a light path: an emitter chosen by power
    /// ([`EmitterTables::select_for_emission`](crate::emitter_tables::EmitterTables), probability
    /// `P`), a point on it and a direction. With `sel = 1 / P`: point lights emit uniformly over
    /// the sphere (`weight = 4 pi I sel`), spot lights uniformly in their cutoff cone
    /// (`weight = I falloff 2 pi (1 - cos_cutoff) sel`), area lights from a uniform point with a
    /// cosine-weighted direction on the normal side (`weight = L(uv) pi A sel`, a textured
    /// radiance at the point's uv, the point uniform by area as Mitsuba 3's shape
    /// `sample_position`). Emitters at
    /// infinity ([`Self::sample_infinite_emission`]) start on a disk outside the scene.
    pub fn sample_emission(&self, u_select: f32, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        use haze_core::sampling::{sample_cosine_hemisphere, sample_uniform_cone, uniform_cone_pdf};
        use haze_core::Frame;
        let (idx, p_select) = self.emitter_tables.select_for_emission(u_select)?;
        let sel = 1.0 / p_select;
        match &self.emitters[idx] {
            Emitter::Point { position, intensity } => Some(EmissionSample {
                p: *position,
                d: sample_uniform_sphere(u_dir),
                n: None,
                weight: *intensity * (4.0 * haze_core::PI * sel),
                emitter: idx as u32,
            }),
            Emitter::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
                cos_cutoff,
                cos_beam,
                texture,
                ..
            } => {
                let cos_max = *cos_cutoff;
                let local = sample_uniform_cone(u_dir, cos_max);
                let f = Emitter::spot_falloff_cos(*cutoff_angle, *beam_width, cos_max, *cos_beam, local);
                let d = to_world.transform_vector3(local).normalize();
                (f > 0.0).then(|| EmissionSample {
                    p: to_world.transform_point3(Vec3::ZERO),
                    d,
                    n: None,
                    weight: *intensity
                        * Emitter::spot_texture(texture, *cutoff_angle, local)
                        * (f * sel / uniform_cone_pdf(cos_max)),
                    emitter: idx as u32,
                })
            }
            Emitter::Area { shape, radiance } => {
                let sh = &self.shapes[*shape as usize];
                let table = self.emitter_tables.area[idx].as_ref()?;
                let s = table.sample(sh, u_pos);
                let d = Frame::from_normal(s.n).to_world(sample_cosine_hemisphere(u_dir));
                Some(EmissionSample {
                    p: s.p,
                    d,
                    n: Some(s.n),
                    weight: radiance.eval(s.tex) * (haze_core::PI * table.area * sel),
                    emitter: idx as u32,
                })
            }
            Emitter::Projector(proj) => {
                // A uniform point of the image plane `z = 1`: the solid-angle pdf is
                // `cos^3(theta) / A_image`, so the weight `I / pdf` is `pi s E(uv) A_image`.
                let local =
                    Vec3::new((1.0 - 2.0 * u_dir.x) * proj.tan_x, (1.0 - 2.0 * u_dir.y) * proj.tan_y, 1.0);
                let e = proj.irradiance.eval(u_dir);
                (!e.is_black()).then(|| EmissionSample {
                    p: proj.position(),
                    d: proj.to_world.transform_vector3(local).normalize(),
                    n: None,
                    weight: e * (haze_core::PI * proj.scale * 4.0 * proj.tan_x * proj.tan_y * sel),
                    emitter: idx as u32,
                })
            }
            Emitter::Constant { .. } | Emitter::EnvMap(_) | Emitter::Directional { .. } => self
                .sample_infinite_emission(idx, u_pos, u_dir)
                .map(|(p, d, w)| EmissionSample { p, d, n: None, weight: w * sel, emitter: idx as u32 }),
        }
    }

    /// The start of a light path from the emitter at infinity `idx` (`constant`, `envmap`,
    /// `directional`), before the emitter choice: a direction of travel `d` (`-w`, with `w` the
    /// direction towards the light drawn as next-event estimation draws it from `u_dir`:
    /// uniform over the sphere, the envmap's importance table, the sun's one direction) and an
    /// origin uniform on the disk of radius `r` (the [`BoundingSphere`]'s) perpendicular to
    /// `d`, centred at `c - r d` upstream of the sphere's centre `c`. Every line of direction
    /// `d` that meets the sphere crosses the disk once, with the position pdf `1 / (pi r^2)`,
    /// so the flux per sample is (pbrt-v4's infinite lights, `SampleLe`; `docs/theory.md` §13)
    ///
    /// ```text
    ///   weight = L(w) pi r^2 / p(w)        (directional: E pi r^2)
    /// ```
    ///
    /// When the scattering media lie in a small sphere `(c_m, r_m)` of their own
    /// ([`Scene::media_sphere`]), the origin comes instead from the mixture of the two disks,
    /// share [`MEDIA_SHARE`] from the media's (its point moved along `d` onto the scene disk's
    /// plane), and the position pdf is the mixture's at the origin (T38b):
    ///
    /// ```text
    ///   p(x) = (1 - s) [|x - c|_perp <= r] / (pi r^2) + s [|x - c_m|_perp <= r_m] / (pi r_m^2)
    ///   weight = L(w) / (p(w) p(x))
    /// ```
    ///
    /// Returns `(origin, d, weight)`; `None` for other emitters or a black sample. The origin
    /// lies outside the sphere, so the path enters the scene from outside.
    ///
    /// [`BoundingSphere`]: crate::emitter_tables::BoundingSphere
    pub fn sample_infinite_emission(
        &self,
        idx: usize,
        u_pos: Vec2,
        u_dir: Vec2,
    ) -> Option<(Vec3, Vec3, Rgb)> {
        let (d, le_over_pdf) = match &self.emitters[idx] {
            Emitter::Constant { radiance } => {
                (-sample_uniform_sphere(u_dir), *radiance * (1.0 / uniform_sphere_pdf()))
            }
            Emitter::EnvMap(map) => {
                let s = map.sample(u_dir)?;
                if s.pdf.is_nan() || s.pdf <= 0.0 {
                    return None;
                }
                (-s.d, s.radiance * (1.0 / s.pdf))
            }
            Emitter::Directional { d, irradiance } => (*d, *irradiance),
            _ => return None,
        };
        if le_over_pdf.is_black() || !le_over_pdf.is_finite() {
            return None;
        }
        let sphere = self.emitter_tables.sphere;
        let r = sphere.radius;
        let frame = haze_core::Frame::from_normal(d);
        let Some(media) = self.emitter_tables.media else {
            let q = haze_core::sampling::sample_uniform_disk_concentric(u_pos);
            let origin = sphere.center + r * (frame.to_world(Vec3::new(q.x, q.y, 0.0)) - d);
            return Some((origin, d, le_over_pdf * (haze_core::PI * r * r)));
        };
        // The disk chosen by `u_pos.x`, rescaled to stay uniform.
        let (disk, u) = if u_pos.x < MEDIA_SHARE {
            (media, Vec2::new(u_pos.x / MEDIA_SHARE, u_pos.y))
        } else {
            (sphere, Vec2::new((u_pos.x - MEDIA_SHARE) / (1.0 - MEDIA_SHARE), u_pos.y))
        };
        let q = haze_core::sampling::sample_uniform_disk_concentric(u);
        let p = disk.center + disk.radius * frame.to_world(Vec3::new(q.x, q.y, 0.0));
        // Onto the plane tangent to the scene's sphere upstream, `(x - c) . d = -r`.
        let origin = p - d * ((p - sphere.center).dot(d) + r);
        let pdf = infinite_origin_pdf(origin, d, sphere, media);
        (pdf > 0.0).then(|| (origin, d, le_over_pdf * (1.0 / pdf)))
    }

    /// Medium containing the point `p`, found by casting a ray and looking at the first shape
    /// that declares media: arriving at it from its inside (the ray leaves through the side the
    /// normal points to) means `p` is in its interior medium, otherwise in its exterior medium.
    /// Shapes without media are skipped, as they do not change the medium (Mitsuba 3's rule).
    pub fn medium_at(&self, p: Vec3) -> Option<MediumId> {
        // An irrational-ish direction avoids grazing axis-aligned geometry.
        let d = Vec3::new(0.267_261_24, 0.801_783_7, 0.534_522_5);
        let mut ray = haze_core::Ray::new(p, d);
        for _ in 0..1024 {
            let h = self.intersect(&ray)?;
            // The medium on the side the ray comes from, of every boundary touching the hit.
            let b = self.boundary_at(h.shape, h.p, h.n);
            if b.is_transition() {
                return b.medium_towards(-d, None);
            }
            ray = haze_core::Ray::new(haze_core::ray::offset_origin(h.p, h.n, d), d);
        }
        None
    }
}

/// A point sampled on an emitter at a finite position: where a light path or a connection to
/// the emitter starts. [`Scene::emitted_intensity`] evaluates what leaves it in a direction, so
/// that the callers (the caustic paths' emission, single scattering's light points) do not
/// match the emitter kinds themselves.
#[derive(Clone, Copy, Debug)]
pub struct EmitterPoint {
    pub emitter: u32,
    pub p: Vec3,
    /// The surface normal and texture point of an area emitter's point; `None` at a point or
    /// spot light.
    pub surface: Option<(Vec3, TexPoint)>,
    /// Density of `p` per unit area on an area emitter; 1 at a point or spot light (a delta
    /// position, chosen with certainty).
    pub pdf: f32,
}

impl Scene {
    /// A point on the emitter `emitter`: a point or spot light's position, or a point of an area
    /// emitter uniform by area (as Mitsuba 3's shape `sample_position`). `None` for emitters at
    /// infinity (`constant`, `envmap`, `directional`) and for the `projector`, which only
    /// volpath renders.
    pub fn sample_emitter_point(&self, emitter: u32, u: Vec2) -> Option<EmitterPoint> {
        let (p, surface, pdf) = match &self.emitters[emitter as usize] {
            Emitter::Point { position, .. } => (*position, None, 1.0),
            Emitter::Spot { to_world, .. } => (to_world.transform_point3(Vec3::ZERO), None, 1.0),
            Emitter::Area { shape, .. } => {
                let table = self.emitter_tables.area.get(emitter as usize)?.as_ref()?;
                let ss = table.sample(&self.shapes[*shape as usize], u);
                (ss.p, Some((ss.n, ss.tex)), ss.pdf)
            }
            Emitter::Projector(_)
            | Emitter::Constant { .. }
            | Emitter::EnvMap(_)
            | Emitter::Directional { .. } => return None,
        };
        Some(EmitterPoint { emitter, p, surface, pdf })
    }

    /// Radiant intensity leaving `ep` in the unit direction `d`, per unit solid angle (and, on
    /// an area emitter, per unit area): `I` at a point light, `I falloff(d)` at a spot light,
    /// `L(uv) cos(n, d)` on an area emitter, zero behind its surface. Divided by `ep.pdf` it is
    /// the estimate of the emitter's intensity towards `d`.
    pub fn emitted_intensity(&self, ep: &EmitterPoint, d: Vec3) -> Rgb {
        match &self.emitters[ep.emitter as usize] {
            Emitter::Point { intensity, .. } => *intensity,
            Emitter::Spot { intensity, cutoff_angle, beam_width, to_local, cos_cutoff, cos_beam, .. } => {
                let local = to_local.transform_vector3(d).normalize();
                *intensity
                    * Emitter::spot_falloff_cos(*cutoff_angle, *beam_width, *cos_cutoff, *cos_beam, local)
            }
            Emitter::Area { shape, .. } => {
                let Some((n, tex)) = ep.surface else { return Rgb::ZERO };
                let cos = n.dot(d);
                match self.area_radiance(*shape, n, tex, d) {
                    Some((_, le)) if cos > 0.0 => le * cos,
                    _ => Rgb::ZERO,
                }
            }
            _ => Rgb::ZERO,
        }
    }
}

impl Scene {
    /// A rough measure of the power emitter `emitter` sends towards a set of targets, for
    /// choosing among emitters in proportion to it (only the ratios matter; the caustic paths
    /// aim at the delta shapes with it). With `Ω(x)` the solid angle the targets subtend from
    /// the point `x` (`solid_angle`) and `A(d)` their cross-section perpendicular to the
    /// direction `d` (`cross_section`), and bars the mean over the channels:
    ///
    /// ```text
    ///   point, spot     Ī Ω(p)              (p the position; the spot's cone ignored)
    ///   area            L̄ A Ω(c) / π        (A the area, c its bounding sphere's centre,
    ///                                         L̄ a textured radiance's mean)
    ///   directional     Ē A(d)              (d the direction of travel)
    /// ```
    ///
    /// `None` for the environments (`constant`, `envmap`: light from every direction, no
    /// position) and the `projector`, which only volpath renders.
    pub fn emitter_power_towards(
        &self,
        emitter: u32,
        solid_angle: impl Fn(Vec3) -> f32,
        cross_section: impl Fn(Vec3) -> f32,
    ) -> Option<f32> {
        match &self.emitters[emitter as usize] {
            Emitter::Point { position, intensity } => Some(intensity.mean() * solid_angle(*position)),
            Emitter::Spot { to_world, intensity, .. } => {
                Some(intensity.mean() * solid_angle(to_world.transform_point3(Vec3::ZERO)))
            }
            Emitter::Area { shape, radiance } => {
                let area = self.area_sampler(emitter)?.area;
                let c = self.shapes[*shape as usize].geometry.bounding_sphere().map_or(Vec3::ZERO, |s| s.0);
                Some(radiance.mean().mean() * area * solid_angle(c) / haze_core::PI)
            }
            Emitter::Directional { d, irradiance } => Some(irradiance.mean() * cross_section(*d)),
            Emitter::Constant { .. } | Emitter::EnvMap(_) | Emitter::Projector(_) => None,
        }
    }
}

/// Share of the light paths from infinity whose origin is aimed at the media's sphere when there
/// is one (`docs/theory.md` §13, (T38b)): half, so that the scene's surfaces keep half their
/// surface VPLs while the media get at least 2.5 times their density of VRLs.
pub const MEDIA_SHARE: f32 = 0.5;

/// The density per unit area, on the plane perpendicular to `d`, of the origin `x` of a light
/// path from infinity drawn from the mixture of the scene's disk and the media's (T38b).
pub fn infinite_origin_pdf(x: Vec3, d: Vec3, scene: BoundingSphere, media: BoundingSphere) -> f32 {
    let across = |c: Vec3| {
        let v = x - c;
        (v - d * v.dot(d)).length_squared()
    };
    let disk = |s: BoundingSphere, share: f32| {
        if across(s.center) <= s.radius * s.radius * (1.0 + 1e-5) {
            share / (haze_core::PI * s.radius * s.radius)
        } else {
            0.0
        }
    };
    disk(scene, 1.0 - MEDIA_SHARE) + disk(media, MEDIA_SHARE)
}

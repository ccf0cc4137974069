//! The scene the integrators render: camera, shapes, media, emitters, integrator settings, and
//! ray queries through the acceleration structure.

use crate::accel::Accel;
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::emitter_tables::EmitterTables;
use crate::interaction::SurfaceInteraction;
use crate::medium::{Medium, MediumId};
use crate::shape::Shape;
use glam::Vec3;
use haze_core::Ray;
use std::path::PathBuf;

/// The `<integrator>` element: its plugin name and the parameters every integrator shares.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorSpec {
    /// Plugin name, e.g. `volpath`.
    pub name: String,
    /// Longest path, counted in scattering events as Mitsuba 3 does; `-1` means unlimited.
    /// Mitsuba's default is `-1`.
    pub max_depth: i32,
    /// Depth from which Russian roulette starts. Mitsuba's default is 5.
    pub rr_depth: u32,
    /// Do not show emitters seen directly by the camera.
    pub hide_emitters: bool,
}

impl Default for IntegratorSpec {
    fn default() -> Self {
        IntegratorSpec { name: "volpath".into(), max_depth: -1, rr_depth: 5, hide_emitters: false }
    }
}

pub struct Scene {
    /// The file the scene came from, if any (for messages).
    pub path: Option<PathBuf>,
    pub camera: Camera,
    /// Samples per pixel from the sampler's `sample_count` (Mitsuba default 4).
    pub spp: u32,
    pub integrator: IntegratorSpec,
    pub shapes: Vec<Shape>,
    pub media: Vec<Medium>,
    pub emitters: Vec<Emitter>,
    pub(crate) emitter_tables: EmitterTables,
    accel: Accel,
}

impl Scene {
    /// Assembles a scene and builds its acceleration structure.
    pub fn new(
        path: Option<PathBuf>,
        camera: Camera,
        spp: u32,
        integrator: IntegratorSpec,
        shapes: Vec<Shape>,
        media: Vec<Medium>,
        emitters: Vec<Emitter>,
    ) -> Self {
        let accel = Accel::build(&shapes);
        let emitter_tables = EmitterTables::new(&emitters, &shapes);
        Scene { emitter_tables, path, camera, spp, integrator, shapes, media, emitters, accel }
    }

    /// Closest hit with `t` in `(0, ray.t_max)`.
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        self.accel.intersect(&self.shapes, ray)
    }

    /// True if anything blocks `ray` before `ray.t_max`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
    }

    pub fn medium(&self, id: MediumId) -> &Medium {
        &self.media[id as usize]
    }

    /// Axis-aligned bounds of all finite geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.accel.bounds()
    }
}

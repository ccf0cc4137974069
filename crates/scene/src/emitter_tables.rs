//! Per-emitter sampling data that the [`Scene`](crate::Scene) builds once and `lights.rs` reads
//! when it samples emitters.

use crate::emitter::Emitter;
use crate::shape::{AreaSampler, Shape};

/// Per-emitter data needed to sample it (area tables of area lights).
#[derive(Clone, Debug, Default)]
pub struct EmitterTables {
    pub area: Vec<Option<AreaSampler>>,
    /// Some emitter is an environment map ([`Scene::prefetch_emitter_sample`](crate::Scene::prefetch_emitter_sample) has work).
    pub has_envmap: bool,
}

impl EmitterTables {
    pub fn new(emitters: &[Emitter], shapes: &[Shape]) -> Self {
        let area = emitters
            .iter()
            .map(|e| match e {
                Emitter::Area { shape, .. } => Some(AreaSampler::new(&shapes[*shape as usize])),
                _ => None,
            })
            .collect();
        let has_envmap = emitters.iter().any(|e| matches!(e, Emitter::EnvMap(_)));
        EmitterTables { area, has_envmap }
    }
}

//! Camera segments as the many-light estimators see them: one medium interval of a camera
//! chain (`gather.rs` walks the chains).

use crate::vrl::{Segment, VrlMedium};
use haze_core::Rgb;
use haze_scene::{MediumId, Scene};

/// One medium interval of a camera chain (a gathering segment).
#[derive(Clone, Copy, Debug)]
pub struct CameraSegment {
    pub seg: Segment,
    pub medium: MediumId,
    /// Camera-path throughput at `seg.o`: transmittance of the media crossed before this
    /// interval times the delta surfaces' sampling weights (`gather.rs`).
    pub tr_before: Rgb,
    /// Scattering events of the camera path before this segment (`crate::depth`).
    pub events: u32,
}

/// Most gathering segments kept per camera chain; a chain crossing more boundaries than this
/// gathers on its first `MAX_SEGMENTS` intervals only (`gather.rs`).
pub const MAX_SEGMENTS: usize = 64;

/// The medium of a segment in the form the estimators take. A heterogeneous medium gets its
/// homogeneous proxy (`docs/theory.md` §12.5): the mean of its majorant cells as `sigma_t` and
/// the albedo volume's maximum; only importances and early-outs read it, the estimators evaluate
/// the medium itself (`crate::hetero`).
pub fn estimator_medium(scene: &Scene, id: MediumId) -> VrlMedium {
    let m = scene.medium(id);
    let sigma_t = m.mean_majorant();
    VrlMedium { sigma_s: sigma_t * m.albedo_bound(), sigma_t, phase: m.phase }
}

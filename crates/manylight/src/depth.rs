//! The path-length rule every many-light method shares with `volpath` (`docs/theory.md` §2.2).
//!
//! `volpath` (Mitsuba 3's convention) counts *scattering events*: medium collisions and
//! non-null surface vertices; a `null` boundary and a thin sheet's straight transmission are
//! not events, and neither is the emission or the camera. With `max_depth = D` it keeps exactly
//! the paths of at most `D - 1` events (`D = 1`: emitters seen directly; `D = 2`: direct light),
//! whichever way the path was found. The many-light methods build each path from a camera part
//! of `c` events and a light part of `e` events, joined by a connection whose two ends are
//! events too:
//!
//! ```text
//!   emitted light reached by the camera part:            c          <= D - 1
//!   next-event estimation at a camera vertex:            c + 1      <= D - 1
//!   a VRL, VPL or surface VPL to a camera segment/point: e + c + 2  <= D - 1
//!   a caustic path splatted to the pinhole:              e + 1      <= D - 1
//! ```
//!
//! with `c` the camera path's events *before* the receiving segment or point and `e` the light
//! path's events *before* the virtual light's own vertex (a VRL's start, a VPL's or surface
//! VPL's vertex). Every light carries its `e` and every receiver its `c`, and each connection
//! is checked, so each method estimates the sum `volpath` computes for every `max_depth` (Russian
//! roulette changes no expectation). Unlimited depth (`-1`) is haze's hard cap
//! [`haze_scene::MAX_PATH_DEPTH`].

use haze_scene::Scene;

/// The most scattering events a path may have in `scene`: `max_depth - 1`
/// ([`haze_scene::depth_limit`] for `-1`).
#[inline]
pub fn max_events(scene: &Scene) -> u32 {
    haze_scene::depth_limit(scene.integrator.max_depth).saturating_sub(1)
}

/// True when a virtual light after `light` events may be joined to a camera receiver after
/// `camera` events: the connection adds the light's vertex and the receiver, two events.
#[inline]
pub fn connects(scene: &Scene, light: u32, camera: u32) -> bool {
    light as u64 + camera as u64 + 2 <= max_events(scene) as u64
}

/// The most events a light path may have before a virtual light that some receiver can still
/// use (the primary camera segments have `c = 0`): `max_depth - 3`, `None` when no virtual light
/// is usable at all (`max_depth` 1 or 2: emitted and direct light only).
#[inline]
pub fn light_events(max_depth: i32) -> Option<u32> {
    haze_scene::depth_limit(max_depth).saturating_sub(1).checked_sub(2)
}

//! The salts of haze's random streams, in one place: each constant is mixed into a seed or key
//! so that one use of a seed, pass, pixel or camera-segment key draws numbers independent of
//! every other use of the same key. The values are part of every image (changing one changes
//! the images whose stream it salts); a new stream takes a salt of its own, different from all
//! below.

// Samplers (`crate::rng`, `crate::sampler`).

/// [`crate::Sampler::new`]: added to its first key before it is hashed into the PCG32 state
/// (the golden-ratio increment of SplitMix64).
pub const SAMPLER_STATE: u64 = 0x9e37_79b9_7f4a_7c15;
/// [`crate::Sampler::new`]: added to the seed before it is hashed with the second key into the
/// PCG32 stream selector.
pub const SAMPLER_SEQUENCE: u64 = 0x632b_e59b_d9b4_e019;
/// A pattern sampler's per-pixel seed (`sampler/pattern.rs`): `mix64(seed ^ mix64(pixel ^ it))`.
pub const PATTERN_PIXEL: u64 = 0x5851_f42d_4c95_7f2d;
/// A pattern sampler's permutation seeds of one dimension (`sampler/pattern.rs`): the seed times
/// each, for the stratum's index and the x and y of its sub-stratum (Kensler's and Mitsuba's
/// multipliers; any odd numbers would do).
pub const PATTERN_PERMUTATIONS: [u32; 3] = [0x51633e2d, 0x68bc21eb, 0x02e5be93];
/// A pattern sampler's per-pixel Cranley-Patterson scramble of x and of y, hashed with the
/// pixel's seed (`sampler/permute.rs`, `hash2`).
pub const PATTERN_SCRAMBLE: [u64; 2] = [0x48bc_48eb, 0x98bc_51ab];

// Transmittance (`haze-render`).

/// Ratio tracking of a shadow ray through a heterogeneous medium when the caller gives no
/// sampler (`integrators/nee.rs`): the seed of a sampler keyed by the ray's bits.
pub const SHADOW_RATIO_TRACKING: u64 = 0x6865_7465_726f;

// Virtual lights (`haze-manylight`).

/// Light paths (`lighttrace.rs`): `Sampler::new(seed ^ it, path, pass)`, apart from the camera
/// paths of the same seed.
pub const LIGHT_STREAM: u64 = 0x005e_ed11_c7a1_17e5;
/// The pilot run that finds how many light paths make the requested VRL count
/// (`lighttrace.rs`, `paths_for_vrl_count`): its paths are traced with `seed ^ it`, apart from
/// the pass's own.
pub const LIGHT_PILOT: u64 = 0x9170_7000;
/// The ratio tracking of one light evaluation in a heterogeneous medium (`hetero.rs`,
/// `tracker`): `Sampler::new(it, uniforms, light salt)`, apart from every other stream.
pub const TRACK_STREAM: u64 = 0x7261_7469_6f5f_7472;

/// The caustic paths' samplers (`splat.rs`): `Sampler::new(seed ^ it, path, pass)`.
pub const CAUSTIC_PATHS: u64 = 0x5b1a_7c0f_fee0_0001;
/// Each light's own numbers at a camera segment or gathering point
/// (`integrators::light_uniforms`): `mix64(key ^ mix64(light ^ it))`, so that an exhaustive cut
/// draws exactly the brute-force sum's numbers.
pub const LIGHT_UNIFORMS: u64 = 0x1f3d_5b79_a2c4_e6f1;
/// Set in a surface VPL's index for `light_uniforms` (indices stay below it), so that surface
/// VPLs draw numbers of their own beside the VRLs or VPLs of the same index.
pub const SURFACE_VPL_INDEX: u32 = 0x8000_0000;

// Light trees and their cuts (`haze-manylight`).

/// The agglomerative builder's last step (PLOC over the groups' roots, `tree/build.rs`):
/// `seed ^ it`, apart from the groups' own merges.
pub const PLOC_ROOTS: u64 = 0x70b;
/// The trees of one pass (`integrators/lightcuts`): the medium-only tree is built with the
/// pass's tree seed, the tree of lights after a surface bounce with `seed ^ it[0]`, the surface
/// VPLs' tree with `seed ^ it[1]`.
pub const TREE_SEEDS: [u64; 2] = [1, 2];
/// The descent from one cut node to a light (`tree/stochastic.rs`):
/// `mix64(key ^ mix64(node ^ it))`.
pub const CUT_NODE_DESCENT: u64 = 0x5eed_c0de_d1ce_f00d;
/// A camera segment's cut of tree `g` (0: medium-only, 1: after a surface bounce):
/// `key ^ it * (g + 1)` (wrapping).
pub const SEGMENT_CUT: u64 = 0xa5a5_5a5a_0f0f_f0f0;
/// The further joint samples `j >= 1` of a light the stochastic cut chose (`--light-samples`):
/// `mix64(key ^ j * it)` (wrapping); sample 0 uses the segment's key.
pub const LIGHT_SAMPLES: u64 = 0x3c6e_f372_fe94_f82b;
/// A camera segment's cut of the surface VPLs' tree: `key ^ it`.
pub const SURFACE_VPL_CUT: u64 = 0x7a3c_91e5_d04b_26f8;
/// A gathering point's choice of tree (`light_uniforms(key ^ it, 0)`) and its cut of tree `g`
/// (0, 1: the VRL or VPL trees, 2: the surface VPLs'): `key ^ it * (g + 2)` (wrapping).
pub const POINT_CUT: u64 = 0x51ed_2705_a3c1_9e4d;

//! Integer hashing shared by the random streams ([`crate::rng`]) and the sample patterns
//! ([`crate::sampler`]); a leaf module so that neither depends on the other for it.

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijection on `u64` whose output bits each
/// depend on every input bit, so nearby integer keys (pixel, pass, light index) give unrelated
/// seeds.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

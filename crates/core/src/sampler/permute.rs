//! Random permutations of `0..n` evaluated one index at a time, and the integer hashes that seed
//! them.

/// Element `index` of a pseudo-random permutation of `0..n` chosen by `seed` (`index < n`,
/// `n >= 1`): Kensler's hash-based permutation ("Correlated Multi-Jittered Sampling", Pixar
/// Technical Memo 13-01, 2013, listing 3; Mitsuba 3's `permute_kensler`). Each step is a
/// bijection of the low bits under the mask `w` (odd multiplications and xor-shifts of masked
/// bits), so the hash permutes `0..=w`; cycle walking (re-hashing values `>= n`) restricts it to
/// `0..n`.
pub fn permute(index: u32, n: u32, seed: u32) -> u32 {
    debug_assert!(index < n, "permute: index {index} out of 0..{n}");
    if n <= 1 {
        return 0;
    }
    let mut w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let p = seed;
    let mut i = index;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            break;
        }
    }
    ((i as u64 + p as u64) % n as u64) as u32
}

/// A 32-bit key from two: the SplitMix64 finaliser of their concatenation (decorrelates
/// neighbouring pixels, dimensions and rounds before they seed permutations and scrambles).
#[inline]
pub fn hash2(a: u64, b: u64) -> u32 {
    (crate::hash::mix64(a ^ crate::hash::mix64(b.wrapping_add(0x9e37_79b9_7f4a_7c15))) >> 32) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_a_permutation_for_every_size_and_seed() {
        for n in [1u32, 2, 3, 4, 5, 7, 9, 16, 25, 31, 64, 100, 121, 1000, 1024] {
            for seed in [0u32, 1, 7, 0xdead_beef, u32::MAX] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = permute(i, n, seed);
                    assert!(j < n && !seen[j as usize], "n {n} seed {seed}: {i} -> {j} repeats");
                    seen[j as usize] = true;
                }
            }
        }
    }

    #[test]
    fn different_seeds_give_different_permutations() {
        let n = 64;
        let a: Vec<u32> = (0..n).map(|i| permute(i, n, 1)).collect();
        let b: Vec<u32> = (0..n).map(|i| permute(i, n, 2)).collect();
        assert_ne!(a, b);
        // Not the identity either.
        assert!(a.iter().enumerate().filter(|(i, &j)| *i as u32 == j).count() < 8);
    }

    /// Where index 0 lands is uniform over `0..n` across seeds (chi-square over the n cells).
    #[test]
    fn image_of_an_index_is_uniform_over_seeds() {
        let n = 16u32;
        let seeds = 32_000u32;
        for index in [0u32, 5, 15] {
            let mut counts = vec![0.0f64; n as usize];
            for s in 0..seeds {
                counts[permute(index, n, hash2(s as u64, 17)) as usize] += 1.0;
            }
            let expected = vec![seeds as f64 / n as f64; n as usize];
            let r = haze_testkit::chi2::chi2_test(&counts, &expected);
            assert!(r.p_value > 1e-3, "index {index}: {r:?}");
        }
    }
}

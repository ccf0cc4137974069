//! Rendering a range of passes so that the image does not depend on how the range was split
//! across threads, processes or machines.
//!
//! Pass `k` of seed `s` is fully determined by `(s, k)` (see `haze_render::progressive`), but
//! floating-point addition is not associative: summing the films of passes 0..4 as
//! `((p0 + p1) + p2) + p3` and as `(p0 + p1) + (p2 + p3)` differs in the last bits. So the
//! films of a pass range are always summed over one fixed binary tree, the **pass tree**:
//! the node `[lo, hi)` splits at `lo + P`, `P` the largest power of two below `hi - lo`. Every
//! aligned block `[first + kB, first + (k+1)B)` (`B` a power of two, clipped to the range) is
//! a node of that tree, so a worker that renders one block and sums it over its subtree
//! computes exactly the node's value, and [`merge_blocks`] then combines the nodes as a single
//! process would ([`render_passes`] over the whole range): bit for bit, whatever the block size
//! or the number of workers.

use crate::methods::Method;
pub use crate::options::PassSettings;
use anyhow::{bail, Result};
use haze_render::progressive::RenderSettings;
use haze_render::Film;
use haze_scene::Scene;
use std::ops::Range;
use std::sync::atomic::AtomicBool;

/// The film of a pass range and what rendering it reported.
pub struct PassesOutput {
    pub film: Film,
    /// Samples that came out NaN or infinite and were replaced by zero.
    pub invalid_samples: u64,
}

/// The split point of the pass-tree node `[lo, hi)` (`hi - lo >= 2`).
pub fn split(lo: u32, hi: u32) -> u32 {
    let len = hi - lo;
    debug_assert!(len >= 2);
    lo + (1u32 << (31 - (len - 1).leading_zeros()))
}

/// The pass range `passes` cut into aligned blocks of `max_block` passes rounded down to a
/// power of two (the last block may be shorter): each block is a node of the pass tree.
pub fn pass_blocks(passes: Range<u32>, max_block: u32) -> Vec<Range<u32>> {
    let b = 1u32 << (31 - max_block.max(1).leading_zeros());
    let mut out = Vec::new();
    let mut lo = passes.start;
    while lo < passes.end {
        let hi = lo.saturating_add(b).min(passes.end);
        out.push(lo..hi);
        lo = hi;
    }
    out
}

/// Sums the node `[lo, hi)` of the pass tree; `known(lo, hi)` gives a node's film when it is
/// already known (it must for single passes).
fn tree_sum(lo: u32, hi: u32, known: &mut impl FnMut(u32, u32) -> Result<Option<Film>>) -> Result<Film> {
    if let Some(film) = known(lo, hi)? {
        return Ok(film);
    }
    if hi - lo < 2 {
        bail!("pass {lo} is missing");
    }
    let mid = split(lo, hi);
    let mut left = tree_sum(lo, mid, known)?;
    let right = tree_sum(mid, hi, known)?;
    left.merge(&right);
    Ok(left)
}

/// Renders the passes `passes` with `method`, each pass into its own film, summed over the
/// pass tree. `cancel` is polled between passes (an error says the render was interrupted);
/// `on_pass` is called with each finished pass index.
pub fn render_passes(
    method: &Method,
    scene: &Scene,
    settings: &PassSettings,
    passes: Range<u32>,
    cancel: &AtomicBool,
    mut on_pass: impl FnMut(u32),
) -> Result<PassesOutput> {
    if passes.is_empty() {
        bail!("no passes to render (the pass range {passes:?} is empty)");
    }
    if settings.spp_per_pass == 0 {
        bail!("spp_per_pass must be at least 1");
    }
    let mut invalid_samples = 0;
    let film = tree_sum(passes.start, passes.end, &mut |lo, hi| {
        if hi - lo > 1 {
            return Ok(None);
        }
        let one = RenderSettings {
            spp: settings.spp_per_pass,
            time_limit: None,
            seed: settings.seed,
            spp_per_pass: settings.spp_per_pass,
            components: settings.components,
            first_pass: lo,
            sampler: settings.sampler,
        };
        let out = method.render(scene, &one, cancel, |_| {});
        if out.interrupted || out.passes != 1 {
            bail!("interrupted before pass {lo} was rendered");
        }
        invalid_samples += out.invalid_samples;
        on_pass(lo);
        Ok(Some(out.film))
    })?;
    Ok(PassesOutput { film, invalid_samples })
}

/// Combines the films of blocks of the pass range `passes` (as [`pass_blocks`] cuts it, each
/// summed over its own subtree, e.g. by [`render_passes`] in another process) into the film
/// of the whole range, bit for bit what [`render_passes`] over `passes` gives. The blocks may
/// come in any order; a missing or unaligned block is an error.
pub fn merge_blocks(passes: Range<u32>, blocks: Vec<(Range<u32>, Film)>) -> Result<Film> {
    if passes.is_empty() {
        bail!("no passes to merge (the pass range {passes:?} is empty)");
    }
    let mut slots: Vec<(Range<u32>, Option<Film>)> = blocks.into_iter().map(|(r, f)| (r, Some(f))).collect();
    if let Some((r, f)) = slots.windows(2).find_map(|w| {
        let (a, b) = (&w[0].1, &w[1].1);
        let (a, b) = (a.as_ref()?, b.as_ref()?);
        let same = a.width == b.width && a.height == b.height && a.has_components() == b.has_components();
        (!same).then(|| (w[1].0.clone(), b))
    }) {
        bail!("block {r:?} has a {}x{} film unlike the others", f.width, f.height);
    }
    let film = tree_sum(passes.start, passes.end, &mut |lo, hi| match slots
        .iter_mut()
        .find(|(r, _)| r.start == lo && r.end == hi)
    {
        Some((_, film)) => match film.take() {
            Some(f) => Ok(Some(f)),
            None => bail!("block {lo}..{hi} is used twice"),
        },
        None => Ok(None),
    })?;
    if let Some((r, _)) = slots.iter().find(|(_, f)| f.is_some()) {
        bail!("block {r:?} is not a node of the pass tree of {passes:?} (blocks must come from pass_blocks)");
    }
    Ok(film)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2x1 film whose sums are awkward floating-point numbers, different for every pass.
    fn pass_film(k: u32) -> Film {
        let data =
            (0..12).map(|i| ((k * 12 + i) as f64 * 0.731).sin() * 10f64.powi((k % 7) as i32 - 3)).collect();
        Film::from_raw(2, 1, false, data, 1).unwrap()
    }

    fn direct(passes: Range<u32>) -> Film {
        tree_sum(passes.start, passes.end, &mut |lo, hi| Ok((hi - lo == 1).then(|| pass_film(lo)))).unwrap()
    }

    #[test]
    fn split_is_at_the_largest_power_of_two_below_the_length() {
        assert_eq!(split(0, 2), 1);
        assert_eq!(split(0, 5), 4);
        assert_eq!(split(8, 16), 12);
        assert_eq!(split(4, 7), 6);
    }

    #[test]
    fn blocks_merge_to_the_single_process_sum_bit_for_bit() {
        for first in [0u32, 3] {
            for count in 1..=37u32 {
                let passes = first..first + count;
                let want = direct(passes.clone());
                for block in [1u32, 2, 3, 4, 8, 16, 64] {
                    let mut blocks: Vec<_> = pass_blocks(passes.clone(), block)
                        .into_iter()
                        .map(|r| (r.clone(), direct(r)))
                        .collect();
                    blocks.reverse();
                    let got = merge_blocks(passes.clone(), blocks).unwrap();
                    assert_eq!(got.data(), want.data(), "{passes:?} in blocks of {block}");
                    assert_eq!(got.samples, count as u64);
                }
            }
        }
        // The tree matters: a left fold over the passes gives other bits.
        let mut fold = pass_film(0);
        for k in 1..8 {
            fold.merge(&pass_film(k));
        }
        assert_ne!(fold.data(), direct(0..8).data());
    }

    #[test]
    fn missing_or_foreign_blocks_are_errors() {
        let e = merge_blocks(0..4, vec![(0..2, direct(0..2))]).err().unwrap();
        assert!(e.to_string().contains("pass 2 is missing"), "{e}");
        let e = merge_blocks(0..4, vec![(0..2, direct(0..2)), (1..3, direct(1..3)), (2..4, direct(2..4))])
            .err()
            .unwrap();
        assert!(e.to_string().contains("not a node"), "{e}");
    }
}

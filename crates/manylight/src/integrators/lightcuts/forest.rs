//! A pass's lights of one group with their light tree ([`Forest`]), and how the tree cuts build
//! it ([`TreeSettings`]).

use super::kinds::{ClusterKind, LightKind, SurfaceVpls};
use crate::tree::build::{build_agglomerative, build_median_split, BuildSettings};
use crate::tree::cone::{DirCone, LineCone};
use crate::tree::lights::LightSummary;
use crate::tree::stochastic::SampleTree;
use crate::tree::LightTree;
use crate::vpl::SurfaceVpl;
use crate::vrl::VrlMedium;
use haze_core::streams::TREE_SEEDS;

/// Which tree builder to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// The paper's three-step parallel agglomerative build.
    Agglomerative,
    /// Top-down median split (baseline).
    MedianSplit,
}

/// How a tree cut ([`super::StochasticCut`], [`super::BoundCut`]) builds its light trees.
#[derive(Clone, Copy, Debug)]
pub struct TreeSettings {
    pub builder: Builder,
    /// The agglomerative builder's settings; its `seed` is replaced by each pass's tree seed.
    pub build: BuildSettings,
}

impl Default for TreeSettings {
    fn default() -> Self {
        TreeSettings { builder: Builder::Agglomerative, build: BuildSettings::default() }
    }
}

impl TreeSettings {
    /// The light tree over `summaries` with the configured builder.
    pub fn tree(&self, summaries: &[LightSummary], seed: u64) -> LightTree {
        match self.builder {
            Builder::Agglomerative => build_agglomerative(summaries, &BuildSettings { seed, ..self.build }),
            Builder::MedianSplit => build_median_split(summaries, seed),
        }
    }

    /// `lights` with their tree and its [`SampleTree`] (every tree cut cuts gathering points
    /// stochastically); no cones (`ClusterKind::prepare` adds them for the tight bound).
    pub fn forest<K: LightKind>(&self, lights: Vec<K::Light>, media: &[VrlMedium], seed: u64) -> Forest<K> {
        let summaries: Vec<LightSummary> = {
            use rayon::prelude::*;
            lights.par_iter().map(|l| K::summary(l, media)).collect()
        };
        let tree = self.tree(&summaries, seed);
        let sample = SampleTree::new(&tree);
        Forest { lights, tree, cones: Vec::new(), dir_cones: Vec::new(), sample }
    }

    /// A pass's forests with trees: both medium groups' (`prepare` adds what the cut needs
    /// beyond the tree) and the surface VPLs', from the pass's tree seed `seed`.
    pub fn forests<K: ClusterKind>(
        &self,
        [a, b]: [Vec<K::Light>; 2],
        surface: Vec<SurfaceVpl>,
        media: &[VrlMedium],
        seed: u64,
        prepare: impl FnMut(&mut Forest<K>),
    ) -> ([Forest<K>; 2], Forest<SurfaceVpls>) {
        let mut forests =
            [self.forest::<K>(a, media, seed), self.forest::<K>(b, media, seed ^ TREE_SEEDS[0])];
        forests.iter_mut().for_each(prepare);
        (forests, self.forest::<SurfaceVpls>(surface, media, seed ^ TREE_SEEDS[1]))
    }
}

/// One group's lights (medium-only or after a surface bounce, or the surface VPLs) and, with a
/// tree cut, their tree.
pub struct Forest<K: LightKind> {
    pub lights: Vec<K::Light>,
    pub tree: LightTree,
    /// Cones of the VRLs' directions per node (`--bound tight` only; empty otherwise).
    pub cones: Vec<LineCone>,
    pub dir_cones: Vec<DirCone>,
    /// The tree laid out for the stochastic cut's descents (empty without a tree).
    pub sample: SampleTree,
}

impl<K: LightKind> Forest<K> {
    /// The lights without a tree (the exhaustive cut needs none).
    pub fn without_tree(lights: Vec<K::Light>) -> Self {
        Forest {
            lights,
            tree: LightTree::default(),
            cones: Vec::new(),
            dir_cones: Vec::new(),
            sample: SampleTree::default(),
        }
    }
}

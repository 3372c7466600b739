//! The oracle per sample, and its per-pixel view: what multisampled captures are judged against.
//!
//! A view that rasterizes per sample ([`View::with_samples`]) emits one fragment per covered
//! sample into the sample-expanded framebuffer, so the per-sample oracle is the ordinary
//! [`Oracle`] of that view: every sample's fragments in canonical order, indexed by sample index
//! `pixel * n + s`. With one sample at the centre it is today's oracle, bit for bit (the
//! multisampling suite checks it on the shared meshes).
//!
//! The per-pixel view ([`SampleOracle::per_pixel`]) is what per-pixel storage with coverage masks
//! can hold at best: each pixel's fragments merged into one node per primitive, with the mask of
//! the samples it covers and the nearest of their depth keys (the rule the masked-node schemes
//! apply when they capture). The oracle merges with its own code, from its per-sample lists, and
//! never calls the schemes' merge: a bug there cannot hide in the reference it is judged
//! against.

use std::collections::BTreeMap;

use fragsim_capture::{Capture, Identity, PixelLists};
use fragsim_capture::{MaskedLists, MaskedNode};
use fragsim_raster::{SamplePattern, View, Viewport};

use crate::Oracle;

/// A view that does not rasterize per sample, given to [`SampleOracle::build`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the per-sample oracle needs a view rasterizing per sample (View::with_samples)")]
pub struct UnsampledViewError;

/// The exact per-sample fragment lists of a view rasterizing per sample.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SampleOracle {
    pattern: SamplePattern,
    pixels: Viewport,
    oracle: Oracle,
}

impl SampleOracle {
    /// The per-sample oracle of `view`.
    ///
    /// # Errors
    /// A view that does not rasterize per sample.
    pub fn build(view: &View<'_>) -> Result<Self, UnsampledViewError> {
        view.samples().ok_or(UnsampledViewError)?;
        Ok(Self::of_view(view))
    }

    /// The per-sample oracle of `view` at its samples, or, for a view that does not rasterize
    /// per sample, at one sample at the pixel centre: then its oracle, bit for bit (what a
    /// masked-node capture at one sample is judged against).
    #[must_use]
    pub fn of_view(view: &View<'_>) -> Self {
        Self {
            pattern: view.samples().unwrap_or(SamplePattern::CENTRE),
            pixels: view.pixel_viewport(),
            oracle: Oracle::build(view),
        }
    }

    /// The sample pattern.
    #[must_use]
    pub fn pattern(&self) -> SamplePattern {
        self.pattern
    }

    /// The render target in pixels.
    #[must_use]
    pub fn pixel_viewport(&self) -> Viewport {
        self.pixels
    }

    /// The per-sample lists as an [`Oracle`] over the sample-expanded framebuffer: what any
    /// scheme run on the sampled view is diffed against.
    #[must_use]
    pub fn oracle(&self) -> &Oracle {
        &self.oracle
    }

    /// Per pixel, the fragments of all its samples: what a per-sample counting pass on a GPU
    /// (one count per covered sample) adds up.
    #[must_use]
    pub fn sample_counts(&self) -> Vec<u32> {
        let n = self.pattern.count() as usize;
        let depths = self.oracle.depth_complexity();
        depths.chunks(n).map(|pixel| pixel.iter().sum()).collect()
    }

    /// The per-pixel view: every pixel's fragments merged into one node per primitive, its mask
    /// the samples of the pixel whose lists hold the primitive, its depth key the nearest of
    /// theirs.
    #[must_use]
    pub fn per_pixel(&self) -> MaskedLists {
        nodes_per_pixel(self.oracle.lists(), self.pattern.count())
    }

    /// How a per-sample resolve (`candidate`, indexed like [`SampleOracle::oracle`]) departs
    /// from the per-sample oracle, fragments compared by primitive id in order (a masked node
    /// carries its nearest depth, not each sample's).
    ///
    /// # Panics
    /// If `candidate` covers another number of samples.
    #[must_use]
    pub fn sample_error(&self, candidate: &PixelLists) -> SampleDeviation {
        self.error_by(candidate, primitive_id)
    }

    /// [`SampleOracle::sample_error`] of a capture of any identity, from a scheme run on the
    /// sampled view: entries compared by what its words identify, primitive ids (full and
    /// primitive-only words) or depth keys (key-only words hold no primitive id, and comparing
    /// their zero low halves would call every reordering right).
    ///
    /// # Panics
    /// If `capture` covers another number of samples.
    #[must_use]
    pub fn capture_error(&self, capture: &Capture) -> SampleDeviation {
        let identify = match capture.identity {
            Identity::KeyOnly => depth_key,
            Identity::KeyAndPrim | Identity::PrimOnly | Identity::MaskedNodes(_) => primitive_id,
        };
        self.error_by(&capture.lists, identify)
    }

    /// The error of `candidate`, each entry reduced to what `identify` compares.
    fn error_by(&self, candidate: &PixelLists, identify: fn(u64) -> u32) -> SampleDeviation {
        assert_eq!(
            candidate.pixels(),
            self.oracle.pixels(),
            "sample counts differ"
        );
        let mut error = SampleDeviation::default();
        for sample in 0..candidate.pixels() {
            let (want, got) = (self.oracle.pixel(sample), candidate.pixel(sample));
            error.fragments += want.len() as u64;
            error.lost += want.len().saturating_sub(got.len()) as u64;
            let ids = |list: &[u64]| list.iter().map(|&e| identify(e)).collect::<Vec<_>>();
            if ids(want) != ids(got) {
                error.wrong_samples += 1;
                if want.len() == got.len() {
                    error.misordered_samples += 1;
                }
            }
        }
        error.samples = candidate.pixels() as u64;
        error
    }
}

/// The primitive id of a packed entry (its low half).
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry's low half is its primitive id"
)]
fn primitive_id(entry: u64) -> u32 {
    entry as u32
}

/// The depth key of a packed entry (its high half).
fn depth_key(entry: u64) -> u32 {
    (entry >> 32) as u32
}

/// What a per-sample resolve lost or misordered, against the per-sample oracle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleDeviation {
    /// Samples compared.
    pub samples: u64,
    /// Sample fragments in the oracle.
    pub fragments: u64,
    /// Sample fragments missing from the resolve (storage overflow).
    pub lost: u64,
    /// Samples whose list of primitives differs from the oracle's in any way.
    pub wrong_samples: u64,
    /// Of those, samples with every fragment present but in another order.
    pub misordered_samples: u64,
}

/// The per-pixel view of per-sample lists (`samples` a pixel, indexed `pixel * samples + s`):
/// every pixel's fragments merged into one node per primitive, its mask the samples of the
/// pixel whose lists hold the primitive, its depth key the nearest of theirs.
#[must_use]
pub(crate) fn nodes_per_pixel(lists: &PixelLists, samples: u32) -> MaskedLists {
    let n = samples as usize;
    let pixels = lists.pixels() / n;
    let mut nodes: Vec<(u32, MaskedNode)> = Vec::new();
    let mut by_prim: BTreeMap<u32, MaskedNode> = BTreeMap::new();
    for pixel in 0..pixels {
        by_prim.clear();
        for sample in 0..samples {
            for &packed in lists.pixel(pixel * n + sample as usize) {
                let (depth_key, prim) = (depth_key(packed), primitive_id(packed));
                let node = by_prim.entry(prim).or_insert(MaskedNode {
                    depth_key,
                    prim,
                    mask: 0,
                });
                node.mask |= 1 << sample;
                node.depth_key = node.depth_key.min(depth_key);
            }
        }
        #[expect(
            clippy::cast_possible_truncation,
            reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
        )]
        nodes.extend(by_prim.values().map(|&node| (pixel as u32, node)));
    }
    MaskedLists::from_nodes(samples, pixels, nodes)
}

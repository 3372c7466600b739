//! The serial oracle: every fragment of every pixel in canonical order, and the per-pixel diff
//! that says where a scheme's capture departs from it.
//!
//! The oracle's references share nothing with the schemes but the rasterizer: [`Oracle::build`]
//! counts each pixel's fragments (the depth complexity), allocates one flat array by the prefix
//! sum of the counts, fills it in submission order and sorts each pixel's list by `(depth key,
//! primitive id)` with the standard library's sort; the per-sample oracle's per-pixel view is
//! merged by this crate's own code ([`samples`]), not by the masked-node schemes' merge. From the
//! capture crate it takes the types captures and promises are held in; dumps it takes decoded
//! and their words checked from the format's crate (`fragsim_dump`, which decodes them with the
//! catalog's layouts and each scheme's post pass) and judges them ([`verdict::JudgeDump`]).
//! `fragsim_dump::Dump::record` runs fragsim's own scheme serially to write the dump fragsim
//! would write as a backend: a candidate, never the oracle's reference.
//!
//! ```
//! use fragsim_oracle::Oracle;
//! use fragsim_raster::{OrbitCamera, Scene, Viewport};
//! let scene = Scene::procedural("spheres:3").unwrap();
//! let view = scene.view(Viewport::new(32, 32).unwrap(), &OrbitCamera::default()).unwrap();
//! let oracle = Oracle::build(&view);
//! assert_eq!(oracle.max_depth_complexity(), 6);
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod compare;
mod diff;
pub mod edge_ties;
pub mod memory_cap;
pub mod precision;
pub mod samples;
pub mod verdict;

pub use diff::{Diff, PixelMismatch};

use fragsim_capture::{Capture, Identity, PixelLists};
use fragsim_raster::{Fragment, View};

/// How the oracle orders (or merges) fragments of one pixel at one depth key: the tie policies
/// that shipping GPU code differs on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Ties {
    /// Order ties by primitive id: fragsim's canonical order, compared fragment for fragment.
    #[default]
    ByPrimitive,
    /// Keep every fragment at an equal depth, in no particular order among themselves (FreePipe's
    /// MDTS on 32-bit keys): compared by depth key, duplicates counted.
    KeepDuplicates,
    /// Merge fragments at an equal depth into one (nvpro-samples' loop32, 32-bit depth peeling):
    /// compared by distinct depth key.
    MergeEqualDepths,
}

impl Ties {
    /// The mask that keeps what this policy compares of a packed entry, for a capture of
    /// `identity`.
    pub(crate) fn mask(self, identity: Identity) -> u64 {
        match (self, identity) {
            (_, Identity::PrimOnly) => u64::from(u32::MAX),
            (Self::ByPrimitive, Identity::KeyAndPrim | Identity::MaskedNodes(_)) => u64::MAX,
            _ => u64::MAX << 32,
        }
    }

    /// `list` (canonical order) as this policy expects it, masked by `mask`: appended to `out`.
    pub(crate) fn expected(self, list: &[u64], mask: u64, out: &mut Vec<u64>) {
        let start = out.len();
        out.extend(list.iter().map(|e| e & mask));
        if self == Self::MergeEqualDepths {
            let mut kept = start;
            for i in start..out.len() {
                if i == start || out[i] != out[kept - 1] {
                    out[kept] = out[i];
                    kept += 1;
                }
            }
            out.truncate(kept);
        }
    }
}

/// The exact per-pixel fragment lists of a view.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Oracle {
    /// Every pixel's fragments in canonical order: the same type a capture's lists have.
    lists: PixelLists,
}

impl Oracle {
    /// Rasterizes `view` twice (count, then fill) and sorts every pixel's list.
    #[must_use]
    pub fn build(view: &View<'_>) -> Self {
        Self::from_stream(view.viewport().pixels(), |emit| {
            for prim in 0..view.triangle_count() {
                view.rasterize(prim, &mut |f| emit(f));
            }
        })
    }

    /// The oracle of a hand-written fragment stream over `pixels` pixels (every fragment's pixel
    /// must be below `pixels`): what the property suites check schemes against.
    #[must_use]
    pub fn from_fragments(pixels: usize, fragments: &[Fragment]) -> Self {
        Self::from_stream(pixels, |emit| fragments.iter().for_each(|&f| emit(f)))
    }

    /// Runs `stream` twice (count, then fill) and sorts every pixel's list.
    fn from_stream(pixels: usize, stream: impl Fn(&mut dyn FnMut(Fragment))) -> Self {
        let mut counts = vec![0_usize; pixels];
        stream(&mut |f| counts[f.pixel as usize] += 1);
        let mut offsets = Vec::with_capacity(pixels + 1);
        offsets.push(0);
        for &c in &counts {
            offsets.push(offsets[offsets.len() - 1] + c);
        }
        let mut next = offsets[..pixels].to_vec();
        let mut entries = vec![0_u64; offsets[pixels]];
        stream(&mut |f| {
            let p = f.pixel as usize;
            entries[next[p]] = f.packed();
            next[p] += 1;
        });
        let mut lists = PixelLists { offsets, entries };
        lists.sort_each_pixel();
        Self { lists }
    }

    /// An oracle whose per-pixel lists are a capture's (each sorted to canonical order): a dump
    /// used as the reference of a comparison.
    #[must_use]
    pub fn from_capture(capture: &Capture) -> Self {
        let mut lists = capture.lists.clone();
        lists.sort_each_pixel();
        Self { lists }
    }

    /// Every pixel's fragments in canonical order.
    #[must_use]
    pub fn lists(&self) -> &PixelLists {
        &self.lists
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.lists.pixels()
    }

    /// Pixel `p`'s fragments, packed `key << 32 | prim`, in canonical order.
    #[must_use]
    pub fn pixel(&self, p: usize) -> &[u64] {
        self.lists.pixel(p)
    }

    /// Total fragments.
    #[must_use]
    pub fn fragments(&self) -> usize {
        self.lists.entries.len()
    }

    /// Per-pixel depth complexity (fragment count).
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a pixel holds at most one fragment per triangle, and triangle ids are u32"
    )]
    pub fn depth_complexity(&self) -> Vec<u32> {
        self.lists.lengths().map(|n| n as u32).collect()
    }

    /// The largest depth complexity of any pixel.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a pixel holds at most one fragment per triangle, and triangle ids are u32"
    )]
    pub fn max_depth_complexity(&self) -> u32 {
        self.lists.lengths().max().unwrap_or(0) as u32
    }

    /// Pixel `p`'s list as `ties` expects it: canonical (`ByPrimitive`), depth keys only with
    /// duplicates (`KeepDuplicates`), or distinct depth keys (`MergeEqualDepths`); keys are
    /// packed `key << 32`.
    #[must_use]
    pub fn expected(&self, p: usize, ties: Ties) -> Vec<u64> {
        let mut out = Vec::new();
        ties.expected(self.pixel(p), ties.mask(Identity::KeyAndPrim), &mut out);
        out
    }
}

//! The counting pass: the first geometry pass of every scheme whose storage is sized to the scene.
//!
//! **Algorithm.** One `u32` counter per pixel, initially 0; every fragment does
//! `atomicAdd(&count[p], 1)` (one step) and is done. The post pass reads each counter back: the
//! pixel's depth complexity. This is what an exact-storage A-buffer runs before its capture pass
//! (a count, a prefix sum of the counts into offsets, then the fill), and what sizes MDTS's `K` to
//! the scene (`--k auto`), adaptive bucket peeling's slots and the layer records of the multi-pass
//! schemes.
//!
//! **Guarantee.** Fetch-and-add loses no increment under any interleaving: each counter ends at
//! its pixel's exact fragment count. A scheme sized by this pass reports it: one more geometry
//! pass, its time and its counters (`Run::after_count_pass`).
//!
//! The counts come from the scheme's own pass over the scene, never from the oracle: the oracle
//! is what the result is checked against, and a scheme that read it would be sized by the answer.
//!
//! ```
//! use fragsim_capture::{depth_count::{DepthCount, DepthCounts}, executors};
//! use fragsim_raster::{OrbitCamera, Scene, Viewport};
//! let scene = Scene::procedural("spheres:3").unwrap();
//! let view = scene.view(Viewport::new(32, 32).unwrap(), &OrbitCamera::default()).unwrap();
//! let counts = DepthCounts::from_run(executors::run_serial(&view, &DepthCount::new(view.viewport())));
//! assert_eq!(counts.max(), 6);
//! ```

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::capture::{Capacity, Identity};
use crate::executors::Run;
use crate::guarantee::Guarantee;
use crate::scheme::{Descriptor, Promise, Scheme, Step};

/// The counting pass as a scheme: its capture holds one entry per pixel, the pixel's count.
#[derive(Clone, Debug)]
pub struct DepthCount {
    descriptor: Descriptor,
}

impl DepthCount {
    /// A counter for every pixel of `viewport`.
    #[must_use]
    pub fn new(viewport: Viewport) -> Self {
        Self {
            descriptor: Descriptor {
                name: "count".into(),
                layout: Layout::counters_and_slots(viewport.pixels(), 0),
                identity: Identity::KeyAndPrim,
                guarantee: Guarantee::Exact,
                promise: Promise::All(Capacity::Unbounded),
                pixels: viewport.pixels(),
                counts_every_drop: false,
            },
        }
    }
}

impl Scheme for DepthCount {
    /// The pixel whose counter the fragment increments.
    type State = u32;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> u32 {
        fragment.pixel
    }

    fn step<M: Memory>(&self, pixel: &mut u32, memory: &M) -> Step {
        WordMemory::<u32>::fetch_add(memory, *pixel as usize, 1);
        Step::Stored
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        out.push(u64::from(WordMemory::<u32>::load(memory, pixel)));
        0
    }
}

/// What a counting pass found, and what it cost.
#[derive(Clone, Debug)]
pub struct DepthCounts {
    /// Per pixel, its fragment count.
    pub counts: Vec<u32>,
    /// The pass's run (its capture emptied: the counts are above).
    pub run: Run,
}

impl DepthCounts {
    /// The counts of a finished run of [`DepthCount`].
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "each entry counts one pixel's fragments, at most one per triangle, and triangle ids are u32"
    )]
    pub fn from_run(mut run: Run) -> Self {
        let counts = run.capture.entries.iter().map(|&c| c as u32).collect();
        run.capture.entries = Vec::new();
        run.capture.offsets = Vec::new();
        Self { counts, run }
    }

    /// The largest count: the scene's maximum depth complexity.
    #[must_use]
    pub fn max(&self) -> u32 {
        self.counts.iter().copied().max().unwrap_or(0)
    }

    /// The sum of the counts: the scene's fragments.
    #[must_use]
    pub fn total(&self) -> usize {
        self.counts.iter().map(|&c| c as usize).sum()
    }
}

//! The `Scheme` trait: a per-fragment state machine doing one memory operation per step.

use std::fmt::Debug;

use fragsim_memory::{Layout, Memory};

use crate::capture::{Capacity, Capture, Identity, Keeps};
use crate::guarantee::Guarantee;
use crate::walk_input::WalkInput;

/// Default cap on the per-pixel storage a scheme may allocate: 4 GiB.
pub const MEMORY_CAP_DEFAULT: u64 = 4 << 30;

/// What a step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The fragment needs more steps.
    Continue,
    /// The fragment (or the value it carried) is stored; its walk is over.
    Stored,
    /// A value was dropped for lack of storage (counted, never hidden); the walk is over.
    Dropped,
    /// The fragment was rejected by the scheme's own test, by design (a depth-peeling pass
    /// ignores fragments that are not in its layer); the walk is over.
    Discarded,
}

/// Which of a pixel's fragments a scheme promises to keep (see [`Keeps`], which adds the
/// per-pixel overflow counts read back by the post pass).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Promise {
    /// The `K` nearest in canonical order.
    Nearest(u32),
    /// The `K` farthest.
    Farthest(u32),
    /// Every fragment that fits the storage; what overflows it is counted by the scheme and
    /// checked against what the capacity predicts.
    All(Capacity),
}

/// A run of pixels the post pass treats alike ([`Scheme::pixel_run`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelRun {
    /// This many pixels hold empty lists and overflowed nothing: skipped.
    Empty(usize),
    /// This many pixels are to be resolved one by one ([`Scheme::resolve_pixel`]).
    Resolve(usize),
}

impl PixelRun {
    /// The run of `words_per_pixel` words a pixel from `pixel`'s first word on, before `end`:
    /// empty where the pixels' first words lie in a run of untouched words, else to resolve
    /// while their first words lie in the run of written blocks (at least `pixel` itself).
    pub fn of_first_words<W: fragsim_memory::Word, A: fragsim_memory::WordMemory<W>>(
        words: &A,
        pixel: usize,
        end: usize,
        words_per_pixel: usize,
    ) -> Self {
        let (first, last) = (pixel * words_per_pixel, end * words_per_pixel);
        // The pixels whose first word lies in a run of `n` words from `first`.
        let pixels = |n: usize| n.div_ceil(words_per_pixel);
        match words.untouched_run(first, last) {
            0 => Self::Resolve(pixels(words.written_run(first, last)).max(1)),
            untouched => Self::Empty(pixels(untouched)),
        }
    }
}

/// Where a walk stands for a SIMT scheduler ([`Scheme::simt`], read by the scheduled executor): all `false` for a scheme
/// without locks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Simt {
    /// The walk's last step failed to take a lock and its next step retries it: no progress.
    pub spinning: bool,
    /// The walk stands at a reconvergence point (the exit of a loop, the end of a divergent
    /// branch): under [`Policy::Lockstep`](crate::executors::scheduled::Policy::Lockstep) its next step runs only once every other active lane of
    /// its warp stands at one too.
    pub reconverging: bool,
}

/// Why a scheme could not be set up.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CaptureError {
    /// A scheme parameter is out of range (K = 0, say).
    #[error("{0}")]
    BadParameter(String),
    /// The storage would exceed the memory cap: its tables and page tables, allocated before
    /// any fragment ([`Layout::least_bytes`]), or the pages of words a frame's writes reached.
    #[error(
        "{scheme} would need {needed} bytes of per-pixel storage, more than the cap of {cap} bytes"
    )]
    TooMuchMemory {
        /// The scheme.
        scheme: String,
        /// Bytes it would need.
        needed: u64,
        /// The cap.
        cap: u64,
    },
    /// A view other than the one the scheme was built for: another number of pixels, or
    /// another sample count (a per-sample scheme needs a view rasterizing per sample at its
    /// count).
    #[error(
        "{scheme} was built for {pixels} pixels at {samples} samples, the view is {view_pixels} \
         pixels at {view_samples} samples"
    )]
    OtherView {
        /// The scheme.
        scheme: String,
        /// The pixels it was built for.
        pixels: usize,
        /// The samples a pixel it was built for.
        samples: u32,
        /// The view's pixels.
        view_pixels: usize,
        /// The view's samples a pixel (1 for a view that does not rasterize per sample).
        view_samples: u32,
    },
}

/// What a scheme is, as the rest of the simulator sees it: written once, by the scheme's
/// constructor ([`Descriptor::within`] checks it against the memory cap there), and read through
/// [`Scheme::descriptor`] by the trait's accessors ([`Scheme::name`], [`Scheme::layout`], ...).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Descriptor {
    /// A short name, e.g. `mdts` or `abuffer`: the catalog's spelling.
    pub name: String,
    /// The storage the scheme needs.
    pub layout: Layout,
    /// What the captured words identify.
    pub identity: Identity,
    /// What the scheme guarantees against the oracle (each module's header says why).
    pub guarantee: Guarantee,
    /// Which fragments the scheme promises to keep.
    pub promise: Promise,
    /// Number of pixels the scheme's storage covers.
    pub pixels: usize,
    /// Whether every fragment a one-pass frame does not keep ends some walk as
    /// [`Step::Dropped`] ([`Scheme::counts_every_drop`]).
    pub counts_every_drop: bool,
}

impl Descriptor {
    /// The descriptor, once what its layout allocates before any fragment
    /// ([`Layout::least_bytes`]: its tables and page tables) fits `memory_cap` bytes. The pages
    /// of words are allocated as writes reach them, and checked against the cap then: a frame
    /// whose pages exceed it is reported over the cap (`RunStats::over_cap`), never returned as
    /// a result.
    ///
    /// # Errors
    /// [`CaptureError::TooMuchMemory`], under the descriptor's name.
    pub fn within(self, memory_cap: u64) -> Result<Self, CaptureError> {
        let needed = self.layout.least_bytes();
        if needed > memory_cap {
            return Err(CaptureError::TooMuchMemory {
                scheme: self.name,
                needed,
                cap: memory_cap,
            });
        }
        Ok(self)
    }
}

/// A capture scheme: how a fragment walks per-pixel memory, and how the memory is read back.
///
/// Contract: [`Scheme::step`] performs **exactly one** indivisible operation on `memory` per call:
/// one atomic or plain word operation, the granularity at which GPU atomics are atomic, or one
/// operation the hardware makes indivisible on a whole pixel (the k-buffer's render-target read
/// and write-back, each a step under the pixel's lock). Executors may interleave steps of
/// different fragments arbitrarily and get every behaviour the GPU could show.
pub trait Scheme: Sync {
    /// A fragment's progress between steps.
    type State: Send + Clone + Debug;

    /// What a walk starts from: the rasterizer's [`Fragment`](fragsim_raster::Fragment), or for a scheme whose walks start
    /// from something gathered from a triangle's fragments (a masked node), that
    /// ([`WalkInput`]).
    type Input: WalkInput;

    /// What the scheme is: its name, storage, identity, guarantee, promise and pixels, built
    /// once by its constructor. The accessors below read it.
    fn descriptor(&self) -> &Descriptor;

    /// A short name, e.g. `mdts` or `abuffer` ([`Descriptor::name`]).
    fn name(&self) -> String {
        self.descriptor().name.clone()
    }

    /// The storage the scheme needs ([`Descriptor::layout`]).
    fn layout(&self) -> Layout {
        self.descriptor().layout
    }

    /// What the captured words identify ([`Descriptor::identity`]).
    fn identity(&self) -> Identity {
        self.descriptor().identity
    }

    /// Which fragments the scheme promises to keep ([`Descriptor::promise`]).
    fn promise(&self) -> Promise {
        self.descriptor().promise
    }

    /// What the scheme guarantees against the oracle ([`Descriptor::guarantee`]).
    fn guarantee(&self) -> Guarantee {
        self.descriptor().guarantee
    }

    /// Whether every fragment a one-pass frame does not keep ends some walk as [`Step::Dropped`]
    /// (MDTS carries each evicted value to the end of its slots, the A-buffer and the layer
    /// counter drop past their storage, the k-buffer drops what falls off its K slots), so that
    /// the frame's counted drops equal what its capture lacks ([`Descriptor::counts_every_drop`]).
    /// Schemes that lose values with no walk to count them say no: a z-buffer's `atomicMin`
    /// overwrites the farther value, a linked list's resolve stops after its `K` nodes.
    fn counts_every_drop(&self) -> bool {
        self.descriptor().counts_every_drop
    }

    /// Number of pixels the scheme's storage covers ([`Descriptor::pixels`]).
    fn pixels(&self) -> usize {
        self.descriptor().pixels
    }

    /// Whether the scheme's frame is one geometry pass with no between-pass kernel (the default
    /// [`Scheme::end_pass`]) and its words are addressed by the pixel's index alone: a
    /// fragment's walk and a pixel's resolve use `Fragment::pixel` and `pixel` only to find the
    /// pixel's own words, the same number for every pixel, and no table or other pixel's words
    /// are involved. An executor may then number the pixels in an order of its own and resolve
    /// a group of pixels as soon as their fragments are in: the tiled executor numbers them
    /// tile by tile, so that a tile's words are contiguous, and resolves each tile in its own
    /// task (`executors/tiled/storage.rs`). `false`, the default, is always correct.
    fn tile_local(&self) -> bool {
        false
    }

    /// A fresh gathering of the rasterizer's fragments into this scheme's walk inputs, one per
    /// thread that rasterizes ([`WalkInput::gather`]); the default holds nothing.
    fn gathering(&self) -> <Self::Input as WalkInput>::Gathering {
        Default::default()
    }

    /// The state of a fragment before its first step in the first geometry pass.
    fn begin(&self, fragment: Self::Input) -> Self::State;

    /// The state of a fragment before its first step in geometry pass `pass` (from 0), or `None`
    /// when the pass ignores fragments. One-pass schemes need not override it.
    fn begin_pass(&self, pass: u32, fragment: Self::Input) -> Option<Self::State> {
        (pass == 0).then(|| self.begin(fragment))
    }

    /// One memory operation of the fragment's walk.
    fn step<M: Memory>(&self, state: &mut Self::State, memory: &M) -> Step;

    /// Loads the words that the fragment's walk of the first geometry pass begins with, ahead
    /// of the walk ([`fragsim_memory::WordMemory::prefetch`]): an executor that rasterizes a run of fragments
    /// before walking them calls it as each is rasterized, so that their cache misses overlap.
    /// No step and no memory operation of the GPU; schemes that do not override it load
    /// nothing ahead.
    fn prefetch<M: Memory>(&self, fragment: Self::Input, memory: &M) {
        let _ = (fragment, memory);
    }

    /// Where the walk stands for a SIMT scheduler (a spin on a lock, a reconvergence point): what
    /// the scheduled executor's lockstep policy and deadlock detection read. Schemes without
    /// locks need not override it.
    fn simt(&self, state: &Self::State) -> Simt {
        let _ = state;
        Simt::default()
    }

    /// Work between geometry passes, after pass `pass` (a per-pixel kernel on the GPU); returns
    /// whether another geometry pass is needed. One-pass schemes need not override it.
    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let _ = (pass, memory);
        false
    }

    /// The post pass for one pixel, after every pass is done: appends the pixel's list in
    /// canonical order to `out` and returns how many of its fragments overflowed storage.
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32;

    /// The run of pixels from `pixel` on, before `end`, that the post pass may treat alike,
    /// found in bulk from the memory's written flags ([`WordMemory::untouched_run`],
    /// [`WordMemory::written_run`]) without reading their words: pixels whose lists are empty
    /// and nothing overflowed for certain, skipped; or pixels to resolve one by one before
    /// asking again. [`PixelRun::Resolve`] of every pixel up to `end`, the default, is always
    /// correct.
    ///
    /// [`WordMemory::untouched_run`]: fragsim_memory::WordMemory::untouched_run
    /// [`WordMemory::written_run`]: fragsim_memory::WordMemory::written_run
    fn pixel_run<M: Memory>(&self, memory: &M, pixel: usize, end: usize) -> PixelRun {
        let _ = memory;
        PixelRun::Resolve(end - pixel)
    }

    /// The post pass over every pixel, serially (`crate::post_pass`: the empty parts of the frame
    /// skipped in bulk, [`Scheme::pixel_run`]).
    fn resolve<M: Memory>(&self, memory: &M) -> Capture {
        crate::post_pass::resolve_serial(self, memory)
    }

    /// The promise with the per-pixel overflow counts filled in.
    fn keeps(&self, overflow: Vec<u32>) -> Keeps {
        match self.promise() {
            Promise::Nearest(k) => Keeps::Nearest(k),
            Promise::Farthest(k) => Keeps::Farthest(k),
            Promise::All(capacity) => Keeps::All { capacity, overflow },
        }
    }

    /// Runs one fragment's walk to the end on `memory`, counting the steps into `steps`.
    fn insert<M: Memory>(&self, fragment: Self::Input, memory: &M, steps: &mut u64) -> Step {
        self.insert_state(self.begin(fragment), memory, steps)
    }

    /// Runs a walk from `state` to the end on `memory`, counting the steps into `steps`.
    fn insert_state<M: Memory>(&self, mut state: Self::State, memory: &M, steps: &mut u64) -> Step {
        walk_to_end(steps, || self.step(&mut state, memory))
    }
}

/// Runs `step` until it ends the walk, counting each step into `steps`: a walk's loop, for
/// [`Scheme::insert_state`] and the schemes that run it on a span of memory.
#[inline]
pub fn walk_to_end(steps: &mut u64, mut step: impl FnMut() -> Step) -> Step {
    loop {
        *steps += 1;
        match step() {
            Step::Continue => {}
            done => return done,
        }
    }
}

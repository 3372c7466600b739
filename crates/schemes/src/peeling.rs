//! Classical depth peeling (DP): Everitt 2001, "Interactive order-independent transparency"
//! (after Mammen 1989), the baseline of FreePipe's Table 3 and bucket depth peeling's Table 2.
//!
//! **Algorithm.** One geometry pass per layer. Pass 0 is an ordinary z-buffer pass: each fragment
//! does `atomicMin(&cur, value)`. Pass `i ≥ 1` first reads the previous layer's word
//! (`load(&prev)`: the paper's second depth test, done there with a shadow-map comparison) and
//! drops the fragment unless it is strictly farther (`value > prev`); a survivor then does
//! `atomicMin(&cur, value)`: two steps, one memory operation each. Between passes a per-pixel
//! kernel ([`Scheme::end_pass`]) appends each pixel's `cur` to its layer list, copies it into
//! `prev` (the GPU swaps the two depth buffers) and resets `cur`. The pass that captures nothing
//! at any pixel ends the loop (Everitt's occlusion query returning 0). A walk ends `Stored` when
//! its `atomicMin` lowered the word (it passed the depth test then; a nearer fragment may still
//! displace it) and `Discarded` when it failed the peel test or the depth test.
//!
//! **Guarantee.** Pass `i` captures, at every pixel, the smallest value strictly above layer
//! `i − 1`: the `(i+1)`-th value in ascending order. Per-location atomicity of `atomicMin` is all
//! this needs, so it holds under any interleaving (`tests/suite/peeling.rs` runs the serial, parallel and
//! scheduled executors). What the value is decides what is exact:
//! - `DepthPeeling<u64>` (default): `depth_key << 32 | prim`. Every fragment is distinct, so every
//!   fragment is one layer: exact, fragment for fragment ([`Promise::All`](fragsim_capture::Promise::All)).
//! - `DepthPeeling<u32>`: the depth key alone, as the classical algorithm. Fragments of one pixel
//!   with **equal depths merge**: the pass keeps one key for all of them, and the next pass's
//!   strict test peels them all away together. The capture holds each distinct depth once;
//!   [`Identity::KeyOnly`](fragsim_capture::Identity::KeyOnly) keeps the promise of every fragment, so the oracle's diff reports the
//!   merged duplicates as lost, which is the truth about this variant.
//!
//! **Passes.** `L + 1` geometry passes, where `L` is the largest number of layers at any pixel:
//! the depth complexity for `u64` words, the number of distinct depths for `u32` words. This is
//! the papers' accounting: both tables list 13 DP passes for the Dragon, 12 layers and the pass
//! that finds nothing.
//!
//! **Memory per pixel.** Two working words (`prev`, `cur`), `max_layers` output slots, and a
//! `u32` layer-overflow counter: `(2 + max_layers) · 8 + 4` bytes with `u64` words,
//! `(2 + max_layers) · 4 + 4` with `u32`. Layers beyond `max_layers` are counted as overflow in
//! memory and reported by the post pass, never written out of bounds; peeling goes on to the end so
//! that the count is exact.
//!
//! Unlike the GPU, which blends each layer into a colour accumulator as it is peeled and so needs
//! only the two depth buffers (FreePipe §5.2: 2 MB at 512 × 512), the model keeps every layer so
//! that the capture can be compared with the oracle; the output slots are that price. Unlike the
//! paper, which decides "strictly farther" by a float depth comparison against a texture, the test
//! compares the words themselves, so with `u64` words fragments of equal depth are peeled one by
//! one in primitive order.

use fragsim_memory::{Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::{depth_test, LayerStorage, MdtsWord};
use fragsim_capture::{CaptureError, Descriptor, Scheme, Step, MEMORY_CAP_DEFAULT};

/// Classical depth peeling over words of type `W` (default `u64`: exact fragment for fragment;
/// `u32`: depth keys, equal depths merge).
#[derive(Clone, Debug)]
pub struct DepthPeeling<W: MdtsWord = u64> {
    storage: LayerStorage<W>,
}

/// Working word: the layer the previous pass peeled.
const PREV: usize = 0;
/// Working word: the layer this pass is peeling.
const CUR: usize = 1;

/// A fragment's walk in one peeling pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Peel<W> {
    /// The pixel's first working word.
    pub base: usize,
    /// The fragment's word.
    pub value: W,
    /// The next step.
    pub phase: PeelPhase,
}

/// The two steps of a peeling pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeelPhase {
    /// `load` the previous layer; the fragment goes on only if strictly farther.
    Test,
    /// `atomicMin` on the layer being peeled.
    Compete,
}

impl<W: MdtsWord> DepthPeeling<W> {
    /// Depth peeling with storage for `max_layers` layers per pixel (pass the scene's maximum depth
    /// complexity to keep everything), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `max_layers == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, max_layers: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        Ok(Self {
            storage: LayerStorage::new("peeling", viewport, 2, max_layers, memory_cap)?,
        })
    }

    /// Like [`DepthPeeling::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`DepthPeeling::new`].
    pub fn with_layers(viewport: Viewport, max_layers: u32) -> Result<Self, CaptureError> {
        Self::new(viewport, max_layers, MEMORY_CAP_DEFAULT)
    }

    /// Output slots per pixel.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the layers are the u32 max_layers the storage was built with"
    )]
    pub fn max_layers(&self) -> u32 {
        self.storage.layers() as u32
    }
}

impl<W: MdtsWord> Scheme for DepthPeeling<W> {
    type State = Peel<W>;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        self.storage.descriptor()
    }

    fn begin(&self, fragment: Fragment) -> Peel<W> {
        Peel {
            base: self.storage.working(fragment.pixel as usize),
            value: W::encode(fragment),
            phase: PeelPhase::Compete,
        }
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Peel<W>> {
        let mut peel = self.begin(fragment);
        // Pass 0 has no previous layer: it is a plain z-buffer pass.
        if pass > 0 {
            peel.phase = PeelPhase::Test;
        }
        Some(peel)
    }

    fn step<M: Memory>(&self, peel: &mut Peel<W>, memory: &M) -> Step {
        let words = W::words(memory);
        match peel.phase {
            PeelPhase::Test => {
                if peel.value > words.load(peel.base + PREV) {
                    peel.phase = PeelPhase::Compete;
                    Step::Continue
                } else {
                    Step::Discarded
                }
            }
            // The depth test: a fragment that does not lower the word fails it, as on the GPU.
            PeelPhase::Compete => {
                depth_test(words.fetch_min(peel.base + CUR, peel.value), peel.value)
            }
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let words = W::words(memory);
        let layers = self.storage.layers();
        let mut captured = false;
        for pixel in 0..self.storage.pixels() {
            let base = self.storage.working(pixel);
            let layer = words.load(base + CUR);
            // An empty pixel keeps its `prev`, so no later pass lets anything through there.
            if layer == W::MAX {
                continue;
            }
            captured = true;
            words.store(base + PREV, layer);
            words.store(base + CUR, W::MAX);
            let slot = pass as usize;
            self.storage
                .put(memory, pixel, (slot < layers).then_some(slot), layer);
        }
        captured
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        self.storage.resolve(memory, pixel, out)
    }
}

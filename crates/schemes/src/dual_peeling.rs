//! Dual depth peeling (DDP): Bavoil & Myers 2008, "Order Independent Transparency with Dual Depth
//! Peeling" (NVIDIA), the baseline "DDP" / "Dual DP" of FreePipe's Table 3 and bucket depth
//! peeling's Table 2.
//!
//! **Algorithm.** Each pass peels the nearest and the farthest remaining layer of every pixel at
//! once. The GPU keeps `(−near, far)` in an RG32F target with MAX blending, cleared to
//! `(−MAX, −MAX)`, and ping-pongs two of them. Here a pixel has a `near` and a `far` word for the
//! pass being peeled and a copy of both from the previous pass. Pass 0 (the paper's
//! initialisation pass) does `atomicMin(&near, value)` then `atomicMin(&far, !value)`. Pass
//! `i ≥ 1` first reads the previous bounds (`load(&prev_near)`, `load(&prev_far)`) and drops the
//! fragment unless `prev_near < value < prev_far`, strictly (the paper's shader: a fragment equal
//! to a bound is on a layer peeled last pass, one outside has been peeled before); a survivor does
//! the two `atomicMin`s. Four steps, one memory operation each. Between passes a per-pixel kernel
//! ([`Scheme::end_pass`]) appends `near` to the front of the pixel's list and `far`, where it
//! differs, to the back, copies both into the previous bounds and resets them. The pass that
//! captures nothing at any pixel ends the loop. A walk ends `Stored` when one of its `atomicMin`s
//! lowered its word, `Discarded` otherwise.
//!
//! The far word holds the complement `!value`, so that `atomicMin` on it keeps the largest value:
//! the GPU negates `near` so that one blend equation (MAX) and one clear value serve both
//! channels; the complement lets one atomic (MIN) and one initial value (all ones) serve both
//! words. A single `atomicMax` on a packed pair would not do: a 64-bit maximum is lexicographic,
//! not the per-channel maximum the blender computes.
//!
//! **Guarantee.** After pass `i` the bounds are the `(i+1)`-th smallest and the `(i+1)`-th largest
//! value of the pixel, so the front list grows ascending from the nearest and the back list
//! descending from the farthest until they meet; per-location atomicity of `atomicMin` suffices,
//! under any interleaving. With `DualDepthPeeling<u64>` (default, `depth_key << 32 | prim`) every
//! fragment is a distinct value: exact, fragment for fragment ([`Promise::All`](fragsim_capture::Promise::All)). With
//! `DualDepthPeeling<u32>` (depth keys, as the paper's float depths) **equal depths merge**: all
//! fragments sharing the nearest (or farthest) depth are one layer, peeled together, and the
//! capture holds that depth once; the oracle's diff reports the duplicates as lost. (The paper's
//! shader shades every fragment equal to a bound, but into MAX-blended colour targets, which keep
//! the per-channel maximum of their contributions rather than blending them all: its colours merge
//! too.)
//!
//! **Passes.** `⌈L/2⌉ + 1`, where `L` is the largest number of layers at any pixel (depth
//! complexity for `u64`, distinct depths for `u32`): `⌈L/2⌉` passes capture, the last one finds
//! nothing. The paper's sample shades a pair one pass after it is found and stops when no *back*
//! colour was written (its occlusion query wraps the back-blend pass), which takes `⌊L/2⌋ + 2`
//! passes: the same for odd `L`, one more for even `L`. The papers' tables follow that count
//! (12 layers: 13 DP passes, 8 DDP passes).
//!
//! **Memory per pixel.** Four working words (the GPU's two RG32F targets), `max_layers` output
//! slots and a `u32` layer-overflow counter: `(4 + max_layers) · 8 + 4` bytes with `u64` words,
//! `(4 + max_layers) · 4 + 4` with `u32`. The front list fills slots from the first, the back list
//! from the last; a layer that finds no free slot between them is counted as overflow and reported
//! by the post pass (peeling goes on so that the count is exact), so with too few slots the kept
//! layers are the nearest and the farthest ones.
//!
//! Unlike the GPU, which blends the peeled layers into front and back colour accumulators and
//! never stores them (FreePipe §5.2 counts 4 MB at 512 × 512: the two depth targets), the model
//! stores every layer so that the capture can be compared with the oracle. Unlike the paper's
//! shader, which reads both bounds in one RG32F texture fetch, the two bounds are two words read by
//! two loads.

use fragsim_memory::{Memory, Word, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::LayerStorage;
use crate::common::MdtsWord;
use fragsim_capture::{CaptureError, Descriptor, Scheme, Step, MEMORY_CAP_DEFAULT};

/// Dual depth peeling over words of type `W` (default `u64`: exact fragment for fragment; `u32`:
/// depth keys, equal depths merge).
#[derive(Clone, Debug)]
pub struct DualDepthPeeling<W: MdtsWord = u64> {
    storage: LayerStorage<W>,
}

/// Working word: the near bound the previous pass peeled.
const PREV_NEAR: usize = 0;
/// Working word: the far bound the previous pass peeled, complemented.
const PREV_FAR: usize = 1;
/// Working word: the near bound this pass is peeling.
const NEAR: usize = 2;
/// Working word: the far bound this pass is peeling, complemented.
const FAR: usize = 3;

/// A fragment's walk in one dual peeling pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DualPeel<W> {
    /// The pixel's first working word.
    pub base: usize,
    /// The fragment's word.
    pub value: W,
    /// The next step.
    pub phase: DualPhase,
    /// Whether the fragment lowered the near word (it is the nearest so far).
    pub won_near: bool,
}

/// The four steps of a dual peeling pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DualPhase {
    /// `load` the previous near bound; go on only if strictly farther.
    TestNear,
    /// `load` the previous far bound; go on only if strictly nearer.
    TestFar,
    /// `atomicMin` on the near word.
    Near,
    /// `atomicMin` of the complement on the far word.
    Far,
}

impl<W: MdtsWord> DualDepthPeeling<W> {
    /// Dual depth peeling with storage for `max_layers` layers per pixel (pass the scene's maximum
    /// depth complexity to keep everything), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `max_layers == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, max_layers: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        Ok(Self {
            storage: LayerStorage::new("dual-peeling", viewport, 4, max_layers, memory_cap)?,
        })
    }

    /// Like [`DualDepthPeeling::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`DualDepthPeeling::new`].
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

impl<W> DualPeel<W> {
    /// After a bound test: on to `next` if the fragment lies strictly between the bounds.
    fn go_on_if(&mut self, inside: bool, next: DualPhase) -> Step {
        if inside {
            self.phase = next;
            Step::Continue
        } else {
            Step::Discarded
        }
    }
}

/// The order-reversing complement, so that `atomicMin` keeps the largest value.
fn complement<W: Word>(value: W) -> W {
    W::MAX.wrapping_sub(value)
}

impl<W: MdtsWord> Scheme for DualDepthPeeling<W> {
    type State = DualPeel<W>;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        self.storage.descriptor()
    }

    fn begin(&self, fragment: Fragment) -> DualPeel<W> {
        DualPeel {
            base: self.storage.working(fragment.pixel as usize),
            value: W::encode(fragment),
            phase: DualPhase::Near,
            won_near: false,
        }
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<DualPeel<W>> {
        let mut peel = self.begin(fragment);
        // Pass 0 has no bounds yet: it is the paper's min-max initialisation pass.
        if pass > 0 {
            peel.phase = DualPhase::TestNear;
        }
        Some(peel)
    }

    fn step<M: Memory>(&self, peel: &mut DualPeel<W>, memory: &M) -> Step {
        let words = W::words(memory);
        match peel.phase {
            DualPhase::TestNear => {
                let inside = peel.value > words.load(peel.base + PREV_NEAR);
                peel.go_on_if(inside, DualPhase::TestFar)
            }
            DualPhase::TestFar => {
                let inside = peel.value < complement(words.load(peel.base + PREV_FAR));
                peel.go_on_if(inside, DualPhase::Near)
            }
            DualPhase::Near => {
                peel.won_near = peel.value < words.fetch_min(peel.base + NEAR, peel.value);
                peel.phase = DualPhase::Far;
                Step::Continue
            }
            DualPhase::Far => {
                let far = complement(peel.value);
                let won_far = far < words.fetch_min(peel.base + FAR, far);
                if peel.won_near || won_far {
                    Step::Stored
                } else {
                    Step::Discarded
                }
            }
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let words = W::words(memory);
        let layers = self.storage.layers();
        let pass = pass as usize;
        // Pass `i` takes front slot `i` and back slot `layers − 1 − i` (every earlier pass of a
        // pixel that still captures found two distinct layers), while they stay apart.
        let front = (2 * pass < layers).then_some(pass);
        let back = (2 * pass + 1 < layers).then(|| layers - 1 - pass);
        let mut captured = false;
        for pixel in 0..self.storage.pixels() {
            let base = self.storage.working(pixel);
            let near = words.load(base + NEAR);
            // An empty pixel keeps its bounds, so no later pass lets anything through there.
            if near == W::MAX {
                continue;
            }
            captured = true;
            let far_word = words.load(base + FAR);
            words.store(base + PREV_NEAR, near);
            words.store(base + PREV_FAR, far_word);
            words.store(base + NEAR, W::MAX);
            words.store(base + FAR, W::MAX);
            self.storage.put(memory, pixel, front, near);
            let far = complement(far_word);
            if far != near {
                self.storage.put(memory, pixel, back, far);
            }
        }
        captured
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        self.storage.resolve(memory, pixel, out)
    }
}

//! The stencil-routed A-buffer (SRAB): Myers and Bavoil, "Stencil routed A-buffer" (SIGGRAPH 2007
//! sketch) and NVIDIA's "Stencil Routed K-Buffer" SDK sample (2007), as FreePipe (Liu et al.,
//! I3D 2010, §2 and Table 3, "SRAB", 2 geometry passes) measures it.
//!
//! **Algorithm.** Each pixel is an 8-sample MSAA pixel whose samples all sit at the pixel centre,
//! and a stencil value routes each fragment to one sample: every fragment decrements the stencil
//! of all 8 samples and is written only to the sample whose stencil equals the reference, so the
//! `i`-th fragment to arrive lands in sample `i`, in rasterization order. Here that is a per-pixel
//! counter: `s = fetch_add(counter, 1)`, then a `store` into sample `s` (two steps, as the
//! A-buffer). Past the samples a fragment is lost, and counted: the counter keeps counting. A
//! full-screen post pass sorts each pixel's samples with a bitonic network (the sketch's
//! `O(N log² N)` sort; [`crate::common::sort::bitonic_sort`]).
//!
//! **Passes.** With `passes = P`, up to `P` geometry passes capture `8 P` fragments per pixel:
//! pass `p` re-clears the stencil and keeps the fragments that arrive `8p`-th to `(8p + 7)`-th,
//! in samples `8p..8p + 8` of the pixel (the SDK sample: "up to 16 fragments per pixel are
//! captured in rasterization order, in 2 geometry passes"). A pass runs only when the previous one
//! overflowed somewhere (the sketch's overflow detection). FreePipe's "2g" for every scene of its
//! Table 3 is this protocol with `P = 2` on scenes deeper than 8; on scenes of depth complexity at
//! most 8 one pass suffices and one is reported. The sort is a full-screen pass, not a geometry
//! pass, and is not counted in `RunStats.passes`.
//!
//! **Guarantee.** One pass is RMW-safe (a counter taken by an atomic, then a private slot, as the
//! A-buffer): under any interleaving it captures every fragment of pixels of depth complexity at
//! most 8, and exactly 8 of the others, the rest counted as overflow ([`Promise::All`]). Which 8
//! depends on arrival order. Several passes are exact only when every pass sees each pixel's
//! fragments in the *same* order, which the GPU guarantees (fragments of one pixel reach the ROP
//! in API order) and the serial executor reproduces. Under the parallel or scheduled executors the
//! order may change from pass to pass: a fragment may then be captured twice and another never;
//! the diff reports both (`tests/suite/kbuffer/srab.rs`).
//!
//! **Memory per pixel:** `8 P` samples of 8 bytes and a 4-byte counter: 68 bytes for one pass,
//! 132 for two. FreePipe's Table 3 counts 16 MB at 512×512, i.e. 64 bytes a pixel: 8 samples of
//! 4-byte colour and 4-byte depth-stencil (or 16 depths of 4 bytes).
//!
//! Unlike the GPU, whose stencil is an 8-bit value that saturates or wraps, the counter is a `u32`
//! that never wraps, so the overflow is exact. Unlike the GPU's samples, which hold a colour and a
//! depth, a sample is one `u64` `depth_key << 32 | prim`.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::sort::bitonic_sort;
use fragsim_capture::Guarantee;
use fragsim_capture::{Capacity, Identity};
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// MSAA samples per pixel: the most D3D10 hardware offered, and the sketch's limit.
pub const SAMPLES: u32 = 8;

/// The stencil-routed A-buffer.
#[derive(Clone, Debug)]
pub struct StencilRouted {
    descriptor: Descriptor,
    passes: u32,
}

/// A fragment's progress: route, then write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// Before the `fetch_add` on the pixel's stencil counter.
    Stencil {
        /// The pixel.
        pixel: u32,
        /// The geometry pass.
        pass: u32,
        /// The value to store.
        value: u64,
    },
    /// Routed to a sample; the store is next.
    Write {
        /// The sample's word.
        sample: usize,
        /// The value to store.
        value: u64,
    },
}

impl StencilRouted {
    /// Up to `passes` geometry passes of 8 samples each, within `memory_cap` bytes.
    ///
    /// # Errors
    /// `passes == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, passes: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        if passes == 0 {
            return Err(CaptureError::BadParameter(
                "the stencil-routed A-buffer needs at least 1 pass of 8 samples, got 0".into(),
            ));
        }
        let descriptor = Descriptor {
            // The pass count is a parameter, like MDTS's K: the catalog's one spelling for every
            // configuration (runs report their passes and slots beside it).
            name: "srab".into(),
            layout: Layout::counters_and_slots(
                viewport.pixels(),
                viewport.pixels() * (SAMPLES * passes) as usize,
            ),
            identity: Identity::KeyAndPrim,
            guarantee: Guarantee::ExactInArrivalOrder,
            promise: Promise::All(Capacity::PerPixel(SAMPLES * passes)),
            pixels: viewport.pixels(),
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            passes,
        })
    }

    /// The sketch's form: one pass, 8 samples, the default memory cap.
    ///
    /// # Errors
    /// As [`StencilRouted::new`].
    pub fn single_pass(viewport: Viewport) -> Result<Self, CaptureError> {
        Self::new(viewport, 1, MEMORY_CAP_DEFAULT)
    }

    /// Samples per pixel over all passes.
    #[must_use]
    pub fn capacity(&self) -> u32 {
        SAMPLES * self.passes
    }
}

impl Scheme for StencilRouted {
    type State = Route;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Route {
        Route::Stencil {
            pixel: fragment.pixel,
            pass: 0,
            value: fragment.packed(),
        }
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Route> {
        Some(Route::Stencil {
            pixel: fragment.pixel,
            pass,
            value: fragment.packed(),
        })
    }

    fn step<M: Memory>(&self, route: &mut Route, memory: &M) -> Step {
        match *route {
            Route::Stencil { pixel, pass, value } => {
                let arrival = WordMemory::<u32>::fetch_add(memory, pixel as usize, 1);
                let window = pass * SAMPLES..(pass + 1) * SAMPLES;
                if window.contains(&arrival) {
                    *route = Route::Write {
                        sample: pixel as usize * self.capacity() as usize + arrival as usize,
                        value,
                    };
                    Step::Continue
                } else if arrival < window.start || pass + 1 < self.passes {
                    // Captured by an earlier pass, or left to the next one: by design.
                    Step::Discarded
                } else {
                    Step::Dropped
                }
            }
            Route::Write { sample, value } => {
                WordMemory::<u64>::store(memory, sample, value);
                Step::Stored
            }
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let routed = (pass + 1) * SAMPLES;
        let overflowed =
            (0..self.descriptor.pixels).any(|p| WordMemory::<u32>::load(memory, p) > routed);
        let more = overflowed && pass + 1 < self.passes;
        if more {
            // The next pass's stencil clear.
            for p in 0..self.descriptor.pixels {
                WordMemory::<u32>::store(memory, p, 0);
            }
        }
        more
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        // The last pass saw every fragment of the pixel arrive, so its counter is the pixel's
        // depth complexity; passes stop only once every pixel fits what was routed.
        let arrived = WordMemory::<u32>::load(memory, pixel);
        let stored = arrived.min(self.capacity());
        let first = pixel * self.capacity() as usize;
        let start = out.len();
        out.extend((0..stored as usize).map(|i| WordMemory::<u64>::load(memory, first + i)));
        bitonic_sort(&mut out[start..]);
        arrived - stored
    }
}

//! The z-buffer: FreePipe's opaque mode (Liu et al., I3D 2010, §3 and §4.1.2; Table 2), after
//! Catmull 1974.
//!
//! **Algorithm.** One word per pixel, initially all ones; each fragment does one
//! `atomicMin(&z[pixel], depth_key << 32 | prim)`. The primitive id stands for the colour payload:
//! depth and payload travel in one word, so the word always holds the payload of the fragment whose
//! depth it holds.
//!
//! **Guarantee.** Exact: after the pass each pixel holds its nearest fragment in canonical order
//! (ties in depth go to the lower primitive id), under any interleaving, since `atomicMin` is one
//! indivisible step ([`Promise::Nearest`] with `K = 1`). One geometry pass, one memory operation
//! per fragment; memory: 8 bytes per pixel.
//!
//! Unlike FreePipe, whose GPU (compute capability 1.3) had no 64-bit `atomicMin`, the depth and
//! the colour are not split across two 32-bit `atomicMin`s on words that share their high 20 bits
//! (§4.1.2): that heuristic can pair one fragment's depth with another's colour when two depths
//! agree in those bits. 64-bit `atomicMin` exists since compute capability 3.5.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::depth_test;
use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// The z-buffer over packed `depth_key << 32 | prim` words.
#[derive(Clone, Debug)]
pub struct ZBuffer {
    descriptor: Descriptor,
}

/// A fragment's one step: its pixel's word and its packed value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthTest {
    /// The pixel's word.
    pub pixel: usize,
    /// `depth_key << 32 | prim`.
    pub value: u64,
}

impl ZBuffer {
    /// A z-buffer for `viewport` within `memory_cap` bytes.
    ///
    /// # Errors
    /// Storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, memory_cap: u64) -> Result<Self, CaptureError> {
        let descriptor = Descriptor {
            name: "zbuffer".into(),
            layout: Layout::counters_and_slots(0, viewport.pixels()),
            identity: Identity::KeyAndPrim,
            guarantee: Guarantee::Exact,
            promise: Promise::Nearest(1),
            pixels: viewport.pixels(),
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
        })
    }

    /// A z-buffer with the default memory cap.
    ///
    /// # Errors
    /// As [`ZBuffer::new`].
    pub fn for_viewport(viewport: Viewport) -> Result<Self, CaptureError> {
        Self::new(viewport, MEMORY_CAP_DEFAULT)
    }
}

impl Scheme for ZBuffer {
    type State = DepthTest;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> DepthTest {
        DepthTest {
            pixel: fragment.pixel as usize,
            value: fragment.packed(),
        }
    }

    fn step<M: Memory>(&self, test: &mut DepthTest, memory: &M) -> Step {
        depth_test(
            WordMemory::<u64>::fetch_min(memory, test.pixel, test.value),
            test.value,
        )
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let nearest = WordMemory::<u64>::load(memory, pixel);
        // No fragment's word reaches all ones (the largest depth key is that of 1.0).
        if nearest != u64::MAX {
            out.push(nearest);
        }
        0
    }
}

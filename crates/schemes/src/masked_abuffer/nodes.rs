//! The walk input of the masked-node storage: [`PixelNode`], one masked node bound for its pixel,
//! gathered from the rasterizer's per-sample fragments by [`Merging`] (the nodes themselves and
//! their lists are the capture crate's: `fragsim_capture::MaskedNode`).

use fragsim_capture::{merge_samples, MaskedNode, WalkInput};
use fragsim_raster::Fragment;

/// A masked node bound for its pixel: what a walk of the masked-node storage starts from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelNode {
    /// The pixel (not a sample: a pixel of the render target).
    pub pixel: u32,
    /// The node.
    pub node: MaskedNode,
}

/// One thread's gathering of per-sample fragments into [`PixelNode`]s: the current triangle's
/// fragments, merged ([`merge_samples`]) once the next triangle's first fragment or the end of
/// the stream comes.
#[derive(Clone, Debug)]
pub struct Merging {
    /// Samples a pixel of the view.
    samples: u32,
    /// The current triangle's fragments (its clipped pieces' too: they share its primitive id).
    fragments: Vec<Fragment>,
}

impl Merging {
    /// An empty gathering for a view of `samples` samples a pixel.
    #[must_use]
    pub fn new(samples: u32) -> Self {
        Self {
            samples,
            fragments: Vec::new(),
        }
    }

    /// Merges the held fragments into nodes, handed to `emit`, and forgets them.
    fn merge(&mut self, emit: &mut impl FnMut(PixelNode)) {
        merge_samples(self.samples, &mut self.fragments, &mut |pixel, node| {
            emit(PixelNode { pixel, node });
        });
        self.fragments.clear();
    }
}

impl Default for Merging {
    /// One sample a pixel: each fragment its own node of mask 1.
    fn default() -> Self {
        Self::new(1)
    }
}

impl WalkInput for PixelNode {
    type Gathering = Merging;

    fn gather(gathering: &mut Merging, fragment: Fragment, emit: &mut impl FnMut(Self)) {
        // The rasterizer hands over a triangle's fragments one after another: a new primitive
        // id is a new triangle, and the last one's nodes are complete.
        if gathering
            .fragments
            .last()
            .is_some_and(|last| last.prim != fragment.prim)
        {
            gathering.merge(emit);
        }
        gathering.fragments.push(fragment);
    }

    fn flush(gathering: &mut Merging, emit: &mut impl FnMut(Self)) {
        gathering.merge(emit);
    }

    fn pixel(self) -> u32 {
        self.pixel
    }
}

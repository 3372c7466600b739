//! Per-pixel linked lists (Yang et al., "Real-time concurrent linked list construction on the
//! GPU", EGSR 2010), as the Khronos Vulkan-Samples `oit_linked_lists` sample, the WebGPU samples'
//! `a-buffer` and nvpro-samples `vk_order_independent_transparency` ("linked list") ship them.
//!
//! **Algorithm** (modelled from the published descriptions). One global node counter, a per-pixel
//! head pointer and a fixed pool of `pool` nodes. A fragment allocates a node with
//! `n = atomicAdd(&counter, 1) + 1` (node 0 is the list terminator, as in nvpro's sample); past
//! the pool it is discarded. Otherwise it swaps itself in as the pixel's head,
//! `old = atomicExchange(&head[p], n)`, and writes the node: its fragment and `next = old` (two
//! plain stores here, one `uvec4` store on the GPU). Four memory operations per fragment; each
//! pixel's list holds its fragments most recent first.
//!
//! **Resolve policies** (the sorting pass keeps at most `N` fragments in registers):
//! - [`Resolve::KeepFirst`] (Vulkan-Samples' `combine.frag`, WebGPU samples): the first `N` nodes
//!   of the list, i.e. the `N` most recently inserted, are sorted and blended; the rest are
//!   ignored. **The known flaw**: when a pixel's list is longer than `N`, the kept fragments are
//!   the last arrivals, not the nearest, so a near fragment inserted early is lost.
//! - [`Resolve::KeepNearest`] (nvpro's composite pass): the whole list is walked and the `N`
//!   nearest are kept by insertion.
//!
//! **Guarantee.** The exchange makes list construction safe under any interleaving: every
//! fragment that gets a node is in its pixel's list exactly once (loom checks it in
//! `tests/loom/`). With a pool that suffices, `KeepNearest` is exact up to `N`
//! ([`Promise::Nearest`]); `KeepFirst` is exact when every list has at most `N` nodes and
//! otherwise keeps `N` of them, uncounted ([`Capacity::PerPixelUncounted`]: the oracle supplies
//! the count and checks it). A fragment past the pool is lost silently (no per-pixel count survives), and the
//! oracle's diff counts it. One geometry pass; memory: one 32-bit head per pixel, the counter, and
//! per node a 64-bit fragment and a 32-bit `next`.
//!
//! Unlike the GPU samples, which store colour and depth, a node holds `depth_key << 32 | prim`;
//! unlike Vulkan-Samples (terminator `0xFFFFFFFF`), the terminator is node 0, so that every 32-bit
//! word starts at 0.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use fragsim_capture::Guarantee;
use fragsim_capture::{Capacity, Identity};
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step};

/// Which of a long list the resolve keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolve {
    /// The first `N` nodes of the list (the most recent): Vulkan-Samples, WebGPU samples.
    KeepFirst,
    /// The `N` nearest of the whole list: nvpro-samples.
    KeepNearest,
}

/// Per-pixel linked lists with a fixed node pool.
#[derive(Clone, Debug)]
pub struct LinkedList {
    descriptor: Descriptor,
    pool: usize,
    sorted_max: u32,
    resolve: Resolve,
}

/// A fragment's progress through its four memory operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Node {
    /// Before the `atomicAdd` on the global counter.
    Allocate {
        /// The pixel.
        pixel: u32,
        /// The value to store.
        value: u64,
    },
    /// Node `node` is ours: the head exchange is next.
    Link {
        /// The pixel.
        pixel: u32,
        /// The node (1-based).
        node: u32,
        /// The value to store.
        value: u64,
    },
    /// Linked: the fragment's store is next.
    WriteFragment {
        /// The node.
        node: u32,
        /// The previous head.
        next: u32,
        /// The value to store.
        value: u64,
    },
    /// The `next` pointer's store is last.
    WriteNext {
        /// The node.
        node: u32,
        /// The previous head.
        next: u32,
    },
}

impl LinkedList {
    /// Lists over a pool of `pool` nodes, resolved keeping `sorted_max` fragments by `resolve`.
    ///
    /// # Errors
    /// `pool` or `sorted_max` is 0, the pool does not fit 32-bit node indices, or storage beyond
    /// `memory_cap`.
    pub fn new(
        viewport: Viewport,
        pool: usize,
        sorted_max: u32,
        resolve: Resolve,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        if sorted_max == 0 {
            return Err(CaptureError::BadParameter(
                "the linked-list resolve needs to keep at least 1 fragment".into(),
            ));
        }
        if pool == 0 || pool >= u32::MAX as usize {
            return Err(CaptureError::BadParameter(format!(
                "the node pool needs 1 to {} nodes, got {pool}",
                u32::MAX - 1
            )));
        }
        let descriptor = Descriptor {
            name: match resolve {
                Resolve::KeepFirst => "linked-list",
                Resolve::KeepNearest => "linked-list-nearest",
            }
            .into(),
            // Heads, the counter, then the `next` of nodes 1..=pool.
            layout: Layout::counters_and_slots(viewport.pixels() + 1 + pool, pool),
            identity: Identity::KeyAndPrim,
            guarantee: Guarantee::ExactWithinCapacity(sorted_max),
            promise: match resolve {
                // The resolve stops after N nodes and never learns the list's length.
                Resolve::KeepFirst => Promise::All(Capacity::PerPixelUncounted(sorted_max)),
                Resolve::KeepNearest => Promise::Nearest(sorted_max),
            },
            pixels: viewport.pixels(),
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            pool,
            sorted_max,
            resolve,
        })
    }

    /// Nodes in the pool.
    #[must_use]
    pub fn pool(&self) -> usize {
        self.pool
    }

    /// Fragments the resolve keeps per pixel.
    #[must_use]
    pub fn sorted_max(&self) -> u32 {
        self.sorted_max
    }

    /// The 32-bit word of the global counter; node `n`'s `next` is at `counter() + n`.
    fn counter(&self) -> usize {
        self.descriptor.pixels
    }
}

impl Scheme for LinkedList {
    type State = Node;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Node {
        Node::Allocate {
            pixel: fragment.pixel,
            value: fragment.packed(),
        }
    }

    fn step<M: Memory>(&self, state: &mut Node, memory: &M) -> Step {
        match *state {
            Node::Allocate { pixel, value } => {
                let taken = WordMemory::<u32>::fetch_add(memory, self.counter(), 1);
                if taken as usize >= self.pool {
                    return Step::Dropped;
                }
                *state = Node::Link {
                    pixel,
                    node: taken + 1,
                    value,
                };
                Step::Continue
            }
            Node::Link { pixel, node, value } => {
                let next = WordMemory::<u32>::swap(memory, pixel as usize, node);
                *state = Node::WriteFragment { node, next, value };
                Step::Continue
            }
            Node::WriteFragment { node, next, value } => {
                WordMemory::<u64>::store(memory, node as usize - 1, value);
                *state = Node::WriteNext { node, next };
                Step::Continue
            }
            Node::WriteNext { node, next } => {
                WordMemory::<u32>::store(memory, self.counter() + node as usize, next);
                Step::Stored
            }
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let n = self.sorted_max as usize;
        let start = out.len();
        let mut node = WordMemory::<u32>::load(memory, pixel) as usize;
        while node != 0 {
            let value = WordMemory::<u64>::load(memory, node - 1);
            let kept = out.len() - start;
            match self.resolve {
                Resolve::KeepFirst if kept == n => break,
                Resolve::KeepFirst => out.push(value),
                // Insertion into the sorted array of at most N; the farthest falls off.
                Resolve::KeepNearest => {
                    if kept < n {
                        out.push(value);
                    } else if value < out[out.len() - 1] {
                        *out.last_mut().expect("N ≥ 1") = value;
                    }
                    let list = &mut out[start..];
                    let mut i = list.len() - 1;
                    while i > 0 && list[i - 1] > list[i] {
                        list.swap(i - 1, i);
                        i -= 1;
                    }
                }
            }
            node = WordMemory::<u32>::load(memory, self.counter() + node) as usize;
        }
        if self.resolve == Resolve::KeepFirst {
            crate::common::sort::insertion_sort(&mut out[start..]);
        }
        // Fragments past N (and past the pool) leave no per-pixel count: nothing is reported.
        0
    }
}

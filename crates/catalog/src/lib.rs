//! The catalog: every scheme the simulator can run by name, and how to build and run it.
//!
//! One entry per scheme ([`CATALOG`]): its name (the one spelling used on the command line, in
//! JSON, in file names and in dump headers, and the one its [`Scheme::name`](fragsim_capture::Scheme::name)
//! returns), its geometry passes, how it sizes its storage, its memory's layout in a dump
//! ([`DumpLayout`], where it has one), a one-line description, and its constructor: the sizes of
//! a [`Build`] to the scheme, handed to a [`SchemeVisitor`] ([`SchemeName::build`];
//! [`SchemeRunner::run`] is the visitor that runs one frame). What a scheme guarantees is
//! never listed here: it comes from the built scheme
//! ([`Scheme::guarantee`](fragsim_capture::Scheme::guarantee)). Front ends (the command line, the dump
//! reader and writer, the property tests, the fuzz targets) iterate this list, so adding a scheme
//! takes three places: its module in `fragsim-schemes` (a type implementing
//! [`Scheme`](fragsim_capture::Scheme), whose constructor builds its
//! [`Descriptor`](fragsim_capture::Descriptor) once), that module's `pub mod` line (in
//! `crates/schemes/src/lib.rs`, or in its family's folder, as `kbuffer/mod.rs`), and one
//! `catalog!` line here. A scheme no named dump layout fits dumps its raw words
//! ([`DumpLayout::Memory`]); the CUDA and wgpu backends keep their own lists of the schemes they
//! mirror, which a new scheme need not join.
//!
//! **What is not here: weighted blended OIT and tail blending**. An entry is a
//! capture: per-pixel storage of fragments that the oracle judges list by list. WBOIT keeps no
//! fragment (two blend targets, sums over every fragment), so as an entry it would capture empty
//! lists and its verdict would say nothing; tail blending's kept part is the `K` nearest, which
//! `mdts`, `kbuffer-interlock` and `loop64` capture and are judged on, and its tail is blending
//! hardware folding the rest into a colour target, again no list. Both hold colour alone, so both
//! are judged by their colour against the oracle's image: they are shading options
//! (`fragsim_shade::approximate`, `bench --approximate`, `sweep --approximate`), measured with
//! EPR, colour error and its depth-complexity buckets beside the catalog's rows and charts
//! (`docs/baselines/wboit.md`, `docs/baselines/tail-blend.md`). MLAB, which keeps `K` nodes with
//! depths, has both: its node structure is the `mlab` entry, its colour the shading option.
//!
//! The catalog's parts: the entries, their columns and constructors here, [`Build`] and
//! [`SchemeVisitor`] in `build.rs`, [`DumpLayout`] in `dump_layout.rs`, running an entry and the
//! early memory-cap check in `run.rs`.

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/).
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

mod build;
mod dump_layout;
mod run;

pub use build::{Build, SchemeVisitor};
pub use dump_layout::{DumpLayout, SlotWord};
pub use run::{check_memory_cap_early, MemoryWords, NamedRun, RunError, SchemeRunner};

use fragsim_capture::CaptureError;
use fragsim_schemes::abuffer::{
    ABuffer,
    PostSort::{Bitonic, Insertion},
};
use fragsim_schemes::bucket::{Adp, Bdp, Bdp2, Buckets};
use fragsim_schemes::dual_peeling::DualDepthPeeling;
use fragsim_schemes::kbuffer::interlock_ordered::{KBufferInterlockOrdered, Keep};
use fragsim_schemes::kbuffer::multipass::KBufferMultipass;
use fragsim_schemes::kbuffer::{
    KBuffer, WriteBack,
    WriteBack::{RenderTarget, SeparateStores},
};
use fragsim_schemes::layer_counter::LayerCounter;
use fragsim_schemes::linked_list::{
    LinkedList,
    Resolve::{KeepFirst, KeepNearest},
};
use fragsim_schemes::loop32::Loop32;
use fragsim_schemes::masked_abuffer::MaskedABuffer;
use fragsim_schemes::mdts::{
    Direction::{Ascending, Descending},
    Mdts,
};
use fragsim_schemes::mdts_packed::{Colours, MdtsPacked};
use fragsim_schemes::peeling::DepthPeeling;
use fragsim_schemes::stencil_routed::StencilRouted;
use fragsim_schemes::zbuffer::ZBuffer;

/// A slot count: a number, or derived from the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// Sized to the scene's depth complexity by a counting pass of the scheme's own.
    Auto,
    /// Exactly this many.
    Fixed(u32),
}

/// How the user sized the schemes. Nothing here comes from the oracle: where a size is `auto`
/// (or a scheme's storage is sized to the scene by design), the scheme runs its own counting pass
/// first ([`fragsim_capture::depth_count`]), and its run reports that pass.
#[derive(Debug, Clone, Copy)]
pub struct Sizing {
    /// Slots per pixel of the K-sized schemes (`--k`).
    pub k: Count,
    /// Slots per pixel of the capacity-sized schemes (`--capacity`; linked lists: pool nodes).
    pub capacity: Count,
    /// Refuse storage beyond this many bytes (`--memory-cap`).
    pub memory_cap: u64,
}

/// How a scheme sizes its per-pixel storage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    /// This many slots per pixel, whatever the sizing.
    Slots(u32),
    /// [`Sizing::k`] slots per pixel (a counting pass first where it is `auto`).
    K,
    /// [`Sizing::capacity`] slots per pixel (a counting pass first where it is `auto`).
    Capacity,
    /// [`Sizing::k`] nodes kept by the resolve, from a pool of [`Sizing::capacity`] nodes per
    /// pixel (a counting pass first where either is `auto`; `auto` pools hold the scene's
    /// fragments).
    KAndPool,
    /// Sized to the scene by its own counting pass, always (storage for every fragment, or a
    /// record of every layer).
    Counted,
    /// [`Sizing::capacity`] masked nodes per pixel (where it is `auto`, the entry's own counting
    /// pass of nodes first: one `fetch_add` per node, the deepest pixel's count).
    Nodes,
}

/// How many geometry passes a scheme runs (its counting pass, where one runs, not included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Passes {
    /// Exactly this many.
    Fixed(u32),
    /// At most this many: a later pass runs only where an earlier one overflowed.
    UpTo(u32),
    /// `before` passes, then one per `per` layers of the scene's maximum depth complexity
    /// (rounded up), then `after` passes (peeling's last one, which finds nothing).
    PerLayers {
        /// Passes before the layers' (ADP's range and histogram).
        before: u32,
        /// Layers captured per pass.
        per: u32,
        /// Passes after the layers'.
        after: u32,
    },
    /// At least one, repeated until every fragment is confirmed by a count (hazards cost
    /// passes).
    UntilConfirmed,
}

impl Passes {
    /// The least and the most passes (`None`: unbounded) on a scene of maximum depth complexity
    /// `layers`.
    #[must_use]
    pub fn bounds(self, layers: u32) -> (u32, Option<u32>) {
        match self {
            Self::Fixed(n) => (n, Some(n)),
            Self::UpTo(n) => (1, Some(n)),
            Self::PerLayers { before, per, after } => {
                let n = before + layers.div_ceil(per) + after;
                (n, Some(n))
            }
            Self::UntilConfirmed => (1, None),
        }
    }
}

/// One scheme of the catalog.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// Which scheme.
    pub scheme: SchemeName,
    /// Its one spelling: the command line's, JSON's, file names' and dump headers'.
    pub name: &'static str,
    /// Its geometry passes.
    pub passes: Passes,
    /// How it sizes its storage.
    pub storage: Storage,
    /// How its memory is laid out in a dump; `None`: it cannot be dumped.
    pub dump: Option<DumpLayout>,
    /// One line on what it is (the command line's help).
    pub description: &'static str,
    /// For the k-buffer family, the machine its read–modify–write of the K slots runs on (whose
    /// hazard `explain` and `hazard` show); `None` for schemes without a read–modify–write of a
    /// pixel's slots (atomic walks, critical sections).
    pub read_modify_write: Option<WriteBack>,
    /// Whether its constructor takes the scene's primitive order ([`Build::order`]): the
    /// ordered interlock's critical sections follow it.
    pub primitive_order: bool,
}

macro_rules! catalog {
    ($($scheme:ident $name:literal $passes:expr, $storage:expr, $dump:expr,
        $description:literal; $(read-modify-write $machine:expr;)? $(in-primitive-order $ordered:literal;)?
        |$build:ident| $construct:expr;)*) => {
        /// Every scheme the simulator runs by name.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum SchemeName {
            $(#[doc = $description] $scheme,)*
        }

        /// Every scheme, in the order tables list them.
        pub const CATALOG: &[Entry] = &[
            $(Entry {
                scheme: SchemeName::$scheme,
                name: $name,
                passes: $passes,
                storage: $storage,
                dump: $dump,
                description: $description,
                read_modify_write: catalog!(@optional $($machine)?),
                primitive_order: catalog!(@flag $($ordered)?),
            },)*
        ];

        impl SchemeName {
            /// Builds the scheme sized by `build` and hands it, with its slots per pixel where it
            /// has a fixed number, to `visitor`.
            ///
            /// # Errors
            /// A parameter the scheme rejects, or storage beyond the memory cap.
            pub fn build<V: SchemeVisitor>(
                self,
                build: &Build<'_>,
                visitor: V,
            ) -> Result<V::Output, CaptureError> {
                match self {
                    $(SchemeName::$scheme => {
                        let $build = build;
                        let (scheme, slots) = $construct;
                        Ok(visitor.visit(&scheme, slots))
                    })*
                }
            }
        }
    };
    (@optional) => { None };
    (@optional $value:expr) => { Some($value) };
    (@flag) => { false };
    (@flag $value:literal) => { $value };
}

use DumpLayout::{
    CountersAndSlots, KBufferSlots, LayerMajor, LinkedLists, MaskedNodes, Memory, SlotArray,
};
use Passes::{Fixed, PerLayers, UntilConfirmed, UpTo};
use SlotWord::{Fragment, FragmentPlusOne, Key};
use Storage::{Capacity, Counted, KAndPool, Nodes, Slots, K};

catalog! {
    Mdts "mdts" Fixed(1), K, Some(SlotArray(Fragment)),
        "MDTS, 64-bit words (depth key and primitive id), ascending.";
        |b| (Mdts::<u64>::new(b.viewport, b.k, Ascending, b.memory_cap)?, Some(b.k));
    Mdts32 "mdts32" Fixed(1), K, Some(SlotArray(Key)),
        "MDTS, 32-bit depth keys as in FreePipe's Table 1.";
        |b| (Mdts::<u32>::new(b.viewport, b.k, Ascending, b.memory_cap)?, Some(b.k));
    MdtsDesc "mdts-desc" Fixed(1), K, Some(SlotArray(FragmentPlusOne)),
        "MDTS with `atomicMax`, descending.";
        |b| (Mdts::<u64>::new(b.viewport, b.k, Descending, b.memory_cap)?, Some(b.k));
    MdtsProbe "mdts-probe" Fixed(1), K, Some(SlotArray(Fragment)),
        "MDTS (64-bit words) with the probing walk: a load first, `atomicMin` only where it would change the slot (same lists, fewer locked operations).";
        |b| (Mdts::<u64>::new(b.viewport, b.k, Ascending, b.memory_cap)?.probing(), Some(b.k));
    MdtsEmulated64 "mdts-emulated64" Fixed(1), K, Some(Memory),
        "MDTS with each 64-bit `atomicMin` emulated on two 32-bit words inside a per-slot compare-and-swap lock (WebGPU has no 64-bit atomics): exact.";
        |b| (fragsim_schemes::mdts_emulated64::MdtsEmulated64::new(b.viewport, b.k, fragsim_schemes::mdts_emulated64::Emulation::Locked, b.memory_cap)?, Some(b.k));
    MdtsEmulated64Torn "mdts-emulated64-torn" Fixed(1), K, Some(Memory),
        "MDTS with each 64-bit `atomicMin` emulated by unlocked loads and stores of the two halves: exact only without hazards, tears under concurrency.";
        |b| (fragsim_schemes::mdts_emulated64::MdtsEmulated64::new(b.viewport, b.k, fragsim_schemes::mdts_emulated64::Emulation::Torn, b.memory_cap)?, Some(b.k));
    Abuffer "abuffer" Fixed(1), Capacity, Some(CountersAndSlots),
        "FreePipe's A-buffer: `--capacity` slots per pixel (fixed arrays, FreePipe §4.2), overflow counted; insertion-sorted.";
        |b| (ABuffer::fixed(b.viewport, b.capacity, Insertion, b.memory_cap)?, Some(b.capacity));
    AbufferBitonic "abuffer-bitonic" Fixed(1), Capacity, Some(CountersAndSlots),
        "The A-buffer as above, bitonic-sorted.";
        |b| (ABuffer::fixed(b.viewport, b.capacity, Bitonic, b.memory_cap)?, Some(b.capacity));
    AbufferExact "abuffer-exact" Fixed(1), Counted, Some(CountersAndSlots),
        "The A-buffer with storage sized exactly by its own counting pass (`fetch_add` per fragment, then a prefix sum): two geometry passes.";
        |b| (ABuffer::exact(b.counts()?, Insertion, b.memory_cap)?, None);
    Peeling "peeling" PerLayers { before: 0, per: 1, after: 1 }, Counted, Some(Memory),
        "Classical depth peeling, 64-bit words (ties ordered by primitive id): one pass per layer.";
        |b| (DepthPeeling::<u64>::new(b.viewport, b.layers, b.memory_cap)?, None);
    Peeling32 "peeling32" PerLayers { before: 0, per: 1, after: 1 }, Counted, Some(Memory),
        "Classical depth peeling on 32-bit depth keys: equal depths merge.";
        |b| (DepthPeeling::<u32>::new(b.viewport, b.layers, b.memory_cap)?, None);
    DualPeeling "dual-peeling" PerLayers { before: 0, per: 2, after: 1 }, Counted, Some(Memory),
        "Dual depth peeling (nearest and farthest layer per pass), 64-bit words.";
        |b| (DualDepthPeeling::<u64>::new(b.viewport, b.layers, b.memory_cap)?, None);
    DualPeeling32 "dual-peeling32" PerLayers { before: 0, per: 2, after: 1 }, Counted, Some(Memory),
        "Dual depth peeling on 32-bit depth keys.";
        |b| (DualDepthPeeling::<u32>::new(b.viewport, b.layers, b.memory_cap)?, None);
    Zbuffer "zbuffer" Fixed(1), Slots(1), Some(SlotArray(Fragment)),
        "The opaque z-buffer via `atomicMin`: the nearest fragment only.";
        |b| (ZBuffer::new(b.viewport, b.memory_cap)?, Some(1));
    Bdp "bdp" Fixed(2), Slots(32), Some(Memory),
        "Bucket depth peeling, one pass, 16 bucket pairs (HPG 2009 §3.2).";
        |b| (Bdp::<u32>::new(b.viewport, Buckets::Pairs(16), b.memory_cap)?, Some(32));
    BdpSingle "bdp-single" Fixed(2), Slots(32), Some(Memory),
        "Bucket depth peeling, 32 single-value buckets.";
        |b| (Bdp::<u32>::new(b.viewport, Buckets::Singles(32), b.memory_cap)?, Some(32));
    Bdp2 "bdp2" Fixed(3), Slots(64), Some(Memory),
        "Two-pass bucket depth peeling (§3.2).";
        |b| (Bdp2::<u32>::new(b.viewport, 16, b.memory_cap)?, Some(64));
    Adp "adp" PerLayers { before: 2, per: 32, after: 0 }, Counted, Some(Memory),
        "Adaptive bucket depth peeling (§3.3).";
        |b| (Adp::<u32>::new(b.viewport, b.layers, b.memory_cap)?, Some(b.layers));
    Kbuffer "kbuffer" Fixed(1), K, Some(KBufferSlots),
        "The k-buffer: read–insert–write of K slots, exact only without concurrent hazards; render-target write-backs (one step each, committed in primitive order).";
        read-modify-write RenderTarget;
        |b| (KBuffer::with_write_back(b.viewport, b.k, RenderTarget, b.memory_cap)?, Some(b.k));
    KbufferStores "kbuffer-stores" Fixed(1), K, Some(KBufferSlots),
        "The k-buffer with K separate loads and stores (CUDA's): torn write-backs too.";
        read-modify-write SeparateStores;
        |b| (KBuffer::with_write_back(b.viewport, b.k, SeparateStores, b.memory_cap)?, Some(b.k));
    KbufferInterlock "kbuffer-interlock" Fixed(1), K, Some(KBufferSlots),
        "The k-buffer's read–insert–write of K slots as one fragment-shader-interlock critical section (unordered; nvpro-samples' interlock mode): exact under any interleaving.";
        |b| (fragsim_schemes::kbuffer::interlock::KBufferInterlock::new(b.viewport, b.k, b.memory_cap)?, Some(b.k));
    KbufferInterlockOrdered "kbuffer-interlock-ordered" Fixed(1), K, Some(KBufferSlots),
        "The interlocked k-buffer with ordered critical sections (a pixel's in primitive order: Vulkan's ordered interlock, D3D's ROVs): exact under any interleaving.";
        in-primitive-order true;
        |b| (KBufferInterlockOrdered::new(b.viewport, b.k, Keep::Nearest, b.order, b.memory_cap)?, Some(b.k));
    KbufferInterlockOrderedFirst "kbuffer-interlock-ordered-first" Fixed(1), K, Some(KBufferSlots),
        "The ordered interlock keeping the first `--k` fragments of each pixel in primitive order (keep-first made deterministic): the same lists under any interleaving.";
        in-primitive-order true;
        |b| (KBufferInterlockOrdered::new(b.viewport, b.k, Keep::First, b.order, b.memory_cap)?, Some(b.k));
    KbufferSpinlock "kbuffer-spinlock" Fixed(1), K, Some(KBufferSlots),
        "The k-buffer's read–insert–write of K slots under a per-pixel spinlock (compare-and-swap, critical section after the spin loop; nvpro-samples' spinlock mode): exact under independent thread scheduling, deadlocks lockstep warps.";
        |b| (fragsim_schemes::kbuffer::spinlock::KBufferSpinlock::new(b.viewport, b.k, fragsim_schemes::kbuffer::spinlock::Loop::Naive, b.memory_cap)?, Some(b.k));
    KbufferSpinlockFixed "kbuffer-spinlock-fixed" Fixed(1), K, Some(KBufferSlots),
        "The spinlocked k-buffer with the critical section and release inside the lock loop's body: exact, and terminates under lockstep warps too.";
        |b| (fragsim_schemes::kbuffer::spinlock::KBufferSpinlock::new(b.viewport, b.k, fragsim_schemes::kbuffer::spinlock::Loop::Fixed, b.memory_cap)?, Some(b.k));
    KbufferMultipass "kbuffer-multipass" UntilConfirmed, Counted, Some(Memory),
        "The multi-pass k-buffer: k-buffer passes beyond the confirmed boundary until every fragment is confirmed by a count (render-target write-backs).";
        read-modify-write RenderTarget;
        |b| (KBufferMultipass::with_write_back(b.viewport, b.k, b.layers, RenderTarget, b.memory_cap)?, Some(b.k));
    KbufferMultipassStores "kbuffer-multipass-stores" UntilConfirmed, Counted, Some(Memory),
        "The multi-pass k-buffer with K separate loads and stores.";
        read-modify-write SeparateStores;
        |b| (KBufferMultipass::with_write_back(b.viewport, b.k, b.layers, SeparateStores, b.memory_cap)?, Some(b.k));
    Srab "srab" UpTo(2), Slots(16), Some(Memory),
        "The stencil-routed A-buffer: 8 samples per pixel and pass, 2 passes.";
        |b| (StencilRouted::new(b.viewport, 2, b.memory_cap)?, Some(16));
    MdtsPacked "mdts-packed" Fixed(1), K, Some(Memory),
        "MDTS with depth and colour packed into two 32-bit arrays (FreePipe §4.1.2).";
        |b| (MdtsPacked::new(b.viewport, b.k, Colours::Prim, b.memory_cap)?, Some(b.k));
    Loop32 "loop32" Fixed(2), K, Some(Memory),
        "nvpro-samples' loop32: MDTS's `atomicMin` loop stopping on an equal depth (equal depths merge), then a colour pass; K = `--k`.";
        |b| (Loop32::new(b.viewport, b.k, b.memory_cap)?, Some(b.k));
    Loop64 "loop64" Fixed(1), K, Some(SlotArray(Fragment)),
        "nvpro-samples' loop64: one pass of 64-bit `atomicMin` on packed (depth, colour) words, here (depth, primitive): exact, K = `--k`.";
        |b| (fragsim_schemes::loop64::Loop64::new(b.viewport, b.k, b.memory_cap)?, Some(b.k));
    Mlab "mlab" Fixed(1), K, Some(Memory),
        "Multi-layer alpha blending's `--k` nodes (Salvi & Vaidyanathan 2014) in a per-pixel interlock, the two farthest merged when full: the node depths are the K nearest (judged); its colour is approximate, measured by `bench --approximate mlab`.";
        |b| (fragsim_schemes::mlab::Mlab::new(b.viewport, b.k, b.memory_cap)?, Some(b.k));
    LayerCounter "layer-counter" Fixed(1), K, Some(LayerMajor),
        "Bevy 0.15's OIT: `atomicAdd` on a per-pixel layer counter, `--k` layers, the rest discarded.";
        |b| (LayerCounter::new(b.viewport, b.k, b.memory_cap)?, Some(b.k));
    LinkedList "linked-list" Fixed(1), KAndPool, Some(LinkedLists),
        "Per-pixel linked lists (node counter, head exchange), the resolve keeping the first `--k` nodes (the most recent: Vulkan-Samples); node pool `--capacity` per pixel, `exact` = the scene's fragments.";
        |b| (LinkedList::new(b.viewport, b.pool, b.k, KeepFirst, b.memory_cap)?, Some(b.k));
    LinkedListNearest "linked-list-nearest" Fixed(1), KAndPool, Some(LinkedLists),
        "Per-pixel linked lists, the resolve keeping the `--k` nearest (nvpro-samples).";
        |b| (LinkedList::new(b.viewport, b.pool, b.k, KeepNearest, b.memory_cap)?, Some(b.k));
    AbufferMasked "abuffer-masked" Fixed(1), Nodes, Some(MaskedNodes),
        "The masked-node A-buffer (the multisampled OIT of Bevy and nvpro-samples): a primitive's samples in a pixel merged into one node with its coverage mask, `--capacity` nodes a pixel (`auto`: its own counting pass of nodes), overflow counted per pixel; resolved per sample.";
        |b| (MaskedABuffer::new(b.pixel_viewport()?, b.samples, b.capacity, b.memory_cap)?, Some(b.capacity));
}

impl SchemeName {
    /// The scheme's catalog entry.
    #[must_use]
    pub fn entry(self) -> &'static Entry {
        // The catalog lists the variants in declaration order (one macro writes both).
        &CATALOG[self as usize]
    }

    /// The scheme's one spelling.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// The scheme spelled `name`, if the catalog has one.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        CATALOG.iter().find(|e| e.name == name).map(|e| e.scheme)
    }

    /// Whether the scheme, sized by `sizing`, needs the scene's per-pixel depth complexity, and
    /// so a counting pass before its capture.
    #[must_use]
    pub fn needs_count_pass(self, sizing: &Sizing) -> bool {
        let k_auto = sizing.k == Count::Auto;
        let capacity_auto = sizing.capacity == Count::Auto;
        match self.entry().storage {
            Storage::Slots(_) => false,
            Storage::K => k_auto,
            Storage::Capacity => capacity_auto,
            Storage::KAndPool => k_auto || capacity_auto,
            Storage::Counted => true,
            Storage::Nodes => capacity_auto,
        }
    }
}

impl std::fmt::Display for SchemeName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

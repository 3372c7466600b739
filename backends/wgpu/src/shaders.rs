//! The schemes as WGSL shaders (`backends/wgpu/schemes/`, each file named after the Rust module
//! in `crates/schemes/src/` that it mirrors) and, per scheme, its passes, the storage
//! buffers they bind and the dump layout those are read back as (the catalog's layout for the
//! scheme, `docs/dump-format.md`).
//!
//! Guarantee: each shader is the Rust module's algorithm step for step (its file's comment says
//! which), on the dump words of `docs/dump-format.md`; every buffer starts at the word the Rust
//! scheme's memory starts at, so the dump's untouched words are the layout's empty markers.

use fragsim_dump::{Dtype, LayoutSpec};
use fragsim_schemes::linked_list::Resolve;

use crate::device::GpuError;

/// `common.wgsl`: parameters, the planted bugs' constant, the two vertex stages and the
/// fragment, prepended to every scheme.
pub const COMMON: &str = include_str!("../schemes/common.wgsl");
const ABUFFER: &str = include_str!("../schemes/abuffer.wgsl");
const MDTS: &str = include_str!("../schemes/mdts.wgsl");
const KBUFFER: &str = include_str!("../schemes/kbuffer.wgsl");
const LINKED_LIST: &str = include_str!("../schemes/linked_list.wgsl");
const KBUFFER_SPINLOCK: &str = include_str!("../schemes/kbuffer_spinlock.wgsl");
const SAMPLE_COUNTS: &str = include_str!("../schemes/sample_counts.wgsl");
const ABUFFER_SAMPLES: &str = include_str!("../schemes/abuffer_samples.wgsl");
const MDTS_SAMPLES: &str = include_str!("../schemes/mdts_samples.wgsl");
const LINKED_LIST_SAMPLES: &str = include_str!("../schemes/linked_list_samples.wgsl");

/// The scheme names [`GpuScheme::parse`] accepts (the catalog's names).
pub const NAMES: [&str; 8] = [
    "abuffer",
    "abuffer-exact",
    "mdts",
    "mdts32",
    "kbuffer",
    "linked-list",
    "linked-list-nearest",
    "kbuffer-spinlock-fixed",
];

/// Invocations per workgroup of the per-pixel compute passes (`@workgroup_size(64)`).
pub const PIXEL_WORKGROUP: u32 = 64;

/// A scheme the GPU runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuScheme {
    /// FreePipe's fixed A-buffer: an `atomicAdd` counter and `capacity` slots per pixel, then
    /// the per-pixel sort in a compute pass.
    ABuffer {
        /// Slots per pixel.
        capacity: u32,
    },
    /// The exact A-buffer: a counting pass, a prefix sum in a compute pass, the fill pass into
    /// storage sized from the GPU's own total, then the sort.
    ABufferExact,
    /// MDTS on u64 fragment words (`atomicMin` walk; 64-bit atomics).
    Mdts {
        /// Slots per pixel.
        k: u32,
    },
    /// MDTS on u32 depth keys (FreePipe's Table 1).
    Mdts32 {
        /// Slots per pixel.
        k: u32,
    },
    /// The non-atomic k-buffer (its read–modify–write race).
    Kbuffer {
        /// Slots per pixel.
        k: u32,
    },
    /// Per-pixel linked lists: `atomicAdd` node counter, `atomicExchange` heads.
    LinkedList {
        /// Nodes the resolve keeps.
        k: u32,
        /// Pool nodes per pixel (the pool is this times the pixels, as `fragsim --capacity`).
        pool_per_pixel: u32,
        /// Which nodes the resolve keeps (the dump's scheme name).
        resolve: Resolve,
    },
    /// The k-buffer inside a per-pixel spinlock, the holder's path inside the loop body.
    KbufferSpinlock {
        /// Slots per pixel.
        k: u32,
    },
    /// Not a capture scheme but the counting pass of [`crate::sample_counts`]: one `atomicAdd`
    /// per covered sample of a multisampled target. It has no dump layout: `capture` refuses it
    /// and [`GpuScheme::parse`] does not know it.
    SampleCounts,
}

/// The draw through `per_pixel`, or at `samples` > 1 a pixel through `per_sample` (the entry
/// point of the scheme's `*_samples.wgsl` that shades per sample).
fn draw(per_pixel: &'static str, per_sample: &'static str, samples: u32) -> Pass {
    Pass::Draw(if samples > 1 { per_sample } else { per_pixel })
}

/// A pass of a scheme, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// The geometry drawn through this fragment entry point.
    Draw(&'static str),
    /// One workgroup of this compute entry point.
    ComputeOnce(&'static str),
    /// This compute entry point once per pixel ([`PIXEL_WORKGROUP`] a workgroup).
    ComputePerPixel(&'static str),
}

/// One storage buffer of a scheme: its binding, initial word and the dump array it becomes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Storage {
    /// The binding in `@group(0)`.
    pub binding: u32,
    /// The dump array's name (also the buffer's label).
    pub name: &'static str,
    /// The dump array's element type (u64 words are (low, high) u32 pairs on the GPU).
    pub dtype: Dtype,
    /// The dump array's shape.
    pub shape: Vec<u64>,
    /// Every u32 word's value before the first pass.
    pub initial: u32,
    /// Whether the dump holds it: a k-buffer's lock words are the shader's own business, not
    /// part of the slot layout a dump records.
    pub dumped: bool,
}

impl Storage {
    fn new(binding: u32, name: &'static str, dtype: Dtype, shape: Vec<u64>, initial: u32) -> Self {
        Self {
            binding,
            name,
            dtype,
            shape,
            initial,
            dumped: true,
        }
    }

    /// The storage as working memory the dump leaves out.
    fn working(self) -> Self {
        Self {
            dumped: false,
            ..self
        }
    }

    /// Length in u32 words.
    #[must_use]
    pub fn words(&self) -> u64 {
        let per = match self.dtype {
            Dtype::U32 => 1,
            Dtype::U64 => 2,
        };
        self.shape.iter().product::<u64>() * per
    }
}

impl GpuScheme {
    /// The scheme called `name`, with `k` MDTS/k-buffer slots or linked-list nodes kept, and
    /// `capacity` A-buffer slots or linked-list pool nodes per pixel.
    ///
    /// # Errors
    /// An unknown name (the message lists [`NAMES`]) or zero slots.
    pub fn parse(name: &str, k: u32, capacity: u32) -> Result<Self, GpuError> {
        let list = |resolve| Self::LinkedList {
            k,
            pool_per_pixel: capacity,
            resolve,
        };
        let scheme = match name {
            "abuffer" => Self::ABuffer { capacity },
            "abuffer-exact" => Self::ABufferExact,
            "mdts" => Self::Mdts { k },
            "mdts32" => Self::Mdts32 { k },
            "kbuffer" => Self::Kbuffer { k },
            "linked-list" => list(Resolve::KeepFirst),
            "linked-list-nearest" => list(Resolve::KeepNearest),
            "kbuffer-spinlock-fixed" => Self::KbufferSpinlock { k },
            _ => {
                return Err(GpuError::Refused(format!(
                    "unknown scheme {name:?}: the wgpu backend has {}",
                    NAMES.join(", ")
                )))
            }
        };
        let sizes = [scheme.k(), scheme.capacity(), scheme.pool_per_pixel()];
        if sizes.contains(&Some(0)) {
            return Err(GpuError::Refused(format!(
                "{name}: slots, nodes kept and pool nodes per pixel must be at least 1"
            )));
        }
        Ok(scheme)
    }

    /// The scheme's name ([`NAMES`]).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::ABuffer { .. } => "abuffer",
            Self::ABufferExact => "abuffer-exact",
            Self::Mdts { .. } => "mdts",
            Self::Mdts32 { .. } => "mdts32",
            Self::Kbuffer { .. } => "kbuffer",
            Self::LinkedList {
                resolve: Resolve::KeepFirst,
                ..
            } => "linked-list",
            Self::LinkedList {
                resolve: Resolve::KeepNearest,
                ..
            } => "linked-list-nearest",
            Self::KbufferSpinlock { .. } => "kbuffer-spinlock-fixed",
            Self::SampleCounts => "sample-counts",
        }
    }

    /// The dump's K: MDTS and k-buffer slots, linked-list nodes kept.
    #[must_use]
    pub fn k(&self) -> Option<u32> {
        match *self {
            Self::Mdts { k }
            | Self::Mdts32 { k }
            | Self::Kbuffer { k }
            | Self::KbufferSpinlock { k }
            | Self::LinkedList { k, .. } => Some(k),
            Self::ABuffer { .. } | Self::ABufferExact | Self::SampleCounts => None,
        }
    }

    /// The dump's capacity (the fixed A-buffer).
    #[must_use]
    pub fn capacity(&self) -> Option<u32> {
        match *self {
            Self::ABuffer { capacity } => Some(capacity),
            _ => None,
        }
    }

    fn pool_per_pixel(&self) -> Option<u32> {
        match *self {
            Self::LinkedList { pool_per_pixel, .. } => Some(pool_per_pixel),
            _ => None,
        }
    }

    /// Linked lists: the nodes of the pool over `lists` lists (pixels, or (pixel, sample)s).
    #[must_use]
    pub fn pool(&self, lists: u64) -> Option<u64> {
        self.pool_per_pixel().map(|n| u64::from(n) * lists)
    }

    /// The shader's `params.slots`: a pixel's slots (0 where storage is not per pixel).
    #[must_use]
    pub fn slots(&self) -> u32 {
        match self {
            Self::LinkedList { .. } | Self::ABufferExact => 0,
            _ => self.k().or(self.capacity()).unwrap_or(0),
        }
    }

    /// The dump layout's `scheme` (`docs/dump-format.md`), the catalog's for the scheme (what
    /// `fragsim render --dump` writes): both A-buffers are `abuffer`, the linked lists and the
    /// two k-buffers (the catalog's k-buffer slot layout) name themselves; the counting pass,
    /// which writes no dump, its name.
    #[must_use]
    pub fn layout(&self) -> &'static str {
        match self {
            Self::ABuffer { .. } | Self::ABufferExact => "abuffer",
            Self::Mdts { .. } => "mdts",
            Self::Mdts32 { .. } => "mdts32",
            Self::LinkedList { .. }
            | Self::Kbuffer { .. }
            | Self::KbufferSpinlock { .. }
            | Self::SampleCounts => self.name(),
        }
    }

    /// The header's `layout` description, where the layout takes one.
    #[must_use]
    pub fn layout_spec(&self) -> Option<LayoutSpec> {
        match self {
            Self::LinkedList { .. } => Some(LayoutSpec::FRAGSIM_LISTS),
            _ => None,
        }
    }

    /// Whether the dump's lists were sorted on the GPU (the A-buffers' sort pass).
    #[must_use]
    pub fn sorted(&self) -> bool {
        matches!(self, Self::ABuffer { .. } | Self::ABufferExact)
    }

    /// Whether every slot starts at the empty marker (the A-buffers: the dump's `filled`).
    #[must_use]
    pub fn filled(&self) -> bool {
        matches!(self, Self::ABuffer { .. } | Self::ABufferExact)
    }

    /// The dump's `word` field (as `fragsim render --dump` writes it).
    #[must_use]
    pub fn word(&self) -> &'static str {
        match self {
            Self::Mdts32 { .. } => "key",
            _ => "key<<32|prim",
        }
    }

    /// The WGSL file (without [`COMMON`]) of a capture at one sample a pixel.
    #[must_use]
    pub fn source(&self) -> &'static str {
        match self {
            Self::ABuffer { .. } | Self::ABufferExact => ABUFFER,
            Self::Mdts { .. } | Self::Mdts32 { .. } => MDTS,
            Self::Kbuffer { .. } => KBUFFER,
            Self::LinkedList { .. } => LINKED_LIST,
            Self::KbufferSpinlock { .. } => KBUFFER_SPINLOCK,
            Self::SampleCounts => SAMPLE_COUNTS,
        }
    }

    /// The per-sample variant's WGSL file (`*_samples.wgsl`, appended to [`GpuScheme::source`]):
    /// entry points that shade per sample, a list per (pixel, sample); `None` for a scheme without
    /// one (the k-buffers; the counting pass, per sample already).
    #[must_use]
    pub fn per_sample_source(&self) -> Option<&'static str> {
        match self {
            Self::ABuffer { .. } | Self::ABufferExact => Some(ABUFFER_SAMPLES),
            Self::Mdts { .. } | Self::Mdts32 { .. } => Some(MDTS_SAMPLES),
            Self::LinkedList { .. } => Some(LINKED_LIST_SAMPLES),
            Self::Kbuffer { .. } | Self::KbufferSpinlock { .. } | Self::SampleCounts => None,
        }
    }

    /// Whether the scheme captures at `samples` a pixel: every scheme at one, those with a
    /// per-sample variant ([`GpuScheme::per_sample_source`]) and the counting pass at more.
    #[must_use]
    pub fn captures_at(&self, samples: u32) -> bool {
        samples == 1 || *self == Self::SampleCounts || self.per_sample_source().is_some()
    }

    /// The passes before the host reads the storage's size back (the exact A-buffer's counting
    /// pass and prefix sum, over [`GpuScheme::counting_storages`]); empty for the others. At
    /// `samples` > 1 a pixel the draws are the per-sample variant's.
    #[must_use]
    pub fn counting_passes(&self, samples: u32) -> Vec<Pass> {
        match self {
            Self::ABufferExact => vec![
                draw("fs_count", "fs_count_samples", samples),
                Pass::ComputeOnce("cs_prefix"),
            ],
            _ => Vec::new(),
        }
    }

    /// The passes that leave the words the dump holds; at `samples` > 1 a pixel the draws are the
    /// per-sample variant's.
    #[must_use]
    pub fn passes(&self, samples: u32) -> Vec<Pass> {
        match self {
            Self::ABuffer { .. } => vec![
                draw("fs_main", "fs_main_samples", samples),
                Pass::ComputePerPixel("cs_sort_fixed"),
            ],
            Self::ABufferExact => vec![
                draw("fs_exact", "fs_exact_samples", samples),
                Pass::ComputePerPixel("cs_sort_exact"),
            ],
            Self::Mdts { .. } => vec![draw("fs_u64", "fs_u64_samples", samples)],
            Self::Mdts32 { .. } => vec![draw("fs_u32", "fs_u32_samples", samples)],
            Self::LinkedList { .. } => vec![draw("fs_main", "fs_main_samples", samples)],
            // The counting pass shades per sample in its one entry point; the k-buffers have no
            // per-sample variant (`captures_at` refuses them).
            Self::Kbuffer { .. } | Self::KbufferSpinlock { .. } | Self::SampleCounts => {
                vec![Pass::Draw("fs_main")]
            }
        }
    }

    /// The features the shader needs beyond `PRIMITIVE_INDEX`: `mdts.wgsl` declares u64 atomics
    /// whose `atomicMin` returns the old value, so both its entry points need them.
    #[must_use]
    pub fn needs(&self) -> wgpu::Features {
        match self {
            Self::Mdts { .. } | Self::Mdts32 { .. } => {
                wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS
            }
            _ => wgpu::Features::empty(),
        }
    }

    /// The exact A-buffer's counters and offsets over `lists` lists, bound by the counting
    /// passes: the counters count, the prefix sum leaves the offsets (the total last) and the
    /// counters at 0.
    #[must_use]
    pub fn counting_storages(&self, lists: u64) -> Vec<Storage> {
        match self {
            Self::ABufferExact => vec![
                Storage::new(1, "counters", Dtype::U32, vec![lists], 0),
                Storage::new(4, "offsets", Dtype::U32, vec![lists + 1], 0),
            ],
            _ => Vec::new(),
        }
    }

    /// The storage buffers over `pixels` lists (pixels, or the (pixel, sample)s of a per-sample
    /// capture: the layouts are the same over the sample-expanded framebuffer), in the order they
    /// are read back; `total` is the exact A-buffer's slot count (read back after
    /// [`GpuScheme::counting_passes`]).
    #[must_use]
    pub fn storages(&self, pixels: u64, total: u64) -> Vec<Storage> {
        let per_pixel = |k: u32| vec![pixels, u64::from(k)];
        let slots64 = |binding, shape| Storage::new(binding, "slots", Dtype::U64, shape, u32::MAX);
        // The k-buffers: their lock words (zeros; not dumped), then `k` empty slots per pixel,
        // the catalog's k-buffer slot layout.
        let kbuffer = |locks, k: u32| {
            vec![
                Storage::new(5, "locks", Dtype::U32, vec![locks], 0).working(),
                slots64(6, per_pixel(k)),
            ]
        };
        match *self {
            Self::ABuffer { capacity } => vec![
                Storage::new(1, "counters", Dtype::U32, vec![pixels], 0),
                slots64(2, per_pixel(capacity)),
            ],
            Self::ABufferExact => {
                let mut s = self.counting_storages(pixels);
                s.push(slots64(2, vec![total]));
                s
            }
            Self::Mdts { k } => vec![slots64(1, per_pixel(k))],
            // The catalog's render-target k-buffer: three u32 per pixel (its lock, next ticket
            // and last committed ticket: the ROP's ordering, which the CPU models and a fragment
            // shader's plain stores have none of, so the GPU leaves them at 0) before the slots.
            Self::Kbuffer { k } => kbuffer(3 * pixels, k),
            Self::Mdts32 { k } => {
                vec![Storage::new(3, "slots", Dtype::U32, per_pixel(k), u32::MAX)]
            }
            Self::LinkedList { .. } => {
                let pool = self.pool(pixels).unwrap_or(0);
                vec![
                    Storage::new(1, "heads", Dtype::U32, vec![pixels], 0),
                    Storage::new(2, "counter", Dtype::U32, vec![1], 0),
                    Storage::new(3, "next", Dtype::U32, vec![pool], 0),
                    Storage::new(4, "nodes", Dtype::U64, vec![pool], 0),
                ]
            }
            // One lock word per pixel before the slots.
            Self::KbufferSpinlock { k } => kbuffer(pixels, k),
            // A count per list, (pixel, sample) in sample-index order within a pixel; then as
            // many counts of depth-range drops, and as many example depths (sample_counts.wgsl).
            Self::SampleCounts => vec![Storage::new(1, "counts", Dtype::U32, vec![3 * pixels], 0)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_to_its_scheme_and_zero_sizes_are_refused() {
        for name in NAMES {
            assert_eq!(GpuScheme::parse(name, 8, 4).unwrap().name(), name);
        }
        assert!(GpuScheme::parse("abuffer", 8, 0).is_err());
        assert!(GpuScheme::parse("linked-list", 0, 4).is_err());
        let e = GpuScheme::parse("mdts64", 8, 4).unwrap_err();
        assert!(e.to_string().contains("abuffer, abuffer-exact"), "{e}");
    }

    #[test]
    fn per_sample_captures_draw_entry_points_their_variant_defines() {
        // Each draw's entry point is a function of the WGSL the capture compiles: the scheme's
        // file at one sample, its per-sample variant past one (which the k-buffers lack).
        let draws = |passes: Vec<Pass>| -> Vec<&'static str> {
            passes
                .into_iter()
                .filter_map(|p| match p {
                    Pass::Draw(entry) => Some(entry),
                    _ => None,
                })
                .collect()
        };
        let defines = |source: &str, entry: &str| source.contains(&format!("fn {entry}("));
        for name in NAMES {
            let scheme = GpuScheme::parse(name, 8, 4).unwrap();
            let at = |samples| {
                let mut all = scheme.counting_passes(samples);
                all.extend(scheme.passes(samples));
                draws(all)
            };
            for entry in at(1) {
                assert!(defines(scheme.source(), entry), "{name}: {entry}");
            }
            match scheme.per_sample_source() {
                Some(variant) => {
                    assert!(scheme.captures_at(4), "{name}");
                    for entry in at(4) {
                        assert!(defines(variant, entry), "{name} per sample: {entry}");
                        assert!(!defines(scheme.source(), entry), "{name}: {entry} twice");
                    }
                }
                None => assert!(!scheme.captures_at(4) && scheme.captures_at(1), "{name}"),
            }
        }
    }

    #[test]
    fn storages_have_the_shapes_of_their_dump_layouts() {
        let list = GpuScheme::parse("linked-list-nearest", 8, 3).unwrap();
        let shapes: Vec<(&str, Vec<u64>)> = list
            .storages(10, 0)
            .into_iter()
            .map(|s| (s.name, s.shape))
            .collect();
        assert_eq!(
            shapes,
            [
                ("heads", vec![10]),
                ("counter", vec![1]),
                ("next", vec![30]),
                ("nodes", vec![30])
            ]
        );
        let exact = GpuScheme::ABufferExact.storages(10, 17);
        assert_eq!(exact[1].shape, [11]);
        assert_eq!((exact[2].shape.clone(), exact[2].words()), (vec![17], 34));
    }

    #[test]
    fn the_kbuffers_bind_the_catalog_schemes_words_and_dump_its_slot_layout() {
        use fragsim_capture::{Scheme, MEMORY_CAP_DEFAULT};
        use fragsim_catalog::DumpLayout;
        use fragsim_raster::Viewport;
        use fragsim_schemes::kbuffer::spinlock::{KBufferSpinlock, Loop};
        use fragsim_schemes::kbuffer::KBuffer;

        let viewport = Viewport::new(6, 5).unwrap();
        let pixels = viewport.pixels() as u64;
        let words = |s: GpuScheme| -> Vec<(&str, u64, u32, bool)> {
            s.storages(pixels, 0)
                .into_iter()
                .map(|s| (s.name, s.words(), s.initial, s.dumped))
                .collect()
        };
        // The catalog scheme's lock words (zeros, left out of the dump) and its slots (u64 words
        // are two u32 on the GPU; their initial word all ones is u64::MAX).
        let catalog = |l: fragsim_memory::Layout| {
            assert_eq!((l.init32, l.init64, l.table_bytes), (0, u64::MAX, 0));
            vec![
                ("locks", l.words32 as u64, 0, false),
                ("slots", 2 * l.words64 as u64, u32::MAX, true),
            ]
        };
        let kbuffer = KBuffer::new(viewport, 3, MEMORY_CAP_DEFAULT).unwrap();
        assert_eq!(
            words(GpuScheme::Kbuffer { k: 3 }),
            catalog(kbuffer.layout())
        );
        let spinlock = KBufferSpinlock::new(viewport, 3, Loop::Fixed, MEMORY_CAP_DEFAULT).unwrap();
        assert_eq!(
            words(GpuScheme::KbufferSpinlock { k: 3 }),
            catalog(spinlock.layout())
        );
        for s in [
            GpuScheme::Kbuffer { k: 3 },
            GpuScheme::KbufferSpinlock { k: 3 },
        ] {
            assert_eq!(s.layout(), s.name());
            assert_eq!(
                DumpLayout::named(s.layout()),
                Some(DumpLayout::KBufferSlots)
            );
            assert_eq!(s.layout_spec(), None);
            assert_eq!(s.storages(pixels, 0)[1].shape, [pixels, 3]);
        }
    }
}

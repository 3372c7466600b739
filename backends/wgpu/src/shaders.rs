//! The schemes as WGSL fragment shaders (`backends/wgpu/schemes/`, each file named after the
//! Rust module in `crates/capture/src/schemes/` that it mirrors) and, per scheme, the storage
//! buffers its shader binds and the dump layout they are read back as.
//!
//! Guarantee: each shader is the Rust module's algorithm step for step (its file's comment says
//! which), on the dump words of `docs/dump-format.md`; every buffer starts at the layout's empty
//! word, so the dump's empty slots are the layout's empty marker.

use fragsim_oracle::dump::Dtype;

use crate::device::GpuError;

/// `common.wgsl`: parameters, the two vertex stages and the fragment, prepended to every scheme.
pub const COMMON: &str = include_str!("../schemes/common.wgsl");
const ABUFFER: &str = include_str!("../schemes/abuffer.wgsl");
const MDTS: &str = include_str!("../schemes/mdts.wgsl");
const KBUFFER: &str = include_str!("../schemes/kbuffer.wgsl");

/// The scheme names [`GpuScheme::parse`] accepts.
pub const NAMES: [&str; 4] = ["abuffer", "mdts", "mdts32", "kbuffer"];

/// A scheme the GPU runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuScheme {
    /// FreePipe's fixed A-buffer: an `atomicAdd` counter and `capacity` slots per pixel.
    ABuffer {
        /// Slots per pixel.
        capacity: u32,
    },
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
}

/// One storage buffer of a scheme: its binding, size, initial word and dump array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Storage {
    /// The binding in `@group(0)`.
    pub binding: u32,
    /// Its name (labels, messages).
    pub name: &'static str,
    /// Length in u32 words.
    pub words: u64,
    /// Every word's value before the pass.
    pub initial: u32,
    /// The dump array it becomes.
    pub dump_name: &'static str,
    /// The dump array's element type (u64 words are (low, high) u32 pairs on the GPU).
    pub dump_dtype: Dtype,
    /// Whether the array's shape is `[pixels, slots]` (else `[pixels]`).
    pub per_pixel_slots: bool,
}

impl GpuScheme {
    /// The scheme called `name`, with `k` MDTS/k-buffer slots or `capacity` A-buffer slots.
    ///
    /// # Errors
    /// An unknown name (the message lists [`NAMES`]) or zero slots.
    pub fn parse(name: &str, k: u32, capacity: u32) -> Result<Self, GpuError> {
        let scheme = match name {
            "abuffer" => Self::ABuffer { capacity },
            "mdts" => Self::Mdts { k },
            "mdts32" => Self::Mdts32 { k },
            "kbuffer" => Self::Kbuffer { k },
            _ => {
                return Err(GpuError(format!(
                    "unknown scheme {name:?}: the wgpu backend has {}",
                    NAMES.join(", ")
                )))
            }
        };
        if scheme.slots() == 0 {
            return Err(GpuError(format!(
                "{name}: slots per pixel must be at least 1"
            )));
        }
        Ok(scheme)
    }

    /// The scheme's name ([`NAMES`]).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::ABuffer { .. } => "abuffer",
            Self::Mdts { .. } => "mdts",
            Self::Mdts32 { .. } => "mdts32",
            Self::Kbuffer { .. } => "kbuffer",
        }
    }

    /// Slots per pixel.
    #[must_use]
    pub fn slots(&self) -> u32 {
        match *self {
            Self::ABuffer { capacity } => capacity,
            Self::Mdts { k } | Self::Mdts32 { k } | Self::Kbuffer { k } => k,
        }
    }

    /// The dump's K (MDTS layouts).
    #[must_use]
    pub fn k(&self) -> Option<u32> {
        (!matches!(self, Self::ABuffer { .. })).then(|| self.slots())
    }

    /// The dump's capacity (A-buffer).
    #[must_use]
    pub fn capacity(&self) -> Option<u32> {
        matches!(self, Self::ABuffer { .. }).then(|| self.slots())
    }

    /// The dump layout (`docs/dump-format.md`): the k-buffer's sorted array is MDTS's.
    #[must_use]
    pub fn layout(&self) -> &'static str {
        match self {
            Self::ABuffer { .. } => "abuffer",
            Self::Mdts { .. } | Self::Kbuffer { .. } => "mdts",
            Self::Mdts32 { .. } => "mdts32",
        }
    }

    /// The dump's `word` field.
    #[must_use]
    pub fn word(&self) -> &'static str {
        match self {
            Self::Mdts32 { .. } => "key",
            _ => "key<<32|prim",
        }
    }

    /// The WGSL file (without [`COMMON`]).
    #[must_use]
    pub fn source(&self) -> &'static str {
        match self {
            Self::ABuffer { .. } => ABUFFER,
            Self::Mdts { .. } | Self::Mdts32 { .. } => MDTS,
            Self::Kbuffer { .. } => KBUFFER,
        }
    }

    /// The fragment entry point.
    #[must_use]
    pub fn entry_point(&self) -> &'static str {
        match self {
            Self::Mdts { .. } => "fs_u64",
            Self::Mdts32 { .. } => "fs_u32",
            _ => "fs_main",
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

    /// The storage buffers over `pixels` pixels, in the order they are read back.
    #[must_use]
    pub fn storages(&self, pixels: u64) -> Vec<Storage> {
        let slots = pixels * u64::from(self.slots());
        let words64 = |binding, name| Storage {
            binding,
            name,
            words: 2 * slots,
            initial: u32::MAX,
            dump_name: "slots",
            dump_dtype: Dtype::U64,
            per_pixel_slots: true,
        };
        match self {
            Self::ABuffer { .. } => vec![
                Storage {
                    binding: 1,
                    name: "counters",
                    words: pixels,
                    initial: 0,
                    dump_name: "counters",
                    dump_dtype: Dtype::U32,
                    per_pixel_slots: false,
                },
                words64(2, "slots"),
            ],
            Self::Mdts { .. } => vec![words64(1, "words")],
            Self::Kbuffer { .. } => vec![words64(2, "slots")],
            Self::Mdts32 { .. } => vec![Storage {
                binding: 3,
                name: "keys",
                words: slots,
                initial: u32::MAX,
                dump_name: "slots",
                dump_dtype: Dtype::U32,
                per_pixel_slots: true,
            }],
        }
    }
}

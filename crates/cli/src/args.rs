//! Options shared by the subcommands: which scene, seen how, and how schemes are sized.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use fragsim_capture::executors::Executor;
use fragsim_capture::MEMORY_CAP_DEFAULT;
use fragsim_raster::conventions::MAX_SUBPIXEL_BITS;
use fragsim_raster::{Conventions, DepthRange, Scene, VertexPrecision, View, WindowOrigin};

pub use fragsim_catalog::Count;
use fragsim_catalog::Sizing;
use fragsim_dump::{kebab, Encoding, ListNumbering, Payload, SlotOrder};
use fragsim_measure::SchemeSetup;
pub use fragsim_measure::Shard;
pub use fragsim_raster::scene_spec::args::SceneArgs;

/// The rasterization conventions of the view (`docs/semantics.md` §9); the defaults are
/// fragsim's reference.
#[derive(Debug, Clone, Args)]
pub struct ConventionsArgs {
    /// Window origin: `upper-left` (D3D, Vulkan, WebGPU) or `lower-left` (OpenGL), which moves
    /// the fill rule's owner of a shared horizontal edge.
    #[arg(long, value_name = "ORIGIN", default_value = "upper-left", value_parser = kebab::<WindowOrigin>)]
    pub window_origin: WindowOrigin,
    /// Fractional bits of the snapped vertex grid (8, or 4 as older hardware).
    #[arg(long, value_name = "BITS", default_value_t = MAX_SUBPIXEL_BITS, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SUBPIXEL_BITS)))]
    pub subpixel_bits: u32,
    /// Clip-space depth range: `zero-to-one` (D3D, Vulkan) or `minus-one-to-one` (OpenGL).
    #[arg(long, value_name = "RANGE", default_value = "zero-to-one", value_parser = kebab::<DepthRange>)]
    pub depth_range: DepthRange,
    /// Vertex-stage arithmetic: `f64` (fragsim's reference) or `f32` (as a vertex shader).
    #[arg(long, value_name = "PRECISION", default_value = "f64", value_parser = kebab::<VertexPrecision>)]
    pub vertex_precision: VertexPrecision,
    /// Samples a pixel at the standard pattern (1, 2, 4, 8 or 16): above 1 every scheme runs per
    /// sample over the sample-expanded framebuffer (`docs/semantics.md`, "Multisampling"), and a
    /// dump records the count in `scene.conventions.samples`.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub samples: u32,
}

impl ConventionsArgs {
    /// The conventions chosen.
    #[must_use]
    pub fn conventions(&self) -> Conventions {
        Conventions {
            window_origin: self.window_origin,
            subpixel_bits: self.subpixel_bits,
            depth_range: self.depth_range,
            vertex_precision: self.vertex_precision,
            samples: self.samples,
            edge_ties: None,
        }
    }
}

/// `render --dump` and the encoding of its dumps (`docs/dump-format.md`, "Layouts described by
/// the header"): each option goes to the layouts that have its field, the others are written
/// without it (stderr says so).
#[derive(Debug, Clone, Args)]
pub struct DumpArgs {
    /// Also write each scheme's per-pixel words as a dump in `DIR/<scheme>/`.
    #[arg(long = "dump", value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// The slot layouts' order (`mdts`, `mdts32`, `mdts-desc`, `abuffer` with `--capacity`):
    /// `pixel-major` (slot s of pixel p at p·K + s, fragsim's) or `slot-major` (at s·pixels + p,
    /// one image layer per slot).
    #[arg(long, value_name = "ORDER", requires = "dir", value_parser = kebab::<SlotOrder>)]
    pub dump_order: Option<SlotOrder>,
    /// The payload word of slots, list nodes and layers, `DTYPE:DEPTH:SHIFT:PRIM_BITS`: `u64` or
    /// `u32`; `f32`, `unorm24` or `unorm16` depth from bit SHIFT; the primitive id in the low
    /// `PRIM_BITS` bits (fragsim's: `u64:f32:32:32`; a D24 depth over an 8-bit id: `u32:unorm24:8:8`).
    #[arg(long, value_name = "PAYLOAD", requires = "dir", value_parser = str::parse::<Payload>)]
    pub dump_payload: Option<Payload>,
    /// Linked lists' node numbering `NULL:NODE_BASE`: `0:1` (fragsim, nvpro-samples) or
    /// `4294967295:0` (Vulkan-Samples).
    #[arg(long, value_name = "NULL:NODE_BASE", requires = "dir", value_parser = str::parse::<ListNumbering>)]
    pub dump_list_numbering: Option<ListNumbering>,
}

impl DumpArgs {
    /// The encoding asked.
    #[must_use]
    pub fn encoding(&self) -> Encoding {
        Encoding {
            order: self.dump_order,
            payload: self.dump_payload,
            list_numbering: self.dump_list_numbering,
        }
    }
}

/// Says on stderr when `view` of `scene` covers no pixel: the command still runs (and exits 0
/// where its verdicts hold), but its outputs are empty.
pub(crate) fn warn_if_empty(scene: &Scene, view: &View<'_>) {
    if let Some(warning) = scene.empty_view_warning(view) {
        eprintln!("warning: {warning}");
    }
}

/// How schemes are sized and run.
#[derive(Debug, Clone, Args)]
pub struct SchemeArgs {
    /// MDTS (and k-buffer, loop32, layer-counter, linked-list resolve) slots per pixel: FreePipe
    /// allocates 20 (Table 3); `auto` sizes K to the scene's maximum depth complexity by a
    /// counting pass that the scheme's row reports (one more geometry pass, timed).
    #[arg(long, default_value = "20", allow_negative_numbers = true, value_parser = parse_count)]
    pub k: Count,
    /// A-buffer slots per pixel (linked lists: pool nodes per pixel); `auto` (or `exact`) sizes
    /// them to the scene's maximum depth complexity (the linked lists' pool to its fragments) by
    /// a counting pass that the row reports. `abuffer-exact` always sizes each pixel exactly.
    #[arg(long, default_value = "20", allow_negative_numbers = true, value_parser = parse_count)]
    pub capacity: Count,
    /// Executor: serial, parallel, tiled, scheduled (a replayable GPU-like interleaving) or all
    /// (serial, parallel and tiled).
    #[arg(long, value_enum, default_value_t = ExecutorChoice::Parallel)]
    pub executor: ExecutorChoice,
    /// Threads of the parallel executor (default: one per core).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Refuse schemes whose per-pixel storage would exceed this many bytes.
    #[arg(long, default_value_t = MEMORY_CAP_DEFAULT, allow_negative_numbers = true,
          value_parser = parse_bytes)]
    pub memory_cap: u64,
    /// Submit the triangles in the order of this seed's permutation (primitive ids unchanged):
    /// order-independent schemes capture the same lists, order-dependent ones may not.
    #[arg(long, value_name = "SEED")]
    pub shuffle: Option<u64>,
}

impl SchemeArgs {
    /// The setup of the measurements' scheme runs.
    #[must_use]
    pub fn setup(&self) -> SchemeSetup {
        SchemeSetup {
            sizing: self.sizing(),
            executors: self.executors().to_vec(),
            threads: self.threads.map(|t| t as usize),
            shuffle: self.shuffle,
        }
    }

    /// The executors chosen.
    #[must_use]
    pub fn executors(&self) -> &'static [Executor] {
        match self.executor {
            ExecutorChoice::Serial => &[Executor::Serial],
            ExecutorChoice::Parallel => &[Executor::Parallel],
            ExecutorChoice::Tiled => &[Executor::Tiled],
            ExecutorChoice::Scheduled => &[Executor::Scheduled],
            ExecutorChoice::All => &[Executor::Serial, Executor::Parallel, Executor::Tiled],
        }
    }

    /// The sizes chosen.
    #[must_use]
    pub fn sizing(&self) -> Sizing {
        Sizing {
            k: self.k,
            capacity: self.capacity,
            memory_cap: self.memory_cap,
        }
    }
}

fn parse_count(text: &str) -> Result<Count, String> {
    match text {
        "auto" | "exact" => Ok(Count::Auto),
        _ => match text.parse::<u32>() {
            Ok(0) => Err("must be at least 1 (a scheme with 0 slots stores nothing)".into()),
            Ok(n) => Ok(Count::Fixed(n)),
            Err(_) => Err(format!(
                "expected a positive integer, `auto` or `exact`, got {text:?}"
            )),
        },
    }
}

pub(crate) fn parse_bytes(text: &str) -> Result<u64, String> {
    text.parse::<u64>().map_err(|_| match text.parse::<i128>() {
        Ok(n) if n < 0 => format!("a number of bytes cannot be negative, got {n}"),
        _ => format!("expected a number of bytes, got {text:?}"),
    })
}

/// Which executors run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExecutorChoice {
    /// One thread, submission order.
    Serial,
    /// rayon, one logical thread per triangle, std atomics.
    Parallel,
    /// rayon, triangles binned into 32 × 32 pixel tiles, one thread per tile at a time.
    Tiled,
    /// One thread, the scheduled executor's random interleaving of 256 fragments in flight.
    Scheduled,
    /// Serial, parallel and tiled.
    All,
}

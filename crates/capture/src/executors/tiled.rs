//! The tiled executor: triangles binned into screen tiles, each tile's fragments inserted by one
//! thread at a time.
//!
//! Threads inserting into the same cache lines cost more than the atomics themselves; binning
//! triangles into screen tiles so that each tile's pixels are owned by one thread at a time is
//! the known cure (cudaraster, Laine and Karras 2011; Masked Software Occlusion Culling, Hasselgren
//! et al. 2016). A frame runs in two phases:
//! 1. **binning**, in parallel over chunks of triangles: each triangle's pixel bounds
//!    ([`View::pixel_bounds`], `None` for most triangles of a dense mesh, which cover no pixel
//!    centre) list it in every tile they overlap; a counting sort per chunk keeps primitive order
//!    within each tile's list. The geometry is the same in every pass, so a frame bins once.
//! 2. **capture**, one geometry pass after another, in parallel over tiles: a tile's thread scans
//!    its triangles, chunk after chunk, clipped to the tile ([`View::rasterize_each_in`]), and runs
//!    each fragment's walk to its end.
//!
//! Every pixel is written by one thread only, so each pixel sees its fragments in primitive order:
//! the serial executor's order, which FreePipe's per-triangle model can also produce. An atomic
//! scheme's result does not depend on the interleaving (`docs/proof.md`) and a hazard-prone one
//! meets no concurrent writer, so every scheme gives the serial executor's lists here, checked by
//! the tests. The tiled executor changes which interleavings happen, never the result.

use std::ops::Range;
use std::time::Instant;

use fragsim_raster::{PixelRect, View, Viewport};
use rayon::prelude::*;

use super::frame::{rasterize_into, reuse_storage, Counters, Run};
use super::parallel::rayon_frame;
use crate::memory::AtomicMemory;
use crate::scheme::{Scheme, MEMORY_CAP_DEFAULT};

/// Pixels on a side of a tile: 32 × 32 pixels make 256 tiles at 512 × 512, enough to balance 16
/// threads over a model that covers the middle of the screen.
pub const TILE_SIDE: u32 = 32;

/// Triangles per binning work item.
const TRIANGLES_PER_CHUNK: u32 = 16 * 1024;

/// The tiled executor (rayon, std atomics), keeping its storage and bins between frames.
#[derive(Debug, Default)]
pub struct TiledExecutor {
    memory: Option<AtomicMemory>,
    /// The cap on the bytes of storage a frame allocates (`None`: [`MEMORY_CAP_DEFAULT`]); a
    /// frame that needs more is reported [`RunStats::over_cap`](super::RunStats).
    pub memory_cap: Option<u64>,
    chunks: Vec<ChunkBins>,
}

/// One chunk of triangles binned by tile.
#[derive(Debug, Default)]
struct ChunkBins {
    /// Primitive ids, tile after tile, in primitive order within a tile.
    prims: Vec<u32>,
    /// `prims[starts[t]..starts[t + 1]]` is tile `t`'s list.
    starts: Vec<u32>,
    /// The chunk's triangles that cover a pixel centre, with their pixel bounds.
    bounded: Vec<(u32, PixelRect)>,
}

/// The tile grid over a viewport.
#[derive(Clone, Copy, Debug)]
struct Tiles {
    viewport: Viewport,
    columns: u32,
}

impl Tiles {
    fn new(viewport: Viewport) -> Self {
        Self {
            viewport,
            columns: viewport.width.div_ceil(TILE_SIDE),
        }
    }

    fn count(self) -> usize {
        self.columns as usize * self.viewport.height.div_ceil(TILE_SIDE) as usize
    }

    /// The pixels of tile `tile`.
    fn rect(self, tile: usize) -> PixelRect {
        let (column, row) = (tile as u32 % self.columns, tile as u32 / self.columns);
        let last = |index: u32, side: u32| (index * TILE_SIDE + TILE_SIDE - 1).min(side - 1);
        PixelRect {
            x: (column * TILE_SIDE, last(column, self.viewport.width)),
            y: (row * TILE_SIDE, last(row, self.viewport.height)),
        }
    }

    /// The tiles that `rect` overlaps.
    fn overlapped(self, rect: PixelRect) -> impl Iterator<Item = usize> {
        let columns = rect.x.0 / TILE_SIDE..=rect.x.1 / TILE_SIDE;
        let stride = self.columns as usize;
        (rect.y.0 / TILE_SIDE..=rect.y.1 / TILE_SIDE).flat_map(move |row| {
            columns
                .clone()
                .map(move |column| row as usize * stride + column as usize)
        })
    }
}

impl ChunkBins {
    /// Bins the triangles submitted `submitted`-th of `view` ([`View::submitted`]), in submission
    /// order, reusing this chunk's buffers.
    fn bin(&mut self, view: &View<'_>, tiles: Tiles, submitted: Range<u32>) {
        self.bounded.clear();
        self.bounded.extend(
            submitted
                .map(|i| view.submitted(i))
                .filter_map(|prim| view.pixel_bounds(prim).map(|rect| (prim, rect))),
        );
        // Counting sort: counts into `starts[t + 1]`, prefix sums, then a stable scatter that
        // advances `starts[t]` to where tile `t`'s list ends, and a shift back.
        self.starts.clear();
        self.starts.resize(tiles.count() + 1, 0);
        for &(_, rect) in &self.bounded {
            for tile in tiles.overlapped(rect) {
                self.starts[tile + 1] += 1;
            }
        }
        for tile in 0..tiles.count() {
            self.starts[tile + 1] += self.starts[tile];
        }
        self.prims.clear();
        self.prims.resize(self.starts[tiles.count()] as usize, 0);
        for &(prim, rect) in &self.bounded {
            for tile in tiles.overlapped(rect) {
                self.prims[self.starts[tile] as usize] = prim;
                self.starts[tile] += 1;
            }
        }
        self.starts.rotate_right(1);
        self.starts[0] = 0;
    }

    /// Tile `tile`'s triangles, in primitive order.
    fn list(&self, tile: usize) -> &[u32] {
        &self.prims[self.starts[tile] as usize..self.starts[tile + 1] as usize]
    }
}

impl TiledExecutor {
    /// Runs one frame of `scheme` over `view` on the current rayon pool: bins, then every
    /// geometry pass tile by tile, then the post pass.
    pub fn run<S: Scheme>(&mut self, view: &View<'_>, scheme: &S) -> Run {
        let start = Instant::now();
        let memory = reuse_storage(
            &mut self.memory,
            scheme,
            self.memory_cap.unwrap_or(MEMORY_CAP_DEFAULT),
        );
        let tiles = Tiles::new(view.viewport());
        let triangles = view.triangle_count();
        let chunk_count = triangles.div_ceil(TRIANGLES_PER_CHUNK) as usize;
        self.chunks.resize_with(chunk_count, ChunkBins::default);
        self.chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(index, chunk)| {
                let first = index as u32 * TRIANGLES_PER_CHUNK;
                chunk.bin(
                    view,
                    tiles,
                    first..(first + TRIANGLES_PER_CHUNK).min(triangles),
                );
            });
        let chunks = &self.chunks;
        let memory = &*memory;
        let geometry_pass = |pass| {
            (0..tiles.count())
                .into_par_iter()
                .map(|tile| {
                    let rect = tiles.rect(tile);
                    let mut counters = Counters::default();
                    let prims = chunks.iter().flat_map(|chunk| chunk.list(tile)).copied();
                    rasterize_into(view, scheme, memory, pass, prims, rect, &mut counters);
                    counters
                })
                .reduce(Counters::default, Counters::merge)
        };
        rayon_frame(scheme, memory, start, geometry_pass)
    }
}

/// Runs `scheme` over `view` on the tiled executor, on the current rayon pool, on fresh storage.
pub fn run_tiled<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    TiledExecutor::default().run(view, scheme)
}

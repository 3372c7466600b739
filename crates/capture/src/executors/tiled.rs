//! The tiled executor: triangles set up once, binned into screen tiles, each tile's fragments
//! inserted by one thread at a time.
//!
//! Threads inserting into the same cache lines cost more than the atomics themselves; binning
//! triangles into screen tiles so that each tile's pixels are owned by one thread at a time is
//! the known cure (cudaraster, Laine and Karras 2011; Masked Software Occlusion Culling, Hasselgren
//! et al. 2016; llvmpipe's 64-pixel tiles). A frame runs in two phases:
//! 1. **setup and binning**, in parallel over chunks of triangles: each triangle is set up once
//!    ([`View::set_up_each`]: the early rejects drop most triangles of a dense mesh, which cover
//!    no pixel centre, and a survivor becomes the record the scan reads), and each record is
//!    listed in every tile its pixels overlap; a counting sort per chunk keeps submission order
//!    within each tile's list. The geometry is the same in every pass, so a frame sets up and bins
//!    once.
//! 2. **capture**, one geometry pass after another, in parallel over tiles: a tile's thread scans
//!    the part of its records inside the tile ([`View::scan_within`]), chunk after chunk, and runs
//!    each fragment's walk to its end, so that the tile's storage stays in its cache.
//!
//! A scheme whose words are addressed by the pixel's index alone ([`Scheme::tile_local`]: MDTS,
//! the fixed A-buffer) gets its storage laid out by tile (`tiled/storage.rs`): its fragments are
//! numbered tile by tile, so that a tile's words are one contiguous run, and each tile's task
//! resolves the tile's lists as soon as its fragments are in, while its words are in that core's
//! cache; the lists are then put back in screen order. A tile is owned by one core from its
//! capture to its resolve.
//!
//! Every pixel is written by one thread only, so each pixel sees its fragments in primitive order:
//! the serial executor's order, which FreePipe's per-triangle model can also produce. An atomic
//! scheme's result does not depend on the interleaving (`docs/proof.md`) and a hazard-prone one
//! meets no concurrent writer, so every scheme gives the serial executor's lists here, checked by
//! the tests. The tiled executor changes which interleavings happen, never the result.

use std::cell::RefCell;
use std::ops::Range;
use std::time::Instant;

use fragsim_memory::AtomicMemory;
use fragsim_raster::{Fragment, PixelRect, TriangleSetup, View, Viewport};
use rayon::prelude::*;

use super::frame::{self, reuse_storage, walk, Counters, Run};
use super::parallel::rayon_frame;
use crate::post_pass::{resolve_range, Resolved};
use crate::scheme::{Scheme, MEMORY_CAP_DEFAULT};
use crate::walk_input::WalkInput;

mod storage;

use storage::TileStorage;

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

/// One chunk of triangles set up and binned by tile.
#[derive(Debug, Default)]
struct ChunkBins {
    /// The chunk's set-up triangles (pieces, for clipped ones), in submission order.
    setups: Vec<TriangleSetup>,
    /// Indices into `setups`, tile after tile, in submission order within a tile.
    indices: Vec<u32>,
    /// `indices[starts[t]..starts[t + 1]]` is tile `t`'s list.
    starts: Vec<u32>,
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
    #[expect(
        clippy::cast_possible_truncation,
        reason = "tiles are fewer than the viewport's pixels, at most 16384² (Viewport::new)"
    )]
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
    /// Sets up the triangles submitted `submitted`-th of `view` ([`View::submitted`]), in
    /// submission order, and bins them, reusing this chunk's buffers.
    fn bin(&mut self, view: &View<'_>, tiles: Tiles, submitted: Range<u32>) {
        self.setups.clear();
        view.set_up_each(submitted.map(|i| view.submitted(i)), &mut |setup| {
            self.setups.push(setup);
        });
        // Counting sort: counts into `starts[t + 1]`, prefix sums, then a stable scatter that
        // advances `starts[t]` to where tile `t`'s list ends, and a shift back.
        self.starts.clear();
        self.starts.resize(tiles.count() + 1, 0);
        for setup in &self.setups {
            for tile in tiles.overlapped(setup.pixels()) {
                self.starts[tile + 1] += 1;
            }
        }
        for tile in 0..tiles.count() {
            self.starts[tile + 1] += self.starts[tile];
        }
        self.indices.clear();
        self.indices.resize(self.starts[tiles.count()] as usize, 0);
        for (index, setup) in (0_u32..).zip(&self.setups) {
            for tile in tiles.overlapped(setup.pixels()) {
                self.indices[self.starts[tile] as usize] = index;
                self.starts[tile] += 1;
            }
        }
        self.starts.rotate_right(1);
        self.starts[0] = 0;
    }

    /// Tile `tile`'s set-up triangles, in submission order.
    fn list(&self, tile: usize) -> impl Iterator<Item = &TriangleSetup> {
        let indices = &self.indices[self.starts[tile] as usize..self.starts[tile + 1] as usize];
        indices.iter().map(|&index| &self.setups[index as usize])
    }
}

impl TiledExecutor {
    /// Runs one frame of `scheme` over `view` on the current rayon pool: sets up and bins, then
    /// every geometry pass tile by tile, then the post pass.
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
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "chunks start at triangle ids, u32s"
                )]
                let first = index as u32 * TRIANGLES_PER_CHUNK;
                chunk.bin(
                    view,
                    tiles,
                    first..(first + TRIANGLES_PER_CHUNK).min(triangles),
                );
            });
        let chunks = &self.chunks;
        let memory = &*memory;
        if scheme.tile_local() && scheme.pixels() == view.viewport().pixels() {
            return tile_local_frame(view, scheme, memory, tiles, chunks, start);
        }
        let geometry_pass = |pass| {
            (0..tiles.count())
                .into_par_iter()
                .map(|tile| {
                    let mut counters = Counters::default();
                    let fragments = TileFragments {
                        view,
                        tiles,
                        chunks,
                    };
                    fragments.walk(tile, scheme, memory, pass, |pixel| pixel, &mut counters);
                    counters
                })
                .reduce(Counters::default, Counters::merge)
        };
        rayon_frame(scheme, memory, start, geometry_pass)
    }
}

/// What a tile's task scans: the view and its records binned by tile.
#[derive(Clone, Copy)]
struct TileFragments<'a, 'v> {
    view: &'a View<'v>,
    tiles: Tiles,
    chunks: &'a [ChunkBins],
}

impl TileFragments<'_, '_> {
    /// Scans tile `tile`'s records, chunk after chunk, and runs the walk of pass `pass` of each
    /// input gathered from its fragments to its end, each fragment's pixel given to the scheme
    /// as `index(pixel)` (its storage index), counting into `counters`.
    fn walk<S: Scheme>(
        self,
        tile: usize,
        scheme: &S,
        memory: &AtomicMemory,
        pass: u32,
        index: impl Fn(u32) -> u32,
        counters: &mut Counters,
    ) {
        let rect = self.tiles.rect(tile);
        let mut gathering = scheme.gathering();
        let mut run = |input| walk(scheme, memory, pass, input, counters);
        for setup in self.chunks.iter().flat_map(|chunk| chunk.list(tile)) {
            self.view.scan_within(setup, rect, &mut |fragment| {
                let stored = Fragment {
                    pixel: index(fragment.pixel),
                    ..fragment
                };
                S::Input::gather(&mut gathering, stored, &mut run);
            });
        }
        S::Input::flush(&mut gathering, &mut run);
    }
}

/// The frame of a [`Scheme::tile_local`] scheme: its storage numbered tile by tile, each tile's
/// task capturing the tile's fragments and then resolving its lists, the lists put back in
/// screen order after. The pass time includes the tiles' resolves; the resolve time is the
/// assembly in screen order.
fn tile_local_frame<S: Scheme>(
    view: &View<'_>,
    scheme: &S,
    memory: &AtomicMemory,
    tiles: Tiles,
    chunks: &[ChunkBins],
    start: Instant,
) -> Run {
    let resolved = RefCell::new(Vec::new());
    let geometry_pass = |pass| {
        let (counters, lists): (Vec<Counters>, Vec<Resolved>) = (0..tiles.count())
            .into_par_iter()
            .map(|tile| {
                let storage = TileStorage::of(tiles, tile);
                let mut counters = Counters::default();
                let fragments = TileFragments {
                    view,
                    tiles,
                    chunks,
                };
                let index = |pixel| storage.index_of(pixel);
                fragments.walk(tile, scheme, memory, pass, index, &mut counters);
                // A tile no fragment reached holds its storage's initial, empty lists.
                let lists = if counters.fragments == 0 {
                    Resolved::default()
                } else {
                    resolve_range(scheme, memory, storage.indices())
                };
                (counters, lists)
            })
            .unzip();
        *resolved.borrow_mut() = lists;
        counters
            .into_iter()
            .fold(Counters::default(), Counters::merge)
    };
    frame::run(
        scheme,
        memory,
        start,
        rayon::current_num_threads(),
        geometry_pass,
        |_| storage::assemble(scheme, tiles, &resolved.take()),
    )
}

/// Runs `scheme` over `view` on the tiled executor, on the current rayon pool, on fresh storage.
pub fn run_tiled<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    TiledExecutor::default().run(view, scheme)
}

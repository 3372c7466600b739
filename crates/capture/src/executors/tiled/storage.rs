//! Storage laid out by tile: the tiled executor's numbering of pixels, tile after tile, for the
//! schemes whose words are addressed by the pixel's index alone ([`Scheme::tile_local`]), and
//! their lists put back in screen order after each tile resolved its own.
//!
//! A scheme's storage is pixel-major: pixel `p`'s words begin at `p` times its words a pixel.
//! Numbered on the screen (`y · width + x`), a 32 × 32 tile's words are 32 pieces a screen row
//! apart (at 2048² and K = 20, 32 pages of words for one tile). Numbered tile by tile, the same
//! tile's words are one contiguous run (five pages of `u64` words at K = 20), which one thread
//! captures, resolves while they are still in its cache, and shares with no other thread but at
//! the run's two ends. The scheme sees nothing of it: its fragments carry the *storage* index
//! in `Fragment::pixel`, and [`TileStorage`] says which storage indices are which screen pixels.
//!
//! The numbering: tiles in screen order (row of tiles after row of tiles), each tile's pixels
//! row-major within it. Every tile of a row of tiles has that row's height, so tile `(c, r)`
//! begins at `32 · r · width + height_r · 32 · c` and the numbering is a bijection of
//! `0..width · height` whatever the viewport's size (the last column and row of tiles may be
//! narrower). Dumps are not written from this executor's memory: they keep their declared,
//! screen-ordered layout.

use std::ops::Range;

use rayon::prelude::*;

use super::{Tiles, TILE_SIDE};
use crate::capture::{Capture, PixelLists};
use crate::post_pass::Resolved;
use crate::scheme::{Promise, Scheme};

/// Where tile `tile`'s pixels lie in storage numbered tile by tile.
#[derive(Clone, Copy, Debug)]
pub(super) struct TileStorage {
    /// The storage index of the tile's first pixel (its top left).
    first: u32,
    /// The tile's first column and row on the screen.
    x0: u32,
    y0: u32,
    /// The tile's width and height in pixels.
    width: u32,
    height: u32,
    /// The screen's width.
    screen_width: u32,
}

impl TileStorage {
    /// Tile `tile` of `tiles`.
    pub(super) fn of(tiles: Tiles, tile: usize) -> Self {
        let rect = tiles.rect(tile);
        let (x0, y0) = (rect.x.0, rect.y.0);
        let (width, height) = (rect.x.1 - x0 + 1, rect.y.1 - y0 + 1);
        Self {
            first: y0 * tiles.viewport.width + height * x0,
            x0,
            y0,
            width,
            height,
            screen_width: tiles.viewport.width,
        }
    }

    /// The storage index of the screen pixel `pixel` (`y · width + x`), which lies in this tile.
    #[inline]
    pub(super) fn index_of(self, pixel: u32) -> u32 {
        let (x, y) = (pixel % self.screen_width, pixel / self.screen_width);
        debug_assert!(
            x >= self.x0 && y >= self.y0,
            "pixel {pixel} outside the tile"
        );
        self.first + (y - self.y0) * self.width + (x - self.x0)
    }

    /// The tile's storage indices: one contiguous run.
    pub(super) fn indices(self) -> Range<usize> {
        self.first as usize..(self.first + self.width * self.height) as usize
    }
}

/// The capture in screen order from `resolved`, each tile's lists resolved over its storage
/// indices ([`TileStorage::indices`], in tile order): each row of tiles, whose pixels are one
/// contiguous run of screen rows, is written in parallel with the others, its rows taken a tile
/// at a time.
pub(super) fn assemble<S: Scheme>(scheme: &S, tiles: Tiles, resolved: &[Resolved]) -> Capture {
    let pixels = scheme.pixels();
    let columns = tiles.columns as usize;
    let width = tiles.viewport.width as usize;
    // Each row of tiles' first entry, and its pixels' share of the offsets.
    let bands: Vec<&[Resolved]> = resolved.chunks(columns).collect();
    let mut firsts = Vec::with_capacity(bands.len());
    let mut total = 0;
    for band in &bands {
        firsts.push(total);
        total += band.iter().map(|tile| tile.entries.len()).sum::<usize>();
    }
    let mut offsets = vec![0; pixels + 1];
    let mut entries = vec![0; total];
    let mut work = Vec::with_capacity(bands.len());
    let (mut rest_offsets, mut rest_entries) = (&mut offsets[1..], entries.as_mut_slice());
    for (row, (band, &first)) in bands.iter().zip(&firsts).enumerate() {
        let height = tiles.rect(row * columns).y.1 as usize + 1 - row * TILE_SIDE as usize;
        let band_entries = band.iter().map(|tile| tile.entries.len()).sum::<usize>();
        let (out_offsets, tail) = rest_offsets.split_at_mut(height * width);
        rest_offsets = tail;
        let (out_entries, entries_tail) = rest_entries.split_at_mut(band_entries);
        rest_entries = entries_tail;
        work.push((*band, first, height, out_offsets, out_entries));
    }
    work.into_par_iter()
        .for_each(|(band, first, height, out_offsets, out_entries)| {
            write_band(band, tiles, first, height, out_offsets, out_entries);
        });
    // Overflow counts only where the promise reads them (as the screen-ordered post pass).
    let overflow = if matches!(scheme.promise(), Promise::All(_)) {
        let mut overflow = vec![0; pixels];
        #[expect(clippy::shadow_unrelated, reason = "each tile's part of `resolved`")]
        for (tile, resolved) in resolved.iter().enumerate() {
            let rect = tiles.rect(tile);
            let tile_width = (rect.x.1 - rect.x.0 + 1) as usize;
            for &(local, count) in &resolved.overflow {
                let (x, y) = (local % tile_width, local / tile_width);
                overflow[(rect.y.0 as usize + y) * width + rect.x.0 as usize + x] = count;
            }
        }
        overflow
    } else {
        Vec::new()
    };
    Capture {
        lists: PixelLists { offsets, entries },
        identity: scheme.identity(),
        keeps: scheme.keeps(overflow),
    }
}

/// Writes the lists of one row of tiles `band` (`height` screen rows, whose entries begin at
/// `first` in the capture): `offsets[i]` is where the list of the band's screen pixel `i` ends,
/// `entries` the band's entries in screen order.
fn write_band(
    band: &[Resolved],
    tiles: Tiles,
    first: usize,
    height: usize,
    offsets: &mut [usize],
    entries: &mut [u64],
) {
    // Per tile, the next of its non-empty lists and where that list begins in its entries.
    let mut cursors = vec![(0_usize, 0_usize); band.len()];
    let widths: Vec<usize> = (0..band.len())
        .map(|column| {
            let rect = tiles.rect(column);
            (rect.x.1 - rect.x.0 + 1) as usize
        })
        .collect();
    let mut written = 0;
    let mut pixel = 0;
    for row in 0..height {
        for ((tile, cursor), &width) in band.iter().zip(&mut cursors).zip(&widths) {
            let segment = &mut offsets[pixel..pixel + width];
            let (row_first, row_end) = (row * width, (row + 1) * width);
            let mut next = 0;
            while let Some(&(local, end)) = tile.ends.get(cursor.0).filter(|e| e.0 < row_end) {
                let list = &tile.entries[cursor.1..end];
                entries[written..written + list.len()].copy_from_slice(list);
                segment[next..local - row_first].fill(first + written);
                written += list.len();
                segment[local - row_first] = first + written;
                next = local - row_first + 1;
                *cursor = (cursor.0 + 1, end);
            }
            segment[next..].fill(first + written);
            pixel += width;
        }
    }
}

#[cfg(test)]
mod tests {
    use fragsim_raster::Viewport;

    use super::*;

    /// The numbering is a bijection of the screen's pixels onto `0..pixels`, each tile's a
    /// contiguous run, on viewports whose sides are and are not multiples of the tile's.
    #[test]
    fn storage_indices_number_every_pixel_once_a_tile_at_a_time() {
        for (width, height) in [(64, 64), (70, 33), (1, 1), (31, 97), (100, 1)] {
            let viewport = Viewport::new(width, height).unwrap();
            let tiles = Tiles::new(viewport);
            let mut seen = vec![false; viewport.pixels()];
            let mut next = 0;
            for tile in 0..tiles.count() {
                let storage = TileStorage::of(tiles, tile);
                assert_eq!(
                    storage.indices().start,
                    next,
                    "tile {tile} follows the last"
                );
                next = storage.indices().end;
                let rect = tiles.rect(tile);
                for y in rect.y.0..=rect.y.1 {
                    for x in rect.x.0..=rect.x.1 {
                        let index = storage.index_of(y * width + x) as usize;
                        assert!(storage.indices().contains(&index));
                        assert!(!seen[index], "{index} twice");
                        seen[index] = true;
                    }
                }
            }
            assert_eq!(next, viewport.pixels());
            assert!(seen.iter().all(|&s| s), "{width} × {height}");
        }
    }
}

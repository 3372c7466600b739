//! The post pass, written once for every executor: each pixel's list read back from memory into a
//! [`Capture`], the empty parts of the frame skipped in bulk.
//!
//! A frame of a real scene covers a fraction of the viewport (the dragon a sixth of a 2048²
//! frame). The pass therefore asks the scheme how many pixels from the current one are empty for
//! certain, and how many from there are to be resolved ([`Scheme::pixel_run`], from the memory's
//! written flags, a page's mask at a time), steps over the first and resolves the others
//! ([`Scheme::resolve_pixel`]). Each range
//! of pixels is resolved into a short record (its entries, the end of each list that is not
//! empty, its non-zero overflow counts), so that the work grows with the pixels the fragments
//! reached; the capture's offsets are then written once, each range's own in parallel, an empty
//! pixel's offset being its predecessor's. The parallel form is FreePipe's post-sort kernel (one
//! GPU thread per pixel), cut into ranges of pixels on the rayon pool.
//!
//! The one import circle left in the crate is this module's with `scheme.rs`: the post pass reads
//! the [`Scheme`] trait, and the trait's default [`Scheme::resolve`] runs the serial form written
//! here. Both are the post pass, one concern; the circle keeps its serial and parallel forms in
//! one implementation instead of a copy in the trait.

use std::ops::Range;

use rayon::prelude::*;

use fragsim_memory::Memory;

use crate::capture::{Capture, PixelLists};
use crate::scheme::{PixelRun, Promise, Scheme};

/// Pixels per rayon work item: a few pages of slots, enough to amortise a task, small enough to
/// balance a frame whose covered pixels gather in a few places.
const PIXELS_PER_TASK: usize = 4096;

/// One range of pixels resolved: what the capture's offsets and entries are assembled from (here,
/// and by the tiled executor from its tiles, `executors/tiled/storage.rs`).
#[derive(Debug, Default)]
pub(crate) struct Resolved {
    /// The range's entries, pixel after pixel.
    pub(crate) entries: Vec<u64>,
    /// For each pixel whose list is not empty, its index within the range and the end of its
    /// list within `entries`, in pixel order.
    pub(crate) ends: Vec<(usize, usize)>,
    /// For each pixel that overflowed, its index within the range and the count.
    pub(crate) overflow: Vec<(usize, u32)>,
}

/// Resolves the pixels of `range`, stepping over those the scheme knows empty.
pub(crate) fn resolve_range<S: Scheme + ?Sized, M: Memory>(
    scheme: &S,
    memory: &M,
    range: Range<usize>,
) -> Resolved {
    let mut resolved = Resolved::default();
    let mut pixel = range.start;
    while pixel < range.end {
        let run = match scheme.pixel_run(memory, pixel, range.end) {
            PixelRun::Empty(pixels) => {
                pixel += pixels;
                continue;
            }
            // At least one pixel, so that the pass moves on whatever the scheme says.
            PixelRun::Resolve(pixels) => pixel..(pixel + pixels.max(1)).min(range.end),
        };
        pixel = run.end;
        #[expect(
            clippy::shadow_unrelated,
            reason = "the loop's pixel walks the run that the cursor `pixel` just passed"
        )]
        for pixel in run {
            let before = resolved.entries.len();
            let over = scheme.resolve_pixel(memory, pixel, &mut resolved.entries);
            if resolved.entries.len() != before {
                resolved
                    .ends
                    .push((pixel - range.start, resolved.entries.len()));
            }
            if over != 0 {
                resolved.overflow.push((pixel - range.start, over));
            }
        }
    }
    resolved
}

/// Writes the offsets of range `resolved`, whose entries start at `base`: `out[i]` is where the
/// list of the range's pixel `i` ends in the capture's entries.
fn write_ends(resolved: &Resolved, base: usize, out: &mut [usize]) {
    let mut next = 0;
    let mut end = base;
    for &(pixel, local_end) in &resolved.ends {
        out[next..pixel].fill(end);
        end = base + local_end;
        out[pixel] = end;
        next = pixel + 1;
    }
    out[next..].fill(end);
}

/// The capture of `scheme`'s `pixels` from the ranges of [`PIXELS_PER_TASK`] pixels `ranges`, in
/// order, each range's offsets and entries written in parallel when `parallel`.
fn assemble<S: Scheme + ?Sized>(scheme: &S, mut ranges: Vec<Resolved>, parallel: bool) -> Capture {
    let pixels = scheme.pixels();
    let mut bases = Vec::with_capacity(ranges.len());
    let mut total = 0;
    for range in &ranges {
        bases.push(total);
        total += range.entries.len();
    }
    // Zeroed allocations (fresh pages from the system at these sizes, not written twice): every
    // offset is written below, and every entry where there is more than one range.
    let mut offsets = vec![0; pixels + 1];
    let entries = if ranges.len() == 1 {
        std::mem::take(&mut ranges[0].entries)
    } else {
        let mut entries = vec![0; total];
        let mut slices = Vec::with_capacity(ranges.len());
        let mut rest = entries.as_mut_slice();
        for range in &ranges {
            let (slice, tail) = rest.split_at_mut(range.entries.len());
            slices.push(slice);
            rest = tail;
        }
        let copy = |(slice, range): (&mut [u64], &Resolved)| slice.copy_from_slice(&range.entries);
        if parallel {
            slices.into_par_iter().zip(&ranges).for_each(copy);
        } else {
            slices.into_iter().zip(&ranges).for_each(copy);
        }
        entries
    };
    let ends = |((out, range), &base): ((&mut [usize], &Resolved), &usize)| {
        write_ends(range, base, out);
    };
    if parallel {
        offsets[1..]
            .par_chunks_mut(PIXELS_PER_TASK)
            .zip(&ranges)
            .zip(&bases)
            .for_each(ends);
    } else {
        offsets[1..]
            .chunks_mut(PIXELS_PER_TASK)
            .zip(&ranges)
            .zip(&bases)
            .for_each(ends);
    }
    // Overflow counts only where the promise reads them: for MDTS they would be a megapixel of
    // zeros.
    let overflow = if matches!(scheme.promise(), Promise::All(_)) {
        let mut overflow = vec![0; pixels];
        for (first, range) in (0..).step_by(PIXELS_PER_TASK).zip(&ranges) {
            for &(pixel, count) in &range.overflow {
                overflow[first + pixel] = count;
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

/// Range `task` of [`PIXELS_PER_TASK`] pixels of `pixels`.
fn task_range(task: usize, pixels: usize) -> Range<usize> {
    task * PIXELS_PER_TASK..((task + 1) * PIXELS_PER_TASK).min(pixels)
}

/// The post pass on one thread (the serial executor's, and [`Scheme::resolve`]'s).
pub(crate) fn resolve_serial<S: Scheme + ?Sized, M: Memory>(scheme: &S, memory: &M) -> Capture {
    let pixels = scheme.pixels();
    let ranges = (0..pixels.div_ceil(PIXELS_PER_TASK))
        .map(|task| resolve_range(scheme, memory, task_range(task, pixels)))
        .collect();
    assemble(scheme, ranges, false)
}

/// The post pass on the current rayon pool, a range of pixels a task.
pub(crate) fn resolve_parallel<S: Scheme, M: Memory + Sync>(scheme: &S, memory: &M) -> Capture {
    let pixels = scheme.pixels();
    let ranges = (0..pixels.div_ceil(PIXELS_PER_TASK))
        .into_par_iter()
        .map(|task| resolve_range(scheme, memory, task_range(task, pixels)))
        .collect();
    assemble(scheme, ranges, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offsets_of_a_range_fill_the_empty_pixels_with_their_predecessors_end() {
        let resolved = Resolved {
            entries: vec![7; 5],
            ends: vec![(1, 2), (2, 3), (5, 5)],
            overflow: Vec::new(),
        };
        let mut out = [0; 7];
        write_ends(&resolved, 10, &mut out);
        assert_eq!(out, [10, 12, 13, 13, 13, 15, 15]);
        let empty = Resolved::default();
        write_ends(&empty, 4, &mut out);
        assert_eq!(out, [4; 7]);
    }
}

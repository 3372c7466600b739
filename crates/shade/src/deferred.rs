//! The deferred attribute pass: what shading a capture needs beyond its words, recomputed or
//! completed per captured entry, the way a GPU application shades from a visibility buffer.
//!
//! - **Normals** ([`cosines`]): each captured entry's interpolated normal, as `|cos θ|` to the
//!   eye, recomputed from its pixel and primitive id (`fragsim_raster::attributes`). Effects that
//!   need normals (Fresnel) take it; the rest skip the pass.
//! - **Primitive ids of key-only captures** ([`complete`]: 32-bit MDTS, peeling and bucket
//!   schemes): a depth key names no colour, so these captures are completed from the oracle's
//!   lists (what rasterizing again gives): the i-th occurrence of a key takes the primitive of
//!   the i-th fragment with that key in canonical order; a key that matches no fragment (a scheme
//!   that invented one) keeps [`UNKNOWN_PRIM`].
//!
//! Why a pass of its own: a scheme is judged on what its words hold, so everything taken from
//! elsewhere is computed here, once, and the judge can report it (entries recomputed, what was
//! completed from the oracle).

use std::borrow::Cow;

use fragsim_capture::{Capture, Identity, PixelLists};
use fragsim_oracle::Oracle;
use fragsim_raster::attributes::Attributes;
use rayon::prelude::*;

/// The primitive id [`complete`] gives a key that matches no fragment of its pixel.
pub const UNKNOWN_PRIM: u32 = u32::MAX;

/// What [`complete`] reports it took from the oracle for a key-only capture.
pub const COMPLETED_PRIMS: &str = "primitive ids (matched by depth key)";

/// One value per entry of per-pixel lists: value `i` of pixel `p` belongs to entry `i` of `p`'s
/// list.
#[derive(Debug, Clone, PartialEq)]
pub struct PerEntry {
    offsets: Vec<usize>,
    values: Vec<f64>,
}

impl PerEntry {
    /// `value(p, entry)` of every entry of `lists` (pixel `p`'s list is `lists(p)`), pixels in
    /// parallel.
    pub fn of<'l>(
        pixels: usize,
        lists: impl Fn(usize) -> &'l [u64] + Sync,
        value: impl Fn(usize, u64) -> f64 + Sync,
    ) -> Self {
        let mut offsets = Vec::with_capacity(pixels + 1);
        offsets.push(0);
        for p in 0..pixels {
            offsets.push(offsets[p] + lists(p).len());
        }
        let values = (0..pixels)
            .into_par_iter()
            .with_min_len(256)
            .flat_map_iter(|p| lists(p).iter().map(move |&e| (p, e)))
            .map(|(p, e)| value(p, e))
            .collect();
        Self { offsets, values }
    }

    /// The value of `entry` in pixel `p`'s list `list` (the first equal entry: equal entries are
    /// the same fragment, with the same value).
    #[must_use]
    pub fn get(&self, list: &[u64], p: usize, entry: u64) -> f64 {
        let i = list.iter().position(|&e| e == entry).unwrap_or(0);
        self.values[self.offsets[p] + i]
    }

    /// Entries with a value.
    #[must_use]
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether no entry has a value.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// The normals' pass over `lists` (entries with a primitive id in the low half): `|cos θ|` of
/// every entry, from its pixel and primitive id, 1 where the primitive does not cover the pixel
/// (an entry no fragment has).
#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new); an entry packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
pub fn cosines<'l>(
    attributes: &Attributes<'_>,
    pixels: usize,
    lists: impl Fn(usize) -> &'l [u64] + Sync,
) -> PerEntry {
    PerEntry::of(pixels, lists, |p, entry| {
        attributes.cosine(entry as u32, p as u32).unwrap_or(1.0)
    })
}

/// The capture with a depth key and a primitive id in every entry, in the capture's order, and
/// what had to be taken from the oracle for it ([`COMPLETED_PRIMS`], or `None`: nothing).
#[must_use]
pub fn complete<'c>(
    capture: &'c Capture,
    oracle: &Oracle,
) -> (Cow<'c, Capture>, Option<&'static str>) {
    match capture.identity {
        // Packed MDTS carries its own (lossy) depth in the high half: shaded as it is.
        Identity::KeyAndPrim | Identity::PrimOnly | Identity::MaskedNodes(_) => {
            (Cow::Borrowed(capture), None)
        }
        Identity::KeyOnly => {
            let entries = (0..capture.pixels())
                .into_par_iter()
                .with_min_len(256)
                .flat_map_iter(|p| prims_of_keys(capture.pixel(p), oracle.pixel(p)))
                .collect();
            let full = Capture {
                lists: PixelLists {
                    offsets: capture.offsets.clone(),
                    entries,
                },
                identity: Identity::KeyAndPrim,
                keeps: capture.keeps.clone(),
            };
            (Cow::Owned(full), Some(COMPLETED_PRIMS))
        }
    }
}

/// Key-only entries to full ones: the i-th occurrence of a key takes the primitive of the i-th
/// fragment with that key in canonical order (`fragments`: the pixel's, sorted).
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn prims_of_keys(list: &[u64], fragments: &[u64]) -> Vec<u64> {
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_by_key(|&i| list[i] >> 32);
    let mut out = vec![0_u64; list.len()];
    let mut previous: Option<(u64, usize)> = None;
    for i in order {
        let key = list[i] >> 32;
        let occurrence = match previous {
            Some((k, n)) if k == key => n + 1,
            _ => 0,
        };
        previous = Some((key, occurrence));
        let first = fragments.partition_point(|&f| f >> 32 < key);
        let prim = fragments
            .get(first + occurrence)
            .filter(|&&f| f >> 32 == key)
            .map_or(UNKNOWN_PRIM, |&f| f as u32);
        out[i] = (key << 32) | u64::from(prim);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_keys_take_their_primitives_in_canonical_order() {
        let fragments = [(5 << 32) | 2, (5 << 32) | 7, (9 << 32) | 1];
        // A capture that kept both fives (in any order) and the nine, and one invented key.
        assert_eq!(
            prims_of_keys(&[9 << 32, 5 << 32, 5 << 32, 6 << 32], &fragments),
            vec![
                (9 << 32) | 1,
                (5 << 32) | 2,
                (5 << 32) | 7,
                (6 << 32) | u64::from(UNKNOWN_PRIM)
            ]
        );
        // A merging scheme that kept one five gets the first.
        assert_eq!(prims_of_keys(&[5 << 32], &fragments), vec![(5 << 32) | 2]);
    }

    #[test]
    fn per_entry_values_are_found_by_pixel_and_entry() {
        let lists: [&[u64]; 3] = [&[10, 20], &[], &[30]];
        let values = PerEntry::of(3, |p| lists[p], |p, e| (p as u64 * 1000 + e) as f64);
        assert_eq!(values.len(), 3);
        assert_eq!(values.get(lists[0], 0, 20), 20.0);
        assert_eq!(values.get(lists[2], 2, 30), 2030.0);
    }
}

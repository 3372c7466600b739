//! The diff of a masked-node capture ([`Identity::MaskedNodes`](fragsim_capture::Identity)):
//! node by node, masks included, counted in sample fragments.
//!
//! The capture's per-sample lists hold each node, keyed by its nearest depth, in the lists of
//! the samples its mask covers; they are read back into node lists
//! ([`MaskedLists::from_per_sample`], which loses nothing) and compared pixel by pixel with the
//! oracle's per-pixel view ([`nodes_per_pixel`]), merged by the oracle's own code. A stored node
//! is right when the reference has a node of its primitive with its depth key and its mask. A
//! pixel is as promised when every stored node is right, its sample lists are sorted, and the
//! nodes it lacks are exactly as many as its capacity drops (`max(0, n − capacity)` of its `n`
//! nodes), the count it reports on its first sample equal to that. The counts are in the unit
//! of the row's other columns, sample fragments: a node counts the samples its mask covers, so
//! that captured + overflow + lost − extra is the oracle's fragments, as on every row.

use fragsim_capture::{Capacity, Capture, Keeps};
use fragsim_capture::{MaskedLists, MaskedNode};

use crate::samples::nodes_per_pixel;
use crate::{Diff, Oracle, PixelMismatch};

impl Oracle {
    /// [`Oracle::diff_with`] of a capture of masked nodes, `samples` a pixel (any tie policy:
    /// a primitive's samples merge into one node whatever their depths).
    pub(super) fn diff_masked_nodes(&self, capture: &Capture, samples: u32) -> Diff {
        let no_overflow = vec![0; capture.pixels()];
        let (capacity, overflow) = match &capture.keeps {
            Keeps::All { capacity, overflow } => (*capacity, overflow.as_slice()),
            // Masked-node storage keeps every node that fits: any other promise is judged as
            // one keeping all, none reported dropped.
            Keeps::Nearest(_) | Keeps::Farthest(_) => (Capacity::Unbounded, &no_overflow[..]),
        };
        let reference = nodes_per_pixel(self.lists(), samples);
        let got = MaskedLists::from_per_sample(samples, capture, overflow);
        let per_pixel = samples as usize;
        let covered = |nodes: &[&MaskedNode]| -> u64 {
            nodes.iter().map(|n| u64::from(n.mask.count_ones())).sum()
        };
        let mut diff = Diff {
            captured: capture.entries.len() as u64,
            ..Diff::default()
        };
        for p in 0..got.pixels() {
            let (expected, stored) = (reference.pixel(p), got.pixel(p));
            let wrong: Vec<&MaskedNode> = stored.iter().filter(|n| !expected.contains(n)).collect();
            let missing: Vec<&MaskedNode> =
                expected.iter().filter(|n| !stored.contains(n)).collect();
            let predicted = capacity.overflow(expected.len());
            let reported = got.overflow[p] as usize;
            diff.reported_overflow += reported as u64;
            let miscounted = reported != capacity.reported_overflow(expected.len());
            let samples_of = p * per_pixel..(p + 1) * per_pixel;
            let misordered = samples_of
                .into_iter()
                .any(|s| capture.pixel(s).windows(2).any(|w| w[0] >= w[1]));
            let as_promised = wrong.is_empty() && missing.len() == predicted && !misordered;
            if as_promised {
                diff.overflowed += covered(&missing);
            } else {
                diff.lost += covered(&missing);
                diff.extra += covered(&wrong);
            }
            diff.misordered_pixels += u64::from(misordered);
            diff.overflow_miscounted_pixels += u64::from(miscounted);
            if !as_promised || miscounted {
                diff.mismatched_pixels += 1;
                if diff.first_mismatches.len() < Diff::EXAMPLES {
                    diff.first_mismatches.push(PixelMismatch {
                        pixel: p,
                        expected: expected.iter().map(|n| n.packed()).collect(),
                        got: stored.iter().map(|n| n.packed()).collect(),
                    });
                }
            }
        }
        diff
    }
}

//! The per-pixel diff of a capture against the oracle: lost, extra and misordered fragments,
//! overflow predicted against overflow reported. The verdicts are drawn from it elsewhere
//! ([`crate::verdict`]).

use fragsim_capture::{Capture, Identity, Keeps};

use crate::{Oracle, Ties};

mod masked_nodes;

impl Oracle {
    /// Compares a capture with this oracle, pixel by pixel, under the capture's promise, with
    /// ties ordered by primitive id ([`Ties::ByPrimitive`]).
    ///
    /// # Panics
    /// If the capture covers a different number of pixels.
    #[must_use]
    pub fn diff(&self, capture: &Capture) -> Diff {
        self.diff_with(capture, Ties::ByPrimitive)
    }

    /// Compares a capture with this oracle under the tie policy `ties`: the oracle's list is
    /// first made what `ties` expects ([`Oracle::expected`]), then cut to the capture's promise
    /// (its `K` nearest entries), and the capture's entries are compared under the same mask.
    /// A [`Identity::PrimOnly`] capture is always compared by primitive sequence, ties by
    /// primitive id.
    ///
    /// # Panics
    /// If the capture covers a different number of pixels.
    #[must_use]
    pub fn diff_with(&self, capture: &Capture, ties: Ties) -> Diff {
        assert_eq!(
            capture.pixels(),
            self.pixels(),
            "capture and oracle cover different viewports"
        );
        if let Identity::MaskedNodes(samples) = capture.identity {
            return self.diff_masked_nodes(capture, samples);
        }
        let mut diff = Diff::default();
        let mask = ties.mask(capture.identity);
        let masks_captured = mask != u64::MAX && capture.identity != Identity::KeyOnly;
        let mut all = Vec::new();
        // Keys and packed words sort in depth order; bare primitive ids do not, so their order is
        // checked against the oracle's sequence instead of by sortedness.
        let sequence_order = capture.identity == Identity::PrimOnly;
        let mut expected = Vec::new();
        let mut got_sorted = Vec::new();
        for p in 0..self.pixels() {
            all.clear();
            let ties = if capture.identity == Identity::PrimOnly {
                Ties::ByPrimitive
            } else {
                ties
            };
            ties.expected(self.pixel(p), mask, &mut all);
            let got = capture.pixel(p);
            expected.clear();
            let mut overflow_miscounted = false;
            let n = all.len();
            let (allowed_missing, exact_list) = match &capture.keeps {
                Keeps::Nearest(k) => {
                    let kept = n.min(*k as usize);
                    expected.extend_from_slice(&all[..kept]);
                    (n - kept, true)
                }
                Keeps::Farthest(k) => {
                    let kept = n.min(*k as usize);
                    expected.extend_from_slice(&all[n - kept..]);
                    (n - kept, true)
                }
                Keeps::All { capacity, overflow } => {
                    expected.extend_from_slice(&all);
                    // The capacity counts fragments as they arrive, before any tie merging.
                    let arrived = self.pixel(p).len();
                    let predicted = capacity.overflow(arrived);
                    let reported = overflow[p] as usize;
                    diff.reported_overflow += reported as u64;
                    overflow_miscounted = reported != capacity.reported_overflow(arrived);
                    (predicted, predicted == 0)
                }
            };
            diff.overflowed += allowed_missing as u64;
            let masked: Vec<u64>;
            let got = if masks_captured {
                masked = got.iter().map(|e| e & mask).collect();
                masked.as_slice()
            } else {
                got
            };
            got_sorted.clear();
            got_sorted.extend_from_slice(got);
            got_sorted.sort_unstable();
            let mut expected_sorted = expected.clone();
            expected_sorted.sort_unstable();
            let (missing, extra) = multiset_difference(&expected_sorted, &got_sorted);
            let misordered = if sequence_order {
                missing == 0 && extra == 0 && got != expected.as_slice()
            } else {
                got.windows(2).any(|w| w[0] > w[1])
            };
            // Where overflow made the kept subset order-dependent, `allowed_missing` of the
            // expected fragments may be absent; any more is a loss.
            let lost = if exact_list {
                missing
            } else {
                missing.saturating_sub(allowed_missing)
            };
            let unexplained_gap = !exact_list && missing < allowed_missing;
            let differs =
                lost > 0 || extra > 0 || misordered || unexplained_gap || overflow_miscounted;
            if overflow_miscounted {
                diff.overflow_miscounted_pixels += 1;
            }
            diff.lost += lost as u64;
            diff.extra += extra as u64;
            if misordered {
                diff.misordered_pixels += 1;
            }
            if differs {
                diff.mismatched_pixels += 1;
                if diff.first_mismatches.len() < Diff::EXAMPLES {
                    diff.first_mismatches.push(PixelMismatch {
                        pixel: p,
                        expected: expected.clone(),
                        got: got.to_vec(),
                    });
                }
            }
            diff.captured += got.len() as u64;
        }
        diff
    }
}

/// `(|a − b|, |b − a|)` for sorted multisets.
fn multiset_difference(a: &[u64], b: &[u64]) -> (usize, usize) {
    let (mut i, mut j, mut only_a, mut only_b) = (0, 0, 0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Equal => {
                i += 1;
                j += 1;
            }
            std::cmp::Ordering::Less => {
                only_a += 1;
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                only_b += 1;
                j += 1;
            }
        }
    }
    (only_a + a.len() - i, only_b + b.len() - j)
}

/// One pixel where a capture differs from the oracle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PixelMismatch {
    /// Row-major pixel index.
    pub pixel: usize,
    /// What the oracle says the scheme should hold (packed, masked to the capture's identity).
    pub expected: Vec<u64>,
    /// What the scheme holds.
    pub got: Vec<u64>,
}

/// How a capture differs from the oracle.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Diff {
    /// Fragments captured.
    pub captured: u64,
    /// Fragments the scheme was not meant to keep: beyond K, or overflowing fixed storage, as
    /// the oracle predicts them from each pixel's fragment count and the scheme's capacity.
    pub overflowed: u64,
    /// The overflow the scheme itself counted (schemes that keep every fragment that fits).
    pub reported_overflow: u64,
    /// Pixels whose counted overflow differs from the oracle's prediction.
    pub overflow_miscounted_pixels: u64,
    /// Fragments the scheme should have kept but did not.
    pub lost: u64,
    /// Fragments captured that the oracle does not have where the scheme should have kept them
    /// (duplicates, corrupted values).
    pub extra: u64,
    /// Pixels whose list is out of canonical order.
    pub misordered_pixels: u64,
    /// Pixels that differ in any way.
    pub mismatched_pixels: u64,
    /// The first few differing pixels.
    pub first_mismatches: Vec<PixelMismatch>,
}

impl Diff {
    /// How many differing pixels are kept as examples.
    pub const EXAMPLES: usize = 8;

    /// Whether the capture is exactly what its scheme promises.
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.mismatched_pixels == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_capture::{Capacity, PixelLists};

    fn oracle_of(lists: &[&[u64]]) -> Oracle {
        let mut all = PixelLists::with_pixels(lists.len());
        for l in lists {
            all.push_pixel(l.iter().copied());
        }
        Oracle { lists: all }
    }

    fn capture_of(lists: &[&[u64]], keeps: Keeps) -> Capture {
        let mut c = Capture::with_pixels(lists.len(), Identity::KeyAndPrim, keeps);
        for l in lists {
            c.push_pixel(l.iter().copied());
        }
        c
    }

    #[test]
    fn diff_names_lost_extra_and_misordered() {
        let oracle = oracle_of(&[&[1, 2, 3], &[4, 5]]);
        let exact = oracle.diff(&capture_of(&[&[1, 2], &[4, 5]], Keeps::Nearest(2)));
        assert!(exact.is_exact());
        assert_eq!(exact.overflowed, 1);
        let lost = oracle.diff(&capture_of(&[&[1], &[4, 5]], Keeps::Nearest(2)));
        assert_eq!((lost.lost, lost.mismatched_pixels), (1, 1));
        let wrong = oracle.diff(&capture_of(&[&[2, 1], &[4, 4]], Keeps::Nearest(2)));
        assert_eq!(
            (
                wrong.misordered_pixels,
                wrong.extra,
                wrong.lost,
                wrong.mismatched_pixels
            ),
            (1, 1, 1, 2)
        );
    }

    #[test]
    fn primitive_sequences_are_compared_in_depth_order() {
        // Pixel 0: prim 9 is nearer (key 1) than prim 4 (key 2).
        let oracle = oracle_of(&[&[(1 << 32) | 9, (2 << 32) | 4]]);
        let mut right = Capture::with_pixels(
            1,
            Identity::PrimOnly,
            Keeps::All {
                capacity: Capacity::Unbounded,
                overflow: vec![0],
            },
        );
        right.push_pixel([9, 4]);
        assert!(oracle.diff(&right).is_exact());
        let mut swapped = Capture::with_pixels(
            1,
            Identity::PrimOnly,
            Keeps::All {
                capacity: Capacity::Unbounded,
                overflow: vec![0],
            },
        );
        swapped.push_pixel([4, 9]);
        let diff = oracle.diff(&swapped);
        assert_eq!(
            (diff.misordered_pixels, diff.lost, diff.mismatched_pixels),
            (1, 0, 1)
        );
    }

    #[test]
    fn tie_policies_change_what_is_expected() {
        let e = |key: u64, prim: u64| key << 32 | prim;
        let oracle = oracle_of(&[&[e(10, 1), e(10, 2), e(30, 3)]]);
        assert_eq!(oracle.expected(0, Ties::ByPrimitive), oracle.pixel(0));
        assert_eq!(
            oracle.expected(0, Ties::KeepDuplicates),
            vec![e(10, 0), e(10, 0), e(30, 0)]
        );
        assert_eq!(
            oracle.expected(0, Ties::MergeEqualDepths),
            vec![e(10, 0), e(30, 0)]
        );
        // Equal depths merged into one, the later primitive's colour kept (loop32).
        let merged = capture_of(&[&[e(10, 2), e(30, 3)]], Keeps::Nearest(2));
        let canonical = oracle.diff(&merged);
        assert_eq!((canonical.lost, canonical.extra), (1, 1));
        assert_eq!(oracle.diff_with(&merged, Ties::KeepDuplicates).lost, 1);
        assert!(oracle.diff_with(&merged, Ties::MergeEqualDepths).is_exact());
        // Both kept, tie in the other order: misordered canonically, fine by key.
        let swapped = capture_of(&[&[e(10, 2), e(10, 1)]], Keeps::Nearest(2));
        assert_eq!(oracle.diff(&swapped).misordered_pixels, 1);
        assert!(oracle.diff_with(&swapped, Ties::KeepDuplicates).is_exact());
    }

    #[test]
    fn overflowing_abuffer_may_keep_any_subset_but_not_lose_more() {
        let oracle = oracle_of(&[&[1, 2, 3]]);
        let two_slots = |overflow: u32| Keeps::All {
            capacity: Capacity::PerPixel(2),
            overflow: vec![overflow],
        };
        let ok = oracle.diff(&capture_of(&[&[1, 3]], two_slots(1)));
        assert!(ok.is_exact());
        assert_eq!(ok.overflowed, 1);
        let bad = oracle.diff(&capture_of(&[&[3]], two_slots(1)));
        assert_eq!(bad.lost, 1);
        assert!(!bad.is_exact());
    }

    #[test]
    fn overflow_counted_wrong_by_one_either_way_is_a_mismatch() {
        let oracle = oracle_of(&[&[1, 2, 3], &[4]]);
        let two_slots = |overflow: Vec<u32>| Keeps::All {
            capacity: Capacity::PerPixel(2),
            overflow,
        };
        for miscount in [vec![0, 0], vec![2, 0], vec![1, 1]] {
            let diff = oracle.diff(&capture_of(&[&[1, 2], &[4]], two_slots(miscount.clone())));
            assert_eq!(diff.overflow_miscounted_pixels, 1, "{miscount:?}");
            assert!(!diff.is_exact());
            // The overflow shown is the oracle's, not the scheme's.
            assert_eq!(diff.overflowed, 1);
        }
        // A scheme that cannot count its overflow must report none; the oracle supplies it.
        let silent = |overflow: Vec<u32>| Keeps::All {
            capacity: Capacity::PerPixelUncounted(2),
            overflow,
        };
        assert!(oracle
            .diff(&capture_of(&[&[2, 3], &[4]], silent(vec![0, 0])))
            .is_exact());
        assert!(!oracle
            .diff(&capture_of(&[&[2, 3], &[4]], silent(vec![1, 0])))
            .is_exact());
        // Missing fewer than the capacity predicts is a mismatch too (storage beyond capacity).
        assert!(!oracle
            .diff(&capture_of(&[&[1, 2, 3], &[4]], two_slots(vec![1, 0])))
            .is_exact());
    }
}

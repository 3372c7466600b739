//! A differing pixel's two lists side by side ([`Example::rows`]), aligned by fragment rather
//! than by index, so that one missing fragment marks one row, not every row after it.

use super::report::{Entry, Example};

/// The most cells of the table [`aligned`] matches two lists with (16 MiB of them).
const ALIGNED_CELLS: usize = 1 << 22;

/// One row of two lists side by side: the reference's entry, the candidate's.
pub type Row<'e> = (Option<&'e Entry>, Option<&'e Entry>);

impl Entry {
    /// Whether two shown entries are the same fragment: the same depth key and primitive.
    #[must_use]
    pub fn same_fragment(&self, other: &Self) -> bool {
        self.key == other.key && self.prim == other.prim
    }
}

impl Example {
    /// The rows of the two lists side by side ([`aligned`]).
    #[must_use]
    pub fn rows(&self) -> Vec<Row<'_>> {
        aligned(&self.reference, &self.candidate)
    }
}

/// The rows of a differing pixel's two lists side by side, aligned by fragment rather than by
/// index: the longest run of fragments both lists hold in the same order is matched row for
/// row; between two matched rows the rest go in depth order, a reference and a candidate entry
/// of the same primitive on one row (a depth that moved), every other entry on a row of its own.
#[must_use]
pub fn aligned<'e>(reference: &'e [Entry], candidate: &'e [Entry]) -> Vec<Row<'e>> {
    let (n, m) = (reference.len(), candidate.len());
    // Lists too long for the table below are merged in depth order alone.
    if (n + 1).saturating_mul(m + 1) > ALIGNED_CELLS {
        let (reference, candidate): (Vec<&Entry>, Vec<&Entry>) =
            (reference.iter().collect(), candidate.iter().collect());
        return unmatched_rows(&reference, &candidate);
    }
    // common[i][j]: the longest common subsequence of reference[i..] and candidate[j..].
    let mut common = vec![vec![0_u32; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            common[i][j] = if reference[i].same_fragment(&candidate[j]) {
                common[i + 1][j + 1] + 1
            } else {
                common[i + 1][j].max(common[i][j + 1])
            };
        }
    }
    let mut rows = Vec::with_capacity(n.max(m));
    let (mut i, mut j) = (0, 0);
    let (mut gap_reference, mut gap_candidate) = (Vec::new(), Vec::new());
    while i < n || j < m {
        if i < n && j < m && reference[i].same_fragment(&candidate[j]) {
            rows.extend(unmatched_rows(&gap_reference, &gap_candidate));
            gap_reference.clear();
            gap_candidate.clear();
            rows.push((Some(&reference[i]), Some(&candidate[j])));
            (i, j) = (i + 1, j + 1);
        } else if j == m || (i < n && common[i + 1][j] >= common[i][j + 1]) {
            gap_reference.push(&reference[i]);
            i += 1;
        } else {
            gap_candidate.push(&candidate[j]);
            j += 1;
        }
    }
    rows.extend(unmatched_rows(&gap_reference, &gap_candidate));
    rows
}

/// The rows of entries neither list matched between two matched rows, merged in depth order: a
/// reference and a candidate entry of the same primitive share a row.
fn unmatched_rows<'e>(reference: &[&'e Entry], candidate: &[&'e Entry]) -> Vec<Row<'e>> {
    let mut rows = Vec::with_capacity(reference.len() + candidate.len());
    let (mut r, mut c) = (reference.iter().peekable(), candidate.iter().peekable());
    loop {
        let row = match (r.peek(), c.peek()) {
            (None, None) => break,
            (Some(&&a), Some(&&b)) if a.prim.is_some() && a.prim == b.prim => {
                (r.next().copied(), c.next().copied())
            }
            (Some(&&a), Some(&&b)) if b.depth < a.depth => (None, c.next().copied()),
            (Some(_), _) => (r.next().copied(), None),
            (None, Some(_)) => (None, c.next().copied()),
        };
        rows.push(row);
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::aligned;
    use crate::verdict::Entry;

    fn entry(key: u32, prim: u32) -> Entry {
        Entry {
            key: format!("{key:08x}"),
            depth: 0.0,
            prim: Some(prim),
        }
    }

    #[test]
    fn one_missing_fragment_marks_one_row() {
        let reference = [entry(1, 0), entry(2, 1), entry(3, 2)];
        let candidate = [entry(1, 0), entry(3, 2)];
        let rows = aligned(&reference, &candidate);
        let unmatched: Vec<usize> = rows
            .iter()
            .enumerate()
            .filter(|(_, row)| row.1.is_none())
            .map(|(i, _)| i)
            .collect();
        assert_eq!(rows.len(), 3, "a row per reference entry");
        assert_eq!(
            unmatched,
            [1],
            "only the missing fragment's row is unmatched"
        );
    }

    #[test]
    fn a_moved_depth_shares_a_row_with_its_primitive() {
        let reference = [entry(1, 0), entry(2, 1)];
        let candidate = [entry(1, 0), entry(5, 1)];
        let rows = aligned(&reference, &candidate);
        assert_eq!(
            rows.len(),
            2,
            "the moved fragment's two entries share a row"
        );
        assert!(
            rows.iter().all(|(a, b)| a.is_some() && b.is_some()),
            "no entry on a row of its own"
        );
    }
}

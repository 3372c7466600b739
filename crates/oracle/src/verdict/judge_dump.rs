//! What the oracle judges of a dump: the format (`fragsim_dump`, below this crate) reads, checks
//! and decodes a dump's words and knows no reference; [`JudgeDump`] compares them with one.
//! A dump's decoded lists and every one of its words are compared with the oracle exactly
//! ([`JudgeDump::compare`]) or within the precision of an f32 vertex stage
//! ([`JudgeDump::compare_within`]); a masked-node dump (`abuffer-masked`) with the per-pixel
//! view of the per-sample oracle
//! ([`SampleOracle::per_pixel`](crate::samples::SampleOracle::per_pixel)).
//!
//! A masked-node dump's nodes are compared as an A-buffer's fragments are ([`compare_with`]:
//! missing, extra, overflow allowed past `capacity` and counted, counters checked), and each
//! stored node's mask against the reference node of its primitive: a mask that differs makes the
//! reference's node missing and the stored one extra ([`JudgeDump::compare_masked`]).
//!
//! Under the precision of an f32 vertex stage ([`JudgeDump::compare_masked_within`]) the nodes
//! are spread over the samples their masks hold and judged per sample by the precision verdict
//! ([`compare_within`]: coverage at each sample, the joint snaps per vertex), by primitive id; a
//! node's key, the nearest of its samples' depths, must lie in the interval that nearest may
//! take: from the least of its samples' lowest keys to the least of their highest.

use std::path::Path;

use fragsim_capture::{Capacity, Capture, Identity, Keeps};
use fragsim_capture::{MaskedLists, MaskedNode};
use fragsim_dump::{Dump, DumpError, WordCheck};

use crate::compare::{compare_with, flags, CompareOptions, Comparison};
use crate::precision::{compare_within, f32_reference, Bounds, Precision};
use crate::{Oracle, PixelMismatch};

/// One stored node whose coverage mask differs from the reference node of its primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WrongMask {
    /// Row-major pixel index.
    pub pixel: usize,
    /// The node's primitive id.
    pub prim: u32,
    /// The reference node's mask.
    pub expected: u32,
    /// The stored node's mask.
    pub got: u32,
}

/// A masked-node dump against the per-pixel view of the per-sample oracle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaskedComparison {
    /// The nodes compared as fragments (`key << 32 | prim`), each wrong mask folded in as a
    /// missing and an extra node of its pixel.
    pub nodes: Comparison,
    /// Every stored node whose mask differs from the reference's, in pixel order.
    pub wrong_masks: Vec<WrongMask>,
}

/// The oracle's comparisons of a dump with a reference: what the verdict runs on a dump
/// candidate ([`super::judge`]), each returning the comparison the verdict reads.
pub trait JudgeDump {
    /// Compares this dump with `reference`: its decoded lists ([`Dump::capture`]) and every one
    /// of its words ([`Dump::check_words`]), with [`compare_with`].
    ///
    /// # Errors
    /// As [`Dump::capture`].
    ///
    /// # Panics
    /// If the dump and the reference cover different numbers of pixels.
    fn compare(
        &self,
        reference: &Oracle,
        options: &CompareOptions<'_>,
    ) -> Result<Comparison, DumpError>;

    /// The dump judged within the precision of an f32 vertex stage ([`f32_reference`] as the
    /// dump stores depth, [`Precision::stored_as`]; every word read with [`Dump::check_words`],
    /// [`compare_within`]), with the bounds derived and the
    /// reference's covered pixels (what the ambiguous pixels are a share of).
    ///
    /// # Errors
    /// As [`f32_reference`] and [`Dump::capture`].
    fn compare_within(
        &self,
        beside: Option<&Path>,
        options: &CompareOptions<'_>,
    ) -> Result<(Comparison, Bounds, u64), DumpError>;

    /// Compares this masked-node dump with `reference` (the per-pixel view of the per-sample
    /// oracle, [`SampleOracle::per_pixel`](crate::samples::SampleOracle::per_pixel)): the nodes as
    /// an A-buffer's fragments with every word checked ([`compare_with`]), then each stored
    /// node's mask against the reference node of its primitive in the pixel. A wrong mask makes
    /// the reference node missing and the stored one extra: the pixel is
    /// [`flags::MISSING`] and [`flags::EXTRA`], and each such node counts one lost and one
    /// extra fragment.
    ///
    /// # Errors
    /// As [`Dump::masked_lists`], or a reference of another number of pixels or samples.
    fn compare_masked(
        &self,
        reference: &MaskedLists,
        options: &CompareOptions<'_>,
    ) -> Result<MaskedComparison, DumpError>;

    /// Judges this masked-node dump within the precision of an f32 vertex stage: `precision` and
    /// `reference` are the per-sample analysis and oracle of the dump's view
    /// ([`f32_reference`](crate::precision::f32_reference) of a scene declaring the dump's
    /// sample count). Each node stands for its primitive at every sample its mask holds; those
    /// per-sample lists, by primitive id, go through [`compare_within`] (a sample a node wrongly
    /// covers or leaves out is extra or missing there, ambiguous only where coverage at that
    /// sample is undecided under the joint snaps). A node's key is the nearest of its samples'
    /// depths, so it must lie from the least `key_lo` to the least `key_hi` of its primitive's
    /// possibilities at the samples of its mask: a key outside makes the node's first sample
    /// [`flags::MISSING`] and [`flags::EXTRA`] (one lost and one extra fragment). Corrupt
    /// words are charged to their pixel's first sample. The verdicts are per sample
    /// (`pixels × samples`, sample `s` of pixel `p` at `p · samples + s`); `wrong_masks` is empty
    /// (a wrong mask is judged per sample).
    ///
    /// # Errors
    /// As [`Dump::masked_lists`]; an analysis or oracle of another number of samples; a pixel
    /// whose nodes overflowed its capacity (which samples a dropped node covered is unknowable,
    /// so the dump is judged exactly only, [`JudgeDump::compare_masked`]).
    fn compare_masked_within(
        &self,
        precision: &Precision,
        reference: &Oracle,
        options: &CompareOptions<'_>,
    ) -> Result<MaskedComparison, DumpError>;
}

impl JudgeDump for Dump {
    fn compare(
        &self,
        reference: &Oracle,
        options: &CompareOptions<'_>,
    ) -> Result<Comparison, DumpError> {
        let capture = self.capture()?;
        let words = self.check_words()?;
        Ok(compare_with(reference, &capture, Some(&words), options))
    }

    fn compare_within(
        &self,
        beside: Option<&Path>,
        options: &CompareOptions<'_>,
    ) -> Result<(Comparison, Bounds, u64), DumpError> {
        let (oracle, precision) = f32_reference(&self.header.scene, self.viewport()?, beside)?;
        let precision = precision.stored_as(self.depth_format(), &oracle);
        let capture = self.capture()?;
        let words = self.check_words()?;
        let covered = (0..oracle.pixels())
            .filter(|&p| !oracle.pixel(p).is_empty())
            .count() as u64;
        let comparison = compare_within(&precision, &oracle, &capture, Some(&words), options);
        Ok((comparison, precision.bounds(), covered))
    }

    fn compare_masked(
        &self,
        reference: &MaskedLists,
        options: &CompareOptions<'_>,
    ) -> Result<MaskedComparison, DumpError> {
        let lists = self.masked_lists()?;
        if (reference.pixels(), reference.samples) != (lists.pixels(), lists.samples) {
            return Err(DumpError::Invalid(format!(
                "the reference has {} pixels at {} samples, the dump {} at {}",
                reference.pixels(),
                reference.samples,
                lists.pixels(),
                lists.samples
            )));
        }
        let capture = self.capture()?;
        let words = self.check_words()?;
        let oracle = Oracle::from_capture(&reference.packed_capture(Capacity::Unbounded));
        let mut nodes = compare_with(&oracle, &capture, Some(&words), options);
        let mut wrong_masks = Vec::new();
        for p in 0..lists.pixels() {
            for node in lists.pixel(p) {
                let expected = reference.pixel(p).iter().find(|r| r.prim == node.prim);
                if let Some(&MaskedNode { mask, .. }) = expected.filter(|r| r.mask != node.mask) {
                    wrong_masks.push(WrongMask {
                        pixel: p,
                        prim: node.prim,
                        expected: mask,
                        got: node.mask,
                    });
                }
            }
        }
        let flagged: Vec<(usize, u8)> = wrong_masks
            .iter()
            .map(|w| (w.pixel, flags::MISSING | flags::EXTRA))
            .collect();
        let wrong = wrong_masks.len() as u64;
        nodes.diff.lost += wrong;
        nodes.diff.extra += wrong;
        nodes.add_flags(&flagged, options.examples, |p| PixelMismatch {
            pixel: p,
            expected: oracle.pixel(p).to_vec(),
            got: capture.pixel(p).to_vec(),
        });
        Ok(MaskedComparison { nodes, wrong_masks })
    }

    #[expect(
        clippy::cast_possible_truncation,
        reason = "an entry's low half is its primitive id"
    )]
    fn compare_masked_within(
        &self,
        precision: &Precision,
        reference: &Oracle,
        options: &CompareOptions<'_>,
    ) -> Result<MaskedComparison, DumpError> {
        let lists = self.masked_lists()?;
        let n = lists.samples as usize;
        let samples = lists.pixels() * n;
        if precision.pixels() != samples || reference.pixels() != samples {
            return Err(DumpError::Invalid(format!(
                "the analysis covers {} samples and the reference {}, the dump {} pixels at {n} \
                 samples ({samples})",
                precision.pixels(),
                reference.pixels(),
                lists.pixels()
            )));
        }
        if let Some(p) = (0..lists.pixels()).find(|&p| lists.overflow[p] > 0) {
            return Err(DumpError::Invalid(format!(
                "pixel {p} dropped {} nodes past the capacity: which samples they covered is \
                 unknown, so a masked-node dump that overflowed is judged exactly only",
                lists.overflow[p]
            )));
        }
        let words = self.check_words()?;
        let per_sample_words = WordCheck {
            corrupt: (0..samples)
                .map(|i| {
                    if i % n == 0 {
                        words.corrupt[i / n].clone()
                    } else {
                        Vec::new()
                    }
                })
                .collect(),
            counters: None,
            unchecked: words.unchecked,
            ..WordCheck::default()
        };
        let mut capture = Capture::with_pixels(
            samples,
            Identity::PrimOnly,
            Keeps::All {
                capacity: Capacity::Unbounded,
                overflow: vec![0; samples],
            },
        );
        let mut stray_keys: Vec<(usize, u8)> = Vec::new();
        let mut per_sample: Vec<Vec<u64>> = vec![Vec::new(); samples];
        for p in 0..lists.pixels() {
            for node in lists.pixel(p) {
                let covered: Vec<usize> = (0..n)
                    .filter(|&s| node.mask >> s & 1 == 1)
                    .map(|s| p * n + s)
                    .collect();
                let mut interval: Option<(u32, u32)> = None;
                for &sample in &covered {
                    per_sample[sample].push(node.packed());
                    let possible = precision.pixel(sample).iter().find(|q| q.prim == node.prim);
                    if let Some(q) = possible {
                        interval = Some(interval.map_or((q.key_lo, q.key_hi), |(lo, hi)| {
                            (lo.min(q.key_lo), hi.min(q.key_hi))
                        }));
                    }
                }
                let widen = options.depth_ulps;
                let inside = interval.is_none_or(|(lo, hi)| {
                    node.depth_key >= lo.saturating_sub(widen)
                        && node.depth_key <= hi.saturating_add(widen)
                });
                if let (false, Some(&first)) = (inside, covered.first()) {
                    stray_keys.push((first, flags::MISSING | flags::EXTRA));
                }
            }
        }
        for (sample, mut list) in per_sample.into_iter().enumerate() {
            // A node's place in its pixel is its nearest sample's: at another sample the order
            // owes nothing, so each sample lists its nodes as the analysis orders them there.
            let possible = precision.pixel(sample);
            let lowest = |w: &u64| {
                possible
                    .iter()
                    .find(|q| q.prim == *w as u32)
                    .map_or(u32::MAX, |q| q.key_lo)
            };
            list.sort_by_key(|w| (lowest(w), *w));
            capture.push_pixel(list);
        }
        let mut nodes = compare_within(
            precision,
            reference,
            &capture,
            Some(&per_sample_words),
            options,
        );
        let stray = stray_keys.len() as u64;
        nodes.diff.lost += stray;
        nodes.diff.extra += stray;
        nodes.add_flags(&stray_keys, options.examples, |sample| PixelMismatch {
            pixel: sample,
            expected: reference.pixel(sample).to_vec(),
            got: capture.pixel(sample).to_vec(),
        });
        Ok(MaskedComparison {
            nodes,
            wrong_masks: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests;

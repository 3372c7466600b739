//! Judging a backend's [`Output`] against the oracle: the verdict `fragsim compare oracle DUMP`
//! gives, from the same library calls.
//!
//! Guarantee: a dump is decoded by its scheme's own post pass ([`Dump::capture`]), every word is
//! checked against its layout ([`Dump::check_words`]), and the lists are compared with
//! [`compare_within`] under the precision [`Precision::derive`] finds for the view and the vertex
//! stage the backend declares: with [`VertexPrecision::F64`] every bit is owed to the oracle (what
//! `compare oracle DUMP` does by default), with [`VertexPrecision::F32`] the lists are judged
//! within the bounds of an f32 vertex stage against the exact f64 one (what `compare oracle DUMP
//! --vertex-precision f32` does: the case's view is the reference's f64 one, so the oracle built
//! from it is the exact reference [`f32_reference`] builds). Source: `crates/cli/src/compare.rs`.

use fragsim_capture::{Capture, Keeps};
use fragsim_oracle::compare::{CompareOptions, Comparison};
use fragsim_oracle::precision::{compare_within, Precision};
use fragsim_oracle::Oracle;
use fragsim_raster::{Conventions, VertexPrecision, View};

use crate::backend::Output;

#[cfg(doc)]
use fragsim_oracle::{dump::Dump, precision::f32_reference};

/// How many differing pixels a verdict keeps, both lists each.
pub const EXAMPLES: usize = 4;

/// The verdict on `output`, a capture of `view` (built under the reference conventions) by a
/// backend whose vertex stage computes in `vertex_precision`, against `oracle` (built from
/// `view`).
///
/// # Errors
/// A dump of another viewport, or one that cannot be decoded (its message).
pub fn judge(
    view: &View<'_>,
    oracle: &Oracle,
    output: &Output,
    vertex_precision: VertexPrecision,
) -> Result<Comparison, String> {
    let options = CompareOptions {
        examples: EXAMPLES,
        ..CompareOptions::default()
    };
    let conventions = Conventions {
        vertex_precision,
        ..Conventions::REFERENCE
    };
    let precision = Precision::derive(view, &conventions);
    match output {
        Output::Capture(capture) => {
            if capture.pixels() != oracle.pixels() {
                return Err(format!(
                    "the capture covers {} pixels, the case {}",
                    capture.pixels(),
                    oracle.pixels()
                ));
            }
            let comparison = compare_within(&precision, oracle, capture, None, &options);
            Ok(claimed_as_compare_does(comparison, capture))
        }
        Output::Dump(dump) => {
            let viewport = view.viewport();
            let (w, h) = (dump.header.width, dump.header.height);
            if (w, h) != (viewport.width, viewport.height) {
                return Err(format!(
                    "the dump covers {w}x{h} pixels, the case {}x{}",
                    viewport.width, viewport.height
                ));
            }
            let capture = dump.capture().map_err(|e| e.to_string())?;
            let words = dump.check_words().map_err(|e| e.to_string())?;
            let comparison = compare_within(&precision, oracle, &capture, Some(&words), &options);
            Ok(claimed_as_compare_does(comparison, &capture))
        }
    }
}

/// `comparison` with the claimed overflow of a scheme that keeps K nearest (or farthest) set to
/// the overflow its promise allows: such a scheme claims nothing, what lies beyond K is its
/// promise. The exact verdict counts it so (`compare_with`); the precision verdict leaves it at
/// 0, which would break the battery's overflow property on every MDTS pixel past K.
fn claimed_as_compare_does(mut comparison: Comparison, capture: &Capture) -> Comparison {
    if !matches!(capture.keeps, Keeps::All { .. }) {
        comparison.claimed_overflow = comparison.diff.overflowed;
    }
    comparison
}

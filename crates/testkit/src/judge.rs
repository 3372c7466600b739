//! Judging a backend's [`Output`] against the oracle: the verdict `fragsim compare oracle DUMP`
//! gives, by the same call ([`fragsim_oracle::verdict::judge`]).
//!
//! Guarantee: the reference is the oracle of the case's view with the precision
//! [`Reference::of_view`] derives for the vertex stage the backend declares: with
//! [`VertexPrecision::F64`] every bit is owed to the oracle (what `compare oracle DUMP` does by
//! default), with [`VertexPrecision::F32`] the lists are judged within the bounds of an f32 vertex
//! stage against the exact f64 one (what `compare oracle DUMP --vertex-precision f32` does: the
//! case's view is the reference's f64 one). A dump is decoded by its scheme's own post pass and
//! every word is checked against its layout; a capture has no words to check.

use fragsim_oracle::compare::Comparison;
use fragsim_oracle::verdict::{self, Candidate, Options, Reference, VerdictError};
use fragsim_oracle::Oracle;
use fragsim_raster::{VertexPrecision, View};

use crate::backend::Output;

/// How many differing pixels a verdict keeps, both lists each.
pub const EXAMPLES: usize = 4;

/// The verdict on `output`, a capture of `view` (built under the reference conventions) by a
/// backend whose vertex stage computes in `vertex_precision`, against `oracle` (built from
/// `view`).
///
/// # Errors
/// A capture or dump of another viewport, or a dump that cannot be decoded.
pub fn judge(
    view: &View<'_>,
    oracle: &Oracle,
    output: &Output,
    vertex_precision: VertexPrecision,
) -> Result<Comparison, VerdictError> {
    let reference = Reference::of_view(oracle, view, vertex_precision);
    let candidate = match output {
        Output::Capture(capture) => Candidate::Capture(capture),
        Output::Dump(dump) => Candidate::Dump(dump),
    };
    let options = Options {
        depth_ulps: 0,
        examples: EXAMPLES,
    };
    Ok(verdict::judge(&reference, candidate, &options)?.comparison)
}

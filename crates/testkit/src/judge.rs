//! Judging a backend's [`Output`] against the oracle: the verdict `fragsim compare oracle DUMP`
//! gives, from the same library calls.
//!
//! Guarantee: a dump is decoded by its scheme's own post pass ([`Dump::capture`]), every word is
//! checked against its layout ([`Dump::check_words`]), and the lists are compared with
//! [`compare_within`] under the precision [`Precision::derive`] finds for the view and its
//! conventions: what `compare` does with the oracle as the reference and its default flags
//! (`--depth-ulps 0`, the f64 vertex stage). Source: `crates/cli/src/compare.rs`.

use fragsim_oracle::compare::{CompareOptions, Comparison};
use fragsim_oracle::precision::{compare_within, Precision};
use fragsim_oracle::Oracle;
use fragsim_raster::{Conventions, View};

use crate::backend::Output;

#[cfg(doc)]
use fragsim_oracle::dump::Dump;

/// How many differing pixels a verdict keeps, both lists each.
pub const EXAMPLES: usize = 4;

/// The verdict on `output`, a capture of `view`, against `oracle` (built from `view`).
///
/// # Errors
/// A dump of another viewport, or one that cannot be decoded (its message).
pub fn judge(view: &View<'_>, oracle: &Oracle, output: &Output) -> Result<Comparison, String> {
    let options = CompareOptions {
        examples: EXAMPLES,
        ..CompareOptions::default()
    };
    let precision = Precision::derive(view, &Conventions::REFERENCE);
    match output {
        Output::Capture(capture) => {
            if capture.pixels() != oracle.pixels() {
                return Err(format!(
                    "the capture covers {} pixels, the case {}",
                    capture.pixels(),
                    oracle.pixels()
                ));
            }
            Ok(compare_within(&precision, oracle, capture, None, &options))
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
            Ok(compare_within(
                &precision,
                oracle,
                &capture,
                Some(&words),
                &options,
            ))
        }
    }
}

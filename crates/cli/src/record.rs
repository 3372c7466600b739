//! The one output model of `--json` (`docs/json-schema.md`): every command prints JSON Lines,
//! one flat record per line. The records and their context are `fragsim_measure::record`'s; this
//! module prints them.

use fragsim_catalog::Sizing;
use serde::Serialize;

use crate::args::SchemeArgs;
pub use fragsim_measure::record::{line, Context, Slots};

/// Prints one record of kind `record` on stdout, as one line of JSON.
///
/// # Errors
/// The record cannot be serialised (a map with non-string keys: a bug).
pub fn emit<T: Serialize>(
    record: &'static str,
    context: &Context,
    fields: &T,
) -> Result<(), String> {
    outln!("{}", line(record, context, fields)?);
    Ok(())
}

/// `--k` and `--capacity` as a record's context carries them ([`Context::sized`]).
impl From<&SchemeArgs> for Sizing {
    fn from(schemes: &SchemeArgs) -> Self {
        schemes.sizing()
    }
}

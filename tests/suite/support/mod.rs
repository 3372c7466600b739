//! Helpers shared by the suites of this binary (`crate::support`).
//!
//! - [`strategies`]: proptest strategies for viewports, orbit cameras, procedural scenes, random
//!   and closed meshes, planar tilings, capacities `K` and depths (`fragsim_testkit::strategies`,
//!   re-exported so that the suites keep their `crate::support::strategies` paths).
//! - [`json_lines`]: the records of a `--json` output (`docs/json-schema.md`).

pub use fragsim_testkit::strategies;

/// The records of a `--json` output, one JSON object a line (`docs/json-schema.md`); panics
/// naming the line that is not one.
pub fn json_lines(stdout: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|line| {
            let record: serde_json::Value = serde_json::from_str(line)
                .unwrap_or_else(|e| panic!("not a JSON line ({e}): {line}"));
            assert!(record.is_object(), "not a record: {line}");
            record
        })
        .collect()
}

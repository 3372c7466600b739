//! Helpers shared by the suites of this binary (`crate::support`).
//!
//! - [`strategies`]: proptest strategies for viewports, orbit cameras, procedural scenes, random
//!   and closed meshes, planar tilings, capacities `K` and depths (`fragsim_testkit::strategies`,
//!   re-exported so that the suites keep their `crate::support::strategies` paths).
//! - [`json_lines`]: the records of a `--json` output (`docs/json-schema.md`).
//! - [`scratch`]: a fresh directory for a test's files.
//! - [`prim_of`]: the primitive id of a packed entry.
//! - [`run_on`]: one frame of a scheme on any executor, on fresh storage.
//! - [`fragments`]: every fragment of a view, in submission order.

pub(crate) use fragsim_testkit::strategies;

/// The records of a `--json` output, one JSON object a line (`docs/json-schema.md`); panics
/// naming the line that is not one.
pub(crate) fn json_lines(stdout: &[u8]) -> Vec<serde_json::Value> {
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

/// A fresh, empty directory `GROUP/NAME` under cargo's per-test-target temporary directory, where
/// a test writes its files: emptied first, so that nothing of an earlier run is read back.
pub(crate) fn scratch(group: &str, name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(group)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The primitive id of a packed entry (a depth key over a primitive id in one u64): its low 32
/// bits, the depth key above them dropped.
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry packs its primitive id in the low 32 bits; keeping just those is the point"
)]
pub(crate) const fn prim_of(entry: u64) -> u32 {
    entry as u32
}

/// One frame of `scheme` on `executor`, on the fresh storage of that executor's `run_*`;
/// `schedule` is the scheduled executor's.
pub(crate) fn run_on<S: fragsim::capture::Scheme>(
    executor: fragsim::capture::executors::Executor,
    view: &fragsim::raster::View<'_>,
    scheme: &S,
    schedule: &fragsim::capture::executors::scheduled::Schedule,
) -> fragsim::capture::executors::Run {
    use fragsim::capture::executors::{run_parallel, run_serial, run_tiled, Executor};
    match executor {
        Executor::Serial => run_serial(view, scheme),
        Executor::Parallel => run_parallel(view, scheme),
        Executor::Tiled => run_tiled(view, scheme),
        Executor::Scheduled => {
            fragsim::capture::executors::scheduled::run_scheduled(view, scheme, schedule, false).run
        }
    }
}

/// Every fragment of `view`, in submission order (triangle after triangle, each in its scan
/// order).
pub(crate) fn fragments(view: &fragsim::raster::View<'_>) -> Vec<fragsim::raster::Fragment> {
    let mut all = Vec::new();
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| all.push(f));
    }
    all
}

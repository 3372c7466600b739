//! The baselines table (`docs/baselines/kbuffer.md`): passes and losses of the catalog's k-buffer
//! schemes and of the stencil-routed A-buffer on the serial, parallel and scheduled executors,
//! each run diffed against the oracle.
//!
//! Why: the k-buffer family trades passes for exactness, and the table shows where each one
//! loses (only under concurrent hazards) and what its exactness costs. The schemes come from the
//! catalog ([`fragsim_catalog::CATALOG`]): the k-buffer entries on the machines asked for,
//! built by their catalog constructors, and `srab` at every pass count its catalog entry allows.

use fragsim_capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::executors::{run_parallel, run_serial, Executor, Run};
use fragsim_capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim_catalog::{Build, SchemeName, SchemeVisitor, CATALOG};
use fragsim_oracle::Oracle;
use fragsim_raster::{View, Viewport};
use fragsim_schemes::kbuffer::WriteBack;
use fragsim_schemes::stencil_routed::StencilRouted;
use serde::Serialize;

/// One (scheme, executor) run of the table.
#[derive(Debug, Clone, Serialize)]
pub struct BaselineRow {
    /// `Scheme::name`.
    pub scheme: String,
    /// Slots per pixel (samples per pass for the stencil-routed A-buffer).
    pub k: u32,
    /// The executor.
    pub executor: String,
    /// Geometry passes.
    pub passes: u32,
    /// Fragments the scheme was not meant to keep (beyond K, or counted overflow).
    pub overflowed: u64,
    /// Fragments lost.
    pub lost: u64,
    /// Extra fragments.
    pub extra: u64,
    /// Second and later copies of a fragment in one pixel.
    pub duplicates: u64,
    /// Pixels out of order.
    pub misordered_pixels: u64,
    /// Pixels that differ.
    pub error_pixels: u64,
    /// Bytes of per-pixel storage.
    pub memory_bytes: u64,
}

/// The scheduled executor's runs in the table: the CLI's `--executor scheduled` (uniform
/// random, 256 fragments in flight, seed 0) and lockstep warps of whole triangles (4,096 in
/// flight, seed 1).
pub const BASELINE_SCHEDULES: [(&str, Schedule); 2] = [
    (
        "scheduled random 256",
        Schedule {
            policy: Policy::Random,
            in_flight: 256,
            granularity: Granularity::Fragment,
            seed: 0,
        },
    ),
    (
        "scheduled warps 4096 tri",
        Schedule {
            policy: Policy::Warps,
            in_flight: 4096,
            granularity: Granularity::Triangle,
            seed: 1,
        },
    ),
];

/// A scheme's runs on every executor of the table: serial, parallel, then
/// [`BASELINE_SCHEDULES`], each with its label.
fn runs<S: Scheme>(scheme: &S, view: &View<'_>) -> Vec<(&'static str, Run)> {
    let mut runs = vec![
        (Executor::Serial.name(), run_serial(view, scheme)),
        (Executor::Parallel.name(), run_parallel(view, scheme)),
    ];
    for (label, schedule) in &BASELINE_SCHEDULES {
        runs.push((*label, run_scheduled(view, scheme, schedule, false).run));
    }
    runs
}

/// How a row of the table builds its scheme.
#[derive(Debug, Clone)]
enum Built {
    /// By its catalog entry's constructor, with these sizes.
    Catalog(Build<'static>),
    /// The stencil-routed A-buffer at a pass count below its catalog entry's.
    Srab(StencilRouted),
}

/// One scheme of the table to run: how to build it and the `K` column it shows.
#[derive(Debug, Clone)]
pub struct Baseline {
    /// The catalog's scheme.
    pub name: SchemeName,
    /// Slots per pixel (for `srab`: its slots, 8 a pass; both of its configurations carry the
    /// catalog's one spelling, so this column tells them apart).
    pub k: u32,
    /// The built scheme's [`Scheme::name`].
    pub scheme: String,
    built: Built,
}

/// A built scheme's name: building it checks its parameters and the memory cap.
struct NameOf;

impl SchemeVisitor for NameOf {
    type Output = String;

    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) -> String {
        scheme.name()
    }
}

/// The table's schemes, in its order: for each K of `ks` and each machine of `machines`, the
/// catalog's k-buffer schemes on that machine (catalog order,
/// [`Entry::read_modify_write`](fragsim_catalog::Entry::read_modify_write)); then `srab`
/// at 1 up to the passes of its catalog entry. Multi-pass k-buffers' output lists hold `layers`
/// (the scene's maximum depth complexity, as `render` sizes them).
///
/// # Errors
/// A parameter a scheme refuses (`K = 0`), or storage beyond the default memory cap.
pub fn table(
    viewport: Viewport,
    ks: &[u32],
    machines: &[WriteBack],
    layers: u32,
) -> Result<Vec<Baseline>, String> {
    let mut out = Vec::new();
    for &k in ks {
        for &machine in machines {
            let on_machine = CATALOG
                .iter()
                .filter(|e| e.read_modify_write == Some(machine));
            for entry in on_machine {
                let build = Build::fixed(viewport, k, k, layers, MEMORY_CAP_DEFAULT);
                out.push(Baseline {
                    name: entry.scheme,
                    k,
                    scheme: entry
                        .scheme
                        .build(&build, NameOf)
                        .map_err(|e| e.to_string())?,
                    built: Built::Catalog(build),
                });
            }
        }
    }
    let srab = SchemeName::Srab;
    // `UpTo(n)`: a configuration of every pass count up to n.
    let (_, most) = srab.entry().passes.bounds(1);
    for passes in 1..=most.unwrap_or(1) {
        let scheme =
            StencilRouted::new(viewport, passes, MEMORY_CAP_DEFAULT).map_err(|e| e.to_string())?;
        out.push(Baseline {
            name: srab,
            k: 8 * passes,
            scheme: scheme.name(),
            built: Built::Srab(scheme),
        });
    }
    Ok(out)
}

/// The table's rows of one built scheme.
struct Rows<'a, 'v> {
    k: u32,
    view: &'a View<'v>,
    oracle: &'a Oracle,
}

impl SchemeVisitor for Rows<'_, '_> {
    type Output = Vec<BaselineRow>;

    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) -> Vec<BaselineRow> {
        runs(scheme, self.view)
            .into_iter()
            .map(|(executor, run)| {
                let diff = self.oracle.diff(&run.capture);
                BaselineRow {
                    scheme: scheme.name(),
                    k: self.k,
                    executor: executor.into(),
                    passes: run.stats.passes,
                    overflowed: diff.overflowed,
                    lost: diff.lost,
                    extra: diff.extra,
                    duplicates: run.capture.duplicates(),
                    misordered_pixels: diff.misordered_pixels,
                    error_pixels: diff.mismatched_pixels,
                    memory_bytes: run.stats.memory_bytes,
                }
            })
            .collect()
    }
}

/// The table's rows of `baseline`: one per executor, each run diffed against `oracle`.
///
/// # Errors
/// A parameter the scheme refuses (`K = 0`), or storage beyond the default memory cap.
pub fn rows(
    baseline: &Baseline,
    view: &View<'_>,
    oracle: &Oracle,
) -> Result<Vec<BaselineRow>, String> {
    let rows = Rows {
        k: baseline.k,
        view,
        oracle,
    };
    match &baseline.built {
        Built::Catalog(build) => baseline.name.build(build, rows).map_err(|e| e.to_string()),
        Built::Srab(scheme) => Ok(rows.visit(scheme, None)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_raster::{OrbitCamera, Scene};

    #[test]
    fn the_table_lists_the_catalogs_kbuffers_per_k_and_machine_then_srab_per_pass() {
        let viewport = Viewport::new(8, 8).unwrap();
        let machines = [WriteBack::RenderTarget, WriteBack::SeparateStores];
        let table = table(viewport, &[2, 4], &machines, 3).unwrap();
        let listed: Vec<(&str, u32)> = table.iter().map(|b| (b.name.name(), b.k)).collect();
        let kbuffers = |k| {
            [
                ("kbuffer", k),
                ("kbuffer-multipass", k),
                ("kbuffer-stores", k),
                ("kbuffer-multipass-stores", k),
            ]
        };
        let mut expected = [kbuffers(2), kbuffers(4)].concat();
        expected.extend([("srab", 8), ("srab", 16)]);
        assert_eq!(listed, expected);
        // Each built scheme is the catalog's: the same spelling.
        assert!(table.iter().all(|b| b.scheme == b.name.name()));
        // One machine only: its k-buffers.
        let one = super::table(viewport, &[2], &machines[1..], 3).unwrap();
        assert_eq!(one.len(), 2 + 2);
        assert!(super::table(viewport, &[0], &machines, 3).is_err());
    }

    #[test]
    fn every_executor_gives_a_row_and_the_serial_kbuffer_loses_nothing() {
        let scene = Scene::procedural("quads:3").unwrap();
        let view = scene
            .view(Viewport::new(16, 16).unwrap(), &OrbitCamera::default())
            .unwrap();
        let oracle = Oracle::build(&view);
        let table = table(view.viewport(), &[4], &[WriteBack::RenderTarget], 3).unwrap();
        let rows = rows(&table[0], &view, &oracle).unwrap();
        let executors: Vec<&str> = rows.iter().map(|r| r.executor.as_str()).collect();
        assert_eq!(
            executors,
            [
                "serial",
                "parallel",
                "scheduled random 256",
                "scheduled warps 4096 tri"
            ]
        );
        assert_eq!(
            (rows[0].lost, rows[0].error_pixels, rows[0].passes),
            (0, 0, 1)
        );
        assert!(rows.iter().all(|r| r.scheme == "kbuffer" && r.k == 4));
    }
}

//! The baselines table (`docs/baselines/kbuffer.md`): passes and losses of the catalog's k-buffer
//! schemes and of the stencil-routed A-buffer on the serial, parallel and scheduled executors,
//! each run diffed against the oracle.
//!
//! Why: the k-buffer family trades passes for exactness, and the table shows where each one
//! loses (only under concurrent hazards) and what its exactness costs. The schemes come from the
//! catalog ([`fragsim_capture::catalog::CATALOG`]): the entries [`kbuffer_scheme`] builds, on the
//! machines asked for, and `srab` at every pass count its catalog entry allows.

use fragsim_capture::catalog::{SchemeName, CATALOG};
use fragsim_capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::executors::{run_parallel, run_serial, Executor, Run};
use fragsim_capture::schemes::kbuffer::{KBuffer, WriteBack};
use fragsim_capture::schemes::kbuffer_multipass::KBufferMultipass;
use fragsim_capture::schemes::stencil_routed::StencilRouted;
use fragsim_capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim_oracle::Oracle;
use fragsim_raster::{View, Viewport};
use serde::Serialize;

use crate::hazard::duplicates;

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

/// A scheme behind a vtable, run on every executor of the table.
pub trait MeasuredScheme {
    /// `Scheme::name`.
    fn name(&self) -> String;
    /// Its runs on `view`: serial, parallel, then [`BASELINE_SCHEDULES`], each with its label.
    fn runs(&self, view: &View<'_>) -> Vec<(&'static str, Run)>;
}

impl<S: Scheme> MeasuredScheme for S {
    fn name(&self) -> String {
        Scheme::name(self)
    }

    fn runs(&self, view: &View<'_>) -> Vec<(&'static str, Run)> {
        let mut runs = vec![
            (Executor::Serial.name(), run_serial(view, self)),
            (Executor::Parallel.name(), run_parallel(view, self)),
        ];
        for (label, schedule) in &BASELINE_SCHEDULES {
            runs.push((*label, run_scheduled(view, self, schedule, false).run));
        }
        runs
    }
}

/// Catalog scheme `name` as a k-buffer of `k` slots on its own machine
/// ([`SchemeName::write_back`]), multi-pass ones with output lists of `layers`; `None` for a
/// scheme that is no k-buffer.
///
/// # Errors
/// (Inside the `Some`) a parameter the scheme refuses, or storage beyond the default memory cap.
pub fn kbuffer_scheme(
    name: SchemeName,
    viewport: Viewport,
    k: u32,
    layers: u32,
) -> Option<Result<Box<dyn MeasuredScheme>, String>> {
    let machine = name.write_back();
    let built: Result<Box<dyn MeasuredScheme>, _> = match name {
        SchemeName::Kbuffer | SchemeName::KbufferStores => {
            KBuffer::with_write_back(viewport, k, machine, MEMORY_CAP_DEFAULT)
                .map(|s| Box::new(s) as Box<dyn MeasuredScheme>)
        }
        SchemeName::KbufferMultipass | SchemeName::KbufferMultipassStores => {
            KBufferMultipass::with_write_back(viewport, k, layers, machine, MEMORY_CAP_DEFAULT)
                .map(|s| Box::new(s) as Box<dyn MeasuredScheme>)
        }
        _ => return None,
    };
    Some(built.map_err(|e| e.to_string()))
}

/// One scheme of the table to run: how to build it and the `K` column it shows.
pub struct Baseline {
    /// The catalog's scheme.
    pub name: SchemeName,
    /// Slots per pixel (for `srab`: its slots, 8 a pass; both of its configurations carry the
    /// catalog's one spelling, so this column tells them apart).
    pub k: u32,
    /// The scheme, built.
    pub scheme: Box<dyn MeasuredScheme>,
}

/// The table's schemes, in its order: for each K of `ks` and each machine of `machines`, the
/// catalog's k-buffer schemes on that machine (catalog order); then `srab` at 1 up to the
/// passes of its catalog entry. Multi-pass k-buffers' output lists hold `layers` (the scene's
/// maximum depth complexity, as `render` sizes them).
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
            for entry in CATALOG.iter().filter(|e| e.scheme.write_back() == machine) {
                if let Some(scheme) = kbuffer_scheme(entry.scheme, viewport, k, layers) {
                    out.push(Baseline {
                        name: entry.scheme,
                        k,
                        scheme: scheme?,
                    });
                }
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
            scheme: Box::new(scheme),
        });
    }
    Ok(out)
}

/// The table's rows of `baseline`: one per executor, each run diffed against `oracle`.
#[must_use]
pub fn rows(baseline: &Baseline, view: &View<'_>, oracle: &Oracle) -> Vec<BaselineRow> {
    let scheme = &baseline.scheme;
    scheme
        .runs(view)
        .into_iter()
        .map(|(executor, run)| {
            let diff = oracle.diff(&run.capture);
            BaselineRow {
                scheme: scheme.name(),
                k: baseline.k,
                executor: executor.into(),
                passes: run.stats.passes,
                overflowed: diff.overflowed,
                lost: diff.lost,
                extra: diff.extra,
                duplicates: duplicates(&run.capture),
                misordered_pixels: diff.misordered_pixels,
                error_pixels: diff.mismatched_pixels,
                memory_bytes: run.stats.memory_bytes,
            }
        })
        .collect()
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
        assert!(table.iter().all(|b| b.scheme.name() == b.name.name()));
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
        let rows = rows(&table[0], &view, &oracle);
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

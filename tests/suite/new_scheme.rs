//! A scheme written outside fragsim, the way a user adds one: its module is a [`Descriptor`]
//! (name, storage, identity, guarantee, promise, pixels, stated once) and the steps that are its
//! own (`begin`, `step`, `resolve_pixel`). Every executor, the oracle's diff and the scheduled
//! executor's interleavings then take it as they take the catalog's schemes; naming it on the
//! command line is one `catalog!` line more (`crates/catalog/src/lib.rs` says so).
//!
//! The scheme is the far buffer, the z-buffer's mirror: one `atomicMax` per fragment on a word a
//! pixel, which keeps each pixel's farthest fragment (the far layer that dual depth peeling's
//! first pass finds). Its control does the maximum as a load and a store, two steps, which an
//! interleaving tears: the scheduled executor must find a schedule where the control loses.

use fragsim::capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim::capture::executors::tiled::run_tiled;
use fragsim::capture::executors::{run_parallel, run_serial};
use fragsim::capture::{
    Descriptor, Guarantee, Identity, Promise, Scheme, Step, MEMORY_CAP_DEFAULT,
};
use fragsim::memory::{Layout, Memory, WordMemory};
use fragsim::oracle::Oracle;
use fragsim::raster::{Fragment, OrbitCamera, Scene, Viewport};

/// The far buffer: each pixel's farthest fragment in canonical order (ties in depth to the
/// higher primitive id), by `atomicMax`, or by a torn load and store (`torn`, the control).
#[derive(Debug)]
struct FarBuffer {
    descriptor: Descriptor,
    torn: bool,
}

/// A fragment's walk: its pixel's word, its stored value, and what the torn walk loaded.
#[derive(Clone, Debug)]
struct FarWalk {
    pixel: usize,
    /// `packed + 1`: the words start at 0, which then means no fragment (the packed word of
    /// key 0 and primitive 0 is 0 itself).
    value: u64,
    loaded: Option<u64>,
}

impl FarBuffer {
    fn new(viewport: Viewport, torn: bool) -> Self {
        let pixels = viewport.pixels();
        let descriptor = Descriptor {
            name: if torn {
                "far-buffer-torn"
            } else {
                "far-buffer"
            }
            .into(),
            layout: Layout {
                words32: 0,
                init32: 0,
                words64: pixels,
                init64: 0,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            guarantee: if torn {
                Guarantee::ExactWithoutHazards
            } else {
                Guarantee::Exact
            },
            promise: Promise::Farthest(1),
            pixels,
            counts_every_drop: false,
        };
        Self {
            descriptor: descriptor.within(MEMORY_CAP_DEFAULT).unwrap(),
            torn,
        }
    }
}

impl Scheme for FarBuffer {
    type State = FarWalk;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> FarWalk {
        FarWalk {
            pixel: fragment.pixel as usize,
            value: fragment.packed() + 1,
            loaded: None,
        }
    }

    fn step<M: Memory>(&self, walk: &mut FarWalk, memory: &M) -> Step {
        let old = if self.torn {
            let Some(old) = walk.loaded else {
                walk.loaded = Some(WordMemory::<u64>::load(memory, walk.pixel));
                return Step::Continue;
            };
            if walk.value > old {
                WordMemory::<u64>::store(memory, walk.pixel, walk.value);
            }
            old
        } else {
            WordMemory::<u64>::fetch_max(memory, walk.pixel, walk.value)
        };
        if walk.value > old {
            Step::Stored
        } else {
            Step::Discarded
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let farthest = WordMemory::<u64>::load(memory, pixel);
        if farthest != 0 {
            out.push(farthest - 1);
        }
        0
    }
}

#[test]
fn a_scheme_of_one_module_runs_on_every_executor_and_its_torn_control_loses_fragments() {
    let scene = Scene::procedural("bunny").unwrap();
    let view = scene
        .view(Viewport::new(96, 96).unwrap(), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let far = FarBuffer::new(view.viewport(), false);
    for (executor, run) in [
        ("serial", run_serial(&view, &far)),
        ("parallel", run_parallel(&view, &far)),
        ("tiled", run_tiled(&view, &far)),
    ] {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{executor}: {diff:?}");
        assert!(
            run.capture.entries.len() > 1000,
            "{executor}: too few pixels to say anything"
        );
    }
    let torn = FarBuffer::new(view.viewport(), true);
    // The torn control is exact one pixel's fragments after another (the serial executor)...
    assert!(
        oracle.diff(&run_serial(&view, &torn).capture).is_exact(),
        "the torn far buffer lost fragments serially"
    );
    // ...and under the scheduled executor's interleavings the atomic one stays exact while the
    // torn one loses a pixel's farthest fragment on some schedule.
    let mut torn_lost = 0;
    for seed in 0..8 {
        let schedule = Schedule {
            policy: Policy::Random,
            in_flight: 256,
            granularity: Granularity::Fragment,
            seed,
        };
        let run = run_scheduled(&view, &far, &schedule, false).run;
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "seed {seed}: {diff:?}");
        let control = run_scheduled(&view, &torn, &schedule, false).run;
        torn_lost += oracle.diff(&control.capture).mismatched_pixels;
    }
    assert!(
        torn_lost > 0,
        "no schedule tore the control's load and store: the interleavings do not interleave"
    );
}

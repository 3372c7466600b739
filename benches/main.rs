//! Benchmarks of the core on the embedded default scene (the Stanford bunny, 512 × 512, view 30°).
//!
//! - `pass/*`: one frame of the executors end to end (storage re-initialisation, rasterization,
//!   capture, resolve), serial against parallel, in FreePipe's configuration (MDTS with K = 20 and
//!   the A-buffer's fixed arrays of 20 slots: one pass each); the executors keep their storage
//!   between frames as a GPU application does.
//! - `capture/*`: capture alone over the pre-rasterized fragment stream, the generic scheme code
//!   (state machine behind the `Memory` seam) against a bare hand-written loop of `fetch_min` /
//!   `fetch_add` on the same per-pixel arrays with the same fragment addresses: the speed limit of
//!   the memory system for this work. The A-buffer here is the exact one, sized by its own
//!   counting pass (run once, outside the timing, for both sides alike).
//!
//! - `scheduled/*`: the scheduled executor on one core, in simulated memory operations per second
//!   (criterion's throughput: one element = one step = one memory operation).
//!
//! Run: `cargo bench --bench main`; ratios are recorded in `docs/results.md`.

#![allow(
    missing_docs,
    reason = "criterion_group! and criterion_main! generate undocumented items"
)]

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use fragsim::capture::depth_count::{DepthCount, DepthCounts};
use fragsim::capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim::capture::executors::{ParallelExecutor, SerialExecutor};
use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::AtomicMemory;
use fragsim::raster::{Fragment, OrbitCamera, Scene, Viewport};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::Mdts;
use rayon::prelude::*;

/// Fragments per rayon work item when capturing a pre-rasterized stream.
const FRAGMENTS_PER_TASK: usize = 4096;

fn benches(c: &mut Criterion) {
    let scene = Scene::default_scene();
    let view = scene
        .view(
            Viewport::new(512, 512).unwrap(),
            &OrbitCamera::default().at_angle(30.0),
        )
        .unwrap();
    // FreePipe's configuration: fixed arrays of 20 slots, one pass, as `fragsim` runs by default.
    let k = 20;
    let mdts = Mdts::<u64>::ascending(view.viewport(), k).unwrap();
    let abuffer =
        ABuffer::fixed(view.viewport(), k, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    // The capture benches compare the scheme with a bare atomic loop on the same exact storage,
    // sized by the scheme's own counting pass (never by the oracle).
    let counts = DepthCounts::from_run(
        SerialExecutor::default().run(&view, &DepthCount::new(view.viewport())),
    )
    .counts;
    let abuffer_exact = ABuffer::exact_default(&counts).unwrap();

    let mut pass = c.benchmark_group("pass");
    pass.sample_size(20);
    let (mut serial, mut parallel) = (SerialExecutor::default(), ParallelExecutor::default());
    pass.bench_function("mdts/serial", |b| b.iter(|| serial.run(&view, &mdts)));
    pass.bench_function("mdts/parallel", |b| b.iter(|| parallel.run(&view, &mdts)));
    pass.bench_function("abuffer/serial", |b| b.iter(|| serial.run(&view, &abuffer)));
    pass.bench_function("abuffer/parallel", |b| {
        b.iter(|| parallel.run(&view, &abuffer));
    });
    pass.finish();

    let mut fragments: Vec<Fragment> = Vec::new();
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| fragments.push(f));
    }
    let pixels = view.viewport().pixels();
    let mut capture = c.benchmark_group("capture");
    capture.sample_size(30);
    capture.bench_function("mdts/generic", |b| {
        b.iter_batched(
            || mdts.layout().allocate::<AtomicMemory>(),
            |memory| {
                fragments.par_chunks(FRAGMENTS_PER_TASK).for_each(|chunk| {
                    let mut steps = 0;
                    for &f in chunk {
                        mdts.insert(f, &memory, &mut steps);
                    }
                });
                memory
            },
            BatchSize::LargeInput,
        );
    });
    capture.bench_function("mdts/bare-fetch_min", |b| {
        b.iter_batched(
            || {
                (0..pixels * k as usize)
                    .map(|_| AtomicU64::new(u64::MAX))
                    .collect::<Vec<_>>()
            },
            |slots| {
                fragments.par_chunks(FRAGMENTS_PER_TASK).for_each(|chunk| {
                    for &f in chunk {
                        let base = f.pixel as usize * k as usize;
                        let mut carried = f.packed();
                        for slot in &slots[base..base + k as usize] {
                            let old = slot.fetch_min(carried, Relaxed);
                            if old == u64::MAX {
                                break;
                            }
                            carried = carried.max(old);
                        }
                    }
                });
                slots
            },
            BatchSize::LargeInput,
        );
    });
    capture.bench_function("abuffer/generic", |b| {
        b.iter_batched(
            || abuffer_exact.layout().allocate::<AtomicMemory>(),
            |memory| {
                fragments.par_chunks(FRAGMENTS_PER_TASK).for_each(|chunk| {
                    let mut steps = 0;
                    for &f in chunk {
                        abuffer_exact.insert(f, &memory, &mut steps);
                    }
                });
                memory
            },
            BatchSize::LargeInput,
        );
    });
    let mut offsets = vec![0_usize; pixels + 1];
    for p in 0..pixels {
        offsets[p + 1] = offsets[p] + counts[p] as usize;
    }
    capture.bench_function("abuffer/bare-fetch_add", |b| {
        b.iter_batched(
            || {
                let counters: Vec<AtomicU32> = (0..pixels).map(|_| AtomicU32::new(0)).collect();
                let slots: Vec<AtomicU64> = (0..offsets[pixels])
                    .map(|_| AtomicU64::new(u64::MAX))
                    .collect();
                (counters, slots)
            },
            |(counters, slots)| {
                fragments.par_chunks(FRAGMENTS_PER_TASK).for_each(|chunk| {
                    for &f in chunk {
                        let p = f.pixel as usize;
                        let taken = counters[p].fetch_add(1, Relaxed) as usize;
                        if taken < offsets[p + 1] - offsets[p] {
                            slots[offsets[p] + taken].store(f.packed(), Relaxed);
                        }
                    }
                });
                (counters, slots)
            },
            BatchSize::LargeInput,
        );
    });
    capture.finish();

    let mut scheduled = c.benchmark_group("scheduled");
    scheduled.sample_size(10);
    for (label, policy, granularity) in [
        (
            "mdts/random-fragments-w1024",
            Policy::Random,
            Granularity::Fragment,
        ),
        (
            "mdts/warps-triangles-w1024",
            Policy::Warps,
            Granularity::Triangle,
        ),
    ] {
        let schedule = Schedule {
            policy,
            in_flight: 1024,
            granularity,
            seed: 1,
        };
        let steps = run_scheduled(&view, &mdts, &schedule, false)
            .run
            .stats
            .counters
            .steps;
        scheduled.throughput(Throughput::Elements(steps));
        scheduled.bench_function(label, |b| {
            b.iter(|| run_scheduled(&view, &mdts, &schedule, false));
        });
    }
    scheduled.finish();
}

criterion_group!(main_benches, benches);
criterion_main!(main_benches);

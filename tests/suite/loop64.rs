//! nvpro-samples' loop64 (`docs/baselines/loop64.md`): one pass of 64-bit `atomicMin`
//! on packed words, exact on every executor, where loop32 (32-bit depths, equal depths merged)
//! departs then and only then when a pixel's `K` nearest distinct depths repeat a key
//! (`shipping.rs`). Here: on a real scene through the catalog, every executor, loop64's lists are
//! the oracle's `K` nearest and its drops the fragments it lacks; on streams with many equal
//! depths under GPU-like schedules, the `K` nearest every time, where loop32 loses some.

use fragsim::capture::executors::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::executors::Executor;
use fragsim::capture::{Guarantee, MEMORY_CAP_DEFAULT};
use fragsim::catalog::{Count, SchemeName, SchemeRunner, Sizing};
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, Viewport};
use fragsim::schemes::loop32::Loop32;
use fragsim::schemes::loop64::Loop64;

#[test]
fn loop64_is_exact_on_every_executor() {
    let scene = Scene::procedural("spheres:6").unwrap();
    let view = scene
        .view(Viewport::new(48, 48).unwrap(), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let mut runner = SchemeRunner::default();
    let scheme = SchemeName::from_name("loop64").unwrap();
    for k in [3, 16] {
        let sizing = Sizing {
            k: Count::Fixed(k),
            capacity: Count::Fixed(k),
            memory_cap: MEMORY_CAP_DEFAULT,
        };
        for executor in Executor::EVERY {
            let run = runner.run(scheme, executor, &view, &sizing).unwrap();
            assert_eq!(run.guarantee, Guarantee::Exact);
            let diff = oracle.diff(&run.run.capture);
            assert!(diff.is_exact(), "K = {k}, {executor}");
            let kept = run.run.capture.entries.len() as u64;
            let dropped = run.run.stats.counters.dropped;
            assert_eq!(
                kept + dropped,
                oracle.fragments() as u64,
                "K = {k}, {executor}"
            );
        }
    }
}

/// 24 fragments of one pixel over 3 depth keys, `K` = 5, under 16 seeded schedules: loop64
/// keeps the 5 nearest (ties by primitive) every time; loop32 merges equal depths, so it keeps
/// fewer than 5 fragments (the control: the stream does repeat keys among the nearest).
#[test]
fn equal_depths_stay_apart_under_every_schedule() {
    let fragments: Vec<Fragment> = (0..24_u32)
        .map(|prim| Fragment {
            pixel: 0,
            depth_key: depth_key((prim % 3) as f32 / 4.0).unwrap(),
            prim,
        })
        .collect();
    let mut nearest: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    nearest.sort_unstable();
    nearest.truncate(5);
    let viewport = Viewport::new(1, 1).unwrap();
    let loop64 = Loop64::new(viewport, 5, MEMORY_CAP_DEFAULT).unwrap();
    let loop32 = Loop32::new(viewport, 5, MEMORY_CAP_DEFAULT).unwrap();
    for seed in 0..16 {
        let schedule = Schedule {
            policy: if seed % 2 == 0 {
                Policy::Random
            } else {
                Policy::Warps
            },
            in_flight: 8,
            granularity: Granularity::Fragment,
            seed,
        };
        let run = run_fragments(&loop64, &fragments, &schedule, false).run;
        assert_eq!(run.capture.pixel(0), nearest.as_slice(), "{schedule:?}");
        assert_eq!(run.stats.counters.dropped, 19, "{schedule:?}");
        let merged = run_fragments(&loop32, &fragments, &schedule, false).run;
        assert!(merged.capture.pixel(0).len() < 5, "{schedule:?}");
    }
}

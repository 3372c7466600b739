//! The ordered fragment-shader interlock (`docs/baselines/kbuffer-interlock-ordered.md`): a pixel's
//! critical sections in primitive order. Keeping the `K` nearest it is exact on every executor, as
//! the unordered one; keeping the first `K` it keeps exactly the first `K` of each pixel's
//! fragments in submission order on every executor and under every schedule, where keep-first
//! without the order (Bevy's layer counter) keeps whichever arrived first; and it departs from the
//! `K` nearest then and only then when the first `K` submitted are not the `K` nearest. A different
//! submission order (`--shuffle`) keeps different fragments, as on a GPU.

use fragsim::capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim::capture::executors::{Executor, ParallelExecutor};
use fragsim::capture::primitive_order::PrimitiveOrder;
use fragsim::capture::{Capture, Guarantee, MEMORY_CAP_DEFAULT};
use fragsim::catalog::{Count, SchemeName, SchemeRunner, Sizing};
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, View, Viewport};
use fragsim::schemes::kbuffer::interlock_ordered::{KBufferInterlockOrdered, Keep};
use fragsim::schemes::layer_counter::LayerCounter;

fn sizing(k: u32) -> Sizing {
    Sizing {
        k: Count::Fixed(k),
        capacity: Count::Fixed(k),
        memory_cap: MEMORY_CAP_DEFAULT,
    }
}

/// Each pixel's first `k` fragments in `view`'s submission order, sorted (canonical order).
fn first_submitted(view: &View<'_>, k: u32) -> Vec<Vec<u64>> {
    let mut lists = vec![Vec::new(); view.viewport().pixels()];
    for index in 0..view.triangle_count() {
        view.rasterize(view.submitted(index), &mut |f| {
            let list: &mut Vec<u64> = &mut lists[f.pixel as usize];
            if list.len() < k as usize {
                list.push(f.packed());
            }
        });
    }
    for list in &mut lists {
        list.sort_unstable();
    }
    lists
}

fn lists(capture: &Capture) -> Vec<Vec<u64>> {
    (0..capture.pixels())
        .map(|p| capture.pixel(p).to_vec())
        .collect()
}

fn spheres() -> Scene {
    Scene::procedural("spheres:6").unwrap()
}

fn view(scene: &Scene) -> View<'_> {
    scene
        .view(Viewport::new(48, 48).unwrap(), &OrbitCamera::default())
        .unwrap()
}

/// Through the catalog, every executor: the nearest policy exact, the keep-first one the first
/// `K` submitted, which differ from the `K` nearest in some pixel (so the claim is not the
/// nearest one's).
#[test]
fn on_every_executor_nearest_is_exact_and_keep_first_keeps_the_first_submitted() {
    let scene = spheres();
    let view = view(&scene);
    let oracle = Oracle::build(&view);
    let mut runner = SchemeRunner::default();
    let nearest = SchemeName::from_name("kbuffer-interlock-ordered").unwrap();
    let first = SchemeName::from_name("kbuffer-interlock-ordered-first").unwrap();
    for k in [2, 16] {
        let expected = first_submitted(&view, k);
        for executor in Executor::EVERY {
            let run = runner.run(nearest, executor, &view, &sizing(k)).unwrap();
            assert_eq!(run.guarantee, Guarantee::Exact);
            assert!(
                oracle.diff(&run.run.capture).is_exact(),
                "K = {k}, {executor}"
            );
            let first_run = runner.run(first, executor, &view, &sizing(k)).unwrap();
            assert_eq!(first_run.guarantee, Guarantee::ExactWithinCapacity(k));
            assert!(
                lists(&first_run.run.capture) == expected,
                "K = {k}, {executor}"
            );
        }
        // Then and only then: keep-first differs from the nearest where the first K submitted
        // are not the K nearest.
        let departs = (0..oracle.pixels())
            .filter(|&p| {
                let all = oracle.pixel(p);
                expected[p] != all[..all.len().min(k as usize)]
            })
            .count();
        assert_eq!(departs > 0, k == 2, "K = {k}: {departs} pixels depart");
    }
}

/// Under GPU-like schedules (random, warps, lockstep, PCT; fragments and whole triangles per
/// thread) and on real threads with one triangle per task, keep-first in primitive order keeps
/// the same lists, never deadlocking; the layer counter, keep-first in arrival order, keeps
/// others under some schedule (the control).
#[test]
fn keep_first_in_primitive_order_is_the_same_under_every_schedule_where_arrival_order_is_not() {
    const K: u32 = 2;
    let scene = spheres();
    let view = view(&scene);
    let order = PrimitiveOrder::of_view(&view);
    let viewport = view.viewport();
    let ordered = KBufferInterlockOrdered::with_k(viewport, K, Keep::First, Some(&order)).unwrap();
    let counter = LayerCounter::new(viewport, K, MEMORY_CAP_DEFAULT).unwrap();
    let expected = first_submitted(&view, K);
    let mut control_differs = false;
    let policies = [
        Policy::Random,
        Policy::Warps,
        Policy::Lockstep,
        Policy::Pct { depth: 3 },
    ];
    for (i, policy) in policies.into_iter().enumerate() {
        for granularity in [Granularity::Fragment, Granularity::Triangle] {
            let schedule = Schedule {
                policy,
                in_flight: 64,
                granularity,
                seed: i as u64,
            };
            let run = run_scheduled(&view, &ordered, &schedule, false);
            assert!(run.deadlock.is_none(), "{schedule:?}: {:?}", run.deadlock);
            assert!(lists(&run.run.capture) == expected, "{schedule:?}");
            let control = run_scheduled(&view, &counter, &schedule, false);
            control_differs |= lists(&control.run.capture) != expected;
        }
    }
    assert!(
        control_differs,
        "the layer counter kept the first submitted on every schedule"
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap();
    let run = pool.install(|| ParallelExecutor::with_task_size(1).run(&view, &ordered));
    assert!(
        lists(&run.capture) == expected,
        "parallel, one triangle a task"
    );
}

/// A shuffled submission order keeps the first `K` of the new order: draw order matters to
/// keep-first even when the interlock is ordered.
#[test]
fn a_shuffled_submission_keeps_the_first_of_the_new_order() {
    const K: u32 = 2;
    let scene = spheres();
    let shuffled = view(&scene).shuffled(1);
    let first = SchemeName::from_name("kbuffer-interlock-ordered-first").unwrap();
    let run = SchemeRunner::default()
        .run(first, Executor::Serial, &shuffled, &sizing(K))
        .unwrap();
    assert!(lists(&run.run.capture) == first_submitted(&shuffled, K));
    assert!(lists(&run.run.capture) != first_submitted(&view(&scene), K));
}

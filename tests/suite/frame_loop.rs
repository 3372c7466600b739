//! The frame loop's parts run with real schemes: walks in submission order over every pass are
//! the serial executor's frame, interleaved walks end every walk, a scheduled run hands back the
//! memory its post pass read, and storage laid out by tile gives the serial executor's lists.
//! (`fragsim-capture` sits below the schemes, so these live here, beside the other cross-crate
//! suites.)

use fragsim::capture::executors::frame::{interleaved, passes, walks};
use fragsim::capture::executors::run_serial;
use fragsim::capture::executors::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::executors::tiled::TiledExecutor;
use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::{SerialMemory, WordMemory};
use fragsim::raster::{Fragment, OrbitCamera, Scene, Viewport};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::{Direction, Mdts};
use fragsim::schemes::peeling::DepthPeeling;

use crate::support::fragments;

/// Every word of `memory`: the `u32` array, then the `u64` array widened.
fn words(memory: &SerialMemory) -> Vec<u64> {
    let narrow = (0..WordMemory::<u32>::len(memory)).map(|i| WordMemory::<u32>::load(memory, i));
    let wide = (0..WordMemory::<u64>::len(memory)).map(|i| WordMemory::<u64>::load(memory, i));
    narrow.map(u64::from).chain(wide).collect()
}

/// Eight fragments of one pixel, one triangle each, depth keys out of order.
fn one_pixel() -> Vec<Fragment> {
    let keys = [5, 3, 9, 1, 7, 2, 6, 4];
    (0..8)
        .map(|prim| Fragment {
            pixel: 0,
            depth_key: keys[prim as usize],
            prim,
        })
        .collect()
}

#[test]
fn walks_in_submission_order_over_every_pass_are_the_serial_executors_frame() {
    let scene = Scene::procedural("spheres:2").unwrap();
    let view = scene
        .view(Viewport::new(24, 24).unwrap(), &OrbitCamera::default())
        .unwrap();
    let peeling = DepthPeeling::<u64>::new(view.viewport(), 8, MEMORY_CAP_DEFAULT).unwrap();
    let all = fragments(&view);
    let memory: SerialMemory = peeling.layout().allocate();
    let (counters, passes) = passes(&peeling, &memory, |pass| {
        walks(&peeling, &memory, pass, &all)
    });
    let run = run_serial(&view, &peeling);
    assert!(run.stats.passes > 2, "a multi-pass case");
    assert_eq!((counters, passes), (run.stats.counters, run.stats.passes));
    assert_eq!(peeling.resolve(&memory), run.capture);
}

#[test]
fn interleaved_walks_picked_first_are_walks_and_any_pick_ends_every_walk() {
    let fragments = one_pixel();
    let mdts = Mdts::<u64>::ascending(Viewport::new(1, 1).unwrap(), 3).unwrap();
    let in_order: SerialMemory = mdts.layout().allocate();
    let expected = walks(&mdts, &in_order, 0, &fragments);
    let first: SerialMemory = mdts.layout().allocate();
    let counters = interleaved(&mdts, &first, 0, &fragments, |_| 0);
    assert_eq!(counters, expected);
    assert_eq!(words(&first), words(&in_order));
    // The last unfinished walk first: another order of steps, the same sorted slots (MDTS's
    // words do not depend on the interleaving), every fragment's walk ended.
    let last: SerialMemory = mdts.layout().allocate();
    #[expect(
        clippy::shadow_unrelated,
        reason = "the counters of this walk, as `counters` above are of the first"
    )]
    let counters = interleaved(&mdts, &last, 0, &fragments, |unfinished| {
        unfinished.len() - 1
    });
    assert_eq!(counters.fragments, fragments.len() as u64);
    assert_eq!(counters.stored + counters.dropped, counters.fragments);
    assert_eq!(words(&last), words(&in_order));
}

#[test]
fn a_scheduled_run_hands_back_the_memory_its_post_pass_read() {
    let fragments = one_pixel();
    let mdts = Mdts::<u64>::ascending(Viewport::new(1, 1).unwrap(), 3).unwrap();
    let schedule = Schedule {
        policy: Policy::Random,
        in_flight: 4,
        granularity: Granularity::Fragment,
        seed: 1,
    };
    let scheduled = run_fragments(&mdts, &fragments, &schedule, false);
    assert_eq!(mdts.resolve(&scheduled.memory), scheduled.run.capture);
    let serial: SerialMemory = mdts.layout().allocate();
    walks(&mdts, &serial, 0, &fragments);
    assert_eq!(words(&scheduled.memory), words(&serial));
}

/// The tile-local schemes' frames on storage numbered by tile give the serial executor's
/// lists, overflow counts and counters, on viewports whose sides are not multiples of a
/// tile's (narrow last column and row of tiles) and with lists that overflow.
#[test]
fn storage_laid_out_by_tile_gives_the_serial_executors_lists() {
    let scene = Scene::procedural("spheres:4").unwrap();
    for (width, height) in [(70, 45), (97, 33), (31, 31)] {
        let view = scene
            .view(
                Viewport::new(width, height).unwrap(),
                &OrbitCamera::default(),
            )
            .unwrap();
        let viewport = view.viewport();
        let mdts = Mdts::<u64>::new(viewport, 3, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
        let desc =
            Mdts::<u32>::new(viewport, 5, Direction::Descending, MEMORY_CAP_DEFAULT).unwrap();
        let abuffer = ABuffer::fixed(viewport, 3, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
        let mut tiled = TiledExecutor::default();
        for (scheme, serial, run) in [
            (
                mdts.name(),
                run_serial(&view, &mdts),
                tiled.run(&view, &mdts),
            ),
            (
                desc.name(),
                run_serial(&view, &desc),
                tiled.run(&view, &desc),
            ),
            (
                abuffer.name(),
                run_serial(&view, &abuffer),
                tiled.run(&view, &abuffer),
            ),
        ] {
            assert!(
                serial.stats.counters.dropped > 0,
                "{scheme}: a case that overflows"
            );
            assert_eq!(
                serial.capture, run.capture,
                "{scheme} at {width} × {height}"
            );
            assert_eq!(serial.stats.counters, run.stats.counters, "{scheme}");
        }
        assert!(mdts.tile_local() && desc.tile_local() && abuffer.tile_local());
    }
}

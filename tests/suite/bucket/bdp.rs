//! BDP and BDP2: exact within their bucket capacities, and losing exactly what a bucket cannot hold.

use fragsim::capture::executors::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, Scene, Viewport};
use fragsim::schemes::bucket::{Adp, Bdp, Bdp2, Buckets};

use super::{both, honest, predicted_loss, view_of};

#[test]
fn bdp_pairs_are_exact_with_at_most_two_fragments_per_bucket_and_singles_with_one() {
    let scene = Scene::procedural("quads:16").unwrap();
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 16);
    // The scene's premise, from the oracle: no pixel puts 3 layers in one of 16 subintervals, nor
    // 2 in one of 32.
    assert_eq!(predicted_loss(&oracle, 16, 2, true), (0, 2));
    assert_eq!(predicted_loss(&oracle, 32, 1, true).0, 0);
    let pairs = Bdp::<u32>::pairs(view.viewport()).unwrap();
    let singles = Bdp::<u32>::singles(view.viewport()).unwrap();
    let pairs64 = Bdp::<u64>::pairs(view.viewport()).unwrap();
    for run in both(&view, &pairs)
        .into_iter()
        .chain(both(&view, &singles))
        .chain(both(&view, &pairs64))
    {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
        assert_eq!(run.stats.passes, 2, "range pass + capture pass");
        assert_eq!(run.stats.counters.dropped, 0);
    }
}

#[test]
fn bdp_collisions_lose_exactly_everything_but_each_buckets_min_and_max() {
    let scene = Scene::procedural("quads:64").unwrap();
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    let vp = view.viewport();
    let five = Bdp::<u32>::new(vp, Buckets::Pairs(5), MEMORY_CAP_DEFAULT).unwrap();
    let cases = [
        (both(&view, &Bdp::<u32>::pairs(vp).unwrap()), 16, 2, true),
        (both(&view, &Bdp::<u64>::pairs(vp).unwrap()), 16, 2, false),
        (both(&view, &Bdp::<u32>::singles(vp).unwrap()), 32, 1, true),
        (both(&view, &five), 5, 2, true),
    ];
    for (runs, count, keeps, key_only) in cases {
        let (predicted, most) = predicted_loss(&oracle, count, keeps, key_only);
        assert!(most > keeps && predicted > 0, "the scene must collide");
        for run in runs {
            let diff = honest(&oracle, &run, "bdp");
            assert_eq!(diff.lost, predicted, "{count} buckets keeping {keeps}");
            assert_eq!(
                diff.captured + predicted,
                u64::try_from(oracle.fragments()).expect("a 32 × 32 view's fragments"),
            );
            // A walk that lost both of its own MAX tests knows it; later displacements it cannot.
            assert!(run.stats.counters.dropped <= predicted);
        }
    }
}

#[test]
fn bdp2_is_exact_with_at_most_four_fragments_per_bucket_and_loses_only_the_middle_beyond() {
    let scene = Scene::procedural("quads:40").unwrap();
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    let (none, most) = predicted_loss(&oracle, 16, 4, true);
    assert_eq!((none, most), (0, 3), "40 layers put at most 3 in a bucket");
    let bdp2 = Bdp2::<u32>::paper(view.viewport()).unwrap();
    let bdp = Bdp::<u32>::pairs(view.viewport()).unwrap();
    let bdp_loss = predicted_loss(&oracle, 16, 2, true).0;
    assert!(bdp_loss > 0, "BDP alone must lose here");
    for (run, bdp_run) in both(&view, &bdp2).into_iter().zip(both(&view, &bdp)) {
        assert!(oracle.diff(&run.capture).is_exact());
        assert_eq!(run.stats.passes, 3, "range pass + 2 capture passes");
        assert_eq!(oracle.diff(&bdp_run.capture).lost, bdp_loss);
    }
    // Deeper: 5 or more in a bucket, and BDP2 keeps exactly the two smallest and two largest.
    let deep = Scene::procedural("quads:96").unwrap();
    let deep_view = view_of(&deep, 32);
    let deep_oracle = Oracle::build(&deep_view);
    let (predicted, deep_most) = predicted_loss(&deep_oracle, 16, 4, true);
    assert!(deep_most > 4 && predicted > 0);
    let predicted64 = predicted_loss(&deep_oracle, 16, 4, false).0;
    let bdp2_64 = Bdp2::<u64>::paper(deep_view.viewport()).unwrap();
    for run in both(
        &deep_view,
        &Bdp2::<u32>::paper(deep_view.viewport()).unwrap(),
    ) {
        assert_eq!(honest(&deep_oracle, &run, "bdp2").lost, predicted);
    }
    for run in both(&deep_view, &bdp2_64) {
        assert_eq!(honest(&deep_oracle, &run, "bdp2-64").lost, predicted64);
    }
}

/// A one-pixel fragment list with these depths (primitive id = position).
fn one_pixel(depths: &[f32]) -> Vec<Fragment> {
    depths
        .iter()
        .enumerate()
        .map(|(prim, &d)| Fragment {
            pixel: 0,
            depth_key: depth_key(d).unwrap(),
            prim: u32::try_from(prim).expect("a one-pixel list of a few depths"),
        })
        .collect()
}

/// The capture's depths at pixel 0 after a run on `fragments` under a random schedule.
fn captured_depths<S: Scheme<Input = Fragment>>(
    scheme: &S,
    fragments: &[Fragment],
    seed: u64,
) -> (Vec<f32>, u32) {
    let schedule = Schedule {
        policy: Policy::Random,
        in_flight: fragments.len(),
        granularity: Granularity::Fragment,
        seed,
    };
    let run = run_fragments(scheme, fragments, &schedule, false).run;
    let depths = run
        .capture
        .pixel(0)
        .iter()
        .map(|&e| f32::from_bits((e >> 32) as u32))
        .collect();
    (depths, run.stats.passes)
}

#[test]
fn hand_built_bucket_of_five_loses_what_each_scheme_cannot_hold() {
    // Range [0.1, 0.9]: 16 buckets of 0.05, so 0.5 … 0.504 share bucket 8; 1024 subintervals of
    // 0.00078, so 0.5 and 0.5001 share subinterval 512 and the others are alone.
    let depths = [0.502, 0.9, 0.5, 0.504, 0.1, 0.501, 0.503, 0.5001];
    let fragments = one_pixel(&depths);
    let vp = Viewport::new(1, 1).unwrap();
    for seed in 0..8 {
        let (bdp, passes) = captured_depths(&Bdp::<u32>::pairs(vp).unwrap(), &fragments, seed);
        assert_eq!((bdp, passes), (vec![0.1, 0.5, 0.504, 0.9], 2));
        let (single, _) = captured_depths(&Bdp::<u32>::singles(vp).unwrap(), &fragments, seed);
        // 32 buckets of 0.025: 0.5 … 0.504 still share one; its largest survives.
        assert_eq!(single, vec![0.1, 0.504, 0.9]);
        let (bdp2, bdp2_passes) =
            captured_depths(&Bdp2::<u32>::paper(vp).unwrap(), &fragments, seed);
        assert_eq!(
            (bdp2, bdp2_passes),
            (vec![0.1, 0.5, 0.5001, 0.503, 0.504, 0.9], 3)
        );
        let (adp, adp_passes) =
            captured_depths(&Adp::<u32>::for_depth(vp, 8).unwrap(), &fragments, seed);
        // Subintervals 0, 512 (0.5 and 0.5001: the farther wins), 513, 514, 515, 517, 1023.
        assert_eq!(
            (adp, adp_passes),
            (vec![0.1, 0.5001, 0.501, 0.502, 0.503, 0.504, 0.9], 3)
        );
    }
}

#[test]
fn equal_depths_in_one_bucket_are_one_value_with_u32_words_and_two_with_u64() {
    let fragments = one_pixel(&[0.25, 0.75, 0.75]);
    let vp = Viewport::new(1, 1).unwrap();
    let schedule = Schedule {
        policy: Policy::Warps,
        in_flight: 3,
        granularity: Granularity::Fragment,
        seed: 0,
    };
    let narrow = run_fragments(
        &Bdp::<u32>::pairs(vp).unwrap(),
        &fragments,
        &schedule,
        false,
    )
    .run;
    assert_eq!(narrow.capture.pixel(0).len(), 2);
    assert_eq!(
        narrow.stats.counters.dropped, 1,
        "the duplicate knows it is lost"
    );
    let wide = run_fragments(
        &Bdp::<u64>::pairs(vp).unwrap(),
        &fragments,
        &schedule,
        false,
    )
    .run;
    let mut expected: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    expected.sort_unstable();
    assert_eq!(wide.capture.pixel(0), expected.as_slice());
}

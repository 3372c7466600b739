//! The prediction itself: the exact router agrees with HPG eq. 2 worked by hand, and a wrong router
//! predicts losses the runs do not have (the control that the predictions depend on the routing).

use fragsim::capture::executors::run_serial;
use fragsim::oracle::Oracle;
use fragsim::raster::Scene;
use fragsim::schemes::bucket::{Bdp, Bdp2};

use super::{exact_subinterval, predicted_loss, predicted_loss_routed, view_of, Router};

#[test]
fn the_exact_router_agrees_with_eq_2_worked_by_hand() {
    let key = |d: f32| d.to_bits();
    let (near, far) = (key(0.25), key(0.75));
    // 0.25 + 0.5 · j / 16 is exact in f32: bound j itself opens subinterval j.
    for j in 0..16_u32 {
        let bound = 0.25 + 0.5 * j as f32 / 16.0;
        assert_eq!(exact_subinterval(key(bound), near, far, 16), j, "bound {j}");
        if j > 0 {
            // One ulp below a bound is still in the subinterval before it.
            assert_eq!(exact_subinterval(key(bound) - 1, near, far, 16), j - 1);
        }
    }
    assert_eq!(
        exact_subinterval(far, near, far, 16),
        15,
        "the last one is closed"
    );
    assert_eq!(exact_subinterval(key(0.5), key(0.5), key(0.5), 16), 0);
    // Count 5, range [0, 1]: 0.6 is 3/5 only approximately; the f32 nearest 0.6 is
    // 10066330 · 2^-24, and 5 · 10066330 = 50331650 ≥ 3 · 2^24 = 50331648, so subinterval 3.
    assert_eq!(0.6_f32.to_bits() & 0x7F_FFFF | 0x80_0000, 10_066_330);
    assert_eq!(exact_subinterval(key(0.6), key(0.0), key(1.0), 5), 3);
    // The next f32 below it, 10066329 · 2^-24: 5 · 10066329 = 50331645 < 50331648, so 2.
    assert_eq!(exact_subinterval(key(0.6) - 1, key(0.0), key(1.0), 5), 2);
    // Subnormal and normal depths in one range: [2^-149, 2^-126 · 1.5], midpoint-ish.
    let (tiny, small) = (1_u32, key(1.5 * f32::MIN_POSITIVE));
    assert_eq!(exact_subinterval(tiny, tiny, small, 2), 0);
    assert_eq!(exact_subinterval(key(f32::MIN_POSITIVE), tiny, small, 2), 1);
}

/// The control: the loss predictions are sensitive to the routing. Each deliberately wrong router
/// (a bucket index one too high, one subinterval too few, the last subinterval left open as
/// HPG's Listing 1.1 leaves it) predicts a loss that the library's runs do not show, so a library
/// routing with that bug would fail the tests below, which compare runs with the exact router.
#[test]
fn a_wrong_router_predicts_losses_the_runs_do_not_have() {
    let mutants: [(&str, Router); 3] = [
        ("index + 1", |k, n, f, c| {
            (exact_subinterval(k, n, f, c) + 1).min(c - 1)
        }),
        ("count − 1 subintervals", |k, n, f, c| {
            exact_subinterval(k, n, f, (c - 1).max(1))
        }),
        ("last subinterval open", |k, n, f, c| {
            if k == f && f > n {
                c
            } else {
                exact_subinterval(k, n, f, c)
            }
        }),
    ];
    let scene = Scene::procedural("quads:64").unwrap();
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    let vp = view.viewport();
    let measured = [
        (
            oracle
                .diff(&run_serial(&view, &Bdp::<u32>::pairs(vp).unwrap()).capture)
                .lost,
            16,
            2,
        ),
        (
            oracle
                .diff(&run_serial(&view, &Bdp::<u32>::singles(vp).unwrap()).capture)
                .lost,
            32,
            1,
        ),
        (
            oracle
                .diff(&run_serial(&view, &Bdp2::<u32>::paper(vp).unwrap()).capture)
                .lost,
            16,
            4,
        ),
    ];
    for &(lost, count, keeps) in &measured {
        assert_eq!(
            predicted_loss(&oracle, count, keeps, true).0,
            lost,
            "{count} keeping {keeps}"
        );
    }
    for (name, mutant) in mutants {
        let wrong: Vec<u64> = measured
            .iter()
            .map(|&(_, count, keeps)| predicted_loss_routed(&oracle, count, keeps, true, mutant).0)
            .collect();
        let right: Vec<u64> = measured.iter().map(|m| m.0).collect();
        assert_ne!(
            wrong, right,
            "router {name:?} predicts what the runs measured"
        );
    }
}

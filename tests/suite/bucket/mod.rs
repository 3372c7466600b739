//! Bucket depth peeling (HPG 2009 §3.2–3.3, GPU Pro §1.3–1.5): BDP, BDP2 and ADP are exact where
//! the papers say they are, lose exactly the predicted fragments where buckets collide, and never
//! invent or misorder a fragment; their captures do not depend on the executor or the schedule.
//!
//! What each scheme should lose is predicted here, independently of the code under test: HPG
//! eq. 2 is written out in this file in exact rational arithmetic (`exact_subinterval`: the f32
//! depths as integers over a common power of two, an integer division), never with the library's
//! own routing. `a_wrong_router_predicts_losses_the_runs_do_not_have` shows the predictions
//! depend on the routing; with the library's `subinterval` changed by hand to return one bucket
//! higher (`(k as u32 + 1).min(count - 1)`), `cargo test --release --test bucket` (this suite's binary
//! then) failed 6 of its 15 tests (the BDP, BDP2, ADP and random-soup predictions and the control itself).
//!
//! The error rates on the bunny are measured by `bunny_error_rates_are_small_and_ordered`:
//! `cargo test --release --test suite -- --nocapture bucket::bunny` prints them (docs/baselines/bucket.md).

use std::collections::BTreeMap;

use fragsim::capture::executors::{run_parallel, run_serial, Run};
use fragsim::capture::Scheme;
use fragsim::oracle::{Diff, Oracle};
use fragsim::raster::{OrbitCamera, Scene, View, Viewport};

mod adp;
mod bdp;
mod bunny;
mod every_scheme;
mod router;

/// Looking straight down −z at the stacked quads: every quad is a layer of constant depth.
fn head_on() -> OrbitCamera {
    OrbitCamera {
        elevation_degrees: 0.0,
        ..OrbitCamera::default()
    }
}

fn view_of(scene: &Scene, side: u32) -> View<'_> {
    scene
        .view(Viewport::new(side, side).unwrap(), &head_on())
        .unwrap()
}

/// Serial and parallel runs, which must agree capture for capture (MAX and OR commute).
fn both<S: Scheme>(view: &View<'_>, scheme: &S) -> [Run; 2] {
    let serial = run_serial(view, scheme);
    let parallel = run_parallel(view, scheme);
    assert_eq!(serial.capture, parallel.capture, "{}", scheme.name());
    assert_eq!(
        serial.stats.passes, parallel.stats.passes,
        "the executors run as many passes"
    );
    [serial, parallel]
}

/// An f32 depth as an exact dyadic rational: `(mantissa, exponent)` with value
/// `mantissa · 2^exponent`; zero has no exponent (`None`), so that it never forces a common scale.
fn dyadic(key: u32) -> (u128, Option<i32>) {
    let (biased, fraction) = ((key >> 23) & 0xFF, key & 0x7F_FFFF);
    assert!(
        key >> 31 == 0 && biased != 0xFF,
        "depth key {key:#x} is not a finite depth ≥ 0"
    );
    match (biased, fraction) {
        (0, 0) => (0, None),
        (0, f) => (u128::from(f), Some(-149)),
        (e, f) => (u128::from(f | 0x80_0000), Some(e as i32 - 150)),
    }
}

/// HPG eq. 2, written out here rather than taken from the library: the subinterval
/// `floor(count · (d − zNear) / (zFar − zNear))` of depth key `key` in the range `[near, far]`
/// (keys), clamped to `0..count`, a degenerate range giving 0. Computed exactly: the three f32
/// depths are dyadic rationals, brought to their smallest common power of two they are integers,
/// and the quotient is an integer division, so no rounding can move a fragment across a bound.
fn exact_subinterval(key: u32, near: u32, far: u32, count: u32) -> u32 {
    let [d, lo, hi] = [key, near, far].map(dyadic);
    let Some(scale) = [d.1, lo.1, hi.1].into_iter().flatten().min() else {
        return 0; // all three zero: a degenerate range
    };
    let integer = |(mantissa, exponent): (u128, Option<i32>)| {
        let shift = exponent.map_or(0, |e| e - scale) as u32;
        // 24-bit mantissas shifted by at most 93 bits, times a count below 2^11, fit u128.
        assert!(
            shift <= 93,
            "depths {key:#x} {near:#x} {far:#x} span too many binades"
        );
        mantissa << shift
    };
    let (d, lo, hi) = (integer(d), integer(lo), integer(hi));
    if hi <= lo {
        return 0;
    }
    assert!(d >= lo && d <= hi, "the depth lies in its pixel's range");
    let k = u128::from(count) * (d - lo) / (hi - lo);
    // The exact range puts its farthest fragment at `count`: the last subinterval is closed.
    u32::try_from(k)
        .expect("k = count · (d − lo) / (hi − lo) with lo ≤ d ≤ hi is at most count, a u32")
        .min(count - 1)
}

/// Routes a depth key to a subinterval: `(key, near, far, count) -> index`.
type Router = fn(u32, u32, u32, u32) -> u32;

/// Fragments predicted lost when each pixel's range `[min, max]` (from the oracle's list) is cut
/// into `count` subintervals by [`exact_subinterval`] and a subinterval keeps at most `keeps`
/// distinct values (distinct by the packed word, or by the key alone when `key_only`). Also
/// returns the most fragments in one subinterval.
fn predicted_loss(oracle: &Oracle, count: u32, keeps: usize, key_only: bool) -> (u64, usize) {
    predicted_loss_routed(oracle, count, keeps, key_only, exact_subinterval)
}

/// [`predicted_loss`] with another router: the control test feeds it deliberately wrong ones.
fn predicted_loss_routed(
    oracle: &Oracle,
    count: u32,
    keeps: usize,
    key_only: bool,
    route: Router,
) -> (u64, usize) {
    let (mut lost, mut most) = (0_u64, 0_usize);
    for p in 0..oracle.pixels() {
        let list = oracle.pixel(p);
        let (Some(&first), Some(&last)) = (list.first(), list.last()) else {
            continue;
        };
        let (near, far) = ((first >> 32) as u32, (last >> 32) as u32);
        let mut buckets: BTreeMap<u32, Vec<u64>> = BTreeMap::new();
        for &entry in list {
            let value = if key_only { entry >> 32 } else { entry };
            buckets
                .entry(route((entry >> 32) as u32, near, far, count))
                .or_default()
                .push(value);
        }
        for mut values in buckets.into_values() {
            most = most.max(values.len());
            let n = values.len();
            values.dedup();
            lost += (n - values.len().min(keeps)) as u64;
        }
    }
    (lost, most)
}

/// The diff of an approximate capture: nothing invented, nothing out of order.
fn honest(oracle: &Oracle, run: &Run, name: &str) -> Diff {
    let diff = oracle.diff(&run.capture);
    assert_eq!(diff.extra, 0, "{name} invented fragments: {diff:?}");
    assert_eq!(diff.misordered_pixels, 0, "{name} misordered: {diff:?}");
    diff
}

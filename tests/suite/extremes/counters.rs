//! Counters: CUDA's `atomicInc` past capacity against the library's counted `fetch_add`.

use fragsim::capture::executors::{run_parallel, run_serial};
use fragsim::capture::MEMORY_CAP_DEFAULT;
use fragsim::oracle::Oracle;
use fragsim::raster::{Mesh, OrbitCamera, Scene};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::abuffer_atomic_inc::ABufferAtomicInc;

use super::{assert_exact, identity_view, viewport};
use crate::support::prim_of;

#[test]
fn cuda_atomic_inc_past_capacity_overwrites_silently_where_fetch_add_counts_the_drop() {
    let scene = Scene::procedural("spheres:4").unwrap();
    let view = scene
        .view(viewport(64, 64), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 8);
    let capacity = 4;
    let vp = view.viewport();
    // fetch_add: what does not fit is dropped, counted, and the count is the oracle's overflow.
    let fixed = ABuffer::fixed(vp, capacity, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    let counted = assert_exact(&view, &oracle, &fixed);
    // atomicInc(&counter, capacity − 1): the counter wraps, later fragments overwrite slots 0, 1,
    // …, and the post pass reads `n mod capacity` slots. Nothing is dropped or reported.
    let inc = ABufferAtomicInc::wrapping(vp, capacity, MEMORY_CAP_DEFAULT).unwrap();
    let runs = [run_serial(&view, &inc), run_parallel(&view, &inc)];
    let complexity = oracle.depth_complexity();
    let kept: u64 = complexity.iter().map(|&n| u64::from(n % capacity)).sum();
    let overwritten: u64 = complexity
        .iter()
        .map(|&n| u64::from(n.saturating_sub(capacity)))
        .sum();
    for run in &runs {
        assert_eq!(run.stats.counters.dropped, 0);
        assert_eq!(run.capture.entries.len() as u64, kept);
        let diff = oracle.diff(&run.capture);
        assert_eq!(diff.reported_overflow, 0, "atomicInc reports no overflow");
        // The oracle predicts what should have overflowed, so the silence is a miscount at
        // every pixel past capacity, and what is missing beyond that prediction is lost.
        assert_eq!(diff.overflowed, overwritten);
        let past_capacity = complexity.iter().filter(|&&n| n > capacity).count() as u64;
        assert_eq!(diff.overflow_miscounted_pixels, past_capacity);
        assert_eq!(
            diff.lost + diff.overflowed,
            oracle.fragments() as u64 - kept,
            "{diff:?}"
        );
        assert!(!diff.is_exact());
    }
    // Even a pixel of exactly `capacity` fragments reads as empty: its counter wrapped to 0.
    let full = (0..oracle.pixels())
        .filter(|&p| complexity[p] == capacity)
        .collect::<Vec<_>>();
    assert!(!full.is_empty());
    assert!(full.iter().all(|&p| runs[0].capture.pixel(p).is_empty()));
    eprintln!(
        "spheres:4 64x64, capacity {capacity}: {} fragments; fetch_add keeps {}, drops and counts {counted}; \
         atomicInc keeps {kept}, overwrites {overwritten}, loses {} silently (reported overflow 0)",
        oracle.fragments(),
        oracle.fragments() as u64 - counted,
        oracle.fragments() as u64 - kept,
    );
}

#[test]
fn atomic_inc_on_ten_thousand_coincident_fragments_keeps_only_the_remainder() {
    let n = 10_000_u32;
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]; n as usize],
    };
    let view = identity_view(&mesh, 1, 1);
    let oracle = Oracle::build(&view);
    let inc = ABufferAtomicInc::wrapping(view.viewport(), 8, MEMORY_CAP_DEFAULT).unwrap();
    let run = run_serial(&view, &inc);
    // 10,000 = 1250 · 8: the counter ends at 0 and the pixel reads as empty.
    assert!(run.capture.pixel(0).is_empty());
    let diff = oracle.diff(&run.capture);
    assert_eq!((diff.overflowed, diff.lost), (u64::from(n) - 8, 8));
    assert_eq!(diff.overflow_miscounted_pixels, 1);
    // With one fragment fewer the counter ends at 9999 mod 8 = 7: slots 0..=6 hold primitives
    // 9992..=9998, the last written there; slot 7 (primitive 9991) is not read.
    let fewer = Mesh {
        triangles: vec![[0, 1, 2]; n as usize - 1],
        ..mesh.clone()
    };
    let fewer_view = identity_view(&fewer, 1, 1);
    let fewer_run = run_serial(&fewer_view, &inc);
    let prims: Vec<u32> = fewer_run
        .capture
        .pixel(0)
        .iter()
        .map(|&w| prim_of(w))
        .collect();
    assert_eq!(prims, (9992..9999).collect::<Vec<_>>());
    let fixed = ABuffer::fixed(
        fewer_view.viewport(),
        8,
        PostSort::Insertion,
        MEMORY_CAP_DEFAULT,
    );
    let fixed_run = run_serial(&fewer_view, &fixed.unwrap());
    assert_eq!(fixed_run.stats.counters.dropped, u64::from(n) - 1 - 8);
}

//! The verdict under precision per sample: the bunny rasterized per sample at the standard 4× and
//! 8× patterns, its f32 captures (the rasterizer's own f32 vertex stage and an engine-like one)
//! equal to the f64 per-sample oracle within precision and different bit for bit, a dropped sample
//! or a sample depth past its interval different, and the joint snaps deciding shared edges at
//! every sample.

use fragsim::oracle::compare::{compare_with, flags};
use fragsim::oracle::precision::Precision;
use fragsim::oracle::Oracle;
use fragsim::raster::conventions::VertexPrecision;
use fragsim::raster::{
    depth_key, Conventions, DepthRange, OrbitCamera, SamplePattern, Scene, View, Viewport,
};

use super::{capture_of, certain_pixel, f32_vertex, judge, options, shared_edge_pixels, F32};
use crate::support::prim_of;

/// The bunny at `width × height` rasterized per sample at `samples` (the standard pattern) under
/// `vertex_precision`, the rest of the reference conventions.
fn with_sampled_bunny(
    (width, height): (u32, u32),
    samples: u32,
    vertex_precision: VertexPrecision,
    test: impl FnOnce(&View<'_>),
) {
    let scene = Scene::default_scene();
    let viewport = Viewport::new(width, height).unwrap();
    let camera = scene.orbit_camera(viewport, &OrbitCamera::default(), DepthRange::ZeroToOne);
    let conventions = Conventions {
        vertex_precision,
        samples,
        ..Conventions::REFERENCE
    };
    let view = scene.view_under(viewport, &camera, conventions).unwrap();
    assert_eq!(
        view.samples().map(SamplePattern::count),
        Some(samples),
        "the view samples at the asked count"
    );
    test(&view);
}

/// What an engine's f32 vertex stage gives each sample of a per-sample view ([`f32_vertex`]'s
/// snapped positions and depths), rasterized as `docs/semantics.md` rules 6 and 7 state it at each
/// sample of the pattern: the integer edge functions at the sample's fixed-point position, an edge
/// owning the samples exactly on it when it is a top or left edge of the positively oriented
/// triangle (y down), depth interpolated in f64 and rounded once to f32. One sorted list per sample
/// of the sample-expanded framebuffer.
#[expect(
    clippy::cast_possible_truncation,
    reason = "narrowing is the point: an engine keys the f32 rounding of its depth; sample \
              coordinates are of a test view, so they fit usize"
)]
fn engine_like_samples(view: &View<'_>) -> Vec<Vec<u64>> {
    let pattern = view.samples().expect("a per-sample view");
    let pixels = view.pixel_viewport();
    let n = pattern.count() as usize;
    let mut lists = vec![Vec::new(); view.viewport().pixels()];
    let edge = |a: [i64; 2], b: [i64; 2], p: [i64; 2]| {
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    };
    let top_left = |a: [i64; 2], b: [i64; 2]| b[1] < a[1] || (b[1] == a[1] && b[0] > a[0]);
    for prim in 0..view.triangle_count() {
        let indices = view.mesh().triangles[prim as usize];
        assert!(
            indices.iter().all(|&i| view.vertex_window(i).is_some()),
            "the triangle's vertices are in front of the camera"
        );
        let [(a, za), (mut b, mut zb), (mut c, mut zc)] = indices.map(|i| f32_vertex(view, i));
        let mut area = edge(a, b, c);
        if area == 0 {
            continue;
        }
        if area < 0 {
            std::mem::swap(&mut b, &mut c);
            std::mem::swap(&mut zb, &mut zc);
            area = -area;
        }
        let (v, z) = ([a, b, c], [za, zb, zc]);
        let lo = [0, 1].map(|k| v.iter().map(|p| p[k]).min().unwrap() / 256 - 1);
        let hi = [0, 1].map(|k| v.iter().map(|p| p[k]).max().unwrap() / 256 + 1);
        for y in lo[1].max(0)..=hi[1].min(i64::from(pixels.height) - 1) {
            for x in lo[0].max(0)..=hi[0].min(i64::from(pixels.width) - 1) {
                for s in 0..n {
                    let [ox, oy] = pattern.fixed_offset(s);
                    let p = [x * 256 + ox, y * 256 + oy];
                    let e = [(1, 2), (2, 0), (0, 1)].map(|(i, j)| (edge(v[i], v[j], p), (i, j)));
                    let inside = e
                        .iter()
                        .all(|&(value, (i, j))| value > 0 || (value == 0 && top_left(v[i], v[j])));
                    if !inside {
                        continue;
                    }
                    let depth = (0..3).map(|k| e[k].0 as f64 * z[k]).sum::<f64>() / area as f64;
                    if let Some(key) = depth_key(depth as f32) {
                        let sample = (y as usize * pixels.width as usize + x as usize) * n + s;
                        lists[sample].push(u64::from(key) << 32 | u64::from(prim));
                    }
                }
            }
        }
    }
    for list in &mut lists {
        list.sort_unstable();
    }
    lists
}

/// The per-sample f32 captures of the bunny at `samples`: the rasterizer's own f32 vertex stage
/// (a view declaring f32 vertex precision) and [`engine_like_samples`]'s, each with the f64
/// per-sample oracle and the f32 analysis it is judged by.
fn with_f32_samples(
    size: (u32, u32),
    samples: u32,
    test: impl FnOnce(&Oracle, &Precision, [Vec<Vec<u64>>; 2]),
) {
    with_sampled_bunny(size, samples, VertexPrecision::F32, |f32_view| {
        let own = Oracle::build(f32_view);
        let own: Vec<Vec<u64>> = (0..own.pixels()).map(|p| own.pixel(p).to_vec()).collect();
        with_sampled_bunny(size, samples, VertexPrecision::F64, |view| {
            let oracle = Oracle::build(view);
            let precision = Precision::derive(view, &Conventions { samples, ..F32 });
            assert_eq!(
                precision.pixels(),
                oracle.pixels(),
                "the precision reference covers the oracle's samples"
            );
            test(&oracle, &precision, [own, engine_like_samples(view)]);
        });
    });
}

#[test]
fn per_sample_f32_captures_are_equal_at_4_and_8_samples_and_different_bit_for_bit() {
    for samples in [4, 8] {
        with_f32_samples((64, 48), samples, |oracle, precision, captures| {
            for (name, lists) in ["rasterizer's f32 stage", "engine-like"]
                .iter()
                .zip(&captures)
            {
                let exact = compare_with(oracle, &capture_of(lists), None, &options());
                assert!(
                    exact.diff.mismatched_pixels > 0,
                    "{samples}x {name}: the f32 stage must move something"
                );
                let judged = judge(precision, oracle, lists);
                let samples_judged = judged.verdicts.len();
                let errors = judged
                    .verdicts
                    .iter()
                    .filter(|&&v| v & flags::DIFFERS != 0)
                    .count();
                println!(
                    "{samples}x {name}: {samples_judged} samples judged, {} covered, exact \
                     mismatches {}, within precision {}, ambiguous {}, errors {errors}",
                    (0..oracle.pixels())
                        .filter(|&p| !oracle.pixel(p).is_empty())
                        .count(),
                    exact.diff.mismatched_pixels,
                    judged.counts.within_precision,
                    judged.counts.ambiguous,
                );
                assert_eq!(errors, 0, "{samples}x {name}: {:?}", judged.diff);
                assert_eq!(samples_judged, oracle.pixels());
                assert!(judged.counts.within_precision > 0, "{samples}x {name}");
            }
        });
    }
}

#[test]
fn a_dropped_sample_and_a_sample_depth_past_its_interval_are_different_per_sample() {
    for samples in [4, 8] {
        with_f32_samples((64, 48), samples, |oracle, precision, [lists, _]| {
            let p = certain_pixel(precision, &lists);
            let q = precision.pixel(p)[0];
            let i = lists[p].iter().position(|&w| prim_of(w) == q.prim).unwrap();
            let mut dropped = lists.clone();
            dropped[p].remove(i);
            let mut deeper = lists.clone();
            deeper[p][i] = u64::from(q.key_hi + 1) << 32 | u64::from(q.prim);
            deeper[p].sort_unstable();
            for (name, bugged, expected) in [
                ("dropped", dropped, flags::MISSING | flags::MISCOUNTED),
                ("past its interval", deeper, flags::MISSING | flags::EXTRA),
            ] {
                let judged = judge(precision, oracle, &bugged);
                let wrong: Vec<usize> = (0..bugged.len())
                    .filter(|&s| judged.verdicts[s] & flags::DIFFERS != 0)
                    .collect();
                assert_eq!(wrong, [p], "{samples}x {name}: the planted sample alone");
                assert_eq!(judged.verdicts[p] & flags::DIFFERS, expected, "{name}");
                assert_eq!(judged.verdicts[p] & flags::AMBIGUOUS, 0, "{name}");
            }
        });
    }
}

/// Per sample the snaps are inferred over every sample of every pixel: at samples beside an edge
/// shared by two triangles (each one's coverage undecided alone), either snap of the edge gives
/// the sample to exactly one of them, so a dropped or a doubled sample there is an error, not an
/// ambiguity.
#[test]
fn per_sample_joint_snaps_decide_shared_edges_and_catch_a_dropped_or_doubled_sample() {
    with_f32_samples((384, 288), 4, |oracle, precision, [_, lists]| {
        let judged = judge(precision, oracle, &lists);
        assert_eq!(judged.diff.mismatched_pixels, 0, "{:?}", judged.diff);
        let snaps = judged.snaps;
        assert_eq!(snaps.contradicting_pixels, 0, "{snaps:?}");
        let shared = shared_edge_pixels(precision, &lists);
        println!(
            "{} samples judged, {} beside a shared edge, {snaps:?}",
            judged.verdicts.len(),
            shared.len()
        );
        assert!(shared.len() >= 4, "{} shared-edge samples", shared.len());
        for &(p, present, absent) in shared.iter().take(8) {
            assert_eq!(judged.verdicts[p] & flags::AMBIGUOUS, 0, "sample {p}");
            let mut dropped = lists.clone();
            dropped[p].retain(|&w| prim_of(w) != present);
            let flags = judge(precision, oracle, &dropped).verdicts[p];
            assert_ne!(flags & flags::MISSING, 0, "sample {p} dropped: {flags:#b}");
            let key_lo = precision
                .pixel(p)
                .iter()
                .find(|q| q.prim == absent)
                .unwrap()
                .key_lo;
            let mut doubled = lists.clone();
            doubled[p].push(u64::from(key_lo) << 32 | u64::from(absent));
            doubled[p].sort_unstable();
            let doubled_flags = judge(precision, oracle, &doubled).verdicts[p];
            assert_ne!(
                doubled_flags & flags::EXTRA,
                0,
                "sample {p} doubled: {doubled_flags:#b}"
            );
        }
    });
}

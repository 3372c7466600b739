//! The verdict under precision on the bunny: an engine-like capture (fragsim's pipeline with an
//! f32 vertex stage: f32 matrix and arithmetic, f32 vertex depths) judged against the f64 oracle
//! passes with no error, and each planted bug in it (a dropped fragment, a wrong primitive id, an
//! unsorted list, an extra fragment, a depth one ulp past its interval) is an error that no
//! ambiguity excuses; with f64 vertex precision the verdict is today's exact one. Per sample the
//! same holds at every sample of the standard 4× and 8× patterns (`per_sample`).

use crate::support::prim_of;
use fragsim::capture::{Capacity, Capture, Identity, Keeps};
use fragsim::oracle::compare::{compare_with, flags, CompareOptions, Comparison};
use fragsim::oracle::precision::{compare_within, Doubt, Precision};
use fragsim::oracle::Oracle;
use fragsim::raster::conventions::VertexPrecision;
use fragsim::raster::{Conventions, Fragment, OrbitCamera, Scene, ScreenTriangle, View, Viewport};

mod f32_verdict;
mod per_sample;

/// A planted bug: an edit of one pixel's list.
type Plant = dyn Fn(&mut Vec<u64>);

const F32: Conventions = Conventions {
    vertex_precision: VertexPrecision::F32,
    ..Conventions::REFERENCE
};

fn with_bunny(test: impl FnOnce(&View<'_>, &Oracle)) {
    with_bunny_at(96, 80, test);
}

fn with_bunny_at(width: u32, height: u32, test: impl FnOnce(&View<'_>, &Oracle)) {
    let scene = Scene::default_scene();
    let view = scene
        .view(
            Viewport::new(width, height).unwrap(),
            &OrbitCamera::default(),
        )
        .unwrap();
    let oracle = Oracle::build(&view);
    test(&view, &oracle);
}

/// The bunny at 512², its f32 analysis and an engine-like capture's lists: enough shared-edge
/// pixels for the one-snap tests.
fn with_f32_bunny_512(test: impl FnOnce(&Oracle, &Precision, &[Vec<u64>])) {
    with_bunny_at(512, 512, |view, oracle| {
        test(oracle, &Precision::derive(view, &F32), &engine_like(view));
    });
}

/// Vertex `index` through an f32 vertex shader: the matrix rounded to f32, `M·v`, the divide
/// and the viewport map in f32, snapped by rounding to the nearest subpixel.
#[expect(
    clippy::cast_possible_truncation,
    reason = "an f32 vertex shader rounds the matrix to f32, and a test view's subpixel \
              coordinates fit i64"
)]
fn f32_vertex(view: &View<'_>, index: u32) -> ([i64; 2], f64) {
    let m = view.view_projection().to_cols_array().map(|x| x as f32);
    let p = view.mesh().positions[index as usize];
    let row = |r: usize| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    let (x, y, z, w) = (row(0), row(1), row(2), row(3));
    let viewport = view.pixel_viewport();
    let wx = (x / w * 0.5 + 0.5) * viewport.width as f32;
    let wy = (0.5 - y / w * 0.5) * viewport.height as f32;
    (
        [(wx * 256.0).round() as i64, (wy * 256.0).round() as i64],
        f64::from(z / w),
    )
}

/// The capture an f32 vertex stage produces: every pixel's fragments sorted, as an unbounded
/// A-buffer with ids.
fn engine_like(view: &View<'_>) -> Vec<Vec<u64>> {
    let mut fragments: Vec<Fragment> = Vec::new();
    for prim in 0..view.triangle_count() {
        let indices = view.mesh().triangles[prim as usize];
        assert!(
            indices.iter().all(|&i| view.vertex_window(i).is_some()),
            "the triangle's vertices are in front of the camera"
        );
        let [(a, za), (mut b, mut zb), (mut c, mut zc)] = indices.map(|i| f32_vertex(view, i));
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area == 0 {
            continue;
        }
        if area < 0 {
            std::mem::swap(&mut b, &mut c);
            std::mem::swap(&mut zb, &mut zc);
        }
        let tri = ScreenTriangle {
            prim,
            xy: [a, b, c],
            z: [za, zb, zc],
        };
        view.scan(&tri, &mut |f| fragments.push(f));
    }
    let oracle = Oracle::from_fragments(view.viewport().pixels(), &fragments);
    (0..oracle.pixels())
        .map(|p| oracle.pixel(p).to_vec())
        .collect()
}

fn capture_of(lists: &[Vec<u64>]) -> Capture {
    capture_as(lists, Identity::KeyAndPrim)
}

/// The lists as a capture of `identity`: with [`Identity::KeyOnly`] the primitive ids are
/// dropped from the words, as an `mdts32` dump stores them.
fn capture_as(lists: &[Vec<u64>], identity: Identity) -> Capture {
    let keeps = Keeps::All {
        capacity: Capacity::Unbounded,
        overflow: vec![0; lists.len()],
    };
    let mut capture = Capture::with_pixels(lists.len(), identity, keeps);
    let mask = match identity {
        Identity::KeyOnly => u64::MAX << 32,
        _ => u64::MAX,
    };
    for list in lists {
        capture.push_pixel(list.iter().map(|&w| w & mask));
    }
    capture
}

fn options() -> CompareOptions<'static> {
    CompareOptions {
        depth_ulps: 0,
        examples: 4,
        complete: None,
    }
}

fn judge(precision: &Precision, oracle: &Oracle, lists: &[Vec<u64>]) -> Comparison {
    compare_within(precision, oracle, &capture_of(lists), None, &options())
}

/// A pixel with at least two fragments, each of them certain (decided coverage and depth).
fn certain_pixel(precision: &Precision, lists: &[Vec<u64>]) -> usize {
    (0..lists.len())
        .find(|&p| {
            let possible = precision.pixel(p);
            lists[p].len() >= 2
                && possible.iter().all(|q| q.certain())
                && possible.len() == lists[p].len()
        })
        .expect("a decided pixel of depth complexity 2 or more")
}

#[test]
fn an_f32_vertex_stage_passes_within_precision_and_is_different_bit_for_bit() {
    with_bunny(|view, oracle| {
        let precision = Precision::derive(view, &F32);
        let lists = engine_like(view);
        let exact = compare_with(oracle, &capture_of(&lists), None, &options());
        assert!(
            exact.diff.mismatched_pixels > 0,
            "the f32 stage must move something"
        );
        let judged = judge(&precision, oracle, &lists);
        assert_eq!(judged.diff.mismatched_pixels, 0, "{:?}", judged.diff);
        assert!(judged.counts.within_precision > 0);
        let bounds = precision.bounds();
        assert!(bounds.max_snap_radius_subpixels >= 1 && bounds.max_depth_interval_ulps > 0);
        assert_eq!(bounds.unanalysed_triangles, 0);
    });
}

#[test]
fn the_analysis_lists_exactly_the_oracles_fragments_as_the_reference() {
    with_bunny(|view, oracle| {
        let precision = Precision::derive(view, &F32);
        for p in 0..oracle.pixels() {
            let mut listed: Vec<u64> = precision
                .pixel(p)
                .iter()
                .filter_map(|q| {
                    q.reference
                        .map(|key| u64::from(key) << 32 | u64::from(q.prim))
                })
                .collect();
            listed.sort_unstable();
            assert_eq!(listed, oracle.pixel(p), "pixel {p}");
            for q in precision.pixel(p) {
                if let Some(key) = q.reference {
                    assert!((q.key_lo..=q.key_hi).contains(&key), "pixel {p}: {q:?}");
                }
            }
        }
    });
}

#[test]
fn planted_bugs_in_an_f32_capture_are_errors_not_ambiguities() {
    with_bunny(|view, oracle| {
        let precision = Precision::derive(view, &F32);
        let lists = engine_like(view);
        let p = certain_pixel(&precision, &lists);
        let width = lists[p].len();
        let foreign = view.triangle_count() + 7;
        let bugs: [(&str, Box<Plant>, u8); 4] = [
            // The A-buffer's counter went down with the fragment (one fewer `atomicAdd`): the
            // pixel's count is not the one every conforming implementation reaches.
            (
                "dropped",
                Box::new(|l| {
                    l.remove(0);
                }),
                flags::MISSING | flags::MISCOUNTED,
            ),
            (
                "wrong primitive id",
                Box::new(move |l| l[0] = (l[0] & !u64::from(u32::MAX)) | u64::from(foreign)),
                flags::MISSING | flags::EXTRA,
            ),
            ("unsorted", Box::new(|l| l.swap(0, 1)), flags::MISORDERED),
            (
                "extra",
                Box::new(move |l| l.insert(width - 1, l[width - 1])),
                flags::EXTRA | flags::MISCOUNTED,
            ),
        ];
        for (name, plant, expected) in bugs {
            let mut bugged = lists.clone();
            plant(&mut bugged[p]);
            let judged = judge(&precision, oracle, &bugged);
            let wrong: Vec<usize> = (0..bugged.len())
                .filter(|&q| judged.verdicts[q] & flags::DIFFERS != 0)
                .collect();
            assert_eq!(wrong, [p], "{name}: the error is the planted pixel's alone");
            let flags = judged.verdicts[p];
            assert_eq!(flags & flags::DIFFERS, expected, "{name}");
            assert_eq!(flags & flags::AMBIGUOUS, 0, "{name} excused as ambiguous");
        }
    });
}

#[test]
fn a_depth_at_its_bound_passes_and_one_ulp_past_fails() {
    with_bunny(|view, oracle| {
        let precision = Precision::derive(view, &F32);
        let lists: Vec<Vec<u64>> = (0..oracle.pixels())
            .map(|p| oracle.pixel(p).to_vec())
            .collect();
        let p = certain_pixel(&precision, &lists);
        let q = precision.pixel(p)[0];
        for (key, passes) in [
            (q.key_hi, true),
            (q.key_lo, true),
            (q.key_hi + 1, false),
            (q.key_lo - 1, false),
        ] {
            let mut moved = lists.clone();
            let i = moved[p].iter().position(|&e| prim_of(e) == q.prim).unwrap();
            moved[p][i] = u64::from(key) << 32 | u64::from(q.prim);
            moved[p].sort_unstable();
            let judged = judge(&precision, oracle, &moved);
            assert_eq!(
                judged.diff.mismatched_pixels == 0,
                passes,
                "key {key:#x} of {q:?}"
            );
            if !passes {
                assert_eq!(judged.verdicts[p], flags::MISSING | flags::EXTRA);
            }
        }
    });
}

#[test]
fn with_f64_vertex_precision_the_verdict_is_todays_bit_for_bit() {
    with_bunny(|view, oracle| {
        let precision = Precision::derive(view, &Conventions::REFERENCE);
        assert!(precision.is_exact());
        let mut lists: Vec<Vec<u64>> = (0..oracle.pixels())
            .map(|p| oracle.pixel(p).to_vec())
            .collect();
        let deep: Vec<usize> = (0..lists.len()).filter(|&p| lists[p].len() >= 2).collect();
        lists[deep[0]].swap(0, 1);
        lists[deep[1]].remove(0);
        lists[deep[2]][0] += 1 << 32; // one ulp deeper
        for ulps in [0, 1] {
            let options = CompareOptions {
                depth_ulps: ulps,
                ..options()
            };
            let capture = capture_of(&lists);
            assert_eq!(
                compare_within(&precision, oracle, &capture, None, &options),
                compare_with(oracle, &capture, None, &options),
                "{ulps} ulps"
            );
        }
        let f64_capture = judge(&precision, oracle, &engine_like(view));
        assert!(
            f64_capture.diff.mismatched_pixels > 0,
            "bit-exact owes every bit"
        );
    });
}

#[test]
fn a_keep_first_list_may_keep_any_arrivals_but_not_lose_more() {
    with_bunny(|view, oracle| {
        let precision = Precision::derive(view, &F32);
        let lists = engine_like(view);
        let p = (0..lists.len())
            .find(|&p| {
                let possible = precision.pixel(p);
                lists[p].len() >= 3
                    && possible.iter().all(|q| q.certain())
                    && possible.len() == lists[p].len()
            })
            .expect("a decided pixel of depth complexity 3 or more");
        // A list that keeps the first `c` arrivals, `c` one less than the pixel's fragments: the
        // GPU's arrival order kept the farthest ones, not the reference's submission order.
        let c = lists[p].len() - 1;
        let kept: Vec<Vec<u64>> = lists
            .iter()
            .map(|list| list[list.len().saturating_sub(c)..].to_vec())
            .collect();
        let keep_first = |chosen: &[Vec<u64>]| {
            let keeps = Keeps::All {
                capacity: Capacity::PerPixelUncounted(u32::try_from(c).expect("a small capacity")),
                overflow: vec![0; chosen.len()],
            };
            let mut capture = Capture::with_pixels(chosen.len(), Identity::KeyAndPrim, keeps);
            for list in chosen {
                capture.push_pixel(list.iter().copied());
            }
            compare_within(&precision, oracle, &capture, None, &options())
        };
        let judged = keep_first(&kept);
        assert_eq!(judged.diff.mismatched_pixels, 0, "{:?}", judged.diff);
        assert_eq!(judged.verdicts[p] & flags::OVERFLOWED, flags::OVERFLOWED);
        assert_eq!(judged.diff.lost, 0);
        // One more fragment gone than the capacity allows is missing, whichever arrived first.
        let mut planted = kept.clone();
        planted[p].remove(0);
        let bugged = keep_first(&planted);
        assert_eq!(bugged.verdicts[p] & flags::MISSING, flags::MISSING);
        assert_eq!(bugged.diff.lost, 1);
    });
}

/// Pixels where an f32 capture holds a fragment whose coverage the analysis leaves undecided
/// beside one it leaves out whose coverage is undecided too: a centre beside an edge shared by
/// the two triangles, which the capture's snap of the edge's vertices gave to one of them.
fn shared_edge_pixels(precision: &Precision, lists: &[Vec<u64>]) -> Vec<(usize, u32, u32)> {
    let undecided = |p: usize, present: bool| {
        precision.pixel(p).iter().find(|q| {
            q.doubt == Some(Doubt::Coverage)
                && lists[p].iter().any(|&w| prim_of(w) == q.prim) == present
        })
    };
    (0..lists.len())
        .filter_map(|p| Some((p, undecided(p, true)?.prim, undecided(p, false)?.prim)))
        .collect()
}

#[test]
fn one_snap_per_vertex_decides_shared_edges_and_lets_no_dropped_or_doubled_fragment_through() {
    with_f32_bunny_512(|oracle, precision, lists| {
        let judged = judge(precision, oracle, lists);
        assert_eq!(judged.diff.mismatched_pixels, 0, "{:?}", judged.diff);
        let snaps = judged.snaps;
        assert_eq!(snaps.contradicting_pixels, 0, "{snaps:?}");
        assert!(
            snaps.pinned_vertices > 0 && snaps.decided_pixels > 0,
            "{snaps:?}"
        );
        assert!(
            judged.counts.ambiguous <= snaps.joint_pixels - snaps.decided_pixels,
            "{snaps:?}, {} ambiguous",
            judged.counts.ambiguous
        );
        // Judged one by one, both fragments of each of these pixels may be present or absent, so
        // a dropped or doubled one would be excused as ambiguous; jointly, either snap of the shared
        // edge gives the centre to exactly one of them.
        let shared = shared_edge_pixels(precision, lists);
        assert!(shared.len() >= 8, "{} shared-edge pixels", shared.len());
        for &(p, present, absent) in shared.iter().take(8) {
            assert_eq!(judged.verdicts[p] & flags::AMBIGUOUS, 0, "pixel {p}");
            let mut dropped = lists.to_vec();
            dropped[p].retain(|&w| prim_of(w) != present);
            let flags = judge(precision, oracle, &dropped).verdicts[p];
            assert_ne!(flags & flags::MISSING, 0, "pixel {p} dropped: {flags:#b}");
            let key_lo = precision
                .pixel(p)
                .iter()
                .find(|q| q.prim == absent)
                .unwrap()
                .key_lo;
            let mut doubled = lists.to_vec();
            doubled[p].push(u64::from(key_lo) << 32 | u64::from(absent));
            doubled[p].sort_unstable();
            let doubled_flags = judge(precision, oracle, &doubled).verdicts[p];
            assert_ne!(
                doubled_flags & flags::EXTRA,
                0,
                "pixel {p} doubled: {doubled_flags:#b}"
            );
        }
    });
}

/// Key-only words (`mdts32`) name no triangle: at a centre beside a shared edge the one stored
/// key lies in both triangles' intervals, so both snaps of the edge explain the pixel with one
/// fragment. The pixel is then decided in all the dump records (unnamed, not ambiguous), and a
/// dropped or doubled fragment there is still an error: no snap explains a count of 0 or 2.
#[test]
fn key_only_words_leave_the_triangle_unnamed_and_still_catch_a_dropped_or_doubled_fragment() {
    with_f32_bunny_512(|oracle, precision, lists| {
        let key_only = |chosen: &[Vec<u64>]| {
            let capture = capture_as(chosen, Identity::KeyOnly);
            compare_within(precision, oracle, &capture, None, &options())
        };
        let judged = key_only(lists);
        assert_eq!(judged.diff.mismatched_pixels, 0, "{:?}", judged.diff);
        let snaps = judged.snaps;
        assert!(snaps.unnamed_pixels > 0, "{snaps:?}");
        assert_eq!(snaps.contradicting_pixels, 0, "{snaps:?}");
        // The same capture with ids pins the snaps instead: nothing is left unnamed.
        assert_eq!(judge(precision, oracle, lists).snaps.unnamed_pixels, 0);
        let shared = shared_edge_pixels(precision, lists);
        assert!(shared.len() >= 8, "{} shared-edge pixels", shared.len());
        for &(p, present, _) in shared.iter().take(8) {
            assert_eq!(judged.verdicts[p] & flags::AMBIGUOUS, 0, "pixel {p}");
            let mut dropped = lists.to_vec();
            dropped[p].retain(|&w| prim_of(w) != present);
            let flags = key_only(&dropped).verdicts[p];
            assert_ne!(flags & flags::MISSING, 0, "pixel {p} dropped: {flags:#b}");
            let mut doubled = lists.to_vec();
            let kept = *doubled[p].iter().find(|&&w| prim_of(w) == present).unwrap();
            doubled[p].push(kept);
            doubled[p].sort_unstable();
            let doubled_flags = key_only(&doubled).verdicts[p];
            assert_ne!(
                doubled_flags & flags::EXTRA,
                0,
                "pixel {p} doubled: {doubled_flags:#b}"
            );
        }
    });
}

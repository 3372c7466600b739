//! Unit tests of the scan (rules 6 and 7): the covered runs, the block of a small triangle and
//! the setup's test of a box of one centre, each against testing every centre of the box.

use super::tests::soup_views;
use super::*;
use crate::conventions::{Conventions, WindowOrigin};

/// The reference conventions under each window origin, so under both fill rules.
fn under_each_window_origin() -> impl Iterator<Item = (WindowOrigin, Conventions)> {
    [WindowOrigin::UpperLeft, WindowOrigin::LowerLeft]
        .map(|window_origin| {
            let conventions = Conventions {
                window_origin,
                ..Conventions::REFERENCE
            };
            (window_origin, conventions)
        })
        .into_iter()
}

/// Rules 6 and 7 as `docs/semantics.md` states them, the slow way: every pixel centre of the
/// triangle's bounding box within `rect` tested against the three edge functions, left to right
/// in each row, rows top to bottom. The scan that visits only covered centres must emit exactly
/// these fragments in this order.
fn scan_every_centre(view: &View<'_>, tri: &ScreenTriangle, rect: PixelRect) -> Vec<Fragment> {
    use super::edges::{fill_thresholds, fragment_at};
    let mut fragments = Vec::new();
    let [a, b, c] = tri.xy;
    let [lo, hi] = bounding_box(tri.xy);
    let Some(pixels) = rect.centres_within(lo, hi) else {
        return fragments;
    };
    let edges = [(b, c), (c, a), (a, b)];
    let threshold = fill_thresholds(edges, view.conventions().window_origin);
    let area = edge(a, b, c) as f64;
    let width = i64::from(view.viewport().width);
    for y in i64::from(pixels.y.0)..=i64::from(pixels.y.1) {
        for x in i64::from(pixels.x.0)..=i64::from(pixels.x.1) {
            let centre = [x * ONE + HALF, y * ONE + HALF];
            let e = edges.map(|(p, q)| edge(p, q, centre));
            if (0..3).all(|k| e[k] >= threshold[k]) {
                fragments.extend(fragment_at(tri.prim, tri.z, e, area, y * width + x));
            }
        }
    }
    fragments
}

#[test]
#[expect(
    clippy::shadow_unrelated,
    reason = "the loop checks the view and its flipped twin alike"
)]
fn the_scan_of_covered_runs_emits_what_testing_every_centre_emits() {
    // Tiny, large and clipped triangles of a soup under both fill rules, on the whole viewport
    // and on tiles misaligned with it, so that runs are cut by every side of a rectangle.
    let mesh = crate::scenes::triangle_soup(1500, 5);
    let lower_left = Conventions {
        window_origin: WindowOrigin::LowerLeft,
        ..Conventions::REFERENCE
    };
    let mut fragments = 0;
    for (distance_scale, view) in soup_views(&mesh) {
        let camera = Camera {
            view_projection: view.view_projection(),
        };
        let flipped =
            View::with_conventions(&mesh, &camera, view.viewport(), CullMode::None, lower_left)
                .unwrap();
        for view in [view, flipped] {
            let Viewport { width, height } = view.viewport();
            let rects = [
                view.viewport().rect(),
                PixelRect {
                    x: (3, (width / 2).min(width - 1)),
                    y: (height / 3, height - 2),
                },
                PixelRect {
                    x: (width / 2, width / 2),
                    y: (0, height - 1),
                },
            ];
            for prim in 0..view.triangle_count() {
                view.screen_triangles(prim, &mut |tri| {
                    for rect in rects {
                        let mut scanned = Vec::new();
                        view.scan_in(&tri, rect, &mut |f| scanned.push(f));
                        let expected = scan_every_centre(&view, &tri, rect);
                        assert_eq!(scanned, expected, "{prim} at {distance_scale}, {rect:?}");
                        fragments += scanned.len();
                    }
                });
                // The whole path from the vertex stage: the early rejects and the test of a box
                // of one centre in the setup emit what testing every centre of each piece does.
                for rect in rects {
                    let mut expected = Vec::new();
                    view.screen_triangles(prim, &mut |tri| {
                        expected.extend(scan_every_centre(&view, &tri, rect));
                    });
                    let mut rasterized = Vec::new();
                    view.rasterize_in(prim, rect, &mut |f| rasterized.push(f));
                    assert_eq!(rasterized, expected, "{prim} at {distance_scale}, {rect:?}");
                }
            }
        }
    }
    assert!(
        fragments > 100_000,
        "{fragments} fragments: too few to test the runs"
    );
}

/// Tiny triangles whose box holds one centre lying on a vertex or an edge, in both orientations
/// and under both fill rules: the setup's test of that centre must settle it as the scan does.
#[test]
fn a_box_of_one_centre_on_an_edge_is_decided_by_the_fill_rule() {
    // Window positions in pixels on an 8 × 8 viewport (identity camera: x = X/4 − 1, y = 1 − Y/4);
    // pixel (3, 3)'s centre is (3.5, 3.5).
    let at = |x: f32, y: f32| [x / 4.0 - 1.0, 1.0 - y / 4.0, 0.5];
    let mesh = Mesh {
        positions: vec![
            at(3.5, 3.5),
            at(3.875, 3.5),
            at(3.5, 3.875),
            at(3.125, 3.25),
            at(3.875, 3.75),
            at(3.25, 3.875),
        ],
        // On a vertex, on a horizontal and a vertical edge; on a slanted edge; each both ways.
        triangles: vec![
            [0, 1, 2],
            [0, 2, 1],
            [3, 4, 5],
            [3, 5, 4],
            [3, 4, 2],
            [3, 2, 4],
        ],
    };
    let mut covered = 0;
    for (window_origin, conventions) in under_each_window_origin() {
        let camera = Camera {
            view_projection: DMat4::IDENTITY,
        };
        let viewport = Viewport::new(8, 8).unwrap();
        let view =
            View::with_conventions(&mesh, &camera, viewport, CullMode::None, conventions).unwrap();
        for prim in 0..view.triangle_count() {
            let mut expected = Vec::new();
            view.screen_triangles(prim, &mut |tri| {
                expected.extend(scan_every_centre(&view, &tri, viewport.rect()));
            });
            let mut rasterized = Vec::new();
            view.rasterize(prim, &mut |f| rasterized.push(f));
            assert_eq!(rasterized, expected, "{prim} under {window_origin:?}");
            covered += rasterized.len();
        }
    }
    // The fill rule gives some of these centres and withholds others.
    assert!(covered > 0 && covered < 24, "{covered}");
}

/// Small triangles, scanned as one block ([`super::scan`]'s block coverage), emit what testing
/// every centre emits: vertices on a grid of a quarter pixel, so that edges and vertices fall on
/// centres and the fill rule decides, with boxes spanning up to just under the block's side (the
/// largest values the vector lanes hold) and just over it (scanned row by row), in both
/// orientations, under both fill rules, on the viewport and on rectangles that cut the box.
#[test]
#[expect(
    clippy::cast_possible_truncation,
    reason = "the corners are inside the 16384-pixel guard band: their pixels fit u32"
)]
fn small_triangles_scanned_as_one_block_emit_what_testing_every_centre_emits() {
    use super::setup::ScanSetup;
    use super::setup::BLOCK_SIDE;
    let mut rng = crate::rng::SplitMix64::new(35);
    let viewport = Viewport::new(32, 28).unwrap();
    let mesh = Mesh {
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    let camera = Camera {
        view_projection: DMat4::IDENTITY,
    };
    let (mut blocks, mut fragments) = (0, 0);
    for (window_origin, conventions) in under_each_window_origin() {
        let view =
            View::with_conventions(&mesh, &camera, viewport, CullMode::None, conventions).unwrap();
        for prim in 0..4000 {
            // A corner away from the viewport's sides, and vertices within `span` quarter pixels
            // of it: up to a quarter pixel over the block side, so boxes on both sides of the limit.
            let span = 1 + rng.next_u64() % (4 * BLOCK_SIDE as u64 + 2);
            let corner = [2 + rng.next_u64() % 16, 2 + rng.next_u64() % 12].map(|c| c * 256);
            let mut offset = |c: u64| (c + (rng.next_u64() % (span + 1)) * ONE as u64 / 4) as i64;
            let [a, b, c] = [(); 3].map(|()| [offset(corner[0]), offset(corner[1])]);
            let area = edge(a, b, c);
            if area == 0 {
                continue;
            }
            // Oriented as the pipeline orients a triangle: positive doubled area.
            let xy = if area > 0 { [a, b, c] } else { [a, c, b] };
            let tri = ScreenTriangle {
                prim,
                xy,
                z: [0.25, 0.5, 0.75],
            };
            let rects = [
                viewport.rect(),
                PixelRect {
                    x: (0, (corner[0] / 256 + 1) as u32),
                    y: ((corner[1] / 256 + 2) as u32, 27),
                },
            ];
            for rect in rects {
                let mut scanned = Vec::new();
                view.scan_in(&tri, rect, &mut |f| scanned.push(f));
                assert_eq!(
                    scanned,
                    scan_every_centre(&view, &tri, rect),
                    "{xy:?} in {rect:?} under {window_origin:?}"
                );
                fragments += scanned.len();
                let origin = view.conventions().window_origin;
                blocks +=
                    usize::from(ScanSetup::within(&tri, rect, origin).is_some_and(|s| s.block));
            }
        }
    }
    assert!(
        blocks > 5_000 && fragments > 5_000,
        "{blocks} blocks, {fragments} fragments"
    );
}

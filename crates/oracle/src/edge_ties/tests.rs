use fragsim_raster::{
    Camera, Conventions, CullMode, EdgeTies, Fragment, Mesh, SplitMix64, View, Viewport,
    WindowOrigin,
};

use super::{pipeline_rule, thresholds, TiePoints, ONE};
use crate::Oracle;

/// The identity view-projection: a vertex's x, y are its normalised device coordinates.
const IDENTITY: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

/// `triangles` random triangles on a `side × side` viewport whose corners lie on the grid of
/// 1/16 pixel that sample positions lie on (so that many samples fall exactly on edges), plus a
/// fan of four triangles around the first sample of pixel (2, 2), its arms to the corners of a
/// square of 4 pixels: its diagonals, shared by two triangles each, and its square's sides pass
/// through that sample's positions in other pixels.
#[expect(
    clippy::cast_possible_truncation,
    clippy::shadow_unrelated,
    reason = "test positions are f32, as the mesh stores them; the triangles of a few hundred vertices; `triangles` becomes the mesh's index list"
)]
fn soup(side: u32, triangles: usize, first_sample: [i64; 2], seed: u64) -> Mesh {
    let mut rng = SplitMix64::new(seed);
    // Window position in 1/16 pixel to normalised device coordinates.
    let s = 8.0 * f64::from(side);
    let at = |x: f64, y: f64, z: f32| [(x / s - 1.0) as f32, (1.0 - y / s) as f32, z];
    let mut positions = Vec::new();
    for _ in 0..3 * triangles {
        let mut sixteenths = || (rng.next_u64() % (16 * u64::from(side) + 1)) as f64;
        let (x, y) = (sixteenths(), sixteenths());
        positions.push(at(x, y, rng.next_f64() as f32));
    }
    let centre = first_sample.map(|o| (32 + o / 16) as f64);
    let corner = |dx: f64, dy: f64| at(centre[0] + 32.0 * dx, centre[1] + 32.0 * dy, 0.5);
    let ring = [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ];
    for k in 0..4 {
        positions.extend([at(centre[0], centre[1], 0.5), ring[k], ring[(k + 1) % 4]]);
    }
    let triangles = (0..positions.len() as u32 / 3)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// Every fragment of `view` under `rule`, found by testing every sample of every screen
/// triangle's box with the rule's thresholds: the definition [`TiePoints`] shortcuts.
#[expect(
    clippy::cast_possible_truncation,
    reason = "sample indices are below 16; depths are f32, as a GPU's; fragments index a small test viewport's samples"
)]
fn rasterized_under(view: &View<'_>, rule: EdgeTies) -> Oracle {
    let pixels = view.pixel_viewport();
    let pattern = view
        .samples()
        .unwrap_or(fragsim_raster::SamplePattern::CENTRE);
    let n = i64::from(pattern.count());
    let mut fragments = Vec::new();
    for prim in 0..view.triangle_count() {
        view.screen_triangles(prim, &mut |tri| {
            let [a, b, c] = tri.xy;
            let area = fragsim_raster::edge_function(a, b, c);
            let edges = [(b, c), (c, a), (a, b)];
            let threshold = thresholds(edges, rule);
            for j in 0..i64::from(pixels.height) {
                for i in 0..i64::from(pixels.width) {
                    for s in 0..n {
                        let o = pattern.fixed_offset(s as usize);
                        let at = [i * ONE + o[0], j * ONE + o[1]];
                        let e = edges.map(|(p, q)| fragsim_raster::edge_function(p, q, at));
                        if (0..3).any(|k| e[k] < threshold[k]) {
                            continue;
                        }
                        let z = (e[0] as f64 * tri.z[0]
                            + e[1] as f64 * tri.z[1]
                            + e[2] as f64 * tri.z[2])
                            / area as f64;
                        if let Some(depth_key) = fragsim_raster::depth_key(z as f32) {
                            fragments.push(Fragment {
                                pixel: ((j * i64::from(pixels.width) + i) * n + s) as u32,
                                depth_key,
                                prim,
                            });
                        }
                    }
                }
            }
        });
    }
    Oracle::from_fragments(view.viewport().pixels(), &fragments)
}

#[test]
fn each_rule_owns_the_edges_it_names() {
    // Edges of a positively oriented triangle in y-down rows: d.y < 0 is a left edge (the
    // interior to its right), d.y == 0 with d.x > 0 a top edge (the interior below).
    let directions = [
        [3, -2],
        [-3, -2],
        [0, -5],
        [3, 2],
        [-3, 2],
        [0, 5],
        [4, 0],
        [-4, 0],
    ];
    for rule in EdgeTies::ALL {
        for d in directions {
            let owns = if d[1] != 0 {
                (d[1] < 0) == rule.left()
            } else {
                (d[0] > 0) == rule.top()
            };
            let edge = ([10, 20], [10 + d[0], 20 + d[1]]);
            let got = thresholds([edge; 3], rule);
            assert_eq!(got, [i64::from(!owns); 3], "{rule:?} {d:?}");
        }
    }
}

#[test]
fn the_pipeline_rule_gives_the_rasterizers_thresholds() {
    for origin in [WindowOrigin::UpperLeft, WindowOrigin::LowerLeft] {
        let edges = [([0, 0], [5, 0]), ([5, 0], [0, 7]), ([0, 7], [0, 0])];
        assert_eq!(
            thresholds(edges, pipeline_rule(origin)),
            fragsim_raster::fill_thresholds(edges, origin)
        );
    }
}

#[test]
fn the_oracle_under_each_rule_is_what_rasterizing_under_it_gives() {
    let camera = Camera::from_row_major(IDENTITY);
    for (samples, seed) in [(1, 1), (1, 2), (4, 3), (8, 4)] {
        let side = 6;
        let pattern = fragsim_raster::SamplePattern::standard(samples).unwrap();
        let mesh = soup(side, 40, pattern.fixed_offset(0), seed);
        let conventions = Conventions {
            samples,
            ..Conventions::REFERENCE
        };
        let viewport = Viewport::new(side, side).unwrap();
        let view =
            View::with_conventions(&mesh, &camera, viewport, CullMode::None, conventions).unwrap();
        let oracle = Oracle::build(&view);
        let pipeline = pipeline_rule(WindowOrigin::UpperLeft);
        assert_eq!(rasterized_under(&view, pipeline), oracle, "the definition");
        let ties = TiePoints::of(&view);
        assert!(!ties.is_empty(), "seed {seed}: no tie in the soup");
        for rule in EdgeTies::ALL {
            let under = ties
                .oracle_under(&oracle, pipeline, rule)
                .unwrap_or_else(|| oracle.clone());
            assert_eq!(
                under,
                rasterized_under(&view, rule),
                "{rule:?}, {samples} samples, seed {seed}"
            );
            if rule != pipeline {
                assert!(
                    ties.differences(pipeline, rule) > 0,
                    "{rule:?}, {samples} samples, seed {seed}"
                );
            }
        }
    }
}

//! Implementation-defined edge ties through the binary (`docs/semantics.md`
//! §4, "Edge ties"): a capture that decides every sample exactly on an edge by one rule other
//! than fragsim's top-left is EQUAL, exactly and under f32 precision; a hole or a doubled sample
//! on a shared edge, or two rules in one capture, is DIFFERENT; a declared rule is owed.
//!
//! The scene is a grid of 3 × 3 quads on an 8 × 8 viewport through the identity matrix, every
//! vertex on a pixel centre, each quad split along a diagonal: centres lie exactly on shared
//! horizontal, vertical and diagonal edges and on the grid's outline.

use std::path::PathBuf;

use fragsim::dump::{Dump, DumpScheme, Words};
use fragsim::oracle::edge_ties::{pipeline_rule, TiePoints};
use fragsim::oracle::Oracle;
use fragsim::raster::scene_spec::{SceneSpec, ViewProjection};
use fragsim::raster::{EdgeTies, VertexPrecision, Viewport, WindowOrigin};

use super::scratch;
use super::soundness::compared;

const SIDE: u32 = 8;
/// Slots a pixel: more than any list of the grid holds (a doubled sample included).
const CAPACITY: u32 = 4;
const IDENTITY: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

/// The grid's OBJ: 3 × 3 quads split along a diagonal, every vertex on a pixel centre of the
/// 8 × 8 viewport.
fn grid_obj() -> String {
    let mut obj = String::new();
    // Vertex (i, j) on the centre of pixel (2i, 2j): window x = 2i + 1/2 = 4(x + 1).
    for j in 0..4 {
        for i in 0..4 {
            let (x, y) = (2.0 * f64::from(i) + 0.5, 2.0 * f64::from(j) + 0.5);
            let z = 0.25 + 0.05 * f64::from(i) + 0.02 * f64::from(j);
            obj += &format!("v {} {} {z}\n", x / 4.0 - 1.0, 1.0 - y / 4.0);
        }
    }
    for j in 0..3 {
        for i in 0..3 {
            let v = |di: u32, dj: u32| 4 * (j + dj) + i + di + 1;
            obj += &format!("f {} {} {}\n", v(0, 0), v(1, 0), v(1, 1));
            obj += &format!("f {} {} {}\n", v(0, 0), v(1, 1), v(0, 1));
        }
    }
    obj
}

/// A scene's oracle (fragsim's top-left rule) and the lists each rule gives.
struct Grid {
    dir: PathBuf,
    scene: SceneSpec,
    viewport: Viewport,
    oracle: Oracle,
    ties: TiePoints,
}

impl Grid {
    /// The grid of quads on 8 × 8 pixels, with `ties` declared (or not).
    fn new(name: &str, ties: Option<EdgeTies>) -> Self {
        Self::of(name, &grid_obj(), Viewport::new(SIDE, SIDE).unwrap(), ties)
    }

    /// The mesh `obj` (its x, y normalised device coordinates) seen through the identity matrix
    /// on `viewport`, with `ties` declared (or not), written in a scratch directory `name`.
    fn of(name: &str, obj: &str, viewport: Viewport, ties: Option<EdgeTies>) -> Self {
        let dir = scratch(name);
        let mesh = dir.join("mesh.obj");
        std::fs::write(&mesh, obj).unwrap();
        let mut scene = SceneSpec::hashed_mesh(&mesh, 0.0, 0.0).unwrap();
        scene.view_projection = Some(ViewProjection {
            row_major: IDENTITY,
            precision: VertexPrecision::F64,
        });
        scene.conventions.edge_ties = ties;
        let loaded = scene.load(None).unwrap();
        let view = scene.view(&loaded, viewport).unwrap();
        Self {
            oracle: Oracle::build(&view),
            ties: TiePoints::of(&view),
            dir,
            scene,
            viewport,
        }
    }

    /// The lists under `rule` (in rows; an upper-left window).
    fn lists(&self, rule: EdgeTies) -> Vec<Vec<u64>> {
        let pipeline = pipeline_rule(WindowOrigin::UpperLeft);
        let under = self.ties.oracle_under(&self.oracle, pipeline, rule);
        let oracle = under.as_ref().unwrap_or(&self.oracle);
        (0..oracle.pixels())
            .map(|p| oracle.pixel(p).to_vec())
            .collect()
    }

    /// `lists` written as a sorted fixed-capacity A-buffer dump in `name`, its directory.
    fn dump(&self, name: &str, lists: &[Vec<u64>]) -> PathBuf {
        let loaded = self.scene.load(None).unwrap();
        let view = self.scene.view(&loaded, self.viewport).unwrap();
        let scheme = DumpScheme::ABufferFixed {
            capacity: CAPACITY,
            sorted: true,
        };
        let mut dump = Dump::record(&view, self.scene.clone(), &scheme, "test").unwrap();
        let c = CAPACITY as usize;
        let mut slots = vec![u64::MAX; lists.len() * c];
        for (p, list) in lists.iter().enumerate() {
            assert!(list.len() <= c, "pixel {p} holds more than {c} fragments");
            slots[p * c..p * c + list.len()].copy_from_slice(list);
        }
        let counters = lists
            .iter()
            .map(|l| u32::try_from(l.len()).expect("at most CAPACITY fragments a pixel"))
            .collect();
        dump.arrays.insert("slots".into(), Words::U64(slots));
        dump.arrays.insert("counters".into(), Words::U32(counters));
        let dir = self.dir.join(name);
        dump.write(&dir).unwrap();
        dir
    }
}

/// Both ways of judging the grid: every bit owed, and within an f32 vertex stage's precision.
const JUDGED: [&[&str]; 2] = [&[], &["--vertex-precision", "f32"]];

/// A pixel whose list under `a` and under `b` has as many fragments but not the same: a centre
/// on an edge shared by two triangles, owned by one under `a` and by the other under `b`.
fn shared_edge_pixel(a: &[Vec<u64>], b: &[Vec<u64>]) -> usize {
    (0..a.len())
        .find(|&p| a[p].len() == b[p].len() && a[p] != b[p])
        .expect("a centre on a shared edge the rules give to different triangles")
}

#[test]
fn a_capture_deciding_edge_ties_by_any_one_rule_is_equal() {
    let grid = Grid::new("ties-one-rule", None);
    for rule in EdgeTies::ALL {
        let lists = grid.lists(rule);
        let dir = grid.dump(rule.name(), &lists);
        for options in JUDGED {
            let record = compared(&dir, options, 0);
            assert_eq!(record["equal"], true, "{rule:?} {options:?}: {record}");
            assert_eq!(record["edge_ties"], rule.name(), "{options:?}: {record}");
        }
        if rule != EdgeTies::TopLeft {
            assert_ne!(
                lists,
                grid.lists(EdgeTies::TopLeft),
                "{rule:?} changes nothing"
            );
        }
    }
}

#[test]
fn a_hole_on_a_shared_edge_is_different() {
    let grid = Grid::new("ties-hole", None);
    let (top_left, bottom_right) = (
        grid.lists(EdgeTies::TopLeft),
        grid.lists(EdgeTies::BottomRight),
    );
    let p = shared_edge_pixel(&top_left, &bottom_right);
    // Neither triangle's fragment: what fragsim's `--bug top-edge` plants.
    let mut holed = top_left.clone();
    holed[p].retain(|w| bottom_right[p].contains(w));
    assert_eq!(holed[p].len() + 1, top_left[p].len());
    let dir = grid.dump("hole", &holed);
    for options in JUDGED {
        let record = compared(&dir, options, 1);
        assert_eq!(record["equal"], false, "{options:?}: {record}");
        assert_eq!(record["mismatched_pixels"], 1, "{options:?}: {record}");
    }
}

#[test]
fn a_doubled_sample_on_a_shared_edge_is_different() {
    let grid = Grid::new("ties-double", None);
    let (top_left, bottom_right) = (
        grid.lists(EdgeTies::TopLeft),
        grid.lists(EdgeTies::BottomRight),
    );
    let p = shared_edge_pixel(&top_left, &bottom_right);
    // Both triangles' fragments.
    let mut doubled = top_left.clone();
    doubled[p].extend(bottom_right[p].iter().filter(|w| !top_left[p].contains(w)));
    doubled[p].sort_unstable();
    assert_eq!(doubled[p].len(), top_left[p].len() + 1);
    let dir = grid.dump("double", &doubled);
    for options in JUDGED {
        let record = compared(&dir, options, 1);
        assert_eq!(record["equal"], false, "{options:?}: {record}");
        assert_eq!(record["mismatched_pixels"], 1, "{options:?}: {record}");
    }
}

#[test]
fn two_edge_tie_rules_in_one_capture_are_different() {
    let grid = Grid::new("ties-mixed", None);
    let (top_left, bottom_right) = (
        grid.lists(EdgeTies::TopLeft),
        grid.lists(EdgeTies::BottomRight),
    );
    // The left half of the picture by one rule, the right half by the other: each half alone
    // is some conforming capture's, and each differs from the other rule's somewhere.
    let left = |p: usize| (p % SIDE as usize) < SIDE as usize / 2;
    let differ = |half: &dyn Fn(usize) -> bool| {
        (0..top_left.len()).any(|p| half(p) && top_left[p] != bottom_right[p])
    };
    assert!(differ(&left) && differ(&|p| !left(p)));
    let mixed: Vec<Vec<u64>> = (0..top_left.len())
        .map(|p| {
            if left(p) {
                top_left[p].clone()
            } else {
                bottom_right[p].clone()
            }
        })
        .collect();
    let dir = grid.dump("mixed", &mixed);
    for options in JUDGED {
        let record = compared(&dir, options, 1);
        assert_eq!(record["equal"], false, "{options:?}: {record}");
    }
}

#[test]
fn a_declared_edge_tie_rule_is_owed() {
    let grid = Grid::new("ties-declared", Some(EdgeTies::BottomRight));
    let declared = grid.dump("declared", &grid.lists(EdgeTies::BottomRight));
    let other = grid.dump("other", &grid.lists(EdgeTies::TopLeft));
    for options in JUDGED {
        let record = compared(&declared, options, 0);
        assert_eq!(record["equal"], true, "{options:?}: {record}");
        assert_eq!(record["edge_ties"], "bottom-right", "{options:?}: {record}");
        let other_record = compared(&other, options, 1);
        assert_eq!(other_record["equal"], false, "{options:?}: {other_record}");
    }
}

#[test]
fn a_tie_on_an_edge_leaving_the_viewport_may_fall_either_way_under_f32_precision_only() {
    // Found by the wgpu conform test on lavapipe: one triangle, corners (0, 0), (17, 10),
    // (1, −2) in half pixels on 8 × 4 pixels; the centres (5, 1) and (13, 7) lie exactly on its
    // edge from (1, −2) to (17, 10), which reaches past the viewport, and lavapipe covered the
    // second alone (it clips there). No fill rule does that, so exactly it is DIFFERENT; an f32
    // vertex stage may clip, so under precision it is ambiguous, not an error.
    let at = |h: [i32; 2], z: f32| {
        let (x, y) = (f64::from(h[0]) / 8.0 - 1.0, 1.0 - f64::from(h[1]) / 4.0);
        format!("v {x} {y} {z}\n")
    };
    let obj = at([0, 0], 0.0) + &at([17, 10], 0.0) + &at([1, -2], 0.25) + "f 1 2 3\n";
    let scene = Grid::of("ties-clipped", &obj, Viewport::new(8, 4).unwrap(), None);
    let (top_left, right) = (
        scene.lists(EdgeTies::TopLeft),
        scene.lists(EdgeTies::TopRight),
    );
    let differing: Vec<usize> = (0..top_left.len())
        .filter(|&p| top_left[p] != right[p])
        .collect();
    assert_eq!(differing, [2, 30], "the two centres on the right edge");
    let mut one = top_left.clone();
    one[30] = right[30].clone();
    let dir = scene.dump("one-of-two", &one);
    let record = compared(&dir, &[], 1);
    assert_eq!(record["equal"], false, "{record}");
    assert_eq!(record["mismatched_pixels"], 1, "{record}");
    let f32_record = compared(&dir, &["--vertex-precision", "f32"], 0);
    assert_eq!(f32_record["equal"], true, "{f32_record}");
    assert_eq!(f32_record["ambiguous_pixels"], 1, "{f32_record}");
}

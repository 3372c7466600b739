//! The verdict's mutation battery. A scene deeper than K with
//! shared edges and coplanar duplicates (three nested spheres, and a quad drawn three times in
//! front of them and another behind) is recorded in every dump layout; its dumps are mutated,
//! seeded and deterministically, in every way no conforming implementation could store (a
//! fragment dropped at each list position, a list emptied, a duplicate, a swap in sorted layouts,
//! a nearby triangle's id, a depth past its derived interval, a counter off by one, a node
//! unlinked or orphaned, a node past k lost, a torn word, a stray word past the counter with
//! `filled`, a K-nearest list short at coplanar fragments, exact storage's room cut, grown or
//! taken away, a K-slot list holding another K than its promise names, a list counter off at a
//! full pool, bits set outside a payload's fields), and in ways some conforming
//! implementation could (another arrival order in unsorted layouts, a depth moved inside its
//! interval, a key-only triangle swap at a shared edge). Each mutant is judged bit-exactly and
//! within the precision of an f32 vertex stage: every non-conforming one must be DIFFERENT, every
//! conforming one EQUAL where the judge admits it. Per-sample arrays are judged under the f32
//! analysis of the per-sample view as any other layout; masked nodes exactly only (the kinds
//! choose their sites from one list's possibilities, and a node stands for several samples'
//! lists). The test prints a kill table by kind and layout, per judge (`docs/testing.md` has it
//! and its command). Two families run on scenes of their own: triangles clipped by the near plane
//! ([`clipped`]) and headers that contradict themselves ([`header`]).

mod clipped;
mod header;
mod kinds;
mod storage;

use std::path::Path;

use fragsim::capture::Capacity;
use fragsim::capture::MaskedLists;
use fragsim::catalog::SchemeName;
use fragsim::dump::Direction;
use fragsim::dump::{DepthFormat, Dtype, Dump, DumpScheme, LayoutSpec, Payload, SlotOrder};
use fragsim::oracle::compare::{compare_with, flags, CompareOptions, Comparison};
use fragsim::oracle::precision::{compare_within, f32_reference, Precision};
use fragsim::oracle::samples::SampleOracle;
use fragsim::oracle::verdict::JudgeDump;
use fragsim::oracle::Oracle;
use fragsim::raster::conventions::VertexPrecision;
use fragsim::raster::scene_spec::SceneSpec;
use fragsim::raster::{Conventions, Scene, SplitMix64, View, Viewport};

use kinds::{mutant, Change, Kind, Pool, Site, KINDS};
use storage::{Item, Storage};

use super::scratch;

/// How many pixels each (kind, layout) mutates, one mutant each.
const MUTANTS: usize = 24;
/// Slots of the K-list layouts, fewer than the scene's layers.
const K: u32 = 2;
/// Slots a pixel of the fixed A-buffers, fewer than the deepest pixels (which overflow).
const CAPACITY: u32 = 4;
/// A unorm depth payload (a D24 depth) above a 32-bit primitive id.
const UNORM24: Payload = Payload {
    dtype: Dtype::U64,
    depth: DepthFormat::Unorm24,
    depth_shift: 32,
    prim_bits: 32,
};

/// Where the scene lies from the origin, in units of its largest sphere's radius: far enough that
/// an f32 vertex stage's rounding reaches a fraction of a subpixel (the orbit camera centres it),
/// so that some pixel centres lie inside the margin of an edge and their coverage is in doubt.
const OFFSET: f32 = 600.0;

/// How a mutant is judged.
enum Judge<'a> {
    /// Bit for bit against the oracle.
    Exact,
    /// Against an analysis: the f32 vertex stage's, or the exact one as a unorm field stores it.
    Within(Box<Precision>),
    /// A masked-node dump against the per-pixel view of the per-sample oracle.
    Masked(&'a MaskedLists),
}

impl Judge<'_> {
    fn judge(&self, oracle: &Oracle, dump: &Dump) -> Comparison {
        let options = CompareOptions::default();
        if let Self::Masked(lists) = self {
            return dump.compare_masked(lists, &options).unwrap().nodes;
        }
        let capture = dump.capture().unwrap();
        let words = dump.check_words().unwrap();
        match self {
            Self::Within(precision) => {
                compare_within(precision, oracle, &capture, Some(&words), &options)
            }
            _ => compare_with(oracle, &capture, Some(&words), &options),
        }
    }

    /// Whether a fragment stored as `item` at pixel `p` is one this judge admits there.
    fn admits(&self, oracle: &Oracle, p: usize, item: Item, ids: bool) -> bool {
        match self {
            Self::Within(precision) => precision.pixel(p).iter().any(|e| {
                (!ids || e.prim == item.prim()) && (e.key_lo..=e.key_hi).contains(&item.key())
            }),
            _ => oracle.pixel(p).contains(&item.word),
        }
    }
}

/// One layout under test: its dump in fragsim's own encoding (which the battery mutates), the
/// encoding it is judged in, its reference and judges.
struct Layout<'a> {
    name: &'static str,
    own: Dump,
    encoding: Option<LayoutSpec>,
    oracle: &'a Oracle,
    /// The judges, named: "exact" and, where the layout can be, "f32".
    judges: Vec<(&'static str, Judge<'a>)>,
    /// The f32 analysis as the layout stores depth, where it is judged so.
    possible: Option<&'a Precision>,
    format: DepthFormat,
    triangles: &'a [[u32; 3]],
}

/// A quad of side 1 at depth `z`, its four corners from vertex `first` (1-based), drawn `times`
/// times: coplanar duplicates, each a triangle pair sharing a diagonal.
fn quad(z: f32, first: usize, times: usize) -> String {
    let mut obj = String::new();
    for (x, y) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
        obj += &format!("v {} {} {}\n", x + OFFSET, y + OFFSET, z + OFFSET);
    }
    let [a, b, c, d] = [first, first + 1, first + 2, first + 3];
    for _ in 0..times {
        obj += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
    }
    obj
}

/// The battery's scene: three nested spheres (depth complexity 6, shared edges everywhere), a
/// quad drawn three times in front of them and one behind, written as an OBJ file.
fn scene_file(dir: &Path) -> std::path::PathBuf {
    let spheres = Scene::procedural("spheres:3").unwrap().mesh;
    let mut obj = String::new();
    for [x, y, z] in &spheres.positions {
        obj += &format!("v {} {} {}\n", x + OFFSET, y + OFFSET, z + OFFSET);
    }
    for [a, b, c] in &spheres.triangles {
        obj += &format!("f {} {} {}\n", a + 1, b + 1, c + 1);
    }
    let n = spheres.positions.len();
    obj += &quad(1.1, n + 1, 3);
    obj += &quad(-1.1, n + 5, 3);
    let path = dir.join("battery.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// The pixels of `layout` in each pool, from its unmutated dump's verdicts.
fn pools(layout: &Layout<'_>, storage: &Storage, correct: &[Comparison]) -> [Vec<usize>; 3] {
    let mut pools: [Vec<usize>; 3] = Default::default();
    let ids = storage.has_ids();
    for p in 0..layout.oracle.pixels() {
        let reference = layout.oracle.pixel(p);
        // Overflow past K or the capacity is the layout's promise, not a doubt.
        let doubtless = |c: &Comparison| c.verdicts[p] & !flags::OVERFLOWED == 0;
        if reference.len() < 2 {
            continue;
        }
        let certain = layout.possible.is_none_or(|precision| {
            let possible = precision.pixel(p);
            possible.len() == reference.len() && possible.iter().all(|e| e.certain())
        });
        let disjoint = layout.possible.is_none_or(|precision| {
            let mut spans: Vec<(u32, u32)> = precision
                .pixel(p)
                .iter()
                .map(|e| (e.key_lo, e.key_hi))
                .collect();
            spans.sort_unstable();
            spans.windows(2).all(|w| w[0].1 < w[1].0)
        });
        let decided = correct.iter().all(doubtless);
        let equal = correct.iter().all(|c| c.verdicts[p] & flags::DIFFERS == 0);
        if certain && disjoint && decided {
            pools[0].push(p);
        }
        let stored = storage.read(&layout.own, p);
        let tied = stored.iter().any(|item| {
            reference
                .iter()
                .filter(|&&r| (r >> 32) as u32 == item.key())
                .count()
                >= 2
        });
        if tied && equal && certain {
            pools[1].push(p);
        }
        if !ids && equal {
            if let Some(possible) = layout.possible.map(|precision| precision.pixel(p)) {
                let site = site(layout, p, Some(possible), &|_, _| 0);
                if kinds::edge_key(&site, &stored).is_some() {
                    pools[2].push(p);
                }
            }
        }
    }
    pools
}

fn site<'a>(
    layout: &'a Layout<'_>,
    p: usize,
    possible: Option<&'a [fragsim::oracle::precision::Possible]>,
    step: &'a dyn Fn(u32, i64) -> u32,
) -> Site<'a> {
    Site {
        p,
        reference: layout.oracle.pixel(p),
        possible,
        triangles: layout.triangles,
        step,
    }
}

/// One row of the kill table: a kind on a layout under one judge.
struct Tally {
    kind: String,
    layout: &'static str,
    judge: &'static str,
    right: usize,
    tried: usize,
    conforming: bool,
}

/// Runs every kind on `layout`; returns its rows and the misjudged mutants.
fn run(layout: &Layout<'_>, seed: u64, tallies: &mut Vec<Tally>, wrong: &mut Vec<String>) {
    let storage = Storage::of(&layout.own);
    let encoded = |dump: &Dump| dump.in_layout(layout.encoding).unwrap();
    let correct_dump = encoded(&layout.own);
    let correct: Vec<Comparison> = layout
        .judges
        .iter()
        .map(|(_, judge)| judge.judge(layout.oracle, &correct_dump))
        .collect();
    for ((name, _), c) in layout.judges.iter().zip(&correct) {
        assert!(
            c.is_equal(),
            "{} unmutated, {name}: {:?}",
            layout.name,
            c.counts
        );
    }
    let pools = pools(layout, &storage, &correct);
    assert!(
        pools[0].len() >= MUTANTS,
        "{}: {} clean pixels",
        layout.name,
        pools[0].len()
    );
    let format = layout.format;
    let step =
        move |key: u32, by: i64| format.key_of_field((format.field_of_key(key) as i64 + by) as u64);
    for (index, &kind) in KINDS.iter().enumerate() {
        let pool = match kind.pool() {
            Pool::Clean => &pools[0],
            Pool::Tie => &pools[1],
            Pool::Edge => &pools[2],
        };
        let mut rng = SplitMix64::new(seed << 8 | index as u64);
        let mut order = pool.clone();
        // A seeded shuffle: the first MUTANTS pixels the kind applies to.
        for i in (1..order.len()).rev() {
            let j = rng.next_u64() % (i as u64 + 1);
            order.swap(i, usize::try_from(j).expect("at most i"));
        }
        // Per judge: mutants judged as expected, mutants tried, and whether they were expected
        // EQUAL (a conforming change).
        let mut counts = vec![(0, 0, false); layout.judges.len()];
        let mut mutants_tried = 0;
        for &p in &order {
            if mutants_tried == MUTANTS || (mutants_tried == 1 && kind.global(&storage)) {
                break;
            }
            let possible = layout.possible.map(|precision| precision.pixel(p));
            let Some((changed, change)) = mutant(
                &layout.own,
                &storage,
                &site(layout, p, possible, &step),
                kind,
            ) else {
                continue;
            };
            let mut changed = encoded(&changed);
            if kind == Kind::OutsideBits && kinds::outside_fields(&mut changed, p).is_none() {
                continue;
            }
            mutants_tried += 1;
            for ((judge_name, judge), count) in layout.judges.iter().zip(&mut counts) {
                let expected = match change {
                    Change::Broken => false,
                    Change::Reordered => true,
                    Change::Moved(item) => judge.admits(layout.oracle, p, item, storage.has_ids()),
                    Change::OtherSnap => matches!(judge, Judge::Within(_)),
                };
                let got = judge.judge(layout.oracle, &changed).is_equal();
                count.1 += 1;
                count.2 |= expected;
                if got == expected {
                    count.0 += 1;
                } else {
                    wrong.push(format!(
                        "{} {} pixel {p} ({change:?}), {judge_name}: equal {got}, expected {expected}",
                        layout.name,
                        kind.name(),
                    ));
                }
            }
        }
        for ((judge, _), &(right, tried, conforming)) in layout.judges.iter().zip(&counts) {
            if tried > 0 {
                tallies.push(Tally {
                    kind: kind.name(),
                    layout: layout.name,
                    judge,
                    right,
                    tried,
                    conforming,
                });
            }
        }
    }
}

/// The kill table: a row per kind, a column per layout, `right/tried` per judge (exact, then
/// f32), `=` before the count where the change is conforming under that judge (kept EQUAL, not
/// killed); `-` where the kind has no meaning for the layout, `n/a` where the judge cannot judge
/// it.
fn table(layouts: &[&'static str], tallies: &[Tally]) -> String {
    let mut out = format!("{:<18}", "kind \\ layout");
    for name in layouts {
        out += &format!(" {name:>13}");
    }
    out.push('\n');
    let mut kinds: Vec<&str> = Vec::new();
    for t in tallies {
        if !kinds.contains(&t.kind.as_str()) {
            kinds.push(&t.kind);
        }
    }
    for kind in kinds {
        out += &format!("{kind:<18}");
        for &name in layouts {
            let cell = |judge: &str| {
                tallies
                    .iter()
                    .find(|t| t.kind == kind && t.layout == name && t.judge == judge)
                    .map(|t| {
                        let kept = if t.conforming { "=" } else { "" };
                        format!("{kept}{}/{}", t.right, t.tried)
                    })
            };
            let text = match (cell("exact"), cell("f32")) {
                (None, None) => "-".to_string(),
                (Some(e), None) => format!("{e} n/a"),
                (Some(e), Some(f)) => format!("{e} {f}"),
                (None, Some(f)) => format!("- {f}"),
            };
            out += &format!(" {text:>13}");
        }
        out.push('\n');
    }
    out
}

#[test]
fn every_non_conforming_mutant_is_different_and_every_conforming_change_equal() {
    let dir = scratch("mutation-battery");
    let mesh = scene_file(&dir);
    let spec = SceneSpec::mesh(&mesh, 30.0, 15.0);
    let scene = spec.load(None).unwrap();
    let viewport = Viewport::new(48, 36).unwrap();
    let view = spec.view(&scene, viewport).unwrap();
    let (oracle, f32_analysis) = f32_reference(&spec, viewport, None).unwrap();
    assert!(
        oracle.max_depth_complexity() > CAPACITY + 2,
        "deeper than K"
    );
    let triangles = &scene.mesh.triangles[..];
    let exact_conventions = Conventions {
        vertex_precision: VertexPrecision::F64,
        ..spec.conventions
    };
    let unorm_exact =
        Precision::derive(&view, &exact_conventions).stored_as(UNORM24.depth, &oracle);
    let unorm_f32 = f32_analysis.clone().stored_as(UNORM24.depth, &oracle);
    let record = |scene_view: &View<'_>, scene_spec: &SceneSpec, scheme: DumpScheme| {
        Dump::record(scene_view, scene_spec.clone(), &scheme, "battery").unwrap()
    };
    let mdts = |direction| DumpScheme::Mdts { k: K, direction };
    let abuffer = DumpScheme::ABufferFixed {
        capacity: CAPACITY,
        sorted: false,
    };
    let lists = |scheme| DumpScheme::LinkedLists {
        scheme,
        k: K,
        // Room past the scene's fragments, for a counter one too many.
        pool: u32::try_from(oracle.fragments()).expect("a test view's fragments") + 8,
        spec: LayoutSpec::FRAGSIM_LISTS,
    };
    let engine_numbering = LayoutSpec::LinkedList {
        payload: Payload::FRAGMENT,
        null: u32::MAX,
        node_base: 0,
    };
    let slot_major = LayoutSpec::Slots {
        order: SlotOrder::SlotMajor,
        payload: None,
    };
    let single: [(&str, DumpScheme, Option<LayoutSpec>); 19] = [
        ("mdts", mdts(Direction::Ascending), None),
        ("mdts-desc", mdts(Direction::Descending), None),
        ("mdts32", DumpScheme::Mdts32 { k: K }, None),
        // Every layer: more key-only fragments at shared edges whose coverage is in doubt.
        (
            "mdts32-all",
            DumpScheme::Mdts32 {
                k: oracle.max_depth_complexity(),
            },
            None,
        ),
        (
            "kbuffer",
            DumpScheme::KBuffer {
                scheme: SchemeName::Kbuffer,
                k: K,
            },
            None,
        ),
        // The ordered interlocks: the K nearest, and the first K in primitive order.
        (
            "kbuf-ordered",
            DumpScheme::KBuffer {
                scheme: SchemeName::KbufferInterlockOrdered,
                k: K,
            },
            None,
        ),
        (
            "kbuf-first",
            DumpScheme::KBuffer {
                scheme: SchemeName::KbufferInterlockOrderedFirst,
                k: K,
            },
            None,
        ),
        ("abuffer", abuffer.clone(), None),
        // Sorted in place on the GPU: judged in stored order.
        (
            "abuf-sorted",
            DumpScheme::ABufferFixed {
                capacity: CAPACITY,
                sorted: true,
            },
            None,
        ),
        (
            "abuffer-offs",
            DumpScheme::ABufferExact {
                counts: oracle.depth_complexity(),
                sorted: false,
            },
            None,
        ),
        ("list", lists(SchemeName::LinkedList), None),
        (
            "list-engine",
            lists(SchemeName::LinkedList),
            Some(engine_numbering),
        ),
        ("list-nearest", lists(SchemeName::LinkedListNearest), None),
        // A pool of exactly the scene's fragments, as `--capacity auto` sizes it.
        (
            "list-full",
            DumpScheme::LinkedLists {
                scheme: SchemeName::LinkedList,
                k: K,
                pool: u32::try_from(oracle.fragments()).expect("a test view's fragments"),
                spec: LayoutSpec::FRAGSIM_LISTS,
            },
            None,
        ),
        (
            "layer-major",
            DumpScheme::LayerMajor {
                k: K,
                payload: Payload::FRAGMENT,
            },
            None,
        ),
        ("mdts-slotmaj", mdts(Direction::Ascending), Some(slot_major)),
        ("abuf-slotmaj", abuffer.clone(), Some(slot_major)),
        (
            "mdts-unorm24",
            mdts(Direction::Ascending),
            Some(LayoutSpec::Slots {
                order: SlotOrder::PixelMajor,
                payload: Some(UNORM24),
            }),
        ),
        (
            "list-unorm24",
            lists(SchemeName::LinkedList),
            Some(LayoutSpec::LinkedList {
                payload: UNORM24,
                null: u32::MAX,
                node_base: 0,
            }),
        ),
    ];
    let mut layouts = Vec::new();
    for (name, scheme, encoding) in single {
        let unorm = name.ends_with("unorm24");
        let (exact, within, possible) = if unorm {
            (
                Judge::Within(Box::new(unorm_exact.clone())),
                Judge::Within(Box::new(unorm_f32.clone())),
                &unorm_f32,
            )
        } else {
            (
                Judge::Exact,
                Judge::Within(Box::new(f32_analysis.clone())),
                &f32_analysis,
            )
        };
        layouts.push(Layout {
            name,
            own: record(&view, &spec, scheme),
            encoding,
            oracle: &oracle,
            judges: vec![("exact", exact), ("f32", within)],
            possible: Some(possible),
            format: if unorm {
                UNORM24.depth
            } else {
                DepthFormat::F32
            },
            triangles,
        });
    }
    // Per sample: 4 samples a pixel, each sample a list; and the masked nodes, a list a pixel.
    let mut sampled = spec.clone();
    sampled.conventions.samples = 4;
    let small = Viewport::new(24, 18).unwrap();
    let view4 = sampled.view(&scene, small).unwrap();
    let samples = SampleOracle::build(&view4).unwrap();
    let per_pixel = samples.per_pixel();
    // The f32 analysis per sample: bounds at each sample position (the per-sample f32 refusal
    // is lifted, `docs/semantics.md` §10, "Per sample").
    let f32_per_sample = Precision::derive(
        &view4,
        &Conventions {
            vertex_precision: VertexPrecision::F32,
            ..sampled.conventions
        },
    );
    let nodes = Oracle::from_capture(&per_pixel.packed_capture(Capacity::Unbounded));
    let deepest = nodes.max_depth_complexity();
    for (name, scheme) in [
        ("mdts-4x", mdts(Direction::Ascending)),
        ("abuffer-4x", abuffer),
    ] {
        layouts.push(Layout {
            name,
            own: record(&view4, &sampled, scheme),
            encoding: None,
            oracle: samples.oracle(),
            judges: vec![
                ("exact", Judge::Exact),
                ("f32", Judge::Within(Box::new(f32_per_sample.clone()))),
            ],
            possible: Some(&f32_per_sample),
            format: DepthFormat::F32,
            triangles,
        });
    }
    layouts.push(Layout {
        name: "masked-4x",
        own: Dump::record_masked(&view4, sampled.clone(), deepest, "battery").unwrap(),
        encoding: None,
        oracle: &nodes,
        // Exactly only: the kinds choose their sites (away from any edge, past an interval) from
        // one list's possibilities, and a node stands for the lists of the samples of its mask.
        // Its f32 judgement (`Dump::compare_masked_within`) is the oracle's unit test's.
        judges: vec![("exact", Judge::Masked(&per_pixel))],
        possible: None,
        format: DepthFormat::F32,
        triangles,
    });
    let bounds = f32_analysis.bounds();
    run_battery(
        &layouts,
        1000,
        &format!(
            "scene: {} fragments, depth complexity up to {}; f32 analysis: vertex error up to \
             {:.2} subpixels, {} (pixel, triangle) pairs in doubt\n\
             cells: right/tried exactly, then under f32 precision; =: a conforming change, kept \
             EQUAL; -: no such mutant in the layout; n/a: not judged so",
            oracle.fragments(),
            oracle.max_depth_complexity(),
            bounds.max_vertex_error_subpixels,
            bounds.ambiguous_pairs,
        ),
    );
}

/// Runs every kind on every layout (seeded by the layout's index), prints `scene` and the kill
/// table, and checks that more than `least` mutants were judged, every one as expected.
fn run_battery(layouts: &[Layout<'_>], least: usize, scene: &str) {
    let (mut tallies, mut wrong) = (Vec::new(), Vec::new());
    for (seed, layout) in layouts.iter().enumerate() {
        run(layout, seed as u64, &mut tallies, &mut wrong);
    }
    let names: Vec<&str> = layouts.iter().map(|l| l.name).collect();
    println!("{scene}\n{}", table(&names, &tallies));
    let total: usize = tallies.iter().map(|t| t.tried).sum();
    assert!(total > least, "{total} judgements");
    assert!(wrong.is_empty(), "misjudged mutants: {wrong:#?}");
}

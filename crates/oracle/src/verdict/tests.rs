//! The verdict's entry points on a small scene: the oracle against itself, a dump of fragsim's
//! own MDTS, and that dump with one fragment taken out; a masked-node dump whose nodes a merge
//! with a planted bug made.

use fragsim_capture::{merge_samples, MaskedLists, MaskedNode};
use fragsim_dump::Direction;
use fragsim_raster::{Fragment, VertexPrecision, View, Viewport};

use super::*;
use crate::samples::SampleOracle;
use fragsim_dump::{DumpScheme, Words};

/// Calls `test` with the view of a small scene (32 × 24), its oracle and fragsim's MDTS dump
/// of it (K = every fragment, so that the dump holds every fragment).
fn with_scene(test: impl FnOnce(&View<'_>, &Oracle, &Dump)) {
    let spec = SceneSpec::named("spheres:2", 30.0, 15.0);
    let scene = spec.load(None).unwrap();
    let view = scene
        .view(Viewport::new(32, 24).unwrap(), &spec.orbit())
        .unwrap();
    let oracle = Oracle::build(&view);
    let k = oracle.max_depth_complexity();
    let scheme = DumpScheme::Mdts {
        k,
        direction: Direction::Ascending,
    };
    let dump = Dump::record(&view, spec, &scheme, "test").unwrap();
    test(&view, &oracle, &dump);
}

const OPTIONS: Options = Options {
    depth_ulps: 0,
    examples: 4,
};

#[test]
fn the_oracle_judged_against_itself_is_equal() {
    with_scene(|view, oracle, _| {
        for precision in [VertexPrecision::F64, VertexPrecision::F32] {
            let reference = Reference::of_view(oracle, view, precision);
            let verdict = judge(&reference, Candidate::Oracle(oracle), &OPTIONS).unwrap();
            assert!(
                verdict.equal,
                "{precision:?}: {:?}",
                verdict.comparison.counts
            );
            assert_eq!(verdict.mismatched_lists(), 0);
            assert_eq!(verdict.comparison.diff.captured, oracle.fragments() as u64);
            assert!(verdict.examples.is_empty() && verdict.notes.is_empty());
            assert_eq!(verdict.bounds.is_some(), precision == VertexPrecision::F32);
        }
    });
}

#[test]
fn a_dump_missing_one_fragment_is_different_at_that_pixel_alone() {
    with_scene(|view, oracle, dump| {
        let reference = Reference::of_view(oracle, view, VertexPrecision::F64);
        let equal = judge(&reference, Candidate::Dump(dump), &OPTIONS).unwrap();
        assert!(equal.equal && equal.comparison.words_checked);
        assert_eq!(equal.compared.rsplit(", ").next(), Some("bit for bit"));
        // The nearest fragment of the first pixel with two dropped: the next one moves up, as if the
        // nearest never arrived (no word rule is broken, only the list).
        let k = dump.header.k.unwrap() as usize;
        let pixel = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() >= 2)
            .unwrap();
        let mut dropped = dump.clone();
        let Some(Words::U64(slots)) = dropped.arrays.get_mut("slots") else {
            panic!("an MDTS dump holds u64 slots");
        };
        let list = &mut slots[pixel * k..(pixel + 1) * k];
        list.rotate_left(1);
        list[k - 1] = u64::MAX;
        let verdict = judge(&reference, Candidate::Dump(&dropped), &OPTIONS).unwrap();
        assert!(!verdict.equal);
        assert_eq!(verdict.mismatched_lists(), 1);
        assert_eq!(verdict.comparison.diff.lost, 1);
        let [example] = verdict.examples.as_slice() else {
            panic!("one example: {:?}", verdict.examples);
        };
        let width = dump.header.width as usize;
        assert_eq!(
            (example.pixel, example.x as usize, example.y as usize),
            (pixel, pixel % width, pixel / width)
        );
        assert_eq!(example.verdict, ["missing"]);
        assert_eq!(example.reference.len(), example.candidate.len() + 1);
    });
}

/// A masked-node dump of `spheres:3` at 4 samples whose nodes are those `merge` makes of the
/// per-sample oracle's fragments (the capacity the most nodes a pixel has), with the per-pixel
/// view of the per-sample oracle it is judged against.
/// A merge of a pixel's sample fragments into masked nodes, as `merge_samples` is.
type Merge = fn(u32, &mut [Fragment], &mut dyn FnMut(u32, MaskedNode));

#[expect(
    clippy::cast_possible_truncation,
    reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32); the test's sample indices index a small viewport; a pixel holds at most one fragment per triangle, and triangle ids are u32"
)]
fn masked_dump_merged_by(merge: Merge) -> (Dump, Reference<'static>) {
    let mut spec = SceneSpec::named("spheres:3", 30.0, 15.0);
    spec.conventions.samples = 4;
    let scene = spec.load(None).unwrap();
    let view = spec.view(&scene, Viewport::new(24, 18).unwrap()).unwrap();
    let sampled = SampleOracle::build(&view).unwrap();
    let lists = sampled.oracle().lists();
    let mut fragments: Vec<Fragment> = (0..lists.pixels())
        .flat_map(|sample| {
            lists.pixel(sample).iter().map(move |&packed| Fragment {
                pixel: sample as u32,
                depth_key: (packed >> 32) as u32,
                prim: packed as u32,
            })
        })
        .collect();
    let pixels = view.pixel_viewport().pixels();
    let mut nodes = Vec::new();
    merge(4, &mut fragments, &mut |pixel, node| {
        nodes.push((pixel, node));
    });
    let merged = MaskedLists::from_nodes(4, pixels, nodes);
    let capacity = (0..pixels).map(|p| merged.pixel(p).len()).max().unwrap();
    let mut dump = Dump::record_masked(&view, spec, capacity as u32, "test").unwrap();
    let counters: Vec<u32> = (0..pixels).map(|p| merged.pixel(p).len() as u32).collect();
    let (mut words, mut masks) = (
        vec![u64::MAX; pixels * capacity],
        vec![0; pixels * capacity],
    );
    for p in 0..pixels {
        for (i, node) in merged.pixel(p).iter().enumerate() {
            words[p * capacity + i] = node.packed();
            masks[p * capacity + i] = node.mask;
        }
    }
    for (name, array) in [
        ("counters", Words::U32(counters)),
        ("masks", Words::U32(masks)),
        ("nodes", Words::U64(words)),
    ] {
        *dump.arrays.get_mut(name).unwrap() = array;
    }
    let (w, h) = (dump.header.width, dump.header.height);
    (dump, Reference::masked(sampled.per_pixel(), (w, h)))
}

/// The masked-node schemes' merge ([`merge_samples`]) with one bug planted: a node keeps the
/// farthest depth key of its samples, not the nearest.
fn merge_keeping_the_farthest(
    samples: u32,
    fragments: &mut [Fragment],
    emit: &mut dyn FnMut(u32, MaskedNode),
) {
    fragments.sort_unstable_by_key(|f| (f.pixel / samples, f.prim, f.depth_key));
    let mut rest = &*fragments;
    while let Some(first) = rest.first() {
        let (pixel, prim) = (first.pixel / samples, first.prim);
        let same = rest
            .iter()
            .take_while(|f| f.pixel / samples == pixel && f.prim == prim)
            .count();
        let mask = rest[..same]
            .iter()
            .fold(0_u32, |mask, f| mask | 1 << (f.pixel % samples));
        let depth_key = rest[same - 1].depth_key;
        emit(
            pixel,
            MaskedNode {
                depth_key,
                prim,
                mask,
            },
        );
        rest = &rest[same..];
    }
}

#[test]
#[expect(
    clippy::shadow_unrelated,
    reason = "each planted bug's reference and verdict are its own case's"
)]
fn a_bug_planted_in_the_schemes_merge_is_caught_by_the_oracles_own_merge() {
    // The control: the schemes' merge, as it is, holds the per-pixel view exactly.
    let (dump, reference) = masked_dump_merged_by(|samples, fragments, mut emit| {
        merge_samples(samples, fragments, &mut emit);
    });
    let verdict = judge(&reference, Candidate::Dump(&dump), &OPTIONS).unwrap();
    assert!(verdict.equal, "{:?}", verdict.comparison.counts);
    // The planted bug: the reference does not share it, so the verdict sees it.
    let (planted, reference) = masked_dump_merged_by(merge_keeping_the_farthest);
    let verdict = judge(&reference, Candidate::Dump(&planted), &OPTIONS).unwrap();
    assert!(!verdict.equal);
    assert!(verdict.comparison.counts.extra > 0 && verdict.comparison.counts.missing > 0);
}

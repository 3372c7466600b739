//! The verdict's entry points on a small scene: the oracle against itself, a dump of fragsim's
//! own MDTS, and that dump with one fragment taken out.

use fragsim_capture::schemes::mdts::Direction;
use fragsim_raster::{VertexPrecision, View, Viewport};

use super::*;
use crate::dump::{DumpScheme, Words};

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

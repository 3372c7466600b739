//! Tests of the masked-node dump under an f32 vertex stage: equal per sample at 4 and 8 samples,
//! and a dropped sample or a stray key different.

use fragsim_dump::Words;
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::{Conventions, Viewport};

use super::*;
use crate::precision::f32_reference;

const CAPACITY: u32 = 64;

fn options() -> CompareOptions<'static> {
    CompareOptions {
        depth_ulps: 0,
        examples: 4,
        complete: None,
    }
}

/// A masked-node dump of `spheres:3` at `samples` made through the rasterizer's f32 vertex
/// stage, with the per-sample f64 oracle and f32 analysis it is judged by.
fn f32_masked(samples: u32) -> (Dump, Precision, Oracle) {
    let mut spec = SceneSpec::named("spheres:3", 30.0, 15.0);
    spec.conventions = Conventions {
        vertex_precision: VertexPrecision::F32,
        samples,
        ..Conventions::REFERENCE
    };
    let viewport = Viewport::new(40, 30).unwrap();
    let loaded = spec.load(None).unwrap();
    let view = spec.view(&loaded, viewport).unwrap();
    let dump = Dump::record_masked(&view, spec.clone(), CAPACITY, "test").unwrap();
    let (oracle, precision) = f32_reference(&spec, viewport, None).unwrap();
    (dump, precision, oracle)
}

/// The words of array `name`, which the dump holds as u32.
fn u32s<'d>(dump: &'d Dump, name: &str) -> &'d [u32] {
    match &dump.arrays[name] {
        Words::U32(words) => words,
        Words::U64(_) => panic!("array {name} is u64"),
    }
}

/// The words of array `name`, which the dump holds as u64.
fn u64s<'d>(dump: &'d Dump, name: &str) -> &'d [u64] {
    match &dump.arrays[name] {
        Words::U64(words) => words,
        Words::U32(_) => panic!("array {name} is u32"),
    }
}

/// The first stored node covering at least two samples, each certain for its primitive:
/// its slot, word and mask, and the least highest key of those samples.
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry's low half is its primitive id"
)]
fn certain_node(dump: &Dump, precision: &Precision, n: usize) -> (usize, u64, u32, u32) {
    let counters = u32s(dump, "counters");
    let nodes = u64s(dump, "nodes");
    let masks = u32s(dump, "masks");
    (0..counters.len())
        .flat_map(|p| (0..counters[p] as usize).map(move |i| (p, p * CAPACITY as usize + i)))
        .find_map(|(p, slot)| {
            let (word, mask) = (nodes[slot], masks[slot]);
            let entries: Option<Vec<_>> = (0..n)
                .filter(|&s| mask >> s & 1 == 1)
                .map(|s| {
                    let q = precision
                        .pixel(p * n + s)
                        .iter()
                        .find(|q| q.prim == word as u32);
                    q.filter(|q| q.certain()).copied()
                })
                .collect();
            let entries = entries.filter(|e| e.len() >= 2)?;
            let hi = entries.iter().map(|q| q.key_hi).min()?;
            Some((slot, word, mask, hi))
        })
        .expect("a node covering two certain samples")
}

#[test]
fn an_f32_masked_dump_is_equal_per_sample_and_a_dropped_sample_or_a_stray_key_is_not() {
    for samples in [4, 8] {
        let (dump, precision, oracle) = f32_masked(samples);
        let judged = dump
            .compare_masked_within(&precision, &oracle, &options())
            .unwrap();
        assert_eq!(judged.nodes.verdicts.len(), oracle.pixels());
        assert_eq!(
            judged.nodes.diff.mismatched_pixels, 0,
            "{samples}x: {:?}",
            judged.nodes.diff
        );
        let n = samples as usize;
        let (slot, word, mask, key_hi) = certain_node(&dump, &precision, n);
        let shape = dump.header.arrays["masks"].shape.clone();
        let mut dropped = dump.clone();
        let mut masks = u32s(&dump, "masks").to_vec();
        masks[slot] = mask & (mask - 1);
        dropped.set_array("masks", Words::U32(masks), shape.clone());
        let mut stray = dump.clone();
        let mut nodes = u64s(&dump, "nodes").to_vec();
        nodes[slot] = u64::from(key_hi + 1) << 32 | (word & u64::from(u32::MAX));
        stray.set_array("nodes", Words::U64(nodes), shape);
        // The pixel's first covered sample: the one dropped, or the one a stray key is
        // charged to. Dropping the sample of the node's nearest depth may also leave its key
        // below the other samples' intervals, a second error.
        let planted = slot / CAPACITY as usize * n + mask.trailing_zeros() as usize;
        for (name, bugged) in [
            ("a sample dropped", dropped),
            ("a key past its interval", stray),
        ] {
            #[expect(clippy::shadow_unrelated, reason = "each case's verdict")]
            let judged = bugged
                .compare_masked_within(&precision, &oracle, &options())
                .unwrap();
            let flags = judged.nodes.verdicts[planted];
            assert_ne!(flags & flags::DIFFERS, 0, "{samples}x {name}: {flags:#b}");
            let wrong = judged.nodes.diff.mismatched_pixels;
            assert!(wrong <= 2, "{samples}x {name}: {:?}", judged.nodes.diff);
        }
    }
}

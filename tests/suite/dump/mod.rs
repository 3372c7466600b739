//! The interchange with GPU backends (`docs/dump-format.md`): dumps round-trip through files,
//! decode to exactly what the scheme captured, and `compare` names every kind of difference; the
//! triangle export carries everything a backend needs to reproduce the oracle. CI has no GPU:
//! these tests are the host side of `backends/cuda`.

use std::path::PathBuf;

use fragsim::catalog::SchemeName;
use fragsim::dump::Direction;
use fragsim::dump::{Dump, DumpScheme, Words};
use fragsim::oracle::compare::{CompareOptions, Comparison};
use fragsim::oracle::verdict::JudgeDump;
use fragsim::oracle::Oracle;
use fragsim::raster::scene_spec::SceneSpec;
use fragsim::raster::{Scene, Viewport};

mod allowances;
mod binary;
mod bounded_input;
mod compare;
mod edge_ties;
mod files;
mod header_lies;
mod layouts;
mod mutations;
mod numbers;
mod parse;
mod samples;
mod slots;
mod soundness;

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("dump-tests", name)
}

const SCENE: &str = "spheres:3";
/// Not square, so that a width/height mix-up cannot pass.
const WIDTH: u32 = 48;
const HEIGHT: u32 = 36;

fn spec() -> SceneSpec {
    SceneSpec::named(SCENE, 30.0, 15.0)
}

fn with_view<R>(f: impl FnOnce(&fragsim::raster::View<'_>, &Oracle) -> R) -> R {
    let scene = Scene::procedural(SCENE).unwrap();
    let view = scene
        .view(Viewport::new(WIDTH, HEIGHT).unwrap(), &spec().orbit())
        .unwrap();
    let oracle = Oracle::build(&view);
    f(&view, &oracle)
}

fn every_layout(oracle: &Oracle) -> Vec<DumpScheme> {
    let k = oracle.max_depth_complexity();
    assert!(k >= 4, "the scene must have several layers, got {k}");
    vec![
        DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        },
        DumpScheme::Mdts {
            k: 2,
            direction: Direction::Descending,
        },
        DumpScheme::Mdts32 { k: 3 },
        // The k-buffers' slots: the K nearest, and the first K in primitive order (fewer than
        // the scene's layers, so that the promise differs from MDTS's).
        DumpScheme::KBuffer {
            scheme: SchemeName::Kbuffer,
            k,
        },
        DumpScheme::KBuffer {
            scheme: SchemeName::KbufferInterlockOrderedFirst,
            k: 2,
        },
        DumpScheme::ABufferFixed {
            capacity: k,
            sorted: true,
        },
        DumpScheme::ABufferFixed {
            capacity: 2,
            sorted: false,
        },
        DumpScheme::ABufferExact {
            counts: oracle.depth_complexity(),
            sorted: false,
        },
    ]
}

fn u64_slots(dump: &mut Dump) -> &mut Vec<u64> {
    match dump.arrays.get_mut("slots") {
        Some(Words::U64(w)) => w,
        _ => panic!("no u64 slots"),
    }
}

fn counters(dump: &mut Dump) -> &mut Vec<u32> {
    match dump.arrays.get_mut("counters") {
        Some(Words::U32(w)) => w,
        _ => panic!("no counters"),
    }
}

/// The dump compared with the oracle, every word read.
fn judged(dump: &Dump, oracle: &Oracle) -> Comparison {
    let options = CompareOptions {
        examples: 8,
        ..CompareOptions::default()
    };
    dump.compare(oracle, &options).unwrap()
}

/// A pixel whose list has between `min` and `max` fragments.
fn pixel_with(oracle: &Oracle, min: usize, max: usize) -> usize {
    (0..oracle.pixels())
        .find(|&p| (min..=max).contains(&oracle.pixel(p).len()))
        .unwrap_or_else(|| panic!("no pixel with {min}..={max} fragments"))
}

/// A 2 × 2 MDTS dump header (K = 2) whose `slots` array has this file name and shape (JSON).
fn mdts_header(file: &str, shape: &str) -> String {
    format!(
        r#"{{"format": "fragsim-dump", "version": 1, "scene": {{"name": "quads:2",
            "view_degrees": 30.0, "elevation_degrees": 15.0}}, "width": 2, "height": 2,
            "scheme": "mdts", "k": 2,
            "arrays": {{"slots": {{"file": {file:?}, "dtype": "u64", "shape": {shape}}}}}}}"#
    )
}

/// Parses `header` from memory with a reader that records every file name it is asked for and
/// returns eight empty slots.
fn parse_recording(header: &str) -> (Result<Dump, String>, Vec<String>) {
    let mut asked = Vec::new();
    let parsed = Dump::parse("dump.json", header.as_bytes(), |file| {
        asked.push(file.to_string());
        Ok(vec![0xFF; 8 * 8])
    });
    (parsed.map_err(|e| e.to_string()), asked)
}

//! The `dump_layouts` target: dumps built from the fuzzer's bytes field by field, so that every
//! input reaches the layout decoders rather than the JSON parser. Each input is one dump of a
//! slot (slot-major or pixel-major, any payload), linked-list, layer-major or memory layout (`docs/dump-format.md`) on a viewport of at most
//! 4 × 3 pixels, with the header's scene fields arbitrary: raw f64 bit patterns for the orbit and
//! the engine's view-projection matrix (f32 or f64), any conventions, a mesh hash or a string in
//! its place. Links are drawn from a few node numbers around the pool (so cycles, shared nodes,
//! links out of the pool and past the node counter are common), counters run past their storage,
//! and an array may have the wrong size or type.
//!
//! Checked, for every input:
//! - the header encodes, and parses back to the same dump with every number bit for bit, or
//!   encoding refuses a non-finite number (one of the scene's own checks);
//! - a dump that breaks its layout (an array of the wrong size or type, `k` of 0, a payload whose
//!   fields overlap, a list's `null` that is a node's number) is refused with an error naming
//!   what is wrong: by parsing where the header alone contradicts itself, else by decoding and
//!   by the word check alike;
//! - any other dump decodes, and its word check and lists are what a model of the layout's rules
//!   written here gives: each linked list walked from its head once, cut at its first link out of
//!   the pool, to a node the counter never handed out, or to a node already reached (at most
//!   `pool + pixels` steps in all, so a cycle is found in bounded time); each layer counter past
//!   its `k` layers named; every impossible depth key named; a slot dump decodes and checks as
//!   the same words in fragsim's own encoding (pixel-major, unpacked) do, each corrupt word named
//!   as the dump stores it;
//! - the comparison with an oracle made of the capture itself flags exactly the pixels with
//!   corrupt words, and calls the rest equal (an A-buffer's pixels may differ: its counters may
//!   claim fragments its slots lack).
//!
//! The shape of the memory of a `memory` dump is the scheme's own, from the catalog (or wrong on
//! purpose); its words are arbitrary, so each scheme's resolve runs on memory no run left.

use fragsim::capture::Capture;
use fragsim::catalog::SchemeName;
use fragsim::dump::{
    ArraySpec, Corruption, DepthFormat, Dtype, Dump, DumpError, Header, Payload, Words,
};
use fragsim::oracle::compare::{compare_with, flags, CompareOptions};
use fragsim::oracle::Oracle;
use fragsim::raster::scene_spec::{mesh_hash, ViewProjection};
use fragsim::raster::{DepthRange, VertexPrecision, Viewport, WindowOrigin};

use super::input::Input;
use lists::{layer_major, linked_lists};
use memory::memory;
use slots::slots;

mod lists;
mod memory;
mod slots;

/// The name errors give the header.
const NAME: &str = "fuzz/layouts.json";

/// The header every input starts from: its other fields are set from the input.
const BASE: &str = r#"{"format": "fragsim-dump", "version": 1, "scene": {"name": "quads:1"},
    "width": 1, "height": 1, "scheme": "mdts", "arrays": {}}"#;

/// Builds a dump from `data` and checks it.
pub(crate) fn check(data: &[u8]) {
    let mut input = Input::new(data);
    let built = build(&mut input);
    let dump = &built.dump;
    let (text, files) = match dump.encode() {
        Ok(encoded) => encoded,
        Err(error) => {
            assert!(
                dump.header.scene.check_finite().is_err(),
                "encoding refused a dump whose scene is finite: {error}"
            );
            assert!(
                error.to_string().contains("scene"),
                "{error} does not name the scene"
            );
            return;
        }
    };
    let parsed = Dump::parse(NAME, text.as_bytes(), |file| {
        files
            .get(file)
            .cloned()
            .ok_or_else(|| DumpError::Invalid(format!("{file} was not encoded")))
    });
    // What the header alone contradicts (an array's size, the list numbering) is refused before
    // the arrays are read, naming the fault as decoding would.
    let again = match parsed {
        Ok(again) => again,
        Err(error) => {
            let fault = built.expected.as_ref().err().unwrap_or_else(|| {
                panic!("an encoded dump that keeps its layout does not parse: {error}\n{text}")
            });
            assert!(
                error.to_string().contains(fault.as_str()),
                "the parse error {error:?} does not name {fault:?}\n{text}"
            );
            return;
        }
    };
    assert_eq!(&again, dump, "a dump differs after encoding and parsing");
    // Text equality pins every number to its bits (`==` would let -0.0 pass for 0.0).
    assert_eq!(
        again.encode().expect("it encoded once").0,
        text,
        "a dump encodes differently after parsing"
    );
    let (capture, words) = match (dump.capture(), dump.check_words()) {
        (Ok(capture), Ok(words)) => (capture, words),
        (Err(error), Err(_)) => {
            let fault = built.expected.as_ref().err().unwrap_or_else(|| {
                panic!("a dump that keeps its layout is refused: {error}\n{text}")
            });
            assert!(
                error.to_string().contains(fault.as_str()),
                "the error {error:?} does not name {fault:?}\n{text}"
            );
            return;
        }
        (capture, words) => panic!(
            "decoding and the word check disagree: {:?} against {:?}",
            capture.err(),
            words.err()
        ),
    };
    if let Err(fault) = &built.expected {
        panic!("a dump whose {fault} breaks its layout decodes\n{text}");
    }
    let pixels = dump.viewport().expect("built valid").pixels();
    assert_eq!(capture.pixels(), pixels, "one list per pixel");
    assert_eq!(words.corrupt.len(), pixels, "one word check per pixel");
    if let Ok(Some(model)) = &built.expected {
        for p in 0..pixels {
            let found: Vec<(usize, Corruption)> =
                words.corrupt[p].iter().map(|c| (c.slot, c.why)).collect();
            assert_eq!(found, model.corrupt[p], "pixel {p}'s corrupt words\n{text}");
            assert_eq!(capture.pixel(p), model.lists[p], "pixel {p}'s list\n{text}");
            if let Some(stored) = &model.stored_words {
                let named: Vec<u64> = words.corrupt[p].iter().map(|c| c.word).collect();
                assert_eq!(
                    named, stored[p],
                    "pixel {p}'s corrupt words as stored\n{text}"
                );
            }
        }
        assert_eq!(words.unreachable, model.unreachable, "unreachable nodes");
    } else {
        // A memory dump: the rules are the scheme's own, so every word is unchecked.
        let total: u64 = dump.arrays.values().map(|w| words_len(w) as u64).sum();
        assert_eq!(
            words.unchecked, total,
            "every word of a memory dump is unchecked"
        );
    }
    // The verdict: an oracle made of the capture agrees with it except where a word is corrupt.
    let comparison = compare_with(
        &Oracle::from_capture(&capture),
        &capture,
        Some(&words),
        &CompareOptions::default(),
    );
    for p in 0..pixels {
        let corrupt = !words.corrupt[p].is_empty();
        let flags = comparison.verdicts[p];
        assert_eq!(
            flags & flags::CORRUPT != 0,
            corrupt,
            "pixel {p}: verdict {flags:#x}, corrupt words {:?}",
            words.corrupt[p]
        );
        // Lists, layers and MDTS slots decode with no overflow, so each pixel in canonical
        // order without a corrupt word is its own oracle's; a memory dump's words promise
        // nothing, an A-buffer's counters may claim fragments its slots lack.
        let judged_against_itself =
            matches!(&built.expected, Ok(Some(model)) if model.judged_against_itself);
        if !corrupt && in_order(&capture, p) && judged_against_itself {
            assert_eq!(
                flags & flags::DIFFERS,
                0,
                "pixel {p} differs from itself\n{text}"
            );
        }
    }
}

fn words_len(words: &Words) -> usize {
    match words {
        Words::U32(w) => w.len(),
        Words::U64(w) => w.len(),
    }
}

fn in_order(capture: &Capture, p: usize) -> bool {
    capture.pixel(p).windows(2).all(|w| w[0] <= w[1])
}

/// A dump built from the input, with what decoding it must give: `Err(what)` for a dump that
/// breaks its layout (the error must name `what`), `Ok(Some(model))` for lists and layers,
/// `Ok(None)` for a memory dump (no model: its words are the scheme's own).
struct Built {
    dump: Dump,
    expected: Result<Option<Model>, String>,
}

/// What the layout's rules say of a dump's words: per pixel the (slot, reason) of each corrupt
/// word and the decoded list, and the nodes handed out that no list reaches.
struct Model {
    corrupt: Vec<Vec<(usize, Corruption)>>,
    lists: Vec<Vec<u64>>,
    unreachable: u64,
    /// Slot layouts: per pixel each corrupt word as the dump stores it.
    stored_words: Option<Vec<Vec<u64>>>,
    /// Whether each pixel in canonical order without a corrupt word equals an oracle made of the
    /// capture (not so for an A-buffer, whose counters may claim fragments its slots lack).
    judged_against_itself: bool,
}

fn build(input: &mut Input<'_>) -> Built {
    let mut header = Dump::parse(NAME, BASE.as_bytes(), |f| {
        Err(DumpError::Invalid(format!(
            "{f}: the base header has no arrays"
        )))
    })
    .expect("the base header parses")
    .header;
    header.width = 1 + u32::from(input.u8() % 4);
    header.height = 1 + u32::from(input.u8() % 3);
    scene(input, &mut header);
    let viewport = Viewport::new(header.width, header.height).expect("at most 4 × 3");
    let mut arrays = Vec::new();
    // A kind byte of 7 modulo 8 picks the slot layouts, added after the corpus was grown: the
    // other values keep the kind they had modulo 4.
    let expected = match input.u8() % 8 {
        7 => slots(input, &mut header, viewport, &mut arrays),
        0 | 4 => linked_lists(
            input,
            &mut header,
            viewport,
            SchemeName::LinkedList,
            &mut arrays,
        ),
        1 | 5 => linked_lists(
            input,
            &mut header,
            viewport,
            SchemeName::LinkedListNearest,
            &mut arrays,
        ),
        2 | 6 => layer_major(input, &mut header, viewport, &mut arrays),
        _ => memory(input, &mut header, viewport, &mut arrays).map(|()| None),
    };
    header.arrays = arrays
        .iter()
        .map(|(name, words)| {
            let dtype = match words {
                Words::U32(_) => Dtype::U32,
                Words::U64(_) => Dtype::U64,
            };
            let spec = ArraySpec {
                file: format!("{name}.bin"),
                dtype,
                shape: vec![words_len(words) as u64],
            };
            (name.to_string(), spec)
        })
        .collect();
    let arrays = arrays
        .into_iter()
        .map(|(name, words)| (name.to_string(), words))
        .collect();
    Built {
        dump: Dump { header, arrays },
        expected,
    }
}

/// The scene fields: a named scene or a mesh file with a hash (or any string in its place), the
/// orbit and the engine's matrix from raw f64 bits or small values, any conventions.
fn scene(input: &mut Input<'_>, header: &mut Header) {
    let flags = input.u8();
    let scene = &mut header.scene;
    if flags & 1 != 0 {
        (scene.name, scene.mesh) = (None, Some("mesh.obj".into()));
    }
    scene.mesh_hash = match (flags >> 1) & 3 {
        0 => None,
        1 => Some(mesh_hash(&input.u64().to_le_bytes())),
        _ => Some(
            String::from_utf8_lossy(&(0..input.u8() % 12).map(|_| input.u8()).collect::<Vec<_>>())
                .into_owned(),
        ),
    };
    if flags & 8 != 0 {
        scene.view_degrees = number(input);
        scene.elevation_degrees = number(input);
    }
    if flags & 16 != 0 {
        let precision = if flags & 32 != 0 {
            VertexPrecision::F32
        } else {
            VertexPrecision::F64
        };
        scene.view_projection = Some(ViewProjection {
            row_major: std::array::from_fn(|_| number(input)),
            precision,
        });
    }
    if flags & 64 != 0 {
        let bits = input.u8();
        let conventions = &mut scene.conventions;
        conventions.window_origin = if bits & 1 != 0 {
            WindowOrigin::LowerLeft
        } else {
            WindowOrigin::UpperLeft
        };
        conventions.depth_range = if bits & 2 != 0 {
            DepthRange::MinusOneToOne
        } else {
            DepthRange::ZeroToOne
        };
        conventions.vertex_precision = if bits & 4 != 0 {
            VertexPrecision::F32
        } else {
            VertexPrecision::F64
        };
        conventions.subpixel_bits = u32::from(bits >> 3);
    }
}

/// A header number: raw f64 bits (NaN, infinities, subnormals, extremes), or a small multiple of
/// 1/8.
fn number(input: &mut Input<'_>) -> f64 {
    match input.u8() {
        0..=127 => f64::from_bits(input.u64()),
        b => f64::from(b as i8) / 8.0,
    }
}

/// A payload packing: fragsim's, the two unorm packings engines use, or arbitrary fields (which
/// may overlap or pass the word's top bit: refused).
fn payload(input: &mut Input<'_>) -> Payload {
    match input.u8() % 5 {
        0 | 1 => Payload::FRAGMENT,
        2 => Payload {
            dtype: Dtype::U32,
            depth: DepthFormat::Unorm24,
            depth_shift: 8,
            prim_bits: 8,
        },
        3 => Payload {
            dtype: Dtype::U64,
            depth: DepthFormat::Unorm16,
            depth_shift: 32,
            prim_bits: 16,
        },
        _ => Payload {
            dtype: if input.u8() & 1 != 0 {
                Dtype::U32
            } else {
                Dtype::U64
            },
            depth: match input.u8() % 3 {
                0 => DepthFormat::F32,
                1 => DepthFormat::Unorm24,
                _ => DepthFormat::Unorm16,
            },
            depth_shift: u32::from(input.u8() % 70),
            prim_bits: u32::from(input.u8() % 40),
        },
    }
}

/// A payload word: under fragsim's packing a fragment word of a depth on a grid over `[0, 1]`
/// (or above 1.0), else raw bits of the payload's width.
fn payload_word(input: &mut Input<'_>, payload: &Payload) -> u64 {
    if *payload == Payload::FRAGMENT {
        let depth = match input.u8() {
            255 => 2.0,
            b => f32::from(b) / 254.0,
        };
        u64::from(depth.to_bits()) << 32 | u64::from(input.u8())
    } else {
        match payload.dtype {
            Dtype::U32 => u64::from(input.u32()),
            Dtype::U64 => input.u64(),
        }
    }
}

/// Payload words in the payload's own dtype, or the other one when `wrong_dtype`.
fn payload_words(words: Vec<u64>, payload: &Payload, wrong_dtype: bool) -> Words {
    match (payload.dtype, wrong_dtype) {
        (Dtype::U32, false) | (Dtype::U64, true) => words_of(Dtype::U32, words),
        _ => words_of(Dtype::U64, words),
    }
}

/// Words of `dtype` (u32 words narrowed).
#[expect(
    clippy::cast_possible_truncation,
    reason = "narrowing is the point: a u32 payload's words fit, and a u64 payload written as u32 \
              (the wrong-dtype fault) loses its high half"
)]
fn words_of(dtype: Dtype, words: Vec<u64>) -> Words {
    match dtype {
        Dtype::U32 => Words::U32(words.into_iter().map(|w| w as u32).collect()),
        Dtype::U64 => Words::U64(words),
    }
}

/// `k` of 0 to 3: 0 is refused.
fn k(input: &mut Input<'_>) -> u32 {
    u32::from(input.u8() % 4)
}

/// A length `right`, or, for fault `which` when the input picks it, one off.
fn length(right: usize, fault: u8, which: u8) -> usize {
    if fault == which {
        if right > 1 {
            right - 1
        } else {
            right + 1
        }
    } else {
        right
    }
}

/// The bits of a `payload` word outside its depth and id fields (`docs/dump-format.md`: a word
/// read as a fragment holds 0 there), written out from the format rather than asked of the
/// reader.
pub(super) fn outside_fields(payload: &Payload) -> u64 {
    let bits = |n: u32| if n >= 64 { u64::MAX } else { (1_u64 << n) - 1 };
    bits(payload.dtype.bits())
        & !(bits(payload.prim_bits) | bits(payload.depth.bits()) << payload.depth_shift)
}

//! Slot layouts described by the header: the `slots` array of `mdts`, `mdts-desc`,
//! `mdts32` and `abuffer` slot-major or pixel-major, its words packed as a payload, written as
//! `render --dump` writes them, read back to fragsim's own words and judged by `compare` as
//! fragsim's own dumps are; a mutated word is named as stored; a bad field is a clear error.

use fragsim::catalog::SchemeName;
use fragsim::dump::Direction;
use fragsim::dump::{
    Corruption, DepthFormat, Dtype, Dump, DumpError, DumpScheme, LayoutSpec, Payload, SlotOrder,
    Words,
};
use fragsim::oracle::compare::flags;
use serde_json::json;

use super::binary::{fragsim, render_dump};
use super::{every_layout, judged, scratch, spec, with_view, SCENE};

/// An f32 depth at bit 24 of a u64 word above a 24-bit primitive id: a packing other than
/// fragsim's that still holds every fragment of the test scene exactly.
const F32_OVER_24_BITS: Payload = Payload {
    dtype: Dtype::U64,
    depth: DepthFormat::F32,
    depth_shift: 24,
    prim_bits: 24,
};

fn widened(dump: &Dump, name: &str) -> Vec<u64> {
    match &dump.arrays[name] {
        Words::U32(w) => w.iter().map(|&w| u64::from(w)).collect(),
        Words::U64(w) => w.clone(),
    }
}

/// Slots per pixel of a fixed-storage slot scheme.
fn slots_per_pixel(scheme: &DumpScheme) -> Option<usize> {
    match scheme {
        DumpScheme::Mdts { k, .. } | DumpScheme::Mdts32 { k } | DumpScheme::KBuffer { k, .. } => {
            Some(*k as usize)
        }
        DumpScheme::ABufferFixed { capacity, .. } => Some(*capacity as usize),
        _ => None,
    }
}

#[test]
fn every_slot_layout_in_either_order_and_payload_round_trips_and_compares_equal() {
    with_view(|view, oracle| {
        let pixels = oracle.pixels();
        let dir = scratch("slot-layouts");
        for (i, scheme) in every_layout(oracle).iter().enumerate() {
            let own = Dump::record(view, spec(), scheme, "test").unwrap();
            let own_slots = widened(&own, "slots");
            for order in [SlotOrder::PixelMajor, SlotOrder::SlotMajor] {
                for payload in [None, Some(F32_OVER_24_BITS)] {
                    let layout = LayoutSpec::Slots { order, payload };
                    let encoded = own.in_layout(Some(layout));
                    let keys = matches!(scheme, DumpScheme::Mdts32 { .. });
                    let ranges = matches!(scheme, DumpScheme::ABufferExact { .. });
                    if keys && payload.is_some() || ranges && order == SlotOrder::SlotMajor {
                        let field = if keys { "\"payload\"" } else { "\"order\"" };
                        let error = encoded.unwrap_err().to_string();
                        assert!(error.contains(field), "{scheme:?} {layout:?}: {error}");
                        continue;
                    }
                    let encoded = encoded.unwrap();
                    // Each word lies where the order says, packed as the payload says.
                    let stored = widened(&encoded, "slots");
                    let per_pixel = slots_per_pixel(scheme).unwrap_or(1);
                    let full = own_slots.iter().position(|&w| w != u64::MAX && w != 0);
                    for (at, &word) in own_slots.iter().enumerate() {
                        let (p, s) = (at / per_pixel, at % per_pixel);
                        let expected = match (payload, Some(at) == full) {
                            // The first full word, repacked: the key at bit 24, 24 bits of id.
                            (Some(_), true)
                                if !matches!(
                                    scheme,
                                    DumpScheme::Mdts {
                                        direction: Direction::Descending,
                                        ..
                                    }
                                ) =>
                            {
                                (word >> 32) << 24 | (word & 0xFF_FFFF)
                            }
                            (None, _) => word,
                            _ => continue,
                        };
                        // The format's formulas, written out rather than asked of the reader.
                        let index = match (scheme, order) {
                            (DumpScheme::ABufferExact { .. }, _) => at,
                            (_, SlotOrder::PixelMajor) => p * per_pixel + s,
                            (_, SlotOrder::SlotMajor) => s * pixels + p,
                        };
                        assert_eq!(stored[index], expected, "{scheme:?} {layout:?} slot {at}");
                    }
                    let path = dir.join(format!("{i}-{order:?}-{}", payload.is_some()));
                    encoded.write(&path).unwrap();
                    let read = Dump::read(&path).unwrap();
                    assert_eq!(read, encoded, "{scheme:?} {layout:?}");
                    assert_eq!(read.header.layout, Some(layout));
                    assert_eq!(read.capture().unwrap(), own.capture().unwrap());
                    let words = read.check_words().unwrap();
                    assert_eq!((words.corrupt_words(), words.unchecked), (0, 0));
                    let comparison = judged(&read, oracle);
                    assert!(comparison.is_equal() && comparison.words_checked);
                }
            }
        }
    });
}

/// `depth_key << 32 | prim` with the depth rounded to the nearest of `bits`-bit unorm steps and
/// read back as the nearest f32, as the format decodes a unorm payload.
fn quantised(word: u64, bits: u32) -> u64 {
    let steps = f64::from((1_u32 << bits) - 1);
    let depth = f64::from(f32::from_bits((word >> 32) as u32));
    #[expect(
        clippy::cast_possible_truncation,
        reason = "narrowing is the point: the format reads a unorm depth back as the nearest f32"
    )]
    let back = ((depth * steps).round() / steps) as f32;
    u64::from(back.to_bits()) << 32 | (word & 0xFFFF_FFFF)
}

#[test]
fn unorm_slot_payloads_hold_the_nearest_step_of_each_depth_and_ids_must_fit() {
    with_view(|view, oracle| {
        let scheme = DumpScheme::Mdts {
            k: oracle.max_depth_complexity(),
            direction: Direction::Ascending,
        };
        let own = Dump::record(view, spec(), &scheme, "test").unwrap();
        let lists = own.capture().unwrap();
        for (depth, bits) in [(DepthFormat::Unorm24, 24), (DepthFormat::Unorm16, 16)] {
            let payload = Payload {
                dtype: Dtype::U64,
                depth,
                depth_shift: 32,
                prim_bits: 32,
            };
            let layout = LayoutSpec::Slots {
                order: SlotOrder::SlotMajor,
                payload: Some(payload),
            };
            let encoded = own.in_layout(Some(layout)).unwrap();
            let decoded = encoded.capture().unwrap();
            for p in 0..oracle.pixels() {
                let expected: Vec<u64> =
                    lists.pixel(p).iter().map(|&w| quantised(w, bits)).collect();
                assert_eq!(decoded.pixel(p), expected, "{depth:?}, pixel {p}");
            }
            assert_eq!(encoded.check_words().unwrap().corrupt_words(), 0);
        }
        // A D24 depth over an 8-bit id cannot name this scene's triangles: refused, naming why.
        assert!(view.triangle_count() > 256);
        let narrow = LayoutSpec::Slots {
            order: SlotOrder::PixelMajor,
            payload: Some(Payload {
                dtype: Dtype::U32,
                depth: DepthFormat::Unorm24,
                depth_shift: 8,
                prim_bits: 8,
            }),
        };
        let error = own.in_layout(Some(narrow)).unwrap_err().to_string();
        assert!(
            error.contains("does not fit the payload's 8 \"prim_bits\""),
            "{error}"
        );
    });
}

#[test]
fn a_mutated_slot_major_word_is_caught_and_named_as_stored() {
    with_view(|view, oracle| {
        let pixels = oracle.pixels();
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let layout = LayoutSpec::Slots {
            order: SlotOrder::SlotMajor,
            payload: Some(F32_OVER_24_BITS),
        };
        let dump = Dump::record(view, spec(), &scheme, "test")
            .unwrap()
            .in_layout(Some(layout))
            .unwrap();
        let deep: Vec<usize> = (0..pixels)
            .filter(|&p| oracle.pixel(p).len() >= 3)
            .take(2)
            .collect();
        let [holed, renamed] = [deep[0], deep[1]];
        let mut mutated = dump.clone();
        let Some(Words::U64(slots)) = mutated.arrays.get_mut("slots") else {
            panic!("u64 slots")
        };
        // Slot 1 of one pixel emptied (slot-major: at pixels + p), slot 0 of another renamed.
        slots[pixels + holed] = u64::MAX;
        slots[renamed] ^= 1;
        let after_hole = slots[2 * pixels + holed];
        let check = mutated.check_words().unwrap();
        let corrupt = &check.corrupt[holed][0];
        assert_eq!((corrupt.slot, corrupt.why), (2, Corruption::AfterEmpty));
        assert_eq!(corrupt.word, after_hole, "the word as the dump stores it");
        let comparison = judged(&mutated, oracle);
        assert_eq!(comparison.verdicts[holed], flags::MISSING | flags::CORRUPT);
        assert_eq!(comparison.verdicts[renamed], flags::MISSING | flags::EXTRA);
        assert_eq!(comparison.counts.equal, pixels as u64 - 2);
        // An A-buffer's counted slot holding the empty marker, slot-major.
        let abuffer = DumpScheme::ABufferFixed {
            capacity: k,
            sorted: false,
        };
        let mut abuffer_dump = Dump::record(view, spec(), &abuffer, "test")
            .unwrap()
            .in_layout(Some(layout))
            .unwrap();
        let Some(Words::U64(abuffer_slots)) = abuffer_dump.arrays.get_mut("slots") else {
            panic!("u64 slots")
        };
        abuffer_slots[pixels + holed] = u64::MAX;
        let abuffer_check = abuffer_dump.check_words().unwrap();
        assert_eq!(
            abuffer_check.corrupt[holed][0].why,
            Corruption::EmptyCounted
        );
        assert_eq!(abuffer_check.corrupt_words(), 1);
    });
}

/// The error reading `dump` (encoded, its header edited by `edit`) gives.
fn refused(dump: &Dump, edit: impl FnOnce(&mut serde_json::Value)) -> String {
    let (text, files) = dump.encode().unwrap();
    let mut header: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut header);
    let parsed = Dump::parse("dump.json", header.to_string().as_bytes(), |file| {
        files
            .get(file)
            .cloned()
            .ok_or_else(|| DumpError::Invalid(format!("no {file}")))
    });
    match parsed.and_then(|read| read.capture().map(|_| read)) {
        Ok(_) => panic!("accepted: {header}"),
        Err(error) => error.to_string(),
    }
}

#[test]
fn a_bad_slot_layout_field_is_an_error_naming_it() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let record = |scheme: &DumpScheme| Dump::record(view, spec(), scheme, "test").unwrap();
        let mdts = record(&DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        });
        let kbuffer = record(&DumpScheme::KBuffer {
            scheme: SchemeName::Kbuffer,
            k,
        });
        let slot_major = json!({"kind": "slots", "order": "slot-major"});
        let cases: Vec<(&Dump, serde_json::Value, &str)> = vec![
            (
                &mdts,
                json!({"kind": "slots", "order": "diagonal"}),
                "unknown variant `diagonal`",
            ),
            (&mdts, json!({"kind": "slots"}), "missing field `order`"),
            (
                &mdts,
                json!({"kind": "slots", "order": "slot-major", "stride": 4}),
                "unknown field `stride`",
            ),
            (
                &mdts,
                json!({"kind": "slots", "order": "slot-major",
                       "payload": {"dtype": "u32", "depth": "f32", "depth_shift": 0, "prim_bits": 8}}),
                "the primitive id's 8 bits overlap the depth field at bit 0",
            ),
            // The payload says u32 words, the array holds u64.
            (
                &mdts,
                json!({"kind": "slots", "order": "pixel-major",
                       "payload": {"dtype": "u32", "depth": "unorm24", "depth_shift": 8, "prim_bits": 8}}),
                "array \"slots\" must be U32, as its payload",
            ),
            (
                &mdts,
                json!({"kind": "memory"}),
                "scheme mdts dumps as slots, the header's layout is memory",
            ),
            // A k-buffer's slots are no longer read as its memory of old.
            (
                &kbuffer,
                json!({"kind": "memory"}),
                "scheme kbuffer dumps as slots, the header's layout is memory",
            ),
            (
                &kbuffer,
                json!({"kind": "slots", "order": "pixel-major",
                       "payload": {"dtype": "u32", "depth": "unorm24", "depth_shift": 8, "prim_bits": 0}}),
                "payload \"prim_bits\" 0 must be 1 to 32",
            ),
        ];
        for (dump, layout, expected) in cases {
            let error = refused(dump, |h| h["layout"] = layout.clone());
            assert!(error.contains(expected), "{layout}: {error}");
        }
        let keys = record(&DumpScheme::Mdts32 { k: 3 });
        let error = refused(&keys, |h| {
            h["layout"] = json!({"kind": "slots", "order": "slot-major",
                "payload": {"dtype": "u32", "depth": "f32", "depth_shift": 0, "prim_bits": 0}});
        });
        assert!(error.contains("its layout takes no \"payload\""), "{error}");
        let exact = record(&DumpScheme::ABufferExact {
            counts: oracle.depth_complexity(),
            sorted: false,
        });
        let exact_error = refused(&exact, |h| h["layout"] = slot_major.clone());
        assert!(
            exact_error.contains("\"order\" must be pixel-major"),
            "{exact_error}"
        );
        // A slot-major array one slot short of the scheme's.
        let mdts_error = refused(&mdts, |h| {
            h["layout"] = slot_major.clone();
            h["k"] = json!(k + 1);
        });
        let named = format!("array \"slots\": shape [1728, {k}] disagrees with the header's \"k\" {}, which makes it [{}, 1728]", k + 1, k + 1);
        assert!(mdts_error.contains(&named), "{mdts_error}");
        let kbuffer_error = refused(&kbuffer, |h| h["k"] = json!(0));
        assert!(
            kbuffer_error.contains("scheme kbuffer needs \"k\" ≥ 1"),
            "{kbuffer_error}"
        );
    });
}

/// The header of the dump in `dir`.
fn json_header(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("dump.json")).unwrap()).unwrap()
}

/// The `compare` record of `fragsim compare oracle DIR --json`, and the exit code.
fn compare_record(dir: &std::path::Path) -> (serde_json::Value, i32) {
    let output = fragsim()
        .args(["compare", "oracle"])
        .arg(dir)
        .args(["--json", "--no-images"])
        .output()
        .unwrap();
    let code = output.status.code().unwrap();
    assert!(code < 2, "{}", String::from_utf8_lossy(&output.stderr));
    (crate::support::json_lines(&output.stdout)[0].clone(), code)
}

#[test]
fn render_dump_writes_every_scheme_in_an_engines_encoding_and_compare_judges_it_the_same() {
    let dir = scratch("slot-layouts-binary");
    let (own, engine) = (dir.join("own"), dir.join("engine"));
    render_dump(&own, "all", &[]);
    render_dump(
        &engine,
        "all",
        &[
            "--dump-order",
            "slot-major",
            "--dump-payload",
            "u64:f32:24:24",
            "--dump-list-numbering",
            "4294967295:0",
        ],
    );
    let header = |scheme: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(engine.join(scheme).join("dump.json")).unwrap())
            .unwrap()
    };
    assert_eq!(header("mdts")["layout"]["order"], "slot-major");
    assert_eq!(header("mdts")["arrays"]["slots"]["shape"][1], 48 * 36);
    // The first full word of fragsim's pixel-major slots (`p · K + s`) lies at `s · pixels + p`,
    // its f32 key moved to bit 24 above a 24-bit id.
    let words = |path: std::path::PathBuf| -> Vec<u64> {
        let bytes = std::fs::read(path).unwrap();
        bytes
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let ours = words(own.join("mdts").join("slots.u64"));
    let theirs = words(engine.join("mdts").join("slots.u64"));
    let k = ours.len() / (48 * 36);
    let full = ours.iter().position(|&w| w != u64::MAX).unwrap();
    let (p, s) = (full / k, full % k);
    let word = ours[full];
    assert_eq!(
        theirs[s * 48 * 36 + p],
        (word >> 32) << 24 | (word & 0xFF_FFFF)
    );
    assert_eq!(header("abuffer")["layout"]["payload"]["depth_shift"], 24);
    assert_eq!(header("linked-list")["layout"]["null"], 4_294_967_295_u64);
    assert_eq!(
        header("layer-counter")["layout"]["payload"]["prim_bits"],
        24
    );
    let mut schemes = 0;
    for entry in std::fs::read_dir(&own).unwrap() {
        let name = entry.unwrap().file_name();
        let (engine_record, code) = compare_record(&engine.join(&name));
        let (own_record, own_code) = compare_record(&own.join(&name));
        assert_eq!(code, own_code, "{name:?}");
        for field in [
            "equal",
            "mismatched_pixels",
            "captured",
            "lost",
            "extra",
            "corrupt_words",
        ] {
            assert_eq!(engine_record[field], own_record[field], "{name:?}: {field}");
        }
        schemes += 1;
    }
    assert!(schemes > 30, "{schemes} dumps");
    for scheme in [
        "mdts",
        "mdts-desc",
        "mdts32",
        "abuffer",
        "linked-list",
        "layer-counter",
        "kbuffer",
        "kbuffer-interlock-ordered-first",
        "loop64",
    ] {
        let (record, code) = compare_record(&engine.join(scheme));
        assert_eq!((&record["equal"], code), (&json!(true), 0), "{scheme}");
    }
    // The k-buffers keep their name (their promise) and take the slot encoding; loop64 is mdts.
    assert_eq!(header("kbuffer")["scheme"], "kbuffer");
    assert_eq!(header("kbuffer-spinlock")["layout"]["order"], "slot-major");
    assert_eq!(header("loop64")["scheme"], "mdts");
    // A k-buffer that lost a fragment (a race's lost write-back: a pixel's last full slot never
    // written) is DIFFERENT under either promise, never excused as overflow.
    for scheme in ["kbuffer", "kbuffer-interlock-ordered-first"] {
        let path = own.join(scheme);
        let dump_k = usize::try_from(json_header(&path)["k"].as_u64().unwrap()).unwrap();
        let slots = path.join("slots.u64");
        let mut bytes = std::fs::read(&slots).unwrap();
        let is_empty = |file: &[u8], i: usize| file[i * 8..i * 8 + 8] == [0xff; 8];
        let first_written = (0..bytes.len() / 8 / dump_k)
            .find(|&candidate| !is_empty(&bytes, candidate * dump_k))
            .unwrap();
        let last = (first_written * dump_k..(first_written + 1) * dump_k)
            .rfind(|&i| !is_empty(&bytes, i))
            .unwrap();
        bytes[last * 8..last * 8 + 8].copy_from_slice(&[0xff; 8]);
        std::fs::write(&slots, bytes).unwrap();
        let (record, code) = compare_record(&path);
        assert_eq!(
            (code, &record["lost"]),
            (1, &json!(1)),
            "{scheme}: {record}"
        );
    }
    // Unorm depths are judged by the steps their conversion may land on, derived, with no
    // tolerance to give: EQUAL as written, bit for bit never (`stored_depth` says why).
    for (payload, stored) in [
        ("u64:unorm24:32:32", "unorm24"),
        ("u64:unorm16:32:32", "unorm16"),
    ] {
        let out = dir.join(payload.replace(':', "-"));
        let sized = ["--k", "auto", "--capacity", "auto"];
        let encoding = ["--dump-order", "slot-major", "--dump-payload", payload];
        render_dump(&out, "mdts,abuffer", &[&sized[..], &encoding[..]].concat());
        for scheme in ["mdts", "abuffer"] {
            let (record, code) = compare_record(&out.join(scheme));
            assert_eq!(code, 0, "{payload} {scheme}: {record}");
            assert_eq!(record["stored_depth"], json!(stored), "{payload} {scheme}");
            assert!(
                record["compared"]
                    .as_str()
                    .unwrap()
                    .ends_with(&format!("a {stored} depth")),
                "{record}"
            );
        }
    }
    // The bound is the conversion's: a unorm16 step one above the nearest is a truncating or
    // rounding conversion's (EQUAL), two above is no conversion's (DIFFERENT). The farthest
    // fragment of a pixel (slot 1 of slot-major slots, slot 2 empty), so that no order changes.
    let unorm16 = dir.join("u64-unorm16-32-32").join("mdts");
    let slots = unorm16.join("slots.u64");
    let written = std::fs::read(&slots).unwrap();
    let unorm16_word = |i: usize| u64::from_le_bytes(written[i * 8..i * 8 + 8].try_into().unwrap());
    let pixels = 48 * 36;
    let farthest = (0..pixels)
        .map(|pixel| pixels + pixel)
        .find(|&i| {
            unorm16_word(i) != u64::MAX
                && unorm16_word(i + pixels) == u64::MAX
                && unorm16_word(i) >> 32 < 0xFFF0
        })
        .expect("a pixel holding two fragments");
    for (steps, code) in [(1, 0), (2, 1)] {
        let mut bytes = written.clone();
        let moved = unorm16_word(farthest) + (steps << 32);
        bytes[farthest * 8..farthest * 8 + 8].copy_from_slice(&moved.to_le_bytes());
        std::fs::write(&slots, bytes).unwrap();
        assert_eq!(compare_record(&unorm16).1, code, "{steps} steps deeper");
    }
    // One flipped bit of a slot-major word: exit 1.
    let flipped = engine.join("mdts").join("slots.u64");
    let mut bytes = std::fs::read(&flipped).unwrap();
    let first = bytes.chunks_exact(8).position(|w| w != [0xff; 8]).unwrap();
    bytes[first * 8] ^= 1;
    std::fs::write(&flipped, bytes).unwrap();
    assert_eq!(compare_record(&engine.join("mdts")).1, 1);
    // A bad field in the header, or a payload that does not fit its word: exit 2, naming it.
    let path = engine.join("mdts-desc").join("dump.json");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replace("\"slot-major\"", "\"diagonal\"")).unwrap();
    let output = fragsim()
        .args(["compare", "oracle"])
        .arg(&path)
        .arg("--no-images")
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("unknown variant `diagonal`"), "{stderr}");
    let refused = fragsim()
        .args(["render", "--scene", SCENE, "--no-images", "--dump"])
        .arg(dir.join("refused"))
        .args(["--dump-payload", "u32:f32:8:8"])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    let refused_stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        refused_stderr.contains("does not fit a 32-bit word"),
        "{refused_stderr}"
    );
}

#[test]
fn the_k_buffers_and_loop64_dump_their_own_slot_words() {
    // A k-buffer's dump is its memory's u64 words, its K slots a pixel, under its own name;
    // loop64's memory is the `mdts` dump it writes, placed slot-major.
    let schemes = [
        "loop64",
        "kbuffer",
        "kbuffer-stores",
        "kbuffer-interlock",
        "kbuffer-interlock-ordered",
        "kbuffer-interlock-ordered-first",
        "kbuffer-spinlock",
        "kbuffer-spinlock-fixed",
    ];
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let sizes = fragsim::catalog::Build::fixed(view.viewport(), k, 1, 1, u64::MAX);
        for name in schemes {
            let scheme = SchemeName::from_name(name).unwrap();
            let memory = DumpScheme::Memory {
                scheme,
                k,
                capacity: 1,
                layers: 1,
            };
            let memory = Dump::record(view, spec(), &memory, "test").unwrap();
            let layout = DumpScheme::for_run(scheme, k, &sizes, None).unwrap();
            let mut dump = Dump::record(view, spec(), &layout, "test").unwrap();
            let own_name = name != "loop64";
            assert_eq!(dump.header.scheme, if own_name { name } else { "mdts" });
            if !own_name {
                let order = SlotOrder::SlotMajor;
                let spec = LayoutSpec::Slots {
                    order,
                    payload: None,
                };
                dump = dump.in_layout(Some(spec)).unwrap();
            }
            assert_eq!(
                widened(&dump, "slots"),
                widened(&memory, "words64"),
                "{name}"
            );
            assert_eq!(dump.arrays.len(), 1, "{name}: no locks");
            let comparison = judged(&dump, oracle);
            assert!(comparison.is_equal() && comparison.words_checked, "{name}");
        }
    });
}

//! The interchange with GPU backends (`docs/dump-format.md`): dumps round-trip through files,
//! decode to exactly what the scheme captured, and `compare` names every kind of difference; the
//! triangle export carries everything a backend needs to reproduce the oracle. CI has no GPU:
//! these tests are the host side of `backends/cuda`.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use fragsim::capture::mdts::Direction;
use fragsim::capture::Identity;
use fragsim::oracle::dump::{
    self, verdict, CompareOptions, Corruption, Dtype, Dump, DumpScheme, SceneSpec, TriangleExport,
    Words,
};
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, Viewport};
use proptest::prelude::*;

/// A fresh directory under cargo's per-test-target temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("dump-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
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
fn judged(dump: &Dump, oracle: &Oracle) -> dump::Comparison {
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

#[test]
fn every_layout_round_trips_through_files_and_decodes_to_what_its_scheme_promises() {
    with_view(|view, oracle| {
        for (i, scheme) in every_layout(oracle).iter().enumerate() {
            let dump = Dump::record(view, spec(), scheme, "test").unwrap();
            let dir = scratch(&format!("round-trip-{i}"));
            dump.write(&dir).unwrap();
            let back = Dump::read(&dir).unwrap();
            assert_eq!(back, dump, "{scheme:?}");
            assert_eq!(Dump::read(&dir.join("dump.json")).unwrap(), dump);
            assert_eq!(back.scheme().unwrap(), *scheme);
            let capture = back.capture().unwrap();
            let diff = oracle.diff(&capture);
            assert!(diff.is_exact(), "{scheme:?}: {diff:?}");
            let comparison = dump::compare(oracle, &capture, 0, 4);
            assert!(comparison.is_equal());
            assert_eq!(comparison.diff.captured, diff.captured);
            assert_eq!(comparison.diff.overflowed, diff.overflowed);
            assert_eq!(comparison.counts.equal, u64::from(WIDTH * HEIGHT));
            // Every word read: fragsim's own memory breaks no rule of its layout.
            let words = back.check_words().unwrap();
            assert_eq!(
                (words.corrupt_words(), words.unchecked),
                (0, 0),
                "{scheme:?}"
            );
            let whole = judged(&back, oracle);
            assert!(whole.is_equal() && whole.words_checked, "{scheme:?}");
            assert_eq!(whole.claimed_overflow, diff.overflowed, "{scheme:?}");
        }
    });
}

#[test]
fn a_dump_written_by_hand_as_a_gpu_backend_writes_it_is_read_and_judged() {
    with_view(|_, oracle| {
        // What a CUDA or NumPy writer produces: the MDTS words of every pixel, K slots, empty = all
        // ones, raw little-endian, and a header typed by hand (NumPy dtype names, an extra field).
        let k = oracle.max_depth_complexity() as usize;
        let pixels = (WIDTH * HEIGHT) as usize;
        let mut bytes = Vec::new();
        for p in 0..pixels {
            let list = oracle.pixel(p);
            for slot in 0..k {
                bytes.extend_from_slice(&list.get(slot).copied().unwrap_or(u64::MAX).to_le_bytes());
            }
        }
        let dir = scratch("by-hand");
        std::fs::write(dir.join("words.bin"), &bytes).unwrap();
        let header = format!(
            r#"{{"format": "fragsim-dump", "version": 1, "producer": "numpy",
                "scene": {{"name": "{SCENE}", "view_degrees": 30, "elevation_degrees": 15}},
                "width": {WIDTH}, "height": {HEIGHT}, "scheme": "mdts", "k": {k},
                "arrays": {{"slots": {{"file": "words.bin", "dtype": "<u8", "shape": [{pixels}, {k}]}}}},
                "extra": {{"kernel_ms": 0.25}}, "something_new": true}}"#
        );
        std::fs::write(dir.join("dump.json"), header).unwrap();
        let dump = Dump::read(&dir).unwrap();
        assert_eq!(dump.header.arrays["slots"].dtype, Dtype::U64);
        assert_eq!(dump.header.scene, spec(), "defaults fill the camera");
        assert!(oracle.diff(&dump.capture().unwrap()).is_exact());
    });
}

#[test]
fn compare_names_missing_extra_and_misordered_pixels_and_agrees_with_the_diff() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        let deep: Vec<usize> = (0..oracle.pixels())
            .filter(|&p| oracle.pixel(p).len() >= 3)
            .take(3)
            .collect();
        let [swapped, renamed, holed] = [deep[0], deep[1], deep[2]];
        let k = k as usize;
        let slots = u64_slots(&mut dump);
        slots.swap(swapped * k, swapped * k + 1);
        slots[renamed * k] ^= 1; // another primitive id
        slots[holed * k + 1] = u64::MAX; // an empty slot: what follows is unreachable
        let capture = dump.capture().unwrap();
        let comparison = dump::compare(oracle, &capture, 0, 8);
        let flags = |p: usize| comparison.verdicts[p];
        assert_eq!(flags(swapped), verdict::MISORDERED);
        assert_eq!(flags(renamed), verdict::MISSING | verdict::EXTRA);
        assert_eq!(flags(holed), verdict::MISSING);
        let lost_behind_hole = oracle.pixel(holed).len() as u64 - 1;
        assert_eq!(comparison.diff.lost, 1 + lost_behind_hole);
        assert_eq!(comparison.diff.extra, 1);
        assert_eq!(
            (
                comparison.counts.missing,
                comparison.counts.extra,
                comparison.counts.misordered
            ),
            (2, 1, 1)
        );
        assert_eq!(
            comparison.counts.equal,
            u64::from(WIDTH * HEIGHT) - 3,
            "every other pixel is equal"
        );
        // Reading every word, the hole's successors are words after an empty slot.
        let whole = judged(&dump, oracle);
        assert_eq!(whole.verdicts[holed], verdict::MISSING | verdict::CORRUPT);
        assert_eq!(whole.verdicts[swapped], verdict::MISORDERED);
        assert_eq!(
            whole.corrupt_words,
            oracle.pixel(holed).len().min(k) as u64 - 2,
            "every word behind the hole"
        );
        let whole = oracle.diff(&capture);
        assert_eq!(
            (
                whole.lost,
                whole.extra,
                whole.misordered_pixels,
                whole.mismatched_pixels
            ),
            (
                comparison.diff.lost,
                comparison.diff.extra,
                comparison.diff.misordered_pixels,
                comparison.diff.mismatched_pixels
            )
        );
        let shown: Vec<usize> = comparison
            .diff
            .first_mismatches
            .iter()
            .map(|m| m.pixel)
            .collect();
        let mut expected = vec![swapped, renamed, holed];
        expected.sort_unstable();
        assert_eq!(shown, expected);
    });
}

#[test]
fn abuffer_overflow_by_design_is_equal_but_an_overstated_counter_is_caught() {
    with_view(|view, oracle| {
        let scheme = DumpScheme::ABufferFixed {
            capacity: 2,
            sorted: true,
        };
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        let comparison = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
        assert!(comparison.is_equal());
        assert!(comparison.counts.overflowed > 0);
        assert!(comparison.diff.overflowed > 0);
        let deep = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() >= 3)
            .unwrap();
        match dump.arrays.get_mut("counters") {
            Some(Words::U32(c)) => c[deep] += 1,
            _ => panic!("no counters"),
        }
        let comparison = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
        assert!(!comparison.is_equal());
        assert_eq!(
            comparison.verdicts[deep] & verdict::MISCOUNTED,
            verdict::MISCOUNTED
        );
        assert_eq!(comparison.counts.miscounted, 1);
    });
}

/// Sets word `index` of a dump's `slots` array, whatever its word width.
fn set_slot(dump: &mut Dump, index: usize, word: u64) {
    match dump.arrays.get_mut("slots") {
        Some(Words::U64(w)) => w[index] = word,
        Some(Words::U32(w)) => w[index] = u32::try_from(word).unwrap(),
        None => panic!("no slots"),
    }
}

#[test]
fn a_word_after_an_empty_mdts_slot_is_corrupt_in_every_mdts_layout() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let p = pixel_with(oracle, 1, k as usize - 2);
        let nearest = oracle.pixel(p)[0];
        // A copy of a word the pixel really holds, as each layout stores it: only the layout's
        // rule (nothing follows an empty slot) can tell it is stray.
        let layouts = [
            (
                DumpScheme::Mdts {
                    k,
                    direction: Direction::Ascending,
                },
                nearest,
            ),
            (
                DumpScheme::Mdts {
                    k,
                    direction: Direction::Descending,
                },
                nearest + 1,
            ),
            (DumpScheme::Mdts32 { k }, nearest >> 32),
        ];
        for (scheme, stray) in layouts {
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            let last = p * k as usize + k as usize - 1;
            set_slot(&mut dump, last, stray);
            let lists = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
            assert!(
                lists.is_equal(),
                "{scheme:?}: decoding stops at the empty slot"
            );
            let whole = judged(&dump, oracle);
            assert!(!whole.is_equal(), "{scheme:?}");
            assert_eq!(whole.verdicts[p], verdict::CORRUPT, "{scheme:?}");
            assert_eq!(whole.counts.corrupt, 1);
            assert_eq!(whole.counts.equal, u64::from(WIDTH * HEIGHT) - 1);
            assert_eq!(whole.diff.mismatched_pixels, 1);
            assert_eq!(whole.first_corrupt.len(), 1);
            let word = whole.first_corrupt[0];
            assert_eq!(
                (word.pixel, word.slot, word.word, word.why),
                (p, k as usize - 1, stray, Corruption::AfterEmpty),
                "{scheme:?}"
            );
            assert_eq!(
                whole.diff.first_mismatches[0].pixel, p,
                "shown though its list is equal"
            );
        }
    });
}

/// Where pixel `p`'s slots start in a layout's `slots` array.
type FirstSlot = Box<dyn Fn(usize) -> usize>;

/// The A-buffer layouts, each with where a pixel's slots start.
fn abuffer_layouts(oracle: &Oracle) -> Vec<(DumpScheme, FirstSlot)> {
    let k = oracle.max_depth_complexity();
    let counts = oracle.depth_complexity();
    let offsets: Vec<usize> = std::iter::once(0)
        .chain(counts.iter().scan(0, |sum, &c| {
            *sum += c as usize;
            Some(*sum)
        }))
        .collect();
    vec![
        (
            DumpScheme::ABufferFixed {
                capacity: k,
                sorted: true,
            },
            Box::new(move |p| p * k as usize),
        ),
        (
            DumpScheme::ABufferFixed {
                capacity: k,
                sorted: false,
            },
            Box::new(move |p| p * k as usize),
        ),
        (
            DumpScheme::ABufferExact {
                counts,
                sorted: false,
            },
            Box::new(move |p| offsets[p]),
        ),
    ]
}

#[test]
fn an_abuffer_slot_below_its_counter_holding_the_empty_marker_is_corrupt_not_extra() {
    with_view(|view, oracle| {
        let p = pixel_with(oracle, 2, usize::MAX);
        for (scheme, first) in abuffer_layouts(oracle) {
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            u64_slots(&mut dump)[first(p)] = u64::MAX;
            let whole = judged(&dump, oracle);
            assert_eq!(
                whole.verdicts[p],
                verdict::CORRUPT | verdict::MISSING,
                "{scheme:?}"
            );
            assert_eq!((whole.diff.lost, whole.diff.extra), (1, 0), "{scheme:?}");
            assert_eq!(whole.first_corrupt[0].why, Corruption::EmptyCounted);
            assert_eq!(whole.counts.equal, u64::from(WIDTH * HEIGHT) - 1);
        }
    });
}

#[test]
fn an_abuffer_word_past_its_counter_is_corrupt_when_the_header_says_slots_were_filled() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let p = pixel_with(oracle, 1, k as usize - 1);
        let scheme = DumpScheme::ABufferFixed {
            capacity: k,
            sorted: false,
        };
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        assert!(dump.header.filled, "fragsim's slots start empty");
        let unused: u64 = oracle
            .depth_complexity()
            .iter()
            .map(|&n| u64::from(k - n))
            .sum();
        u64_slots(&mut dump)[p * k as usize + k as usize - 1] = oracle.pixel(p)[0];
        let whole = judged(&dump, oracle);
        assert_eq!(whole.verdicts[p], verdict::CORRUPT);
        assert_eq!(whole.first_corrupt[0].why, Corruption::BeyondCounter);
        assert_eq!(whole.unchecked_words, 0);
        // FreePipe leaves spare slots uninitialised: without the promise nothing is known of
        // them, and the report says how many words went unread instead of judging them.
        dump.header.filled = false;
        let whole = judged(&dump, oracle);
        assert!(whole.is_equal());
        assert_eq!((whole.corrupt_words, whole.unchecked_words), (0, unused));
    });
}

#[test]
fn a_stored_depth_key_above_one_is_corrupt() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let p = pixel_with(oracle, 1, usize::MAX);
        let impossible = (0x3F80_0001u64 << 32) | (oracle.pixel(p)[0] & 0xFFFF_FFFF);
        let mdts = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let abuffer = DumpScheme::ABufferFixed {
            capacity: k,
            sorted: false,
        };
        for scheme in [mdts, abuffer] {
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            // The last of the pixel's words: still in order, so it is wrong only in its key.
            let n = oracle.pixel(p).len();
            u64_slots(&mut dump)[p * k as usize + n - 1] = impossible;
            let whole = judged(&dump, oracle);
            assert_eq!(
                whole.verdicts[p],
                verdict::CORRUPT | verdict::MISSING | verdict::EXTRA,
                "{scheme:?}"
            );
            assert_eq!(whole.first_corrupt[0].why, Corruption::ImpossibleKey);
        }
    });
}

#[test]
fn an_abuffer_counter_other_than_the_pixels_fragment_count_is_overflow_miscounted() {
    with_view(|view, oracle| {
        let capacity = 3u32;
        let counts = oracle.depth_complexity();
        let predicted: u64 = counts
            .iter()
            .map(|&n| u64::from(n.saturating_sub(capacity)))
            .sum();
        assert!(predicted > 0, "the scene must overflow {capacity} slots");
        let deep = pixel_with(oracle, capacity as usize + 2, usize::MAX);
        let shallow = pixel_with(oracle, 2, 2);
        let n = counts[deep];
        // (pixel, counter, verdict): a counter that never stopped (0xFFFFFFFF), one that missed
        // the last fragment of an overflowing pixel (overflow one short of n − capacity), and
        // one larger than a pixel of two fragments could have (its extra slot is still empty).
        let cases = [
            (deep, u32::MAX, verdict::MISCOUNTED | verdict::OVERFLOWED),
            (deep, n - 1, verdict::MISCOUNTED | verdict::OVERFLOWED),
            (shallow, 3, verdict::MISCOUNTED | verdict::CORRUPT),
        ];
        let scheme = DumpScheme::ABufferFixed {
            capacity,
            sorted: false,
        };
        let good = Dump::record(view, spec(), &scheme, "test").unwrap();
        assert!(judged(&good, oracle).is_equal());
        for (p, counter, expected) in cases {
            let mut dump = good.clone();
            counters(&mut dump)[p] = counter;
            let claimed: u64 = counters(&mut dump)
                .iter()
                .map(|&c| u64::from(c.saturating_sub(capacity)))
                .sum();
            let whole = judged(&dump, oracle);
            assert_eq!(
                whole.verdicts[p], expected,
                "counter {counter:#x} at pixel {p}"
            );
            assert_eq!(whole.counts.miscounted, 1);
            assert_eq!(
                whole.diff.overflowed, predicted,
                "overflow is predicted, not claimed"
            );
            assert_eq!(whole.claimed_overflow, claimed);
            assert_eq!(whole.diff.lost, 0, "every fragment that fits is there");
            // The lists alone, counter inferred from the capture, reach the same verdict.
            let lists = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
            assert_eq!(lists.verdicts[p] & verdict::MISCOUNTED, verdict::MISCOUNTED);
            assert_eq!(lists.diff.overflowed, predicted);
        }
    });
}

#[test]
fn a_dump_as_reference_checks_counters_only_where_it_knows_the_count() {
    with_view(|view, oracle| {
        let scheme = DumpScheme::ABufferFixed {
            capacity: 2,
            sorted: false,
        };
        let dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        let capture = dump.capture().unwrap();
        let reference = Oracle::from_capture(&capture);
        let complete = dump::complete_pixels(&capture);
        let overflowing = oracle.depth_complexity().iter().filter(|&&n| n > 2).count() as u64;
        assert!(overflowing > 0);
        assert_eq!(complete.iter().filter(|&&c| !c).count() as u64, overflowing);
        let words = dump.check_words().unwrap();
        let knowing = CompareOptions {
            complete: Some(&complete),
            ..CompareOptions::default()
        };
        assert!(dump::compare_with(&reference, &capture, Some(&words), &knowing).is_equal());
        // Taken as the whole truth, the reference's two fragments a pixel make every overflowing
        // counter look too large: that is why completeness is passed.
        let naive = dump::compare_with(
            &reference,
            &capture,
            Some(&words),
            &CompareOptions::default(),
        );
        assert_eq!(naive.counts.miscounted, overflowing);
    });
}

#[test]
fn a_sorted_abuffer_dump_is_judged_in_stored_order_an_unsorted_one_is_sorted_first() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let deep = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() >= 2)
            .unwrap();
        for sorted in [true, false] {
            let scheme = DumpScheme::ABufferFixed {
                capacity: k,
                sorted,
            };
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            let base = deep * k as usize;
            let slots = u64_slots(&mut dump);
            slots.swap(base, base + 1);
            let comparison = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
            if sorted {
                assert_eq!(comparison.verdicts[deep], verdict::MISORDERED);
            } else {
                assert!(
                    comparison.is_equal(),
                    "the post pass sorts an unsorted dump"
                );
            }
        }
    });
}

#[test]
fn depth_ulps_accepts_keys_within_the_tolerance_and_no_further() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        // Closed spheres: two layers far apart, so a nudged front key stays in front.
        let pixel = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() == 2)
            .unwrap();
        for (nudge, tolerance, equal) in [
            (1u64, 0u32, false),
            (1, 1, true),
            (3, 2, false),
            (3, 3, true),
        ] {
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            u64_slots(&mut dump)[pixel * k as usize] += nudge << 32;
            let comparison = dump::compare(oracle, &dump.capture().unwrap(), tolerance, 8);
            assert_eq!(
                comparison.is_equal(),
                equal,
                "nudge {nudge} ulps, tolerance {tolerance}"
            );
        }
        // A different primitive is never a tolerance match.
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        u64_slots(&mut dump)[pixel * k as usize] += (1 << 32) + 1;
        assert!(!dump::compare(oracle, &dump.capture().unwrap(), 5, 8).is_equal());
    });
}

#[test]
fn a_key_only_reference_compares_keys_only() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let reference = Dump::record(view, spec(), &DumpScheme::Mdts32 { k }, "test").unwrap();
        let reference = reference.capture().unwrap();
        assert_eq!(reference.identity, Identity::KeyOnly);
        let candidate = Dump::record(
            view,
            spec(),
            &DumpScheme::Mdts {
                k,
                direction: Direction::Ascending,
            },
            "test",
        )
        .unwrap()
        .capture()
        .unwrap();
        let as_oracle = Oracle::from_capture(&reference);
        assert!(!dump::compare(&as_oracle, &candidate, 0, 1).is_equal());
        let coarse = dump::with_identity(&candidate, Identity::KeyOnly);
        assert!(dump::compare(&as_oracle, &coarse, 0, 1).is_equal());
    });
}

#[test]
fn malformed_dumps_are_clear_errors() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let good = Dump::record(view, spec(), &scheme, "test").unwrap();
        let cases: Vec<(&str, Breaker)> = vec![
            (
                "version",
                Box::new(|d: &Path| edit_header(d, "\"version\": 1", "\"version\": 9")),
            ),
            (
                "elements",
                Box::new(|d: &Path| {
                    let f = d.join("slots.u64");
                    let mut b = std::fs::read(&f).unwrap();
                    b.truncate(b.len() - 8);
                    std::fs::write(f, b).unwrap();
                }),
            ),
            (
                "cannot read",
                Box::new(|d: &Path| std::fs::remove_file(d.join("slots.u64")).unwrap()),
            ),
            (
                "unknown scheme",
                Box::new(|d: &Path| edit_header(d, "\"scheme\": \"mdts\"", "\"scheme\": \"zbuf\"")),
            ),
            (
                "needs \"k\"",
                Box::new(|d: &Path| edit_header(d, &format!("\"k\": {k}"), "\"k\": 0")),
            ),
            (
                "holds",
                Box::new(|d: &Path| edit_header(d, "\"width\": 48", "\"width\": 24")),
            ),
        ];
        for (i, (message, break_it)) in cases.iter().enumerate() {
            let dir = scratch(&format!("malformed-{i}"));
            good.write(&dir).unwrap();
            break_it(&dir);
            let error = Dump::read(&dir)
                .and_then(|d| d.capture())
                .expect_err(message)
                .to_string();
            assert!(error.contains(message), "{message:?} not in {error:?}");
        }
    });
}

/// Damages a dump directory in one way.
type Breaker<'a> = Box<dyn Fn(&Path) + 'a>;

fn edit_header(dir: &Path, from: &str, to: &str) {
    let path = dir.join("dump.json");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from:?} not in {text}");
    std::fs::write(path, text.replace(from, to)).unwrap();
}

#[test]
fn the_triangle_export_round_trips_and_rescanning_it_reproduces_the_oracle() {
    for (scene, camera) in [
        (SCENE, OrbitCamera::default().at_angle(30.0)),
        // Close enough that triangles cross the near plane: clipped pieces keep their prim.
        (
            "quads:3",
            OrbitCamera {
                distance_scale: 0.3,
                ..OrbitCamera::default()
            },
        ),
    ] {
        let mesh = Scene::procedural(scene).unwrap();
        let view = mesh
            .view(Viewport::new(WIDTH, HEIGHT).unwrap(), &camera)
            .unwrap();
        let oracle = Oracle::build(&view);
        let export =
            TriangleExport::from_view(&view, SceneSpec::named(scene, camera.angle_degrees, 15.0));
        let bytes = export.to_bytes().unwrap();
        assert_eq!(&bytes[..8], b"FRAGTRI1");
        assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), WIDTH);
        assert_eq!(
            u32::from_le_bytes(bytes[16..20].try_into().unwrap()),
            HEIGHT
        );
        let count = u32::from_le_bytes(bytes[28..32].try_into().unwrap()) as usize;
        assert_eq!(count, export.triangles.len());
        assert_eq!((bytes.len() - 40) % 8, 0);
        assert_eq!(TriangleExport::from_bytes(&bytes).unwrap(), export);
        let mut lists = vec![Vec::new(); oracle.pixels()];
        for t in &export.triangles {
            view.scan(t, &mut |f| lists[f.pixel as usize].push(f.packed()));
        }
        for (p, list) in lists.iter_mut().enumerate() {
            list.sort_unstable();
            assert_eq!(list.as_slice(), oracle.pixel(p), "{scene}: pixel {p}");
        }
        assert!(TriangleExport::from_bytes(&bytes[..bytes.len() - 1]).is_err());
    }
}

fn fragsim() -> Command {
    Command::cargo_bin("fragsim").unwrap()
}

fn stdout_of(cmd: &mut Command, code: i32) -> String {
    let output = cmd.output().unwrap();
    assert_eq!(
        output.status.code(),
        Some(code),
        "stdout {}\nstderr {}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

const SIZE: [&str; 4] = ["--width", "48", "--height", "36"];

#[test]
fn the_binary_dumps_compares_and_exits_0_only_when_equal() {
    let dir = scratch("binary");
    let dumps = dir.join("dumps");
    stdout_of(
        fragsim()
            .args([
                "render",
                "--scene",
                SCENE,
                "--scheme",
                "mdts,mdts32,abuffer",
            ])
            .args(SIZE)
            .args(["--no-images", "--dump"])
            .arg(&dumps),
        0,
    );
    for scheme in ["mdts", "mdts32", "abuffer"] {
        let out = stdout_of(
            fragsim()
                .args(["compare", "oracle"])
                .arg(dumps.join(scheme))
                .args(["--json", "--no-image"]),
            0,
        );
        assert!(out.contains("\"equal\": true"), "{out}");
    }
    let text = stdout_of(
        fragsim()
            .arg("compare")
            .arg(dumps.join("abuffer"))
            .arg(dumps.join("mdts"))
            .arg("--no-image"),
        0,
    );
    assert!(text.contains("EQUAL (bit-identical)"), "{text}");
    // One corrupted word: exit 1, the verdict, both lists and a difference image.
    let slots = dumps.join("mdts").join("slots.u64");
    let mut bytes = std::fs::read(&slots).unwrap();
    let first = bytes.chunks_exact(8).position(|w| w != [0xff; 8]).unwrap();
    bytes[first * 8] ^= 1;
    std::fs::write(&slots, bytes).unwrap();
    let image = dir.join("diff.png");
    let text = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .arg("--image")
            .arg(&image),
        1,
    );
    assert!(text.contains("missing 1, extra 1"), "{text}");
    assert!(text.contains("verdict: DIFFERENT"), "{text}");
    assert!(image.exists());
    let json = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .args(["--json", "--no-image"]),
        1,
    );
    assert!(json.contains("\"equal\": false") && json.contains("\"first_differences\""));
    // Nothing to compare, or no dump at all: exit 2.
    stdout_of(fragsim().args(["compare", "oracle", "oracle"]), 2);
    stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("absent")),
        2,
    );
}

/// Runs `fragsim compare oracle DIR --json --no-image` expecting exit code `code`; the report.
fn json_report(dir: &Path, code: i32) -> serde_json::Value {
    let out = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir)
            .args(["--json", "--no-image"]),
        code,
    );
    serde_json::from_str(&out).unwrap()
}

#[test]
fn the_binary_calls_a_word_written_after_an_empty_slot_corrupt_never_equal() {
    let dir = scratch("binary-corrupt");
    let dumps = dir.join("dumps");
    stdout_of(
        fragsim()
            .args([
                "render",
                "--scene",
                SCENE,
                "--scheme",
                "mdts,mdts-desc,mdts32,abuffer",
            ])
            .args(SIZE)
            .args(["--no-images", "--dump"])
            .arg(&dumps),
        0,
    );
    // (layout, slots file, bytes a word, the empty slot's word)
    let layouts = [
        ("mdts", "slots.u64", 8, u64::MAX),
        ("mdts-desc", "slots.u64", 8, 0),
        ("mdts32", "slots.u32", 4, u64::from(u32::MAX)),
    ];
    for (scheme, file, width, empty) in layouts {
        let path = dumps.join(scheme);
        let k = json_report(&path, 0)["candidate"]["k"].as_u64().unwrap() as usize;
        let slots = path.join(file);
        let mut bytes = std::fs::read(&slots).unwrap();
        let word = |bytes: &[u8], i: usize| {
            let mut le = [0u8; 8];
            le[..width].copy_from_slice(&bytes[i * width..(i + 1) * width]);
            u64::from_le_bytes(le)
        };
        // A pixel whose first slot is full and whose last two are empty; its last slot gets a
        // copy of its first word, a word the pixel really holds.
        let pixel = (0..bytes.len() / width / k)
            .find(|&p| word(&bytes, p * k) != empty && word(&bytes, p * k + k - 2) == empty)
            .unwrap();
        let stray = word(&bytes, pixel * k);
        let last = pixel * k + k - 1;
        bytes[last * width..(last + 1) * width].copy_from_slice(&stray.to_le_bytes()[..width]);
        std::fs::write(&slots, &bytes).unwrap();
        let text = stdout_of(
            fragsim()
                .args(["compare", "oracle"])
                .arg(&path)
                .arg("--no-image"),
            1,
        );
        let x = pixel % WIDTH as usize;
        let y = pixel / WIDTH as usize;
        for expected in [
            "corrupt 1".to_string(),
            format!("pixel {pixel} (x {x}, y {y}): corrupt\n"),
            format!("slot {}: {stray:#x} written after an empty slot", k - 1),
            "verdict: DIFFERENT".to_string(),
        ] {
            assert!(
                text.contains(&expected),
                "{scheme}: {expected:?} not in\n{text}"
            );
        }
        assert!(!text.contains("EQUAL"), "{scheme}: {text}");
        let report = json_report(&path, 1);
        assert_eq!(report["equal"], false);
        assert_eq!(report["verdicts"]["corrupt"], 1, "{scheme}");
        assert_eq!(report["words"]["corrupt"], 1);
        let first = &report["first_differences"][0];
        assert_eq!(first["pixel"], pixel);
        assert_eq!(first["verdict"], serde_json::json!(["corrupt"]));
        assert_eq!(first["corrupt_words"][0]["slot"], k - 1);
    }
    // An A-buffer counter that never stopped: overflow-miscounted, and the overflow by design
    // stays what the oracle predicts (none here) instead of the counter's 4294967295 − n.
    let path = dumps.join("abuffer");
    let counters = path.join("counters.u32");
    let mut bytes = std::fs::read(&counters).unwrap();
    let pixel = bytes.chunks_exact(4).position(|c| c != [0; 4]).unwrap();
    bytes[pixel * 4..pixel * 4 + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&counters, &bytes).unwrap();
    let report = json_report(&path, 1);
    assert_eq!(report["verdicts"]["overflow-miscounted"], 1);
    assert_eq!(report["fragments"]["overflowed"], 0);
    assert_eq!(report["first_differences"][0]["pixel"], pixel);
    assert_eq!(
        report["first_differences"][0]["verdict"],
        // `abuffer` is fixed storage written in full (`filled`): the slots the counter now
        // claims hold the empty marker, which is corrupt too.
        serde_json::json!(["overflow-miscounted", "corrupt"])
    );
    let text = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(&path)
            .arg("--no-image"),
        1,
    );
    assert!(
        text.contains("overflowed by design 0 (counters claim"),
        "{text}"
    );
    assert!(text.contains("overflow-miscounted 1"), "{text}");
}

#[test]
fn the_binary_exports_the_triangles_of_the_view_it_names() {
    let dir = scratch("export");
    let file = dir.join("scene.tri");
    let text = stdout_of(
        fragsim()
            .args([
                "export-scene",
                "--scene",
                SCENE,
                "--view",
                "30",
                "--elevation",
                "15",
            ])
            .args(SIZE)
            .arg("--out")
            .arg(&file),
        0,
    );
    assert!(text.contains("screen triangles"), "{text}");
    let read = TriangleExport::read(&file).unwrap();
    with_view(|view, _| assert_eq!(read, TriangleExport::from_view(view, spec())));
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

#[test]
fn dump_parse_reads_a_dump_from_memory_as_read_does_from_files() {
    let (parsed, asked) = parse_recording(&mdts_header("slots.u64", "[4, 2]"));
    let dump = parsed.unwrap();
    assert_eq!(asked, ["slots.u64"]);
    let capture = dump.capture().unwrap();
    assert_eq!(capture.pixels(), 4);
    assert!(
        (0..4).all(|p| capture.pixel(p).is_empty()),
        "every slot empty"
    );
    let (text, files) = dump.encode().unwrap();
    let dir = scratch("parse-vs-read");
    std::fs::write(dir.join("dump.json"), text).unwrap();
    for (file, bytes) in files {
        std::fs::write(dir.join(file), bytes).unwrap();
    }
    assert_eq!(Dump::read(&dir).unwrap(), dump);
}

#[test]
fn regression_dump_parse_refuses_array_file_names_that_leave_the_dump_directory() {
    for file in [
        "../slots.u64",
        "/etc/passwd",
        "sub/slots.u64",
        "..",
        ".",
        "",
        "C:slots",
        "a\\b",
    ] {
        let header = mdts_header(file, "[4, 2]");
        let (parsed, asked) = parse_recording(&header);
        let error = parsed.expect_err(file);
        assert!(
            error.contains("must be a plain file name"),
            "{file:?}: {error}"
        );
        assert!(
            asked.is_empty(),
            "{file:?}: the reader was asked for {asked:?}"
        );
        let dir = scratch("bad-file-name");
        std::fs::write(dir.join("dump.json"), header).unwrap();
        let error = Dump::read(&dir).unwrap_err().to_string();
        assert!(
            error.contains("must be a plain file name"),
            "{file:?}: {error}"
        );
    }
}

#[test]
fn regression_dump_parse_refuses_a_shape_whose_element_count_overflows() {
    let header = mdts_header("slots.u64", "[4294967296, 4294967296, 2]");
    let (parsed, asked) = parse_recording(&header);
    let error = parsed.unwrap_err();
    assert!(error.contains("more than 2^64 elements"), "{error}");
    assert!(asked.is_empty(), "the reader was asked for {asked:?}");
}

/// The scene's four numbers, as bits, so that `-0.0` and `0.0` differ.
fn scene_bits(scene: &SceneSpec) -> [u64; 4] {
    [
        scene.view_degrees,
        scene.elevation_degrees,
        scene.fov_y_degrees,
        scene.distance_scale,
    ]
    .map(f64::to_bits)
}

/// `dump` encoded and parsed back from memory.
fn reparsed(dump: &Dump) -> Result<Dump, String> {
    let (text, files) = dump.encode().map_err(|e| e.to_string())?;
    Dump::parse("dump.json", text.as_bytes(), |file| {
        Ok(files.get(file).cloned().unwrap_or_default())
    })
    .map_err(|e| e.to_string())
}

/// The 2 × 2 MDTS dump of [`mdts_header`] with these scene numbers.
fn dump_with_scene(numbers: [f64; 4]) -> Dump {
    let mut dump = parse_recording(&mdts_header("slots.u64", "[4, 2]"))
        .0
        .unwrap();
    let scene = &mut dump.header.scene;
    [
        scene.view_degrees,
        scene.elevation_degrees,
        scene.fov_y_degrees,
        scene.distance_scale,
    ] = numbers;
    dump
}

/// Any f64 bit pattern that is finite: subnormals, both zeros, the extremes included.
fn finite_f64() -> impl Strategy<Value = f64> {
    any::<u64>()
        .prop_map(f64::from_bits)
        .prop_filter("finite", |v| v.is_finite())
}

/// Any f32 bit pattern that is finite.
fn finite_f32() -> impl Strategy<Value = f32> {
    any::<u32>()
        .prop_map(f32::from_bits)
        .prop_filter("finite", |v| v.is_finite())
}

proptest! {
    // `PROPTEST_CASES` raises the count for a long run (`docs/extremes.md`).
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(4096)
    ))]

    /// Every finite f64 in a header comes back bit for bit through encode and parse, in a dump
    /// header and in a triangle export's scene.
    #[test]
    fn every_finite_f64_in_a_header_round_trips_to_the_same_bits(
        numbers in proptest::array::uniform4(finite_f64())
    ) {
        let dump = dump_with_scene(numbers);
        let again = reparsed(&dump).map_err(TestCaseError::fail)?;
        prop_assert_eq!(scene_bits(&again.header.scene), numbers.map(f64::to_bits));
        prop_assert_eq!(&again, &dump);
        let export = TriangleExport {
            scene: dump.header.scene.clone(),
            width: 2,
            height: 2,
            mesh_triangles: 0,
            triangles: Vec::new(),
        };
        let bytes = export.to_bytes().map_err(|e| TestCaseError::fail(e.to_string()))?;
        let read = TriangleExport::from_bytes(&bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(scene_bits(&read.scene), numbers.map(f64::to_bits));
    }

    /// Every finite f32 that fragsim writes into a JSON report (`explain`'s and `compare`'s
    /// depths) is written shortest as an f32 and reads back as an f32 to the same bits.
    #[test]
    fn every_finite_f32_written_to_json_reads_back_to_the_same_bits(x in finite_f32()) {
        let text = serde_json::to_string(&x).unwrap();
        let back: f32 = serde_json::from_str(&text).map_err(|e| TestCaseError::fail(format!("{text}: {e}")))?;
        prop_assert_eq!(back.to_bits(), x.to_bits(), "{} read back as {}", text, back);
        // Written as an f32, not widened to f64 (up to 17 digits): at most 9 significant digits.
        let mantissa: String = text
            .split(['e', 'E'])
            .next()
            .unwrap_or_default()
            .chars()
            .filter(char::is_ascii_digit)
            .collect();
        let significant = mantissa.trim_start_matches('0').trim_end_matches('0').len();
        prop_assert!(significant <= 9, "{} has {} significant digits", text, significant);
    }

    /// Any decimal, not only the shortest ones fragsim writes (a backend's printf may write 17 or
    /// 40 digits), parses in a header to the nearest f64, and as an f32 to the nearest f32: what
    /// Rust's own correctly rounded `str::parse` gives, an independent implementation; past the
    /// range it is an error.
    #[test]
    fn any_decimal_in_a_header_parses_to_the_nearest_f64(
        negative in any::<bool>(),
        digits in "[0-9]{1,40}",
        point in 0usize..41,
        exponent in -360i32..360,
    ) {
        let point = point.min(digits.len());
        let sign = if negative { "-" } else { "" };
        let fraction = if point == digits.len() { "0" } else { &digits[point..] };
        let whole = if point == 0 { "0" } else { digits[..point].trim_start_matches('0') };
        let whole = if whole.is_empty() { "0" } else { whole };
        let decimal = format!("{sign}{whole}.{fraction}e{exponent}");
        let nearest: f64 = decimal.parse().unwrap();
        let header = mdts_header("slots.u64", "[4, 2]").replace("15.0", &decimal);
        match parse_recording(&header).0 {
            Ok(dump) => prop_assert_eq!(
                dump.header.scene.elevation_degrees.to_bits(),
                nearest.to_bits(),
                "{} parsed as {}, nearest is {}", decimal, dump.header.scene.elevation_degrees, nearest
            ),
            Err(e) => {
                prop_assert!(nearest.is_infinite(), "{}: {}", decimal, e);
                prop_assert!(e.contains("out of range"), "{}: {}", decimal, e);
            }
        }
        // Read as an f32 (report fields), the same decimal rounds once, to the nearest f32.
        let nearest: f32 = decimal.parse().unwrap();
        match serde_json::from_str::<f32>(&decimal) {
            Ok(got) => prop_assert_eq!(got.to_bits(), nearest.to_bits(), "{} read as f32 {}, nearest is {}", decimal, got, nearest),
            Err(e) => prop_assert!(nearest.is_infinite(), "{}: {}", decimal, e),
        }
    }
}

#[test]
fn regression_the_fuzz_found_elevation_parses_to_the_nearest_f64_and_round_trips() {
    // `dump_parse` found it (issue 23): without `float_roundtrip` it parsed to
    // 6.666666665999999e32, which re-encodes as 6.666666666e32 and parses to another number.
    // The same input is checked in as a corpus seed, `regression-elevation-not-read-exactly`.
    let decimal = "666666666600000133584280347126390.0";
    let header = mdts_header("slots.u64", "[4, 2]").replace("15.0", decimal);
    let dump = parse_recording(&header).0.unwrap();
    let nearest: f64 = decimal.parse().unwrap();
    assert_eq!(
        dump.header.scene.elevation_degrees.to_bits(),
        nearest.to_bits(),
        "parsed as {}, nearest is {nearest}",
        dump.header.scene.elevation_degrees
    );
    let again = reparsed(&dump).unwrap();
    assert_eq!(
        scene_bits(&again.header.scene),
        scene_bits(&dump.header.scene)
    );
    assert_eq!(again, dump);
}

#[test]
fn a_nan_or_infinite_scene_number_is_refused_by_name_when_writing() {
    for field in 0..4 {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut numbers = [30.0, 15.0, 45.0, 1.5];
            numbers[field] = bad;
            let dump = dump_with_scene(numbers);
            let name = [
                "view_degrees",
                "elevation_degrees",
                "fov_y_degrees",
                "distance_scale",
            ][field];
            let error = dump.encode().unwrap_err().to_string();
            assert!(
                error.contains(name) && error.contains("must be finite"),
                "{name} = {bad}: {error}"
            );
            let export = TriangleExport {
                scene: dump.header.scene.clone(),
                width: 2,
                height: 2,
                mesh_triangles: 0,
                triangles: Vec::new(),
            };
            let error = export.to_bytes().unwrap_err().to_string();
            assert!(error.contains(name), "{name} = {bad}: {error}");
        }
    }
    assert!(dump_with_scene([30.0, 15.0, 45.0, 1.5]).encode().is_ok());
}

#[test]
fn a_header_number_json_cannot_hold_is_a_parse_error_naming_the_header() {
    for bad in [
        "1e400",
        "-1e400",
        "NaN",
        "Infinity",
        "-Infinity",
        "null",
        "\"15\"",
    ] {
        let header = mdts_header("slots.u64", "[4, 2]").replace("15.0", bad);
        let (parsed, asked) = parse_recording(&header);
        let error = parsed.expect_err(bad);
        assert!(error.starts_with("dump.json: "), "{bad}: {error}");
        assert!(
            asked.is_empty(),
            "{bad}: the reader was asked for {asked:?}"
        );
    }
}

#[test]
fn regression_dump_parse_refuses_two_arrays_naming_the_same_file() {
    // `dump_parse` found it (issue 23, seed `regression-two-arrays-one-file`): an A-buffer whose
    // `offsets` and `slots` both named `slots.u64` parsed, then encoded one array's words under
    // both names and failed to parse back.
    let header = r#"{"format": "fragsim-dump", "version": 1, "scene": {"name": "quads:2",
        "view_degrees": 30.0, "elevation_degrees": 15.0}, "width": 2, "height": 2,
        "scheme": "abuffer", "arrays": {
        "counters": {"file": "counters.u32", "dtype": "u32", "shape": [4]},
        "offsets": {"file": "slots.u64", "dtype": "u32", "shape": [5]},
        "slots": {"file": "slots.u64", "dtype": "u64", "shape": [4]}}}"#;
    let (parsed, asked) = parse_recording(header);
    let error = parsed.unwrap_err();
    assert!(
        error.contains(r#"arrays "offsets" and "slots" both name file "slots.u64""#),
        "{error}"
    );
    assert!(asked.is_empty(), "the reader was asked for {asked:?}");
}

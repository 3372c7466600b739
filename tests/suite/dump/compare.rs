//! `compare` names every kind of difference: missing, extra and misordered pixels, overflow by
//! design against an overstated counter, corrupt words and miscounted overflow, the depth tolerance
//! and key-only references.

use fragsim::capture::Identity;
use fragsim::dump::Direction;
use fragsim::dump::{Corruption, Dump, DumpScheme, Words};
use fragsim::oracle::compare::{self, flags, CompareOptions};
use fragsim::oracle::Oracle;

use super::{counters, judged, pixel_with, spec, u64_slots, with_view, HEIGHT, WIDTH};

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
        let comparison = compare::compare(oracle, &capture, 0, 8);
        let flags = |p: usize| comparison.verdicts[p];
        assert_eq!(flags(swapped), flags::MISORDERED);
        assert_eq!(flags(renamed), flags::MISSING | flags::EXTRA);
        assert_eq!(flags(holed), flags::MISSING);
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
        assert_eq!(whole.verdicts[holed], flags::MISSING | flags::CORRUPT);
        assert_eq!(whole.verdicts[swapped], flags::MISORDERED);
        assert_eq!(
            whole.corrupt_words,
            oracle.pixel(holed).len().min(k) as u64 - 2,
            "every word behind the hole"
        );
        let diff = oracle.diff(&capture);
        assert_eq!(
            (
                diff.lost,
                diff.extra,
                diff.misordered_pixels,
                diff.mismatched_pixels
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
        let comparison = compare::compare(oracle, &dump.capture().unwrap(), 0, 8);
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
        let miscounted = compare::compare(oracle, &dump.capture().unwrap(), 0, 8);
        assert!(!miscounted.is_equal());
        assert_eq!(
            miscounted.verdicts[deep] & flags::MISCOUNTED,
            flags::MISCOUNTED
        );
        assert_eq!(miscounted.counts.miscounted, 1);
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
            let lists = compare::compare(oracle, &dump.capture().unwrap(), 0, 8);
            assert!(
                lists.is_equal(),
                "{scheme:?}: decoding stops at the empty slot"
            );
            let whole = judged(&dump, oracle);
            assert!(!whole.is_equal(), "{scheme:?}");
            assert_eq!(whole.verdicts[p], flags::CORRUPT, "{scheme:?}");
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
                flags::CORRUPT | flags::MISSING,
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
        assert_eq!(whole.verdicts[p], flags::CORRUPT);
        assert_eq!(whole.first_corrupt[0].why, Corruption::BeyondCounter);
        assert_eq!(whole.unchecked_words, 0);
        // FreePipe leaves spare slots uninitialised: without the promise nothing is known of
        // them, and the report says how many words went unread instead of judging them.
        dump.header.filled = false;
        let unfilled = judged(&dump, oracle);
        assert!(unfilled.is_equal());
        assert_eq!(
            (unfilled.corrupt_words, unfilled.unchecked_words),
            (0, unused)
        );
    });
}

#[test]
fn a_stored_depth_key_above_one_is_corrupt() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let p = pixel_with(oracle, 1, usize::MAX);
        let impossible = (0x3F80_0001_u64 << 32) | (oracle.pixel(p)[0] & 0xFFFF_FFFF);
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
                flags::CORRUPT | flags::MISSING | flags::EXTRA,
                "{scheme:?}"
            );
            assert_eq!(whole.first_corrupt[0].why, Corruption::ImpossibleKey);
        }
    });
}

#[test]
fn an_abuffer_counter_other_than_the_pixels_fragment_count_is_overflow_miscounted() {
    with_view(|view, oracle| {
        let capacity = 3_u32;
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
            (deep, u32::MAX, flags::MISCOUNTED | flags::OVERFLOWED),
            (deep, n - 1, flags::MISCOUNTED | flags::OVERFLOWED),
            (shallow, 3, flags::MISCOUNTED | flags::CORRUPT),
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
            let lists = compare::compare(oracle, &dump.capture().unwrap(), 0, 8);
            assert_eq!(lists.verdicts[p] & flags::MISCOUNTED, flags::MISCOUNTED);
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
        let complete = compare::complete_pixels(&capture);
        let overflowing = oracle.depth_complexity().iter().filter(|&&n| n > 2).count() as u64;
        assert!(overflowing > 0);
        assert_eq!(complete.iter().filter(|&&c| !c).count() as u64, overflowing);
        let words = dump.check_words().unwrap();
        let knowing = CompareOptions {
            complete: Some(&complete),
            ..CompareOptions::default()
        };
        assert!(compare::compare_with(&reference, &capture, Some(&words), &knowing).is_equal());
        // Taken as the whole truth, the reference's two fragments a pixel make every overflowing
        // counter look too large: that is why completeness is passed.
        let naive = compare::compare_with(
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
            let comparison = compare::compare(oracle, &dump.capture().unwrap(), 0, 8);
            if sorted {
                assert_eq!(comparison.verdicts[deep], flags::MISORDERED);
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
            (1_u64, 0_u32, false),
            (1, 1, true),
            (3, 2, false),
            (3, 3, true),
        ] {
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            u64_slots(&mut dump)[pixel * k as usize] += nudge << 32;
            let comparison = compare::compare(oracle, &dump.capture().unwrap(), tolerance, 8);
            assert_eq!(
                comparison.is_equal(),
                equal,
                "nudge {nudge} ulps, tolerance {tolerance}"
            );
        }
        // A different primitive is never a tolerance match.
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        u64_slots(&mut dump)[pixel * k as usize] += (1 << 32) + 1;
        assert!(!compare::compare(oracle, &dump.capture().unwrap(), 5, 8).is_equal());
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
        assert!(!compare::compare(&as_oracle, &candidate, 0, 1).is_equal());
        let coarse = compare::with_identity(&candidate, Identity::KeyOnly);
        assert!(compare::compare(&as_oracle, &coarse, 0, 1).is_equal());
    });
}

//! Every allowance comes from the reference, never from the candidate (`docs/semantics.md`,
//! "Allowances come from the reference"): a dump `render --dump` wrote is rewritten so that what
//! it says about its own storage (the room its offsets give, which K fragments it keeps, its
//! node counter, the bits around its payload fields) would excuse a wrong list, and `compare`
//! through the binary calls it DIFFERENT. Each test first checks that the untouched dump is
//! EQUAL, so that it can fail both ways.

use std::path::Path;

use fragsim::dump::{Dump, Words};

use super::binary::{fragsim, stdout_of};
use super::soundness::compared;
use super::{scratch, SCENE};
use crate::support::prim_of;

/// The viewport's side: the test scene at 48 × 48 has pixels deeper than K = 2 at every layout.
const SIDE: &str = "48";

/// `fragsim render` of the test scene serially, running `schemes` with `options`, its dumps in
/// `out`.
fn render(out: &Path, schemes: &str, options: &[&str]) {
    stdout_of(
        fragsim()
            .args([
                "render", "--scene", SCENE, "--width", SIDE, "--height", SIDE,
            ])
            .args(["--scheme", schemes, "--executor", "serial", "--no-images"])
            .arg("--dump")
            .arg(out)
            .args(options),
        0,
    );
}

/// The dump in `dir` read, changed by `edit` and written back in place.
fn rewrite(dir: &Path, edit: impl FnOnce(&mut Dump)) {
    let mut dump = Dump::read(dir).unwrap();
    edit(&mut dump);
    let (header, files) = dump.encode().unwrap();
    std::fs::write(dir.join("dump.json"), header).unwrap();
    for (file, bytes) in files {
        std::fs::write(dir.join(file), bytes).unwrap();
    }
}

fn u32s(dump: &Dump, name: &str) -> Vec<u32> {
    match &dump.arrays[name] {
        Words::U32(words) => words.clone(),
        Words::U64(_) => panic!("{name} is u64"),
    }
}

fn u64s(dump: &Dump, name: &str) -> Vec<u64> {
    match &dump.arrays[name] {
        Words::U64(words) => words.clone(),
        Words::U32(_) => panic!("{name} is u32"),
    }
}

/// The verdict of `compare oracle DIR` on a dump that must be DIFFERENT: its record.
fn different(dir: &Path, what: &str) -> serde_json::Value {
    let report = compared(dir, &[], 1);
    assert_eq!(report["equal"], false, "{what}: {report}");
    report
}

/// The verdict on the untouched dump, which must be EQUAL.
fn equal(dir: &Path, what: &str) {
    let report = compared(dir, &[], 0);
    assert_eq!(report["equal"], true, "{what} untouched: {report}");
}

/// Copies the dump in `from` to a fresh directory `name` beside it.
fn copy_of(from: &Path, name: &str) -> std::path::PathBuf {
    let to = from.with_file_name(name);
    std::fs::create_dir_all(&to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
    }
    to
}

#[test]
fn exact_storage_owes_room_for_every_fragment_whatever_its_offsets_say() {
    // The room the offsets give a pixel was taken as its capacity: a pixel's room cut by one
    // and its last fragment dropped (counter left at n) was EQUAL, and so were offsets all zero
    // with nothing stored.
    let dir = scratch("allow-offsets");
    render(&dir, "abuffer-exact", &["--capacity", "auto"]);
    let path = dir.join("abuffer-exact");
    equal(&path, "abuffer-exact");
    let dump = Dump::read(&path).unwrap();
    let offsets = u32s(&dump, "offsets");
    let counters = u32s(&dump, "counters");
    // The deepest pixel: its counter n is its room.
    let p = (0..counters.len()).max_by_key(|&p| counters[p]).unwrap();
    assert!(counters[p] >= 2, "deepest pixel holds {}", counters[p]);
    assert_eq!(offsets[p + 1] - offsets[p], counters[p]);

    let cut = copy_of(&path, "cut-by-one");
    rewrite(&cut, |copy| {
        let mut offsets = offsets.clone();
        for offset in &mut offsets[p + 1..] {
            *offset -= 1;
        }
        let mut slots = u64s(copy, "slots");
        slots.remove(offsets[p + 1] as usize);
        let total = slots.len() as u64;
        copy.set_array(
            "offsets",
            Words::U32(offsets.clone()),
            vec![offsets.len() as u64],
        );
        copy.set_array("slots", Words::U64(slots), vec![total]);
    });
    let report = different(&cut, "room cut by one");
    assert_eq!(report["lost"], 1, "{report}");
    assert_eq!(report["corrupt_words"], 1, "the room is named: {report}");

    let none = copy_of(&path, "no-room");
    rewrite(&none, |copy| {
        let zeros = vec![0; offsets.len()];
        copy.set_array("offsets", Words::U32(zeros), vec![offsets.len() as u64]);
        copy.set_array("slots", Words::U64(Vec::new()), vec![0]);
    });
    let zeroed_report = different(&none, "offsets all zero");
    let fragments: u64 = counters.iter().map(|&c| u64::from(c)).sum();
    assert_eq!(zeroed_report["lost"], fragments, "{zeroed_report}");
    assert_eq!(zeroed_report["captured"], 0, "{zeroed_report}");
}

/// Each pixel's `k` slots of `slots` (pixel-major) replaced by `pick` of the pixel's full list
/// `all` (every fragment, as the exact A-buffer holds it), sorted, empty slots after.
fn keep(slots: &mut [u64], all: &[u64], offsets: &[u32], k: usize, pick: Pick) {
    for (p, run) in slots.chunks_exact_mut(k).enumerate() {
        let mut list = all[offsets[p] as usize..offsets[p + 1] as usize].to_vec();
        pick(&mut list);
        list.truncate(k);
        list.sort_unstable();
        run.fill(u64::MAX);
        run[..list.len()].copy_from_slice(&list);
    }
}

/// A way to pick which of a pixel's fragments a K-slot list keeps: the list ordered so that the
/// kept ones come first.
type Pick = fn(&mut [u64]);

/// Orders a pixel's fragments by primitive id, first submitted first.
fn by_primitive(list: &mut [u64]) {
    list.sort_unstable_by_key(|&w| prim_of(w));
}

/// Orders a pixel's fragments by primitive id, last submitted first.
fn by_primitive_last_first(list: &mut [u64]) {
    list.sort_unstable_by_key(|&w| std::cmp::Reverse(prim_of(w)));
}

/// Orders a pixel's fragments nearest first.
fn nearest_first(list: &mut [u64]) {
    list.sort_unstable();
}

#[test]
fn each_k_buffer_is_held_to_its_own_ordering_promise() {
    // `kbuffer-interlock-ordered-first` was judged as "any K": its 2 nearest, or the last 2 by
    // primitive, were EQUAL. Each k-buffer keeps the K its promise names, and no other K.
    let dir = scratch("allow-kbuffers");
    let kbuffers = [
        "kbuffer",
        "kbuffer-stores",
        "kbuffer-interlock",
        "kbuffer-interlock-ordered",
        "kbuffer-spinlock",
        "kbuffer-spinlock-fixed",
        "kbuffer-interlock-ordered-first",
    ];
    render(
        &dir,
        &format!("abuffer-exact,{}", kbuffers.join(",")),
        &["--k", "2", "--capacity", "auto"],
    );
    let every = Dump::read(&dir.join("abuffer-exact")).unwrap();
    let (all, offsets) = (u64s(&every, "slots"), u32s(&every, "offsets"));
    let deep = offsets.windows(2).filter(|w| w[1] - w[0] > 2).count();
    assert!(deep > 50, "{deep} pixels deeper than K");
    let picks: [(&str, Pick); 3] = [
        ("the nearest 2", nearest_first),
        ("the first 2 by primitive", by_primitive),
        ("the last 2 by primitive", by_primitive_last_first),
    ];
    for scheme in kbuffers {
        let path = dir.join(scheme);
        equal(&path, scheme);
        let own = u64s(&Dump::read(&path).unwrap(), "slots");
        let owed = if scheme.ends_with("-first") {
            "the first 2 by primitive"
        } else {
            "the nearest 2"
        };
        for (what, pick) in picks {
            let mutant = copy_of(&path, &format!("{scheme}-{}", what.replace(' ', "-")));
            let mut slots = own.clone();
            keep(&mut slots, &all, &offsets, 2, pick);
            rewrite(&mutant, |dump| {
                let shape = vec![slots.len() as u64 / 2, 2];
                dump.set_array("slots", Words::U64(slots.clone()), shape);
            });
            if what == owed {
                // The control: the owed K, rebuilt from the full lists, is the dump itself.
                assert_eq!(slots, own, "{scheme}: {what} rebuilt");
                equal(&mutant, &format!("{scheme} keeping {what}"));
            } else {
                assert_ne!(slots, own, "{scheme}: {what} changes nothing");
                let report = different(&mutant, &format!("{scheme} keeping {what}"));
                assert!(
                    report["lost"].as_u64().unwrap() > 0,
                    "{scheme}, {what}: {report}"
                );
            }
        }
    }
}

#[test]
fn a_linked_list_counter_is_the_scenes_fragment_count_whatever_the_pool() {
    // With `--capacity auto` the pool equals the fragment count N, and a counter of N + 1, 2 N
    // or 0xFFFFFFFF was EQUAL: the counter was checked only against a larger pool.
    let dir = scratch("allow-list-counter");
    render(
        &dir,
        "linked-list,linked-list-nearest",
        &["--k", "2", "--capacity", "auto"],
    );
    for scheme in ["linked-list", "linked-list-nearest"] {
        let path = dir.join(scheme);
        equal(&path, scheme);
        let dump = Dump::read(&path).unwrap();
        let n = u32s(&dump, "counter")[0];
        assert_eq!(Some(u64::from(n)), dump.header.pool, "{scheme}: pool of N");
        for counter in [n + 1, 2 * n, u32::MAX, n - 1, 0] {
            let mutant = copy_of(&path, &format!("{scheme}-counter-{counter}"));
            rewrite(&mutant, |copy| {
                copy.set_array("counter", Words::U32(vec![counter]), vec![1]);
            });
            different(&mutant, &format!("{scheme} counter {counter} of {n}"));
        }
    }
}

#[test]
fn payload_bits_outside_the_declared_fields_are_read_and_must_be_zero() {
    // With `u64:unorm24:32:32`, 0xAB in bits 56-63 of every word was EQUAL, the report saying
    // every word was read and none corrupt.
    let dir = scratch("allow-payload-bits");
    render(
        &dir,
        "mdts,abuffer,linked-list,layer-counter",
        &[
            "--k",
            "2",
            "--capacity",
            "4",
            "--dump-payload",
            "u64:unorm24:32:32",
        ],
    );
    for (scheme, array) in [
        ("mdts", "slots"),
        ("abuffer", "slots"),
        ("linked-list", "nodes"),
        ("layer-counter", "layers"),
    ] {
        let path = dir.join(scheme);
        equal(&path, scheme);
        let mutant = copy_of(&path, &format!("{scheme}-top-byte"));
        rewrite(&mutant, |dump| {
            let words: Vec<u64> = u64s(dump, array)
                .into_iter()
                .map(|w| if w == u64::MAX { w } else { w | 0xAB << 56 })
                .collect();
            let shape = dump.header.arrays[array].shape.clone();
            dump.set_array(array, Words::U64(words), shape);
        });
        let report = different(&mutant, &format!("{scheme} with 0xAB in bits 56-63"));
        assert!(
            report["corrupt_words"].as_u64().unwrap() > 0,
            "{scheme}: {report}"
        );
    }
}

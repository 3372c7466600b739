//! A layout for every catalog scheme: every scheme's memory, run as `render --dump`
//! runs it, records, goes through files and decodes to exactly what the scheme captured, and
//! compares equal with the oracle; linked-list and layer-major dumps in another engine's
//! encoding read the same; each rule of their words names a corrupted word, a cycle included.

use fragsim::capture::executors::Executor;
use fragsim::capture::Capture;
use fragsim::catalog::{Count, DumpLayout, SchemeName, SchemeRunner, Sizing, CATALOG};
use fragsim::dump::{Corruption, DepthFormat, Dtype, Dump, DumpScheme, LayoutSpec, Payload, Words};
use fragsim::oracle::compare::{self, flags};
use fragsim::oracle::Oracle;
use fragsim::raster::View;

use super::{judged, pixel_with, scratch, spec, with_view};

/// `render --dump`'s path for one scheme: a serial run sized by `sizing`, then its dump.
fn dumped(name: &str, view: &View<'_>, sizing: &Sizing) -> (Dump, Capture) {
    let scheme = SchemeName::from_name(name).unwrap();
    let named = SchemeRunner::default()
        .run(scheme, Executor::Serial, view, sizing)
        .unwrap();
    let layout = DumpScheme::for_run(
        scheme,
        named.slots.unwrap_or(1),
        &named.sizes,
        named.counts.as_deref(),
    )
    .unwrap();
    let dump = Dump::record(view, spec(), &layout, "test").unwrap();
    (dump, named.run.capture)
}

fn sizing() -> Sizing {
    Sizing {
        k: Count::Auto,
        capacity: Count::Auto,
        memory_cap: 1 << 32,
    }
}

#[test]
fn every_catalog_scheme_dumps_reads_back_what_it_captured_and_compares_equal() {
    with_view(|view, oracle| {
        let dir = scratch("every-scheme");
        let mut inexact = Vec::new();
        for entry in CATALOG {
            assert!(entry.dump.is_some(), "{} has no dump layout", entry.name);
            if entry.dump == Some(DumpLayout::MaskedNodes) {
                // Masked nodes are no layout of fragments: their dumps are recorded, read back
                // and judged node by node in `dump/samples.rs`.
                continue;
            }
            let (dump, captured) = dumped(entry.name, view, &sizing());
            let path = dir.join(entry.name);
            dump.write(&path).unwrap();
            let read = Dump::read(&path).unwrap();
            assert_eq!(read, dump, "{}", entry.name);
            let header_name = DumpLayout::header_scheme(entry.scheme).unwrap().name();
            assert_eq!(read.header.scheme, header_name, "{}", entry.name);
            let decoded = read.capture().unwrap();
            if entry.dump == Some(DumpLayout::LinkedLists) {
                // Judged on every node its lists reach, all of them owed: the resolve kept each
                // one here (`k` is the scene's depth), under its own promise.
                assert_eq!(decoded.lists, captured.lists, "{}", entry.name);
            } else {
                assert_eq!(decoded, captured, "{}", entry.name);
            }
            let own = compare::compare(oracle, &captured, 0, 4);
            let comparison = judged(&read, oracle);
            // The dump is judged as the scheme's own run is: equal where the run is exact, the
            // same pixels otherwise (bucket schemes' collisions, 32-bit keys' merged ties).
            assert_eq!(comparison.verdicts, own.verdicts, "{}", entry.name);
            assert_eq!(comparison.is_equal(), own.is_equal(), "{}", entry.name);
            assert_eq!(comparison.corrupt_words, 0, "{}", entry.name);
            if !comparison.is_equal() {
                inexact.push(entry.name);
            }
        }
        // Every layout the shipping schemes need compares equal on this scene.
        for name in [
            "mdts",
            "abuffer",
            "linked-list",
            "linked-list-nearest",
            "layer-counter",
        ] {
            assert!(!inexact.contains(&name), "{name} differs from the oracle");
        }
        eprintln!("not equal to the oracle on their own runs either: {inexact:?}");
    });
}

/// The linked list of `linked-list-nearest` sized to the scene, and a pixel of several nodes.
fn lists(view: &View<'_>, oracle: &Oracle) -> (Dump, usize) {
    let (dump, _) = dumped("linked-list-nearest", view, &sizing());
    (dump, pixel_with(oracle, 3, usize::MAX))
}

fn u32s<'a>(dump: &'a mut Dump, name: &str) -> &'a mut Vec<u32> {
    match dump.arrays.get_mut(name) {
        Some(Words::U32(w)) => w,
        _ => panic!("no u32 array {name}"),
    }
}

/// The corrupt words that the comparison found at pixel `p`, which it must call corrupt.
fn corrupt_at(dump: &Dump, oracle: &Oracle, p: usize) -> Vec<Corruption> {
    let comparison = judged(dump, oracle);
    assert_ne!(
        comparison.verdicts[p] & flags::CORRUPT,
        0,
        "pixel {p} is not flagged corrupt"
    );
    let check = dump.check_words().unwrap();
    check.corrupt[p].iter().map(|c| c.why).collect()
}

#[test]
fn a_linked_list_cycle_is_a_corrupt_pixel_found_in_one_walk() {
    with_view(|view, oracle| {
        let (mut dump, p) = lists(view, oracle);
        let head = u32s(&mut dump, "heads")[p];
        let second = u32s(&mut dump, "next")[head as usize - 1];
        // The second node links back to the first: an endless list.
        u32s(&mut dump, "next")[second as usize - 1] = head;
        assert_eq!(corrupt_at(&dump, oracle, p), vec![Corruption::Revisited]);
        // Only this pixel: the cut leaves every other list whole.
        let comparison = judged(&dump, oracle);
        assert_eq!(comparison.counts.corrupt, 1);
    });
}

#[test]
fn links_out_of_the_pool_or_to_unallocated_nodes_are_corrupt() {
    with_view(|view, oracle| {
        let (mut dump, p) = lists(view, oracle);
        let pool = u32::try_from(u32s(&mut dump, "next").len()).expect("a test scene's pool");
        let mut out = dump.clone();
        u32s(&mut out, "heads")[p] = pool + 1;
        assert_eq!(corrupt_at(&out, oracle, p), vec![Corruption::OutOfPool]);
        // A counter that handed out fewer nodes than the lists use.
        let mut short = dump.clone();
        let head = u32s(&mut short, "heads")[p];
        u32s(&mut short, "counter")[0] = head - 1;
        assert!(corrupt_at(&short, oracle, p).contains(&Corruption::Unallocated));
        // A node whose depth key is above 1.0.
        let mut key = dump.clone();
        if let Some(Words::U64(nodes)) = key.arrays.get_mut("nodes") {
            nodes[head as usize - 1] = u64::from(2.0_f32.to_bits()) << 32;
        }
        assert_eq!(corrupt_at(&key, oracle, p), vec![Corruption::ImpossibleKey]);
        // A lost node: unlinked from its list, allocated, reached by no list.
        let mut lost = dump;
        let second = u32s(&mut lost, "next")[head as usize - 1];
        u32s(&mut lost, "heads")[p] = second;
        let comparison = judged(&lost, oracle);
        assert_eq!(lost.check_words().unwrap().unreachable, 1);
        assert_ne!(comparison.verdicts[p] & flags::MISSING, 0);
    });
}

#[test]
fn a_vulkan_samples_linked_list_reads_as_fragsims() {
    with_view(|view, oracle| {
        let (dump, _) = lists(view, oracle);
        // Vulkan-Samples' numbering: nodes from 0, 0xFFFFFFFF ends a list.
        let mut vulkan = dump.clone();
        for name in ["heads", "next"] {
            for link in u32s(&mut vulkan, name) {
                *link = link.wrapping_sub(1);
            }
        }
        vulkan.header.layout = Some(LayoutSpec::LinkedList {
            payload: Payload::FRAGMENT,
            null: u32::MAX,
            node_base: 0,
        });
        assert_eq!(vulkan.capture().unwrap(), dump.capture().unwrap());
        assert!(judged(&vulkan, oracle).is_equal());
        // `render --dump-list-numbering 4294967295:0` writes exactly these lists, and refuses a
        // terminator that is some node's number.
        assert_eq!(dump.in_layout(vulkan.header.layout).unwrap(), vulkan);
        let colliding = LayoutSpec::LinkedList {
            payload: Payload::FRAGMENT,
            null: 1,
            node_base: 1,
        };
        let error = dump.in_layout(Some(colliding)).unwrap_err().to_string();
        assert!(error.contains("\"null\" 1 is a node's number"), "{error}");
        // The same lists with u32 nodes of a unorm24 depth over an 8-bit id: the depths are the
        // unorm's, each within its quantum of the f32 depth.
        let mut packed = dump.clone();
        let Some(Words::U64(nodes)) = dump.arrays.get("nodes") else {
            panic!("no nodes")
        };
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a depth in [0, 1] scaled to 2^24 - 1 fits u32, and the 8-bit id is the \
                      entry's low byte"
        )]
        let unorm = |w: u64| {
            let depth = f64::from(f32::from_bits((w >> 32) as u32));
            let q = (depth * 16_777_215.0).round() as u32;
            q << 8 | (w as u32 & 0xFF)
        };
        packed.arrays.insert(
            "nodes".into(),
            Words::U32(nodes.iter().map(|&w| unorm(w)).collect()),
        );
        packed.header.arrays.get_mut("nodes").unwrap().dtype = Dtype::U32;
        packed.header.layout = Some(LayoutSpec::LinkedList {
            payload: Payload {
                dtype: Dtype::U32,
                depth: DepthFormat::Unorm24,
                depth_shift: 8,
                prim_bits: 8,
            },
            null: 0,
            node_base: 1,
        });
        let decoded = packed.capture().unwrap();
        let original = dump.capture().unwrap();
        assert_eq!(decoded.pixels(), original.pixels());
        let depth = |w: u64| f64::from(f32::from_bits((w >> 32) as u32));
        for p in 0..original.pixels() {
            let (a, b) = (decoded.pixel(p), original.pixel(p));
            assert_eq!(a.len(), b.len());
            // Quantised depths and 8-bit ids may reorder a list: each decoded word has an
            // original of its id within half a quantum (and a little for the f32 rounding).
            for &got in a {
                assert!(
                    b.iter().any(|&want| got & 0xFF == want & 0xFF
                        && (depth(got) - depth(want)).abs() <= 0.6 / 16_777_215.0),
                    "pixel {p}: {got:#x} is no fragment's"
                );
            }
        }
        assert_eq!(packed.check_words().unwrap().corrupt_words(), 0);
    });
}

#[test]
fn a_layer_counter_past_its_layers_and_an_impossible_layer_are_corrupt() {
    with_view(|view, oracle| {
        let (mut dump, _) = dumped("layer-counter", view, &sizing());
        let k = dump.header.k.unwrap();
        // A pixel of exactly `k` fragments: a counter past `k` reads only layers it wrote.
        let p = pixel_with(oracle, k as usize, k as usize);
        let mut past = dump.clone();
        u32s(&mut past, "counters")[p] = k + 1;
        assert_eq!(
            corrupt_at(&past, oracle, p),
            vec![Corruption::CounterPastStorage]
        );
        let pixels = oracle.pixels();
        if let Some(Words::U64(layers)) = dump.arrays.get_mut("layers") {
            // Layer 0 of pixel p, layer-major.
            layers[p] = u64::MAX;
            assert_eq!(layers.len(), k as usize * pixels);
        }
        assert_eq!(
            corrupt_at(&dump, oracle, p),
            vec![Corruption::ImpossibleKey]
        );
    });
}

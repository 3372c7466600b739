//! The start of the verdict's mutation battery (issue 34, "What to build" item 5): correct dumps
//! of a scene deeper than K are mutated in ways no conforming implementation could produce, at
//! pixels the reference decides (every fragment certain and bit-equal under the f32 analysis),
//! seeded and deterministic, and each mutant must be DIFFERENT judged exactly and within the
//! precision of an f32 vertex stage; a change a conforming implementation could make (two
//! fragments stored in the other arrival order) must stay EQUAL both ways. It prints a kill table
//! by kind and layout. Layouts covered
//! so far: `mdts`, `mdts-desc` and `mdts32` (K = 2), the filled fixed A-buffer, fragsim's linked
//! list (K = 2, exact pool); the other layouts and kinds of the issue are still to come.

use fragsim::capture::catalog::SchemeName;
use fragsim::capture::schemes::mdts::Direction;
use fragsim::oracle::compare::CompareOptions;
use fragsim::oracle::dump::{Dump, DumpScheme, LayoutSpec, Words};
use fragsim::oracle::Oracle;
use fragsim::raster::SplitMix64;

use super::{spec, with_view};

/// How many pixels each (kind, layout) mutates, one mutant each.
const MUTANTS: usize = 16;

/// A way to break one pixel's list that no conforming implementation could produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A stored fragment taken out, the rest kept in order.
    Drop,
    /// Every fragment of the pixel taken out.
    Empty,
    /// The second fragment replaced by a copy of the first.
    Duplicate,
    /// The first two fragments swapped: an error in sorted slots, conforming where the stored
    /// order is arrival order (an unsorted A-buffer, a linked list), which must stay equal.
    Swap,
    /// The A-buffer's counter one more than the pixel's fragments (the pool counter of a list).
    CounterPlusOne,
}

const KINDS: [Kind; 5] = [
    Kind::Drop,
    Kind::Empty,
    Kind::Duplicate,
    Kind::Swap,
    Kind::CounterPlusOne,
];

fn u64s(dump: &Dump, name: &str) -> Vec<u64> {
    match &dump.arrays[name] {
        Words::U64(w) => w.clone(),
        Words::U32(w) => w.iter().map(|&x| u64::from(x)).collect(),
    }
}

fn set(dump: &mut Dump, name: &str, words: &[u64]) {
    let stored = match &dump.arrays[name] {
        Words::U64(_) => Words::U64(words.to_vec()),
        Words::U32(_) => Words::U32(words.iter().map(|&w| w as u32).collect()),
    };
    dump.arrays.insert(name.into(), stored);
}

/// `dump` with pixel `p`'s list changed as `kind`, and whether a conforming implementation could
/// store it so; `None` where the kind has no meaning for the layout or the pixel (a swap of a
/// pixel of one fragment).
fn mutant(dump: &Dump, p: usize, kind: Kind) -> Option<(Dump, bool)> {
    let mut conforming = false;
    let mut out = dump.clone();
    match dump.scheme().unwrap() {
        DumpScheme::Mdts { k, direction } => {
            let empty = match direction {
                Direction::Ascending => u64::MAX,
                Direction::Descending => 0,
            };
            mutate_slots(&mut out, "slots", p, k as usize, empty, kind)?;
        }
        DumpScheme::Mdts32 { k } => {
            mutate_slots(&mut out, "slots", p, k as usize, u64::from(u32::MAX), kind)?;
        }
        DumpScheme::ABufferFixed { capacity, .. } => {
            let mut counters = u64s(&out, "counters");
            let n = counters[p] as usize;
            if kind == Kind::CounterPlusOne {
                counters[p] += 1;
            } else {
                // Unsorted slots are in arrival order: a swap there is conforming.
                conforming = kind == Kind::Swap;
                let cut = mutate_slots(&mut out, "slots", p, capacity as usize, u64::MAX, kind)?;
                // The counter follows the fragments taken out; the oracle knows the pixel's.
                counters[p] = (n - cut) as u64;
            }
            set(&mut out, "counters", &counters);
        }
        DumpScheme::LinkedLists { spec, .. } => {
            let LayoutSpec::LinkedList {
                null, node_base, ..
            } = spec
            else {
                return None;
            };
            let (mut heads, mut next) = (u64s(&out, "heads"), u64s(&out, "next"));
            let mut nodes = u64s(&out, "nodes");
            let mut list = Vec::new();
            let mut link = heads[p];
            while link != u64::from(null) {
                list.push(link);
                link = next[(link - u64::from(node_base)) as usize];
            }
            let index = |n: u64| (n - u64::from(node_base)) as usize;
            match kind {
                Kind::Drop if !list.is_empty() => match list.len() {
                    1 => heads[p] = u64::from(null),
                    _ => next[index(list[0])] = next[index(list[1])],
                },
                Kind::Empty if !list.is_empty() => heads[p] = u64::from(null),
                Kind::Duplicate if list.len() >= 2 => nodes[index(list[1])] = nodes[index(list[0])],
                // A list holds its pixel's fragments in arrival order.
                Kind::Swap if list.len() >= 2 => {
                    nodes.swap(index(list[0]), index(list[1]));
                    conforming = true;
                }
                Kind::CounterPlusOne => {
                    let mut counter = u64s(&out, "counter");
                    if counter[0] as usize >= nodes.len() {
                        return None;
                    }
                    counter[0] += 1;
                    set(&mut out, "counter", &counter);
                }
                _ => return None,
            }
            set(&mut out, "heads", &heads);
            set(&mut out, "next", &next);
            set(&mut out, "nodes", &nodes);
        }
        _ => return None,
    }
    Some((out, conforming))
}

/// Breaks pixel `p`'s `k` slots (pixel-major, `empty` the empty word) as `kind`; returns how many
/// fragments it took out, `None` where the kind does not apply.
fn mutate_slots(
    dump: &mut Dump,
    name: &str,
    p: usize,
    k: usize,
    empty: u64,
    kind: Kind,
) -> Option<usize> {
    let mut slots = u64s(dump, name);
    let pixel = &mut slots[p * k..(p + 1) * k];
    let full = pixel.iter().take_while(|&&w| w != empty).count();
    let cut = match kind {
        Kind::Drop if full >= 1 => {
            pixel.copy_within(1..full, 0);
            pixel[full - 1] = empty;
            1
        }
        Kind::Empty if full >= 1 => {
            pixel[..full].fill(empty);
            full
        }
        Kind::Duplicate if full >= 2 => {
            pixel[1] = pixel[0];
            0
        }
        Kind::Swap if full >= 2 && pixel[0] != pixel[1] => {
            pixel.swap(0, 1);
            0
        }
        _ => return None,
    };
    set(dump, name, &slots);
    Some(cut)
}

#[test]
fn every_mutant_of_a_decided_pixel_is_different_and_every_conforming_change_equal() {
    with_view(|view, oracle: &Oracle| {
        let record = |scheme: DumpScheme| Dump::record(view, spec(), &scheme, "battery").unwrap();
        let layouts = [
            (
                "mdts",
                record(DumpScheme::Mdts {
                    k: 2,
                    direction: Direction::Ascending,
                }),
            ),
            (
                "mdts-desc",
                record(DumpScheme::Mdts {
                    k: 2,
                    direction: Direction::Descending,
                }),
            ),
            ("mdts32", record(DumpScheme::Mdts32 { k: 2 })),
            (
                "abuffer",
                record(DumpScheme::ABufferFixed {
                    capacity: oracle.max_depth_complexity(),
                    sorted: false,
                }),
            ),
            (
                "linked-list",
                record(DumpScheme::LinkedLists {
                    scheme: SchemeName::LinkedList,
                    k: 2,
                    // Room past the scene's fragments, for a counter one too many.
                    pool: oracle.fragments() as u32 + 8,
                    spec: LayoutSpec::FRAGSIM_LISTS,
                }),
            ),
        ];
        let options = CompareOptions {
            examples: 0,
            ..CompareOptions::default()
        };
        let mut table = Vec::new();
        let mut wrong = Vec::new();
        for (name, dump) in &layouts {
            let exact = dump.compare(oracle, &options).unwrap();
            let (within, _, _) = dump.compare_within(None, &options).unwrap();
            assert!(exact.is_equal() && within.is_equal(), "{name} itself");
            // Decided pixels of two fragments or more: no doubt, no tolerance, under f32.
            let decided: Vec<usize> = (0..oracle.pixels())
                .filter(|&p| oracle.pixel(p).len() >= 2 && within.verdicts[p] == 0)
                .collect();
            assert!(
                decided.len() > 100,
                "{name}: {} decided pixels",
                decided.len()
            );
            for (seed, kind) in KINDS.iter().enumerate() {
                let mut rng = SplitMix64::new(seed as u64);
                let (mut tried, mut right, mut conforming) = (0, 0, false);
                for _ in 0..MUTANTS {
                    let p = decided[(rng.next_u64() % decided.len() as u64) as usize];
                    let Some((changed, allowed)) = mutant(dump, p, *kind) else {
                        continue;
                    };
                    tried += 1;
                    conforming = allowed;
                    let exact = changed.compare(oracle, &options).unwrap();
                    let (within, _, _) = changed.compare_within(None, &options).unwrap();
                    // A conforming change is equal both ways, any other different both ways.
                    if exact.is_equal() == allowed && within.is_equal() == allowed {
                        right += 1;
                    } else {
                        wrong.push(format!(
                            "{name} {kind:?} pixel {p} (conforming: {allowed}): exact equal {}, \
                             f32 equal {}",
                            exact.is_equal(),
                            within.is_equal()
                        ));
                    }
                }
                if tried == 0 {
                    continue; // The kind has no meaning for the layout (an MDTS slot counter).
                }
                let verdict = if conforming { "kept equal" } else { "killed" };
                let kind = format!("{kind:?}");
                table.push(format!(
                    "{name:<12} {kind:<15} {verdict:<10} {right:>3} of {tried:>3}"
                ));
            }
        }
        println!("layout       kind            verdict    (exact and f32)");
        for row in &table {
            println!("{row}");
        }
        assert!(wrong.is_empty(), "misjudged changes: {wrong:#?}");
    });
}

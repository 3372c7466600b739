//! The mutation kinds: each a change to one pixel's stored list (or to a list's pool) that no
//! conforming implementation could make, or, for the conforming kinds, one that some could.

use fragsim::dump::{Dump, LayoutSpec, SlotOrder, Words};
use fragsim::oracle::precision::Possible;

use super::storage::{links, set, words, Item, Storage};
use crate::support::prim_of;

/// A way to change a capture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// The fragment at this list position taken out, the rest kept in order.
    DropAt(usize),
    /// The last stored fragment taken out.
    DropLast,
    /// At a pixel of coplanar fragments (equal reference depths), one of the tied fragments taken
    /// out: a K-nearest list short of what every conforming list holds (the K-nearest excuse).
    DropTie,
    /// Every fragment of the pixel taken out.
    Empty,
    /// Every fragment of a pixel of coplanar fragments taken out.
    EmptyTie,
    /// The second fragment replaced by a copy of the first.
    Duplicate,
    /// The first two fragments swapped: an error in sorted layouts, arrival order elsewhere.
    Swap,
    /// The whole list reversed: an error in sorted layouts, arrival order elsewhere.
    Reverse,
    /// Two stored fragments of equal depth (coplanar duplicates) swapped: out of the (depth,
    /// id) order in sorted layouts, arrival order elsewhere.
    SwapTie,
    /// A fragment's primitive id replaced by a nearby triangle's that cannot cover the pixel.
    NeighbourId,
    /// A depth moved two steps past the interval the f32 analysis derives for it.
    DepthPast,
    /// The first stored depth moved two steps below its interval.
    DepthBelow,
    /// A depth moved to the end of its interval: conforming under f32 precision.
    DepthInside,
    /// A masked node's coverage mask with one sample more or less (never empty).
    MaskBit,
    /// The counter one more (a pixel's, or a list pool's).
    CounterPlusOne,
    /// The counter one less.
    CounterMinusOne,
    /// A linked list's node unlinked from the middle of its list (still handed out).
    Unlink,
    /// A linked list cut after its first node: the rest orphaned.
    Orphan,
    /// A linked list losing its farthest node, past the resolve's k.
    PastK,
    /// A 64-bit word torn: its high half written, its low half still the empty marker's.
    Torn,
    /// A fragment word written in the slot past the pixel's counter, with `filled`.
    Stray,
    /// A key-only word of a triangle at a shared edge replaced by a key of the triangle across
    /// the edge, which a conforming snap may give the pixel: conforming under f32 precision.
    EdgeKeySwap,
    /// Exact storage (`offsets`): the pixel's room cut by one and its last fragment dropped,
    /// its counter left at n.
    RoomCut,
    /// Exact storage: the pixel's room one more, an empty slot after its fragments, its
    /// counter left at n.
    RoomGrown,
    /// Exact storage: every offset 0 and nothing stored, the counters left as they were.
    NoRoom,
    /// A K-slot list holding the pixel's K nearest fragments.
    NearestK,
    /// A K-slot list holding the pixel's first K fragments in primitive order.
    FirstK,
    /// A K-slot list holding the pixel's last K fragments in primitive order.
    LastK,
    /// A linked list's node counter doubled.
    CounterDoubled,
    /// A linked list's node counter all ones.
    CounterAllOnes,
    /// 0xAB in the bits of the pixel's first stored payload word outside its declared fields
    /// (applied to the dump as encoded, [`outside_fields`]).
    OutsideBits,
}

pub(super) const KINDS: [Kind; 34] = [
    Kind::DropAt(0),
    Kind::DropAt(1),
    Kind::DropAt(2),
    Kind::DropLast,
    Kind::DropTie,
    Kind::Empty,
    Kind::EmptyTie,
    Kind::Duplicate,
    Kind::Swap,
    Kind::Reverse,
    Kind::SwapTie,
    Kind::NeighbourId,
    Kind::DepthPast,
    Kind::DepthBelow,
    Kind::DepthInside,
    Kind::MaskBit,
    Kind::CounterPlusOne,
    Kind::CounterMinusOne,
    Kind::Unlink,
    Kind::Orphan,
    Kind::PastK,
    Kind::Torn,
    Kind::Stray,
    Kind::EdgeKeySwap,
    Kind::DropAt(3),
    Kind::RoomCut,
    Kind::RoomGrown,
    Kind::NoRoom,
    Kind::NearestK,
    Kind::FirstK,
    Kind::LastK,
    Kind::CounterDoubled,
    Kind::CounterAllOnes,
    Kind::OutsideBits,
];

impl Kind {
    /// Its name in the table.
    pub(super) fn name(self) -> String {
        match self {
            Self::DropAt(i) => format!("drop@{i}"),
            other => {
                let debug = format!("{other:?}");
                let mut name = String::new();
                for (i, c) in debug.chars().enumerate() {
                    if c.is_uppercase() && i > 0 {
                        name.push('-');
                    }
                    name.push(c.to_ascii_lowercase());
                }
                name
            }
        }
    }

    /// The pixels it mutates.
    pub(super) fn pool(self) -> Pool {
        match self {
            Self::DropTie | Self::EmptyTie | Self::SwapTie => Pool::Tie,
            Self::EdgeKeySwap => Pool::Edge,
            _ => Pool::Clean,
        }
    }

    /// Whether it changes the whole dump rather than a pixel (a list pool's counter): tried once.
    pub(super) fn global(self, storage: &Storage) -> bool {
        let counter = matches!(
            self,
            Self::CounterPlusOne
                | Self::CounterMinusOne
                | Self::CounterDoubled
                | Self::CounterAllOnes
        );
        (matches!(storage, Storage::Lists) && counter) || self == Self::NoRoom
    }
}

/// Which pixels a kind mutates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Pool {
    /// Two fragments or more, every one certain, their depth intervals disjoint, decided by
    /// every judge.
    Clean,
    /// Two fragments or more of equal reference depth, every one certain.
    Tie,
    /// A key-only pixel whose fragment lies at an edge shared with a triangle that may cover it
    /// instead.
    Edge,
}

/// What a mutant is, for the judges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Change {
    /// No conforming implementation stores it: DIFFERENT under every judge.
    Broken,
    /// Another arrival order: EQUAL under every judge.
    Reordered,
    /// One fragment's depth moved: EQUAL exactly where the judge's interval holds it.
    Moved(Item),
    /// What only an f32 vertex stage may store (another triangle's key at a shared edge, a
    /// list counter one past a full pool): DIFFERENT bit for bit, EQUAL under f32.
    OtherSnap,
}

/// The pixel a mutant changes, and what the judges know of it.
pub(super) struct Site<'a> {
    pub(super) p: usize,
    /// The reference's fragments at the pixel, in canonical order.
    pub(super) reference: &'a [u64],
    /// What a conforming f32 implementation may store there (`None`: judged exactly only).
    pub(super) possible: Option<&'a [Possible]>,
    /// The scene's triangles, by their vertices' ids.
    pub(super) triangles: &'a [[u32; 3]],
    /// Keys of the f32 analysis, as the layout stores depth: the next step past a key.
    pub(super) step: &'a dyn Fn(u32, i64) -> u32,
}

/// `dump` (fragsim's own encoding) with the site's pixel changed as `kind`, and what the change
/// is; `None` where the kind has no meaning for the layout or the pixel.
pub(super) fn mutant(
    dump: &Dump,
    storage: &Storage,
    site: &Site<'_>,
    kind: Kind,
) -> Option<(Dump, Change)> {
    let p = site.p;
    let mut out = dump.clone();
    let list = storage.read(dump, p);
    let n = list.len();
    let mut items = list.clone();
    let unsorted = if storage.sorted() {
        Change::Broken
    } else {
        Change::Reordered
    };
    let change = match kind {
        Kind::DropAt(i) if i < n => {
            items.remove(i);
            Change::Broken
        }
        Kind::DropLast | Kind::DropTie if n >= 1 => {
            // At a tie pixel the last stored fragment of a K-nearest list is one of the tied ones
            // or nearer than them: either way the list is short.
            items.pop();
            Change::Broken
        }
        Kind::Empty | Kind::EmptyTie if n >= 1 => {
            items.clear();
            Change::Broken
        }
        Kind::Duplicate if n >= 2 && items[0] != items[1] => {
            items[1] = items[0];
            Change::Broken
        }
        Kind::Swap if n >= 2 && items[0] != items[1] => {
            items.swap(0, 1);
            unsorted
        }
        Kind::Reverse if n >= 2 => {
            items.reverse();
            if items == list {
                return None;
            }
            unsorted
        }
        Kind::SwapTie => {
            // Key-only words of equal depth are the same word: nothing to swap.
            let i = (1..n)
                .find(|&i| items[i - 1].key() == items[i].key() && items[i - 1] != items[i])?;
            items.swap(i - 1, i);
            unsorted
        }
        Kind::NeighbourId if storage.has_ids() && n >= 1 => {
            let item = items[0];
            let taken = |prim: u32| {
                site.reference.iter().any(|&r| prim_of(r) == prim)
                    || site
                        .possible
                        .is_some_and(|ps| ps.iter().any(|e| e.prim == prim))
            };
            let count = u32::try_from(site.triangles.len()).expect("a test scene's triangles");
            let prim = (1..count)
                .flat_map(|d| [item.prim().wrapping_add(d), item.prim().wrapping_sub(d)])
                .find(|&q| q < count && !taken(q))?;
            items[0].word = item.word & !0xFFFF_FFFF | u64::from(prim);
            Change::Broken
        }
        Kind::DepthPast if n >= 1 => {
            let i = n - 1;
            let (_, hi) = interval(site, storage, items[i])?;
            items[i] = items[i].with_key((site.step)(hi, 2));
            Change::Broken
        }
        Kind::DepthBelow if n >= 1 => {
            let (lo, _) = interval(site, storage, items[0])?;
            let below = (site.step)(lo, -2);
            if below >= lo {
                return None;
            }
            items[0] = items[0].with_key(below);
            Change::Broken
        }
        Kind::MaskBit => {
            let Storage::Masked { samples, .. } = storage else {
                return None;
            };
            let all = (1_u32 << samples) - 1;
            let mask = items.first()?.mask;
            // A sample added where one is free, else one taken away.
            items[0].mask = if mask == all {
                mask & (mask - 1)
            } else {
                mask | (!mask & all) & (!mask & all).wrapping_neg()
            };
            Change::Broken
        }
        Kind::DepthInside if n >= 1 => {
            let i = n - 1;
            let (lo, hi) = interval(site, storage, items[i])?;
            let key = [hi, lo].into_iter().find(|&k| k != items[i].key())?;
            items[i] = items[i].with_key(key);
            Change::Moved(items[i])
        }
        Kind::Torn if storage.has_ids() && n >= 1 => {
            items[0].word |= 0xFFFF_FFFF;
            Change::Broken
        }
        Kind::EdgeKeySwap if !storage.has_ids() => {
            let (i, key) = edge_key(site, &items)?;
            items[i] = items[i].with_key(key);
            items.sort_unstable_by_key(|item| item.word);
            Change::OtherSnap
        }
        Kind::CounterPlusOne
        | Kind::CounterMinusOne
        | Kind::Stray
        | Kind::CounterDoubled
        | Kind::CounterAllOnes => {
            // One more at a full pool: an f32 vertex stage may produce one fragment more than
            // the exact one (a fragment in doubt), dropped past the pool's end.
            let full = matches!(storage, Storage::Lists)
                && words(&out, "counter")[0] >= words(&out, "nodes").len() as u64;
            let change = if full && kind == Kind::CounterPlusOne {
                Change::OtherSnap
            } else {
                Change::Broken
            };
            return counted(&mut out, storage, p, kind, &list).map(|()| (out, change));
        }
        Kind::RoomCut | Kind::RoomGrown | Kind::NoRoom => {
            return roomed(&mut out, storage, p, kind).map(|()| (out, Change::Broken));
        }
        Kind::NearestK | Kind::FirstK | Kind::LastK => {
            let Storage::Slots { k, .. } = *storage else {
                return None;
            };
            let mut all: Vec<Item> = site
                .reference
                .iter()
                .map(|&word| Item { word, mask: 0 })
                .collect();
            match kind {
                Kind::NearestK => {}
                Kind::FirstK => all.sort_by_key(|item| item.prim()),
                _ => all.sort_by_key(|item| std::cmp::Reverse(item.prim())),
            }
            all.truncate(k);
            all.sort_by_key(|item| item.word);
            if !storage.has_ids() || all == list {
                return None;
            }
            items = all;
            Change::Broken
        }
        // Applied to the dump as encoded (`outside_fields`): here it only says where.
        Kind::OutsideBits if n >= 1 => Change::Broken,
        Kind::Unlink | Kind::Orphan | Kind::PastK if matches!(storage, Storage::Lists) => {
            return unlinked(&mut out, p, kind, &list).map(|()| (out, Change::Broken));
        }
        _ => return None,
    };
    storage.write(&mut out, p, &items);
    Some((out, change))
}

/// The f32 analysis's interval of the stored fragment `item` (matched by key where the words
/// carry none, by primitive id otherwise); judged exactly only, the reference's key.
fn interval(site: &Site<'_>, storage: &Storage, item: Item) -> Option<(u32, u32)> {
    let Some(possible) = site.possible else {
        let key = site
            .reference
            .iter()
            .find(|&&r| prim_of(r) == item.prim())?
            >> 32;
        return Some((key as u32, key as u32));
    };
    let entry = if storage.has_ids() {
        possible.iter().find(|e| e.prim == item.prim())?
    } else {
        possible
            .iter()
            .find(|e| (e.key_lo..=e.key_hi).contains(&item.key()))?
    };
    Some((entry.key_lo, entry.key_hi))
}

/// A stored fragment whose coverage the snaps decide, and a key of the triangle across a shared
/// edge that may cover the pixel instead (the middle of its interval, outside the stored one's).
pub(super) fn edge_key(site: &Site<'_>, items: &[Item]) -> Option<(usize, u32)> {
    let possible = site.possible?;
    let shared = |a: u32, b: u32| {
        let (a, b) = (site.triangles[a as usize], site.triangles[b as usize]);
        a.iter().filter(|v| b.contains(v)).count() == 2
    };
    possible
        .iter()
        .filter(|e| !e.certain() && e.reference.is_some())
        .find_map(|present| {
            let i = items
                .iter()
                .position(|item| Some(item.key()) == present.reference)?;
            let across = possible
                .iter()
                .find(|e| e.reference.is_none() && !e.certain() && shared(e.prim, present.prim))?;
            let key = across.key_lo + (across.key_hi - across.key_lo) / 2;
            let outside = !(present.key_lo..=present.key_hi).contains(&key);
            outside.then_some((i, key))
        })
}

/// The counter kinds, and a stray word past the counter.
fn counted(out: &mut Dump, storage: &Storage, p: usize, kind: Kind, list: &[Item]) -> Option<()> {
    let (name, room) = match storage {
        Storage::ABuffer { ranges, .. } => ("counters", ranges[p].1 > list.len()),
        Storage::Masked { capacity, .. } => ("counters", *capacity > list.len()),
        Storage::Layers { k, .. } => ("counters", *k > list.len()),
        Storage::Lists => (
            "counter",
            words(out, "counter")[0] < words(out, "nodes").len() as u64,
        ),
        Storage::Slots { .. } => return None,
    };
    let at = if matches!(storage, Storage::Lists) {
        0
    } else {
        p
    };
    let mut counters = words(out, name);
    let lists = matches!(storage, Storage::Lists);
    match kind {
        // A list counter counts every allocation, past the pool's end too: one more is wrong
        // at a full pool as at a larger one.
        Kind::CounterPlusOne => counters[at] += 1,
        Kind::CounterMinusOne if counters[at] > 0 => counters[at] -= 1,
        Kind::CounterDoubled if lists && counters[at] > 0 => counters[at] *= 2,
        Kind::CounterAllOnes if lists => counters[at] = u64::from(u32::MAX),
        Kind::Stray if room && out.header.filled && !list.is_empty() => {
            // A word where the empty marker must be, the counter unchanged.
            let mut stored = list.to_vec();
            stored.push(list[0]);
            let count = words(out, name)[at];
            storage.write(out, p, &stored);
            set(out, name, &{
                let mut back = words(out, name);
                back[at] = count;
                back
            });
            return Some(());
        }
        _ => return None,
    }
    set(out, name, &counters);
    Some(())
}

/// A linked list's links cut: a node unlinked from the middle, the tail after the head orphaned,
/// or the farthest node past the resolve's k unlinked; the nodes stay handed out.
#[expect(
    clippy::cast_possible_truncation,
    reason = "links are words of a u32 array read widened by `words`, so they fit usize"
)]
fn unlinked(out: &mut Dump, p: usize, kind: Kind, list: &[Item]) -> Option<()> {
    let (mut heads, mut next) = (words(out, "heads"), words(out, "next"));
    let chain = links(&heads, &next, p);
    let n = chain.len();
    let cut = match kind {
        Kind::Unlink if n >= 3 => n / 2,
        Kind::Orphan if n >= 2 => {
            next[chain[0] as usize - 1] = 0;
            set(out, "next", &next);
            return Some(());
        }
        // The farthest node, in a list longer than the two the battery's resolve keeps.
        Kind::PastK if n > 2 => (0..n).max_by_key(|&i| list[i].word)?,
        _ => return None,
    };
    let after = next[chain[cut] as usize - 1];
    match cut {
        0 => heads[p] = after,
        i => next[chain[i - 1] as usize - 1] = after,
    }
    set(out, "heads", &heads);
    set(out, "next", &next);
    Some(())
}

/// The room exact storage (`offsets`) gives: pixel `p`'s cut by one (its last fragment
/// dropped) or grown by one (an empty slot), or every pixel's taken away; the counters are
/// left as they were.
#[expect(
    clippy::cast_possible_truncation,
    reason = "offsets are words of a u32 array read widened by `words`, and only ever cut by one"
)]
fn roomed(out: &mut Dump, storage: &Storage, p: usize, kind: Kind) -> Option<()> {
    if !matches!(storage, Storage::ABuffer { .. }) || !out.arrays.contains_key("offsets") {
        return None;
    }
    let (mut offsets, mut slots) = (words(out, "offsets"), words(out, "slots"));
    let end = offsets[p + 1] as usize;
    match kind {
        Kind::RoomCut if end > offsets[p] as usize => {
            slots.remove(end - 1);
            offsets[p + 1..].iter_mut().for_each(|o| *o -= 1);
        }
        Kind::RoomGrown => {
            slots.insert(end, u64::MAX);
            offsets[p + 1..].iter_mut().for_each(|o| *o += 1);
        }
        Kind::NoRoom => {
            slots.clear();
            offsets.fill(0);
        }
        _ => return None,
    }
    let total = slots.len() as u64;
    let shape = vec![offsets.len() as u64];
    out.set_array(
        "offsets",
        Words::U32(offsets.iter().map(|&o| o as u32).collect()),
        shape,
    );
    out.set_array("slots", Words::U64(slots), vec![total]);
    Some(())
}

/// `encoded` (a mutant as its layout stores it) with 0xAB in the bits outside its payload's
/// fields of pixel `p`'s first stored word; `None` where the layout declares no payload or its
/// fields fill the word.
pub(super) fn outside_fields(encoded: &mut Dump, p: usize) -> Option<()> {
    let (array, at) = match encoded.header.layout? {
        LayoutSpec::Slots {
            order: SlotOrder::PixelMajor,
            payload: Some(payload),
        } => {
            let k = encoded.header.k? as usize;
            ("slots", (payload, p * k))
        }
        LayoutSpec::LinkedList {
            payload,
            null,
            node_base,
        } => {
            let head = u32::try_from(words(encoded, "heads")[p]).expect("a u32 array's word");
            (head != null).then_some(())?;
            ("nodes", (payload, (head - node_base) as usize))
        }
        _ => return None,
    };
    let (payload, index) = at;
    let bits = |n: u32| if n >= 64 { u64::MAX } else { (1 << n) - 1 };
    let fields = bits(payload.prim_bits) | bits(payload.depth.bits()) << payload.depth_shift;
    let outside = bits(payload.dtype.bits()) & !fields;
    // 0xAB repeated over the spare bits.
    let stray = outside & 0xABAB_ABAB_ABAB_ABAB;
    let mut stored = words(encoded, array);
    if stray == 0 || stored[index] == bits(payload.dtype.bits()) {
        return None;
    }
    stored[index] |= stray;
    set(encoded, array, &stored);
    Some(())
}

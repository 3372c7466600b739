//! Each layout's per-pixel lists in fragsim's own encoding of its words, read and written back:
//! what the battery mutates before the dump is re-encoded in the layout under test
//! ([`Dump::in_layout`]).

use fragsim::dump::{Dump, DumpScheme, LayoutSpec, Words};

use crate::support::prim_of;

/// One stored entry: fragsim's fragment word (`key << 32 | prim`; a bare key's `key << 32`), and
/// a masked node's coverage mask (0 elsewhere).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Item {
    pub(super) word: u64,
    pub(super) mask: u32,
}

impl Item {
    pub(super) fn key(self) -> u32 {
        (self.word >> 32) as u32
    }

    pub(super) fn prim(self) -> u32 {
        prim_of(self.word)
    }

    pub(super) fn with_key(self, key: u32) -> Self {
        Self {
            word: u64::from(key) << 32 | (self.word & 0xFFFF_FFFF),
            ..self
        }
    }
}

/// How the slot words of a slot layout hold a fragment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum SlotWord {
    /// The fragment word; empty: all ones (`mdts`, the k-buffers).
    Fragment,
    /// The fragment word plus one; empty: 0 (`mdts-desc`).
    PlusOne,
    /// The bare depth key, u32; empty: all ones (`mdts32`).
    Key,
}

/// Where a layout keeps each pixel's list, in fragsim's own encoding.
#[derive(Clone, Debug)]
pub(super) enum Storage {
    /// `k` slots a pixel, sorted, full slots first (MDTS, the k-buffers).
    Slots { k: usize, word: SlotWord },
    /// Counters and slots, each pixel's slots at `ranges[p]` (fixed capacity or offsets), sorted
    /// in place where the header says so.
    ABuffer {
        ranges: Vec<(usize, usize)>,
        sorted: bool,
    },
    /// Linked lists, fragsim's numbering (link 0 ends a list, link `n` is node `n − 1`).
    Lists,
    /// Bevy's layers: `k` layers of `pixels` pixels, layer-major.
    Layers { k: usize, pixels: usize },
    /// The masked-node A-buffer: counters, nodes and masks, `capacity` slots a pixel of
    /// `samples` samples.
    Masked { capacity: usize, samples: u32 },
}

pub(super) fn words(dump: &Dump, name: &str) -> Vec<u64> {
    match &dump.arrays[name] {
        Words::U64(w) => w.clone(),
        Words::U32(w) => w.iter().map(|&x| u64::from(x)).collect(),
    }
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "a u32 array's words were read widened by `words`, so writing them back narrows \
              nothing"
)]
pub(super) fn set(dump: &mut Dump, name: &str, new: &[u64]) {
    let stored = match &dump.arrays[name] {
        Words::U64(_) => Words::U64(new.to_vec()),
        Words::U32(_) => Words::U32(new.iter().map(|&w| w as u32).collect()),
    };
    dump.arrays.insert(name.into(), stored);
}

/// The links of pixel `p`'s list in fragsim's numbering, head first.
#[expect(
    clippy::cast_possible_truncation,
    reason = "links are words of a u32 array, so they fit usize"
)]
pub(super) fn links(heads: &[u64], next: &[u64], p: usize) -> Vec<u64> {
    let mut list = Vec::new();
    let mut link = heads[p];
    while link != 0 {
        list.push(link);
        link = next[link as usize - 1];
    }
    list
}

impl Storage {
    /// The storage of a dump recorded in fragsim's own encoding.
    pub(super) fn of(dump: &Dump) -> Self {
        if dump.is_masked() {
            return Self::Masked {
                capacity: dump.header.capacity.unwrap() as usize,
                samples: dump.header.scene.conventions.samples,
            };
        }
        let pixels = dump.viewport().unwrap().pixels();
        match dump.scheme().unwrap() {
            DumpScheme::Mdts { k, direction } => Self::Slots {
                k: k as usize,
                word: match direction {
                    fragsim::dump::Direction::Ascending => SlotWord::Fragment,
                    fragsim::dump::Direction::Descending => SlotWord::PlusOne,
                },
            },
            DumpScheme::KBuffer { k, .. } => Self::Slots {
                k: k as usize,
                word: SlotWord::Fragment,
            },
            DumpScheme::Mdts32 { k } => Self::Slots {
                k: k as usize,
                word: SlotWord::Key,
            },
            DumpScheme::ABufferFixed { capacity, sorted } => {
                let c = capacity as usize;
                Self::ABuffer {
                    ranges: (0..pixels).map(|p| (p * c, c)).collect(),
                    sorted,
                }
            }
            DumpScheme::ABufferExact { counts, sorted } => {
                let mut first = 0;
                let ranges = counts
                    .iter()
                    .map(|&c| {
                        first += c as usize;
                        (first - c as usize, c as usize)
                    })
                    .collect();
                Self::ABuffer { ranges, sorted }
            }
            DumpScheme::LinkedLists { spec, .. } => {
                assert_eq!(
                    spec,
                    LayoutSpec::FRAGSIM_LISTS,
                    "mutated in fragsim's numbering"
                );
                Self::Lists
            }
            DumpScheme::LayerMajor { k, .. } => Self::Layers {
                k: k as usize,
                pixels,
            },
            DumpScheme::Memory { .. } => panic!("a scheme's memory has no lists"),
        }
    }

    /// Whether the stored order is the layout's sort order (not arrival order).
    pub(super) fn sorted(&self) -> bool {
        matches!(
            self,
            Self::Slots { .. } | Self::ABuffer { sorted: true, .. }
        )
    }

    /// Whether the words carry primitive ids.
    pub(super) fn has_ids(&self) -> bool {
        !matches!(
            self,
            Self::Slots {
                word: SlotWord::Key,
                ..
            }
        )
    }

    /// Pixel `p`'s stored list, in stored order.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "counters, links and masks are words of u32 arrays read widened by `words`, so \
                  they fit usize and u32"
    )]
    pub(super) fn read(&self, dump: &Dump, p: usize) -> Vec<Item> {
        let item = |word| Item { word, mask: 0 };
        match self {
            Self::Slots { k, word } => {
                let slots = words(dump, "slots");
                let (empty, decode): (u64, fn(u64) -> u64) = match word {
                    SlotWord::Fragment => (u64::MAX, |w| w),
                    SlotWord::PlusOne => (0, |w| w - 1),
                    SlotWord::Key => (u64::from(u32::MAX), |w| w << 32),
                };
                slots[p * k..(p + 1) * k]
                    .iter()
                    .take_while(|&&w| w != empty)
                    .map(|&w| item(decode(w)))
                    .collect()
            }
            Self::ABuffer { ranges, .. } => {
                let (counters, slots) = (words(dump, "counters"), words(dump, "slots"));
                let (first, capacity) = ranges[p];
                let stored = (counters[p] as usize).min(capacity);
                slots[first..first + stored]
                    .iter()
                    .map(|&w| item(w))
                    .collect()
            }
            Self::Lists => {
                let (heads, next) = (words(dump, "heads"), words(dump, "next"));
                let nodes = words(dump, "nodes");
                links(&heads, &next, p)
                    .iter()
                    .map(|&n| item(nodes[n as usize - 1]))
                    .collect()
            }
            Self::Layers { k, pixels } => {
                let (counters, layers) = (words(dump, "counters"), words(dump, "layers"));
                (0..(counters[p] as usize).min(*k))
                    .map(|l| item(layers[l * pixels + p]))
                    .collect()
            }
            Self::Masked { capacity, .. } => {
                let (counters, nodes) = (words(dump, "counters"), words(dump, "nodes"));
                let masks = words(dump, "masks");
                let stored = (counters[p] as usize).min(*capacity);
                (p * capacity..p * capacity + stored)
                    .map(|i| Item {
                        word: nodes[i],
                        mask: masks[i] as u32,
                    })
                    .collect()
            }
        }
    }

    /// Writes pixel `p`'s list as a run that stored `items` would: the slots after them empty,
    /// a counter that counts them (plus any overflow it counted), a linked list through its
    /// first nodes (a shorter list leaves its last nodes handed out and unreached).
    #[expect(
        clippy::cast_possible_truncation,
        reason = "links are words of a u32 array read widened by `words`, so they fit usize"
    )]
    pub(super) fn write(&self, dump: &mut Dump, p: usize, items: &[Item]) {
        match self {
            Self::Slots { k, word } => {
                let mut slots = words(dump, "slots");
                let (empty, encode): (u64, fn(u64) -> u64) = match word {
                    SlotWord::Fragment => (u64::MAX, |w| w),
                    SlotWord::PlusOne => (0, |w| w.wrapping_add(1)),
                    SlotWord::Key => (u64::from(u32::MAX), |w| w >> 32),
                };
                for (s, slot) in slots[p * k..(p + 1) * k].iter_mut().enumerate() {
                    *slot = items.get(s).map_or(empty, |i| encode(i.word));
                }
                set(dump, "slots", &slots);
            }
            Self::ABuffer { ranges, .. } => {
                let (mut counters, mut slots) = (words(dump, "counters"), words(dump, "slots"));
                let (first, capacity) = ranges[p];
                let overflow = counters[p].saturating_sub(capacity as u64);
                for s in 0..capacity {
                    slots[first + s] = items.get(s).map_or(u64::MAX, |i| i.word);
                }
                counters[p] = items.len() as u64 + overflow;
                set(dump, "counters", &counters);
                set(dump, "slots", &slots);
            }
            Self::Lists => {
                let (mut heads, mut next) = (words(dump, "heads"), words(dump, "next"));
                let mut nodes = words(dump, "nodes");
                let list = links(&heads, &next, p);
                assert!(items.len() <= list.len(), "a list only shortens");
                for (item, &n) in items.iter().zip(&list) {
                    nodes[n as usize - 1] = item.word;
                }
                match items.len() {
                    0 => heads[p] = 0,
                    m => next[list[m - 1] as usize - 1] = 0,
                }
                set(dump, "heads", &heads);
                set(dump, "next", &next);
                set(dump, "nodes", &nodes);
            }
            Self::Layers { k, pixels } => {
                let (mut counters, mut layers) = (words(dump, "counters"), words(dump, "layers"));
                for (l, item) in items.iter().enumerate().take(*k) {
                    layers[l * pixels + p] = item.word;
                }
                counters[p] = items.len() as u64;
                set(dump, "counters", &counters);
                set(dump, "layers", &layers);
            }
            Self::Masked { capacity, .. } => {
                let (mut counters, mut nodes) = (words(dump, "counters"), words(dump, "nodes"));
                let mut masks = words(dump, "masks");
                let overflow = counters[p].saturating_sub(*capacity as u64);
                for s in 0..*capacity {
                    let i = p * capacity + s;
                    (nodes[i], masks[i]) = items
                        .get(s)
                        .map_or((u64::MAX, 0), |item| (item.word, u64::from(item.mask)));
                }
                counters[p] = items.len() as u64 + overflow;
                set(dump, "counters", &counters);
                set(dump, "nodes", &nodes);
                set(dump, "masks", &masks);
            }
        }
    }
}

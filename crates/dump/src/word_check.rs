//! The rules every word of a dump's layout obeys, checked word by word ([`Dump::check_words`]):
//! what the decoded lists cannot show, each corrupt word named with its reason ([`Corruption`]),
//! an A-buffer's counters beside their capacities.

use crate::layouts::Direction;
use fragsim_catalog::SchemeName;
use serde::Serialize;

use crate::layouts::DumpScheme;
use crate::spec::{Payload, LARGEST_KEY};
use crate::{Dump, DumpError};

/// Why a stored word is one that its layout says cannot be there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Corruption {
    /// An MDTS slot after the pixel's first empty one holds a word: MDTS fills a pixel's slots
    /// from the first, each insertion shifting the larger words one slot on, so an empty slot is
    /// never followed by a full one (a stray write, a neighbouring pixel's overrun).
    AfterEmpty,
    /// An A-buffer slot below its pixel's counter holds the empty marker: a slot handed out by
    /// the counter whose write never landed (or was overwritten with the marker).
    EmptyCounted,
    /// An A-buffer slot past its pixel's counter holds something other than the empty marker,
    /// in a dump whose header says every slot was filled with it (`"filled": true`).
    BeyondCounter,
    /// A stored word whose depth key is above 1.0's: no fragment has such a key.
    ImpossibleKey,
    /// A linked-list link (a head or a `next`) to a node number outside the pool.
    OutOfPool,
    /// A linked-list link to a node of the pool that the counter never handed out.
    Unallocated,
    /// A linked-list link to a node already reached: a cycle, or two lists sharing a node. The
    /// walk stops there, so a cycle costs one visit per node.
    Revisited,
    /// A counter above the layers it counts, which no run leaves (Bevy's clamp stores the layer
    /// count back over any counter that passed it).
    CounterPastStorage,
    /// A masked node's coverage mask (below its pixel's counter) that is empty or holds a bit
    /// at or past the sample count: a node is stored for at least one covered sample.
    ImpossibleMask,
    /// Exact storage (an A-buffer with `offsets`) whose room for the pixel is not its counter:
    /// the counting pass and the storing pass see the same fragments, so the prefix sum gives
    /// each pixel room for exactly the fragments its counter counts. The word is the room.
    RoomNotCount,
    /// A payload word read as a fragment with a bit set outside its declared depth and id
    /// fields: those bits are never written, so they hold 0.
    OutsideFields,
}

impl Corruption {
    /// A short description for reports.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Self::AfterEmpty => "written after an empty slot",
            Self::EmptyCounted => "empty marker in a counted slot",
            Self::BeyondCounter => "written past the counter",
            Self::ImpossibleKey => "depth key above 1.0",
            Self::OutOfPool => "link out of the node pool",
            Self::Unallocated => "link to a node never allocated",
            Self::Revisited => "link to a node already in a list (a cycle)",
            Self::CounterPastStorage => "counter past its storage",
            Self::ImpossibleMask => "coverage mask empty or past the sample count",
            Self::RoomNotCount => "exact storage's room other than the pixel's counter",
            Self::OutsideFields => "a bit set outside the payload's fields",
        }
    }
}

/// One stored word that its layout says cannot be there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct CorruptWord {
    /// Row-major pixel index.
    pub pixel: usize,
    /// The slot within the pixel (`0..k`, `0..capacity`).
    pub slot: usize,
    /// The word as stored (a u32 word zero-extended).
    pub word: u64,
    /// What is wrong with it.
    pub why: Corruption,
}

/// An A-buffer pixel's counter and the capacity its declared scheme owes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counter {
    /// The counter's value: how many fragments took a slot number.
    pub count: u32,
    /// The fragments the pixel's storage must hold before any may overflow: the header's fixed
    /// capacity, or `u32::MAX` for exact storage, which is sized to hold every fragment (the
    /// room its `offsets` give is a word checked against the counter, never an allowance).
    pub capacity: u32,
}

/// Every word of a dump checked against its layout ([`Dump::check_words`]): what the decoded
/// lists cannot show, since decoding stops where the layout says a pixel's list ends.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WordCheck {
    /// Per pixel, its words that the layout says cannot be there (most pixels: none).
    pub corrupt: Vec<Vec<CorruptWord>>,
    /// A-buffer dumps: each pixel's counter and capacity, for the comparison to check the
    /// counter against the pixel's fragment count.
    pub counters: Option<Vec<Counter>>,
    /// Words a header could have defined but did not, so not checked: an A-buffer's (or a
    /// masked-node A-buffer's) slots past the counter when the header does not say they were
    /// filled with the empty marker (`"filled": true`), every word of a memory dump (its
    /// scheme's memory has no rules here). A dump with any is at best `EQUAL (lists
    /// bit-identical)`.
    pub unchecked: u64,
    /// Words of room that no counter handed out and that no header field defines, so not read: a
    /// linked list's pool nodes past the node counter (a `next` and a payload each), a
    /// layer-major dump's layers past a pixel's counter. No list holds them (a link to such a
    /// node is corrupt), so leaving them unread hides no fragment and no stray link: they do not
    /// keep a dump from being bit-identical.
    pub spare: u64,
    /// Linked lists: nodes the counter handed out that no list reaches (a lost node; its
    /// fragment is missing from the lists, which the comparison counts).
    pub unreachable: u64,
    /// Linked lists: the node counter as stored, which the comparison checks against the
    /// fragments the reference owes (it counts every allocation, past the pool's end too).
    pub list_counter: Option<u32>,
    /// Schemes that keep each pixel's first K fragments in primitive order
    /// (`kbuffer-interlock-ordered-first`): K, for the comparison to check that the fragments
    /// kept are those, not any K.
    pub first_in_primitive_order: Option<u32>,
}

impl WordCheck {
    /// How many words are corrupt.
    #[must_use]
    pub fn corrupt_words(&self) -> u64 {
        self.corrupt.iter().map(|c| c.len() as u64).sum()
    }

    /// Records `word` in `slot` of pixel `pixel` as corrupt, when a rule gave a reason.
    pub(super) fn flag(&mut self, pixel: usize, slot: usize, word: u64, why: Option<Corruption>) {
        if let Some(why) = why {
            self.corrupt[pixel].push(CorruptWord {
                pixel,
                slot,
                word,
                why,
            });
        }
    }
}

impl Dump {
    /// Reads every word of the dump and names each one that its layout says cannot be there
    /// (see [`Corruption`]); for an A-buffer, also gives each pixel's counter. Needs no
    /// reference: it is the layout's own rules.
    ///
    /// # Errors
    /// As [`Dump::capture`]: an unknown scheme, or arrays missing or of the wrong size or type.
    pub fn check_words(&self) -> Result<WordCheck, DumpError> {
        if self.is_masked() {
            return self.check_masked_words();
        }
        let scheme = self.scheme()?;
        self.check_shapes(&scheme)?;
        // A slot layout of the engine's: the rules hold of fragsim's encoding of its words,
        // each corrupt word named as stored.
        if let Some(own) = self.own_slots(&scheme)? {
            let mut check = own.check_words()?;
            self.name_stored_words(&scheme, &mut check)?;
            self.flag_bits_outside_fields(&scheme, &mut check)?;
            return Ok(check);
        }
        // Decoding validates the arrays against the scheme's layout; the check then indexes them
        // freely.
        self.capture()?;
        let pixels = self.viewport()?.pixels();
        let mut check = WordCheck {
            corrupt: vec![Vec::new(); pixels],
            ..WordCheck::default()
        };
        let missing = |n: &str| DumpError::Invalid(format!("missing array {n:?}"));
        match &scheme {
            DumpScheme::Mdts { k, .. } | DumpScheme::KBuffer { k, .. } => {
                let slots = self.u64s("slots")?.ok_or_else(|| missing("slots"))?;
                // A k-buffer's slots obey MDTS's rules: every write-back leaves them sorted, full
                // slots first, so a gap is a hazard's (or a stray write's).
                let direction = match &scheme {
                    DumpScheme::Mdts { direction, .. } => *direction,
                    _ => Direction::Ascending,
                };
                let (empty, key): (u64, fn(u64) -> u32) = match direction {
                    Direction::Ascending => (u64::MAX, |w| (w >> 32) as u32),
                    Direction::Descending => (0, |w| (w.wrapping_sub(1) >> 32) as u32),
                };
                check_mdts(&mut check, slots, *k as usize, empty, key);
                if let DumpScheme::KBuffer {
                    scheme: SchemeName::KbufferInterlockOrderedFirst,
                    k: first_k,
                } = &scheme
                {
                    check.first_in_primitive_order = Some(*first_k);
                }
            }
            DumpScheme::Mdts32 { k } => {
                let slots = self.u32s("slots")?.ok_or_else(|| missing("slots"))?;
                let wide: Vec<u64> = slots.iter().map(|&w| u64::from(w)).collect();
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "the wide words came from u32 slots"
                )]
                check_mdts(&mut check, &wide, *k as usize, u64::from(u32::MAX), |w| {
                    w as u32
                });
            }
            DumpScheme::ABufferFixed { .. } | DumpScheme::ABufferExact { .. } => {
                let counters = self.u32s("counters")?.ok_or_else(|| missing("counters"))?;
                let slots = self.u64s("slots")?.ok_or_else(|| missing("slots"))?;
                let at = scheme.pixel_slots();
                let exact = matches!(scheme, DumpScheme::ABufferExact { .. });
                let mut all = Vec::with_capacity(pixels);
                for (p, &count) in counters.iter().enumerate() {
                    let (first, capacity) = at(p);
                    // Exact storage holds every fragment: its room is owed, not allowed.
                    if exact && count as usize != capacity {
                        check.flag(p, 0, capacity as u64, Some(Corruption::RoomNotCount));
                    }
                    let stored = (count as usize).min(capacity);
                    for (slot, &word) in slots[first..first + capacity].iter().enumerate() {
                        let why = if slot < stored {
                            if word == u64::MAX {
                                Some(Corruption::EmptyCounted)
                            } else {
                                ((word >> 32) as u32 > LARGEST_KEY)
                                    .then_some(Corruption::ImpossibleKey)
                            }
                        } else if self.header.filled {
                            (word != u64::MAX).then_some(Corruption::BeyondCounter)
                        } else {
                            check.unchecked += 1;
                            None
                        };
                        check.flag(p, slot, word, why);
                    }
                    #[expect(
                        clippy::cast_possible_truncation,
                        reason = "a fixed A-buffer's capacity is a u32 (DumpScheme::ABufferFixed); exact storage's is its counter, a u32"
                    )]
                    all.push(Counter {
                        count,
                        capacity: if exact { u32::MAX } else { capacity as u32 },
                    });
                }
                check.counters = Some(all);
            }
            DumpScheme::LinkedLists { .. } | DumpScheme::LayerMajor { .. } => {
                let translated = self.translate(&scheme)?;
                check.corrupt = translated.corrupt;
                check.spare = translated.spare;
                check.unreachable = translated.unreachable;
                if matches!(scheme, DumpScheme::LinkedLists { .. }) {
                    check.list_counter = translated.words32.get(pixels).copied();
                }
            }
            DumpScheme::Memory { .. } => {
                check.unchecked = self.arrays.values().map(|w| w.len() as u64).sum();
            }
        }
        Ok(check)
    }
}

/// The MDTS rules over `k` slots a pixel: full slots first, each holding a possible key, then
/// only empty ones.
fn check_mdts(check: &mut WordCheck, slots: &[u64], k: usize, empty: u64, key: fn(u64) -> u32) {
    for (p, words) in slots.chunks_exact(k).enumerate() {
        let mut seen_empty = false;
        for (slot, &word) in words.iter().enumerate() {
            let why = if word == empty {
                seen_empty = true;
                None
            } else if seen_empty {
                Some(Corruption::AfterEmpty)
            } else {
                (key(word) > LARGEST_KEY).then_some(Corruption::ImpossibleKey)
            };
            check.flag(p, slot, word, why);
        }
    }
}

/// The bits of a `payload` word outside its depth and id fields: never written by a shader that
/// packs the two fields, so a word read as a fragment holds 0 there.
pub(super) fn outside_fields(payload: &Payload) -> u64 {
    let bits = |n: u32| if n >= 64 { u64::MAX } else { (1 << n) - 1 };
    let fields = bits(payload.prim_bits) | bits(payload.depth.bits()) << payload.depth_shift;
    bits(payload.dtype.bits()) & !fields
}

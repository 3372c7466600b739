//! Slot dumps (`mdts`, `mdts32`, `mdts-desc`, `abuffer`, the k-buffers) in an engine's layout
//! ([`LayoutSpec::Slots`]): the `slots` array slot-major or pixel-major, each word packed as the
//! header's payload. Reading turns them into fragsim's own encoding (pixel-major, fragsim's
//! words) before the scheme's resolve and word rules run, so every rule holds of either; writing
//! does the reverse for `render --dump`.
//!
//! The translation maps the layout's empty marker to fragsim's and every other word to a word
//! that is not empty, so the rules read the same on both sides: fragsim's words only move and
//! change encoding. The array is checked to hold exactly the slots the scheme has before any
//! index is taken, so a header cannot make the reader index past it or allocate more than it
//! holds.

use crate::layouts::Direction;
use crate::spec::{LayoutSpec, Payload, SlotOrder};
use crate::word_check::{outside_fields, Corruption, WordCheck};
use crate::{err, Dtype, Dump, DumpError, DumpScheme, Words};

/// How one slot word of a layout maps to fragsim's.
#[derive(Clone, Copy, Debug)]
pub(super) struct SlotCodec {
    /// The payload (`None`: fragsim's own word, which only moves).
    payload: Option<Payload>,
    /// `mdts-desc`: the word is the payload plus one, and 0 is empty.
    plus_one: bool,
}

impl SlotCodec {
    fn new(scheme: &DumpScheme, payload: Option<Payload>) -> Self {
        Self {
            payload,
            plus_one: matches!(
                scheme,
                DumpScheme::Mdts {
                    direction: Direction::Descending,
                    ..
                }
            ),
        }
    }

    /// The codec of a plain slot word (no plus one) packed as `payload` (`None`: fragsim's).
    pub(super) fn plain(payload: Option<Payload>) -> Self {
        Self {
            payload,
            plus_one: false,
        }
    }

    /// fragsim's word for a stored word.
    pub(super) fn own(self, stored: u64) -> u64 {
        let Some(payload) = self.payload else {
            return stored;
        };
        if self.plus_one {
            if stored == 0 {
                0
            } else {
                payload.fragment(stored - 1).0 + 1
            }
        } else if stored == all_ones(payload.dtype) {
            u64::MAX
        } else {
            payload.fragment(stored).0
        }
    }

    /// The stored word for fragsim's word.
    pub(super) fn stored(self, own: u64) -> Result<u64, DumpError> {
        let Some(payload) = self.payload else {
            return Ok(own);
        };
        if !self.plus_one {
            return payload.pack(own);
        }
        if own == 0 {
            return Ok(0);
        }
        let packed = payload.pack(own - 1)?;
        if packed == all_ones(payload.dtype) {
            return err("payload: a word of all ones has no room for mdts-desc's plus one");
        }
        Ok(packed + 1)
    }
}

fn all_ones(dtype: Dtype) -> u64 {
    u64::MAX >> (64 - dtype.bits())
}

/// Where fragsim's pixel-major slot words lie in a dump's `slots` array.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placement {
    order: SlotOrder,
    pixels: usize,
    /// Slots per pixel (1 for exact storage, which is always pixel-major).
    slots: usize,
}

impl Placement {
    /// `slots` slots for each of `pixels` pixels, placed in `order`.
    pub(super) fn new(order: SlotOrder, pixels: usize, slots: usize) -> Self {
        Self {
            order,
            pixels,
            slots,
        }
    }

    /// The pixels.
    pub(super) fn pixels(self) -> usize {
        self.pixels
    }

    /// The `slots` index of fragsim's slot word `own`.
    pub(super) fn stored(self, own: usize) -> usize {
        self.order
            .index(own / self.slots, own % self.slots, self.pixels, self.slots)
    }
}

/// The slots per pixel of a slot scheme with fixed storage (`None`: exact storage).
fn fixed_slots(scheme: &DumpScheme) -> Option<u32> {
    match scheme {
        DumpScheme::Mdts { k, .. } | DumpScheme::Mdts32 { k } | DumpScheme::KBuffer { k, .. } => {
            Some(*k)
        }
        DumpScheme::ABufferFixed { capacity, .. } => Some(*capacity),
        _ => None,
    }
}

/// The dtype fragsim stores the scheme's slots in.
fn own_dtype(scheme: &DumpScheme) -> Dtype {
    match scheme {
        DumpScheme::Mdts32 { .. } => Dtype::U32,
        _ => Dtype::U64,
    }
}

impl Dump {
    /// The placement and codec of a slot dump whose header describes its slots, and how many
    /// slot words the scheme has (`None`: the header describes none).
    fn slot_layout(
        &self,
        scheme: &DumpScheme,
    ) -> Result<Option<(Placement, SlotCodec, usize)>, DumpError> {
        let Some(LayoutSpec::Slots { order, payload }) = self.header.layout else {
            return Ok(None);
        };
        let pixels = self.viewport()?.pixels();
        let (slots, total) = match (fixed_slots(scheme), scheme) {
            // At most 2^28 pixels of 2^32 slots: the product fits.
            (Some(slots), _) => (slots as usize, pixels as u64 * u64::from(slots)),
            (None, DumpScheme::ABufferExact { counts, .. }) => {
                (1, counts.iter().map(|&c| u64::from(c)).sum())
            }
            _ => return err(format!("{} dumps have no slots", scheme.name())),
        };
        let placement = Placement {
            order,
            pixels,
            slots,
        };
        self.check_slot_count(total)?;
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the total is the length of the \"slots\" array (check_slot_count), a usize"
        )]
        let total = total as usize;
        Ok(Some((placement, SlotCodec::new(scheme, payload), total)))
    }

    /// Refuses a `slots` array of other than `total` words.
    fn check_slot_count(&self, total: u64) -> Result<(), DumpError> {
        let len = self
            .arrays
            .get("slots")
            .map(Words::len)
            .ok_or_else(|| DumpError::Invalid("missing array \"slots\"".into()))?;
        if len as u64 == total {
            Ok(())
        } else {
            err(format!(
                "array \"slots\" has {len} words, the scheme's slots are {total}"
            ))
        }
    }

    /// This dump in fragsim's own slot encoding (pixel-major, fragsim's words), when its header
    /// describes another ([`LayoutSpec::Slots`]); `None` when it is in fragsim's already.
    ///
    /// # Errors
    /// A `slots` array of the wrong dtype (the payload's, or the scheme's own without one) or
    /// of other than the scheme's slot count.
    pub(super) fn own_slots(&self, scheme: &DumpScheme) -> Result<Option<Self>, DumpError> {
        let Some((placement, codec, total)) = self.slot_layout(scheme)? else {
            return Ok(None);
        };
        let dtype = codec.payload.map_or(own_dtype(scheme), |p| p.dtype);
        let stored = self.widened("slots", dtype)?;
        let own: Vec<u64> = (0..total)
            .map(|i| codec.own(stored[placement.stored(i)]))
            .collect();
        let mut dump = self.clone();
        dump.header.layout = None;
        // The words are now pixel-major: a slot-major `[k, pixels]` shape would read as the
        // transpose of fragsim's own, so the array is described flat, as it is held.
        if let Some(spec) = dump.header.arrays.get_mut("slots") {
            spec.shape = vec![own.len() as u64];
        }
        dump.arrays
            .insert("slots".into(), words_of(own_dtype(scheme), own));
        Ok(Some(dump))
    }

    /// Names each corrupt word of `check` (found in [`Dump::own_slots`]'s words) as this dump
    /// stores it: the word in its own encoding, zero-extended.
    pub(super) fn name_stored_words(
        &self,
        scheme: &DumpScheme,
        check: &mut WordCheck,
    ) -> Result<(), DumpError> {
        let Some((placement, codec, _)) = self.slot_layout(scheme)? else {
            return Ok(());
        };
        let stored = self.widened(
            "slots",
            codec.payload.map_or(own_dtype(scheme), |p| p.dtype),
        )?;
        let first_slot = scheme.pixel_slots();
        // Every other corrupt word of a slot layout is a slot word (counters are judged apart).
        let slot_words = check
            .corrupt
            .iter_mut()
            .flatten()
            .filter(|word| word.why != Corruption::RoomNotCount);
        for word in slot_words {
            if let Some(&at) = stored.get(placement.stored(first_slot(word.pixel).0 + word.slot)) {
                word.word = at;
            }
        }
        Ok(())
    }

    /// Names each slot word that is read as a fragment (below an A-buffer counter; any full
    /// MDTS or k-buffer slot) and has a bit set outside its payload's fields
    /// ([`Corruption::OutsideFields`]): the translation to fragsim's words drops those bits, so
    /// they are read here, as stored. A slot already named corrupt is not named twice.
    pub(super) fn flag_bits_outside_fields(
        &self,
        scheme: &DumpScheme,
        check: &mut WordCheck,
    ) -> Result<(), DumpError> {
        let Some((placement, codec, _)) = self.slot_layout(scheme)? else {
            return Ok(());
        };
        let Some(payload) = codec.payload else {
            return Ok(());
        };
        let outside = outside_fields(&payload);
        if outside == 0 {
            return Ok(());
        }
        let stored = self.widened("slots", payload.dtype)?;
        let counters = match scheme {
            DumpScheme::ABufferFixed { .. } | DumpScheme::ABufferExact { .. } => {
                self.u32s("counters")?
            }
            _ => None,
        };
        let empty = if codec.plus_one {
            0
        } else {
            all_ones(payload.dtype)
        };
        let at = scheme.pixel_slots();
        for p in 0..placement.pixels {
            let (first, room) = at(p);
            let read = counters.map_or(room, |c| room.min(c[p] as usize));
            for slot in 0..read {
                let word = stored[placement.stored(first + slot)];
                let fields = if codec.plus_one {
                    word.wrapping_sub(1)
                } else {
                    word
                };
                let named = check.corrupt[p]
                    .iter()
                    .any(|c| c.slot == slot && c.why != Corruption::RoomNotCount);
                if word != empty && fields & outside != 0 && !named {
                    check.flag(p, slot, word, Some(Corruption::OutsideFields));
                }
            }
        }
        Ok(())
    }

    /// This dump (in fragsim's own slot encoding, as [`Dump::record`] writes it) with its
    /// `slots` array placed in `order` and packed as `payload`.
    ///
    /// # Errors
    /// A primitive id that does not fit the payload, or a word it cannot hold.
    pub(super) fn slots_as(
        &self,
        scheme: &DumpScheme,
        order: SlotOrder,
        payload: Option<Payload>,
    ) -> Result<Self, DumpError> {
        let own = self.widened("slots", own_dtype(scheme))?;
        let codec = SlotCodec::new(scheme, payload);
        let placement = Placement {
            order,
            pixels: self.viewport()?.pixels(),
            slots: fixed_slots(scheme).map_or(1, |s| s as usize),
        };
        let mut stored = vec![0; own.len()];
        for (i, &word) in own.iter().enumerate() {
            stored[placement.stored(i)] = codec.stored(word)?;
        }
        let dtype = payload.map_or(own_dtype(scheme), |p| p.dtype);
        let shape = match (order, fixed_slots(scheme)) {
            (SlotOrder::SlotMajor, Some(slots)) => {
                vec![u64::from(slots), placement.pixels as u64]
            }
            _ => self.shape_of("slots"),
        };
        let mut dump = self.clone();
        dump.header.layout = Some(LayoutSpec::Slots { order, payload });
        if payload.is_some() {
            // The informative word is fragsim's; the payload describes this one.
            dump.header.word = String::new();
        }
        dump.set_array("slots", words_of(dtype, stored), shape);
        Ok(dump)
    }
}

/// Words of `dtype` (u32 words narrowed: they came from u32 words or a u32 payload).
#[expect(
    clippy::cast_possible_truncation,
    reason = "u32 words narrowed: they came from u32 words or a u32 payload"
)]
pub(super) fn words_of(dtype: Dtype, words: Vec<u64>) -> Words {
    match dtype {
        Dtype::U32 => Words::U32(words.into_iter().map(|w| w as u32).collect()),
        Dtype::U64 => Words::U64(words),
    }
}

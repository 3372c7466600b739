//! The `dump_layouts` target's slot layouts: an MDTS, A-buffer or k-buffer slot dump, slot-major
//! or pixel-major with any payload, and its model: the same words in fragsim's own encoding.

use fragsim::catalog::{DumpLayout, SchemeName, CATALOG};
use fragsim::dump::{Corruption, Dtype, Dump, Header, LayoutSpec, Payload, SlotOrder, Words};
use fragsim::raster::Viewport;

use super::super::input::Input;
use super::{k, length, outside_fields, payload, payload_word, payload_words, words_of, Model};

/// The slot schemes a slot dump may name, whether the A-buffer's storage is exact, and which
/// k-buffer's slots (under its own name: its promise and resolve).
#[derive(Clone, Copy, PartialEq, Eq)]
enum SlotScheme {
    Mdts,
    MdtsDesc,
    Mdts32,
    ABufferFixed,
    ABufferExact,
    KBuffer(SchemeName),
}

/// A slot dump (`mdts`, `mdts-desc`, `mdts32`, `abuffer`, a k-buffer) in a described layout (slot-major or
/// pixel-major, any payload) and its model: the same words in fragsim's own encoding, placed
/// pixel-major and decoded as the format says, read and checked by the reader's own-encoding
/// path. The described dump must decode and check the same, naming each corrupt word as stored.
pub(super) fn slots(
    input: &mut Input<'_>,
    header: &mut Header,
    viewport: Viewport,
    arrays: &mut Vec<(&'static str, Words)>,
) -> Result<Option<Model>, String> {
    let pixels = viewport.pixels();
    let kbuffers: Vec<SchemeName> = CATALOG
        .iter()
        .filter(|e| e.dump == Some(DumpLayout::KBufferSlots))
        .map(|e| e.scheme)
        .collect();
    let scheme = match input.u8() % 6 {
        0 => SlotScheme::Mdts,
        1 => SlotScheme::MdtsDesc,
        2 => SlotScheme::Mdts32,
        3 => SlotScheme::ABufferFixed,
        4 => SlotScheme::ABufferExact,
        _ => SlotScheme::KBuffer(kbuffers[usize::from(input.u8()) % kbuffers.len()]),
    };
    let order = if input.u8() & 1 != 0 {
        SlotOrder::SlotMajor
    } else {
        SlotOrder::PixelMajor
    };
    // One in three: the scheme's own word, no payload.
    let payload = match input.u8() % 3 {
        0 => None,
        _ => Some(payload(input)),
    };
    let k = k(input);
    let abuffer = matches!(scheme, SlotScheme::ABufferFixed | SlotScheme::ABufferExact);
    let counts: Vec<u32> = match scheme {
        SlotScheme::ABufferExact => (0..pixels).map(|_| u32::from(input.u8() % 4)).collect(),
        _ => vec![k; pixels],
    };
    // Faults 0: the slots one word off, 1: the slots in the other dtype; any other value: none.
    let fault = input.u8() % 8;
    let own_dtype = if scheme == SlotScheme::Mdts32 {
        Dtype::U32
    } else {
        Dtype::U64
    };
    let dtype = payload.map_or(own_dtype, |p| p.dtype);
    let all_ones = u64::MAX >> (64 - dtype.bits());
    let empty = if scheme == SlotScheme::MdtsDesc {
        0
    } else {
        all_ones
    };
    let word_payload = payload.unwrap_or(Payload::FRAGMENT);
    let total: usize = counts.iter().map(|&c| c as usize).sum();
    let stored: Vec<u64> = (0..length(total, fault, 0))
        .map(|_| match input.u8() % 4 {
            0 => empty,
            _ => {
                let word = payload_word(input, &word_payload);
                let word = match (scheme, payload) {
                    (SlotScheme::Mdts32, None) => word >> 32,
                    _ => word,
                };
                if scheme == SlotScheme::MdtsDesc {
                    word.wrapping_add(1) & all_ones
                } else {
                    word
                }
            }
        })
        .collect();
    let payload_dtype = Payload {
        dtype,
        ..word_payload
    };
    arrays.push((
        "slots",
        payload_words(stored.clone(), &payload_dtype, fault == 1),
    ));
    if abuffer {
        let counters = (0..pixels)
            .map(|p| match input.u8() {
                255 => u32::MAX,
                b => u32::from(b) % (counts[p] + 3),
            })
            .collect();
        arrays.push(("counters", Words::U32(counters)));
        header.filled = input.u8() & 1 != 0;
        header.sorted = input.u8() & 1 != 0;
    }
    let mut offsets = vec![0_u32];
    if scheme == SlotScheme::ABufferExact {
        for &c in &counts {
            offsets.push(offsets[offsets.len() - 1] + c);
        }
        arrays.push(("offsets", Words::U32(offsets.clone())));
    }
    header.scheme = match scheme {
        SlotScheme::Mdts => "mdts",
        SlotScheme::MdtsDesc => "mdts-desc",
        SlotScheme::Mdts32 => "mdts32",
        SlotScheme::ABufferFixed | SlotScheme::ABufferExact => "abuffer",
        SlotScheme::KBuffer(kbuffer) => kbuffer.name(),
    }
    .into();
    match scheme {
        SlotScheme::ABufferFixed => header.capacity = Some(k),
        SlotScheme::ABufferExact => {}
        _ => header.k = Some(k),
    }
    header.layout = Some(LayoutSpec::Slots { order, payload });
    // What the reader refuses first: `k` or the capacity, the payload, the order, then the
    // slots array.
    let fault = match fault {
        _ if k == 0 && scheme == SlotScheme::ABufferFixed => "\"capacity\"",
        _ if k == 0 && !abuffer => "\"k\"",
        _ if payload.is_some() && scheme == SlotScheme::Mdts32 => "payload",
        _ if payload.is_some_and(|p| p.check().is_err()) => "payload",
        _ if scheme == SlotScheme::ABufferExact && order == SlotOrder::SlotMajor => "\"order\"",
        0 | 1 => "\"slots\"",
        _ => "",
    };
    if !fault.is_empty() {
        return Err(fault.into());
    }
    // The model: fragsim's word of each stored word, placed pixel-major.
    let own_word = |word: u64| match payload {
        None => word,
        Some(_) if scheme == SlotScheme::MdtsDesc && word == 0 => 0,
        Some(p) if scheme == SlotScheme::MdtsDesc => p.fragment(word - 1).0 + 1,
        Some(_) if word == all_ones => u64::MAX,
        Some(p) => p.fragment(word).0,
    };
    let per_pixel = counts[0] as usize;
    // The format's formulas, written out rather than asked of the reader.
    let stored_at = |own: usize| match (scheme, order) {
        (SlotScheme::ABufferExact, _) | (_, SlotOrder::PixelMajor) => own,
        (_, SlotOrder::SlotMajor) => (own % per_pixel) * pixels + own / per_pixel,
    };
    let own: Vec<u64> = (0..total).map(|i| own_word(stored[stored_at(i)])).collect();
    let mut fragsims = Dump {
        header: header.clone(),
        arrays: arrays
            .iter()
            .map(|(name, words)| (name.to_string(), words.clone()))
            .collect(),
    };
    fragsims.header.layout = None;
    // Pixel-major now, so described flat: a slot-major `[k, pixels]` shape would read as the
    // transpose of fragsim's own.
    if let Some(spec) = fragsims.header.arrays.get_mut("slots") {
        spec.shape = vec![total as u64];
    }
    fragsims
        .arrays
        .insert("slots".into(), words_of(own_dtype, own));
    let capture = fragsims.capture().expect("fragsim's own encoding decodes");
    let words = fragsims
        .check_words()
        .expect("fragsim's own encoding is checked");
    let first_slot = |p: usize| match scheme {
        SlotScheme::ABufferExact => offsets[p] as usize,
        _ => p * per_pixel,
    };
    // The own encoding's corrupt words, each named as stored (exact storage's room other than
    // its counter is named by the room itself, at slot 0).
    let mut corrupt: Vec<Vec<(usize, Corruption)>> = words
        .corrupt
        .iter()
        .map(|c| c.iter().map(|w| (w.slot, w.why)).collect())
        .collect();
    let mut stored_words: Vec<Vec<u64>> = words
        .corrupt
        .iter()
        .map(|c| {
            c.iter()
                .map(|w| match w.why {
                    Corruption::RoomNotCount => w.word,
                    _ => stored[stored_at(first_slot(w.pixel) + w.slot)],
                })
                .collect()
        })
        .collect();
    // The format's rule on the bits outside a payload's fields, written out: a slot read as a
    // fragment (below an A-buffer's counter; any MDTS or k-buffer slot) that is not the empty
    // marker holds 0 there, and a slot named for another reason is not named again.
    let outside = payload.map_or(0, |p| outside_fields(&p));
    let counters = arrays
        .iter()
        .find_map(|(name, array)| match (*name, array) {
            ("counters", Words::U32(c)) => Some(c.clone()),
            _ => None,
        });
    if outside != 0 {
        for p in 0..pixels {
            let room = counts[p] as usize;
            let read = counters.as_ref().map_or(room, |c| room.min(c[p] as usize));
            for slot in 0..read {
                let word = stored[stored_at(first_slot(p) + slot)];
                let fields = if scheme == SlotScheme::MdtsDesc {
                    word.wrapping_sub(1)
                } else {
                    word
                };
                let named = corrupt[p]
                    .iter()
                    .any(|&(s, why)| s == slot && why != Corruption::RoomNotCount);
                if word != empty && fields & outside != 0 && !named {
                    corrupt[p].push((slot, Corruption::OutsideFields));
                    stored_words[p].push(word);
                }
            }
        }
    }
    Ok(Some(Model {
        corrupt,
        lists: (0..pixels).map(|p| capture.pixel(p).to_vec()).collect(),
        unreachable: 0,
        stored_words: Some(stored_words),
        judged_against_itself: !abuffer,
    }))
}

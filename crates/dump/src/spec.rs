//! The layout description a dump header carries (`"layout"`, `docs/dump-format.md`): how the
//! arrays of a slot, linked-list, layer-major or memory dump hold the scheme's memory, and how a
//! payload word packs a fragment's depth and primitive id.
//!
//! The description is what lets a dump carry the engine's own buffers rather than fragsim's: a
//! linked list may end at `0xFFFFFFFF` and number its nodes from 0 (Vulkan-Samples) or end at 0
//! and number them from 1 (nvpro-samples, fragsim); a node may hold a u32 word of a unorm24
//! depth above an 8-bit primitive id. The reader converts each payload word to fragsim's
//! fragment word (`depth_key << 32 | prim`, [`Payload::fragment`]) and each node number to
//! fragsim's before the scheme's own resolve runs; a slot array may hold each pixel's slots
//! together or one image layer per slot ([`SlotOrder`]). A header without the description (a
//! dump written before it existed) has the layout its `scheme` names, with fragsim's own
//! encoding ([`Payload::FRAGMENT`], pixel-major slots).

use serde::{Deserialize, Serialize};

use crate::{err, Dtype, DumpError};

/// How a payload word stores the depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthFormat {
    /// The 32 bits of the f32 depth (`floatBitsToUint(gl_FragCoord.z)`): fragsim's depth key.
    F32,
    /// A 24-bit unsigned normalised depth (`uint(z * 16777215.0)`, a D24 depth buffer's).
    Unorm24,
    /// A 16-bit unsigned normalised depth (`uint(z * 65535.0)`, a D16 depth buffer's).
    Unorm16,
}

impl DepthFormat {
    /// The field's width in bits.
    #[must_use]
    pub fn bits(self) -> u32 {
        match self {
            Self::F32 => 32,
            Self::Unorm24 => 24,
            Self::Unorm16 => 16,
        }
    }

    /// Its name in a header and on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::F32 => "f32",
            Self::Unorm24 => "unorm24",
            Self::Unorm16 => "unorm16",
        }
    }

    /// The depth key a stored field reads back as: the f32 bits themselves, or the nearest f32
    /// to a unorm field's value `field / (2^bits − 1)` (what the GPU's depth was rounded from).
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an F32 field is the f32's 32 bits; a unorm field's value narrows to the nearest f32, as the GPU's depth was rounded to"
    )]
    pub fn key_of_field(self, field: u64) -> u32 {
        match self {
            Self::F32 => field as u32,
            Self::Unorm24 | Self::Unorm16 => {
                ((field as f64 / mask(self.bits()) as f64) as f32).to_bits()
            }
        }
    }

    /// The field that stores depth key `key` as fragsim writes it: the bits, or the nearest
    /// unorm step `round(depth · (2^bits − 1))` (a D24 or D16 conversion).
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a depth in [0, 1] scales to a field in [0, 2^bits − 1]; `as` saturates anything else"
    )]
    pub fn field_of_key(self, key: u32) -> u64 {
        match self {
            Self::F32 => u64::from(key),
            Self::Unorm24 | Self::Unorm16 => {
                let steps = mask(self.bits()) as f64;
                (Self::depth(key) * steps).round() as u64
            }
        }
    }

    /// The keys a field of this format may read back as for a depth between keys `lo` and `hi`
    /// (`lo ≤ hi`), whatever conversion an implementation used (`docs/semantics.md` §10,
    /// "Stored depth"): the f32 keys unchanged; for a unorm field of `s = 2^bits − 1` steps, the
    /// steps from `⌊lo · s − ½⌋` to `⌈hi · s + ½⌉`. A shader computes `z · s` in f32, within
    /// half a step below `2^24`, then rounds (a depth buffer's conversion) or truncates
    /// (`uint(z * s)`): either lands in that range, and no other step can.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "first and last are clamped to [0, 2^bits − 1], integers below 2^24"
    )]
    pub fn stored_keys(self, lo: u32, hi: u32) -> (u32, u32) {
        match self {
            Self::F32 => (lo, hi),
            Self::Unorm24 | Self::Unorm16 => {
                let steps = mask(self.bits()) as f64;
                let first = (Self::depth(lo) * steps - 0.5).floor().clamp(0.0, steps);
                let last = (Self::depth(hi) * steps + 0.5).ceil().clamp(0.0, steps);
                (
                    self.key_of_field(first as u64),
                    self.key_of_field(last as u64),
                )
            }
        }
    }

    /// A depth key's value clamped to `[0, 1]`.
    fn depth(key: u32) -> f64 {
        f64::from(f32::from_bits(key)).clamp(0.0, 1.0)
    }
}

/// Where a payload word keeps the depth and the primitive id: the depth field of
/// [`DepthFormat::bits`] bits starts at bit `depth_shift`, the primitive id is the low
/// `prim_bits` bits (below the depth, so that words sort by depth first).
///
/// An unknown field is refused by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Payload {
    /// The word's type.
    pub dtype: Dtype,
    /// How the depth is stored.
    pub depth: DepthFormat,
    /// The depth field's lowest bit.
    pub depth_shift: u32,
    /// Bits of primitive id at the bottom of the word (1 to 32).
    pub prim_bits: u32,
}

/// A payload as an option spells it, `DTYPE:DEPTH:SHIFT:PRIM_BITS` (fragsim's:
/// `u64:f32:32:32`; a D24 depth over an 8-bit id: `u32:unorm24:8:8`), checked as a header's is
/// ([`Payload::check`]).
impl std::str::FromStr for Payload {
    type Err = DumpError;

    fn from_str(text: &str) -> Result<Self, DumpError> {
        let [dtype, depth, shift, prim_bits] = fields(text, "DTYPE:DEPTH:SHIFT:PRIM_BITS")?;
        let number = |field: &str, name: &str| {
            field
                .parse::<u32>()
                .map_err(|e| DumpError::Invalid(format!("{name} {field:?}: {e}")))
        };
        let payload = Self {
            dtype: kebab(dtype)?,
            depth: kebab(depth)?,
            depth_shift: number(shift, "SHIFT")?,
            prim_bits: number(prim_bits, "PRIM_BITS")?,
        };
        payload.check()?;
        Ok(payload)
    }
}

/// The `N` colon-separated fields of `text`, which must have the form `form`.
fn fields<'a, const N: usize>(text: &'a str, form: &str) -> Result<[&'a str; N], DumpError> {
    let parts: Vec<&str> = text.split(':').collect();
    parts
        .try_into()
        .map_err(|_| DumpError::Invalid(format!("{text:?} is not {form}")))
}

/// A value by its kebab-case name, as a dump header spells it (`slot-major`, `unorm24`,
/// `lower-left`): how options name a header's values.
///
/// # Errors
/// No value of `T` has that name (the message lists those that do).
pub fn kebab<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, DumpError> {
    serde_json::from_value(serde_json::Value::String(text.into()))
        .map_err(|e| DumpError::Invalid(e.to_string()))
}

/// The largest depth key of a fragment: depth 1.0 (fragments outside `[0, 1]` are dropped, and
/// `-0.0` is stored as `+0.0`), so a stored key above it is no fragment's.
pub(super) const LARGEST_KEY: u32 = 0x3F80_0000;

impl Payload {
    /// fragsim's own fragment word: u64 `depth_key << 32 | prim`.
    pub const FRAGMENT: Self = Self {
        dtype: Dtype::U64,
        depth: DepthFormat::F32,
        depth_shift: 32,
        prim_bits: 32,
    };

    /// Refuses fields that overlap or do not fit the word.
    ///
    /// # Errors
    /// A primitive id of no bits or more than 32, above the depth field, or a depth field past
    /// the word's top bit.
    pub fn check(&self) -> Result<(), DumpError> {
        let word_bits = u64::from(self.dtype.bits());
        if self.prim_bits == 0 || self.prim_bits > 32 {
            return err(format!(
                "payload \"prim_bits\" {} must be 1 to 32: fragments are told apart by their \
                 primitive id",
                self.prim_bits
            ));
        }
        if self.prim_bits > self.depth_shift {
            return err(format!(
                "payload: the primitive id's {} bits overlap the depth field at bit {}",
                self.prim_bits, self.depth_shift
            ));
        }
        if u64::from(self.depth_shift) + u64::from(self.depth.bits()) > word_bits {
            return err(format!(
                "payload: a {:?} depth at bit {} does not fit a {word_bits}-bit word",
                self.depth, self.depth_shift
            ));
        }
        Ok(())
    }

    /// The fragment word (`depth_key << 32 | prim`) a payload word holds, and whether its depth
    /// key is one a fragment can have (at most 1.0's). Needs a [`Payload::check`]ed payload.
    #[must_use]
    pub fn fragment(&self, word: u64) -> (u64, bool) {
        let field = (word >> self.depth_shift) & mask(self.depth.bits());
        let key = self.depth.key_of_field(field);
        let prim = word & mask(self.prim_bits);
        ((u64::from(key) << 32) | prim, key <= LARGEST_KEY)
    }

    /// The payload word of fragsim's fragment word `fragment` (`depth_key << 32 | prim`), as an
    /// engine's shader packs it: the f32 depth's bits, or its nearest unorm step
    /// (`round(depth · (2^bits − 1))`, a D24 or D16 conversion), with the id in the low bits.
    /// fragsim's empty marker (all ones) packs to the payload's (all ones of its word), so that
    /// storage never written reads as empty in either encoding. [`Payload::fragment`] gives an
    /// f32 word back bit for bit. Needs a [`Payload::check`]ed payload.
    ///
    /// # Errors
    /// A primitive id that needs more than `prim_bits` bits: the word would name another
    /// primitive.
    pub fn pack(&self, fragment: u64) -> Result<u64, DumpError> {
        if fragment == u64::MAX {
            return Ok(mask(self.dtype.bits()));
        }
        let (key, prim) = ((fragment >> 32) as u32, fragment & 0xFFFF_FFFF);
        if prim > mask(self.prim_bits) {
            return err(format!(
                "primitive id {prim} does not fit the payload's {} \"prim_bits\"",
                self.prim_bits
            ));
        }
        let field = self.depth.field_of_key(key);
        Ok(field << self.depth_shift | prim)
    }
}

/// How a slot array places the `slots` slots of its `pixels` pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SlotOrder {
    /// Each pixel's slots together: slot `s` of pixel `p` at `p · slots + s` (fragsim,
    /// FreePipe, a CUDA kernel's `slots[p * K + s]`).
    #[default]
    PixelMajor,
    /// One image layer per slot: slot `s` of pixel `p` at `s · pixels + p` (an engine that
    /// allocates a texture array or `K` render targets, nvpro-samples' loop32).
    SlotMajor,
}

impl SlotOrder {
    /// The array index of slot `slot` of pixel `pixel`.
    #[must_use]
    pub fn index(self, pixel: usize, slot: usize, pixels: usize, slots: usize) -> usize {
        match self {
            Self::PixelMajor => pixel * slots + slot,
            Self::SlotMajor => slot * pixels + pixel,
        }
    }
}

fn mask(bits: u32) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1 << bits) - 1
    }
}

/// A header's `"layout"`: how its arrays hold the scheme's memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum LayoutSpec {
    /// Per-pixel linked lists: `heads` `[pixels]` u32, `next` `[pool]` u32, `nodes` `[pool]`
    /// payload words, `counter` `[1]` u32 (nodes handed out, which may pass the pool). Node
    /// number `n` is array index `n − node_base`; `null` ends a list.
    LinkedList {
        /// The node payload.
        payload: Payload,
        /// The terminator (`0` for fragsim and nvpro-samples, `4294967295` for Vulkan-Samples).
        null: u32,
        /// The first node's number (`1` for fragsim and nvpro-samples, `0` for Vulkan-Samples).
        node_base: u32,
    },
    /// Layer-major layers (Bevy's): `counters` `[pixels]` u32, `layers` `[k, pixels]` payload
    /// words, layer `l` of pixel `p` at `l * pixels + p`.
    LayerMajor {
        /// The layer payload.
        payload: Payload,
    },
    /// The scheme's own memory after its last pass: `words32` and `words64`, in the order its
    /// module documents.
    Memory,
    /// The slot layouts (`mdts`, `mdts32`, `mdts-desc`, `abuffer`, the k-buffers): the `slots` array in
    /// `order`, each word packed as `payload` (absent: the scheme's own word). The empty marker
    /// is all ones of the word (`0` for `mdts-desc`, whose words are the payload plus one).
    Slots {
        /// How the slots of the pixels are placed.
        order: SlotOrder,
        /// The slot payload; absent: fragsim's own word (`mdts32`'s depth keys take none).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        payload: Option<Payload>,
    },
}

impl LayoutSpec {
    /// The payload its words are packed in, where the description gives one.
    #[must_use]
    pub fn payload(&self) -> Option<Payload> {
        match *self {
            Self::LinkedList { payload, .. } | Self::LayerMajor { payload } => Some(payload),
            Self::Slots { payload, .. } => payload,
            Self::Memory => None,
        }
    }

    /// fragsim's own linked lists: node 0 ends a list, nodes numbered from 1.
    pub const FRAGSIM_LISTS: Self = Self::LinkedList {
        payload: Payload::FRAGMENT,
        null: 0,
        node_base: 1,
    };

    /// fragsim's own layer-major layers.
    pub const FRAGSIM_LAYERS: Self = Self::LayerMajor {
        payload: Payload::FRAGMENT,
    };

    /// The `kind` field, for messages.
    #[must_use]
    pub fn kind(&self) -> &'static str {
        match self {
            Self::LinkedList { .. } => "linked-list",
            Self::LayerMajor { .. } => "layer-major",
            Self::Memory => "memory",
            Self::Slots { .. } => "slots",
        }
    }
}

/// How linked lists number their nodes: `null` ends a list, node number `n` is array index
/// `n − node_base`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListNumbering {
    /// The terminator.
    pub null: u32,
    /// The first node's number.
    pub node_base: u32,
}

/// A numbering as an option spells it, `NULL:NODE_BASE` (fragsim's and nvpro-samples': `0:1`;
/// Vulkan-Samples': `4294967295:0`).
impl std::str::FromStr for ListNumbering {
    type Err = DumpError;

    fn from_str(text: &str) -> Result<Self, DumpError> {
        let [null, node_base] = fields(text, "NULL:NODE_BASE")?;
        let number = |field: &str| {
            field
                .parse::<u32>()
                .map_err(|e| DumpError::Invalid(format!("{field:?}: {e}")))
        };
        Ok(Self {
            null: number(null)?,
            node_base: number(node_base)?,
        })
    }
}

/// An encoding asked of every dump written at once (`render --dump-order`, `--dump-payload`,
/// `--dump-list-numbering`): each field goes to the layouts that have it, and an absent field
/// leaves fragsim's own ([`DumpScheme::spec_in`](super::DumpScheme::spec_in)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Encoding {
    /// Slot layouts: how the `slots` array places each pixel's slots.
    pub order: Option<SlotOrder>,
    /// Slot layouts (but `mdts32`'s bare keys), linked lists and layer-major layers: the payload.
    pub payload: Option<Payload>,
    /// Linked lists: the terminator and the node numbering.
    pub list_numbering: Option<ListNumbering>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the expected key is the nearest f32 to the unorm24 depth"
    )]
    fn unorm_depths_decode_to_the_nearest_f32_of_their_value() {
        let unorm24 = Payload {
            dtype: Dtype::U32,
            depth: DepthFormat::Unorm24,
            depth_shift: 8,
            prim_bits: 8,
        };
        unorm24.check().unwrap();
        let (word, possible) = unorm24.fragment(0xFF_FFFF << 8 | 0x2A);
        assert_eq!(word, u64::from(1.0_f32.to_bits()) << 32 | 0x2A);
        assert!(possible);
        let half = unorm24.fragment(0x80_0000 << 8).0;
        assert_eq!(
            (half >> 32) as u32,
            ((8_388_608.0 / 16_777_215.0) as f32).to_bits()
        );
    }

    #[test]
    fn packing_inverts_decoding_for_f32_depths_and_rounds_unorm_ones_to_the_nearest_step() {
        let word = u64::from(0.75_f32.to_bits()) << 32 | 0x12_3456;
        let over_24 = Payload {
            depth_shift: 24,
            prim_bits: 24,
            ..Payload::FRAGMENT
        };
        let packed = over_24.pack(word).unwrap();
        assert_eq!(packed, u64::from(0.75_f32.to_bits()) << 24 | 0x12_3456);
        assert_eq!(over_24.fragment(packed).0, word);
        let unorm16 = Payload {
            depth: DepthFormat::Unorm16,
            ..Payload::FRAGMENT
        };
        // 0.75 · 65535 = 49151.25: the nearest step is 49151.
        assert_eq!(unorm16.pack(word).unwrap() >> 32, 49_151);
        // fragsim's empty marker is the payload's, and an id too wide for it is refused.
        let narrow = Payload {
            dtype: Dtype::U32,
            depth: DepthFormat::Unorm24,
            depth_shift: 8,
            prim_bits: 8,
        };
        assert_eq!(narrow.pack(u64::MAX).unwrap(), u64::from(u32::MAX));
        assert!(narrow
            .pack(word)
            .unwrap_err()
            .to_string()
            .contains("1193046 does not fit"));
    }

    #[test]
    fn f32_keys_above_one_are_flagged_and_bad_packings_refused() {
        let (_, possible) = Payload::FRAGMENT.fragment(u64::from(LARGEST_KEY + 1) << 32);
        assert!(!possible);
        let overlap = Payload {
            prim_bits: 33,
            ..Payload::FRAGMENT
        };
        assert!(overlap.check().is_err());
        let past = Payload {
            dtype: Dtype::U32,
            ..Payload::FRAGMENT
        };
        assert!(past
            .check()
            .unwrap_err()
            .to_string()
            .contains("does not fit a 32-bit word"));
    }
}

//! The masked-node A-buffer's dump (`abuffer-masked`, `docs/dump-format.md`): per-pixel storage
//! whose nodes carry a coverage mask ([`MaskedABuffer`]), read, checked and recorded here, judged
//! by the oracle's verdict (`fragsim_oracle::verdict::JudgeDump`) against the per-pixel view of
//! the per-sample oracle.
//!
//! Arrays: `counters` u32 `[pixels]` (the `fetch_add` counts, never wrapped), `nodes`
//! `[pixels, capacity]` node words (fragsim's `key << 32 | prim`, or the header's payload) and
//! `masks` u32 `[pixels, capacity]` (bit `s`: sample `s`), slot `i` of pixel `p` at
//! `p · capacity + i` (or `i · pixels + p` slot-major, both arrays alike). The header gives
//! `capacity`, the sample count in `scene.conventions.samples`, and optionally a slot layout
//! description (`"layout": {"kind": "slots", …}`) whose order and payload the reader turns into
//! fragsim's words before the scheme's own post pass ([`MaskedABuffer::node_lists`]) runs, so that a
//! dump is decoded exactly as fragsim decodes its own runs.

use fragsim_capture::MaskedLists;
use fragsim_capture::Scheme as _;
use fragsim_capture::{Capacity, Capture};
use fragsim_memory::{SerialMemory, WordMemory};
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::View;
use fragsim_schemes::masked_abuffer::MaskedABuffer;

use crate::slots::{words_of, Placement, SlotCodec};
use crate::spec::{Encoding, LayoutSpec, SlotOrder, LARGEST_KEY};
use crate::word_check::{Corruption, Counter, WordCheck};
use crate::{err, Dtype, Dump, DumpError, Header, Words};
use crate::{FORMAT, VERSION};

/// The header `scheme` of a masked-node dump.
pub const MASKED_SCHEME: &str = "abuffer-masked";

/// A masked-node dump's parameters, read from its header.
#[derive(Clone, Copy, Debug)]
struct Masked {
    capacity: u32,
    samples: u32,
    placement: Placement,
    codec: SlotCodec,
    /// The `nodes` array's dtype (the payload's).
    dtype: Dtype,
}

/// A masked-node dump's words in fragsim's pixel-major order: the counters, the nodes
/// (fragsim's words) and the masks.
type OwnWords = (Vec<u32>, Vec<u64>, Vec<u32>);

impl Dump {
    /// Whether this is a masked-node dump ([`MASKED_SCHEME`]).
    #[must_use]
    pub fn is_masked(&self) -> bool {
        self.header.scheme == MASKED_SCHEME
    }

    /// The masked-node parameters of the header.
    fn masked(&self) -> Result<Masked, DumpError> {
        let capacity = match self.header.capacity {
            Some(c) if c > 0 => c,
            _ => return err(format!("{MASKED_SCHEME} needs \"capacity\" ≥ 1")),
        };
        let samples = self.header.samples()?;
        let (order, payload) = match self.header.layout {
            None => (SlotOrder::PixelMajor, None),
            Some(LayoutSpec::Slots { order, payload }) => (order, payload),
            Some(other) => {
                return err(format!(
                    "scheme {MASKED_SCHEME} dumps as slots, the header's layout is {}",
                    other.kind()
                ))
            }
        };
        if let Some(payload) = payload {
            payload.check()?;
        }
        Ok(Masked {
            capacity,
            samples,
            placement: Placement::new(order, self.viewport()?.pixels(), capacity as usize),
            codec: SlotCodec::plain(payload),
            dtype: payload.map_or(Dtype::U64, |p| p.dtype),
        })
    }

    /// The counters, and the nodes (fragsim's words) and masks in fragsim's pixel-major order.
    fn masked_words(&self, masked: &Masked) -> Result<OwnWords, DumpError> {
        let pixels = self.viewport()?.pixels();
        // At most 2^28 pixels of 2^32 slots: the product fits.
        let slots = pixels as u64 * u64::from(masked.capacity);
        let counters = self.u32s_of("counters", pixels)?.to_vec();
        let nodes = self.widened("nodes", masked.dtype)?;
        let masks = self
            .u32s("masks")?
            .ok_or_else(|| DumpError::Invalid("missing array \"masks\"".into()))?;
        for (name, len) in [("nodes", nodes.len()), ("masks", masks.len())] {
            if len as u64 != slots {
                return err(format!(
                    "array {name:?} has {len} words, {} nodes of {pixels} pixels expected",
                    masked.capacity
                ));
            }
        }
        let at = |i| masked.placement.stored(i);
        let own_nodes = (0..nodes.len())
            .map(|i| masked.codec.own(nodes[at(i)]))
            .collect();
        let own_masks = (0..masks.len()).map(|i| masks[at(i)]).collect();
        Ok((counters, own_nodes, own_masks))
    }

    /// The masked-node A-buffer's lists: the words loaded into its memory and resolved by its own
    /// post pass (each pixel's `min(counter, capacity)` nodes, sorted; the rest counted as
    /// overflow).
    ///
    /// # Errors
    /// Not a masked-node dump, a bad `capacity`, sample count or layout description, arrays
    /// missing or of the wrong size or type.
    pub fn masked_lists(&self) -> Result<MaskedLists, DumpError> {
        let masked = self.masked_checked()?;
        let (counters, nodes, masks) = self.masked_words(&masked)?;
        let scheme =
            MaskedABuffer::new(self.viewport()?, masked.samples, masked.capacity, u64::MAX)?;
        let memory: SerialMemory = scheme.layout().allocate();
        // The scheme's u32 words are the counters, then the masks (`MaskedABuffer::layout`).
        for (i, &w) in counters.iter().chain(&masks).enumerate() {
            WordMemory::<u32>::store(&memory, i, w);
        }
        for (i, &w) in nodes.iter().enumerate() {
            WordMemory::<u64>::store(&memory, i, w);
        }
        Ok(scheme.node_lists(&memory))
    }

    fn masked_checked(&self) -> Result<Masked, DumpError> {
        if !self.is_masked() {
            return err(format!(
                "scheme {}: not a masked-node dump ({MASKED_SCHEME})",
                self.header.scheme
            ));
        }
        self.masked()
    }

    /// The nodes as a capture ([`MaskedLists::packed_capture`]): what [`Dump::capture`] gives of a masked-node
    /// dump.
    pub(super) fn masked_capture(&self) -> Result<Capture, DumpError> {
        let capacity = self.masked_checked()?.capacity;
        Ok(self
            .masked_lists()?
            .packed_capture(Capacity::PerPixel(capacity)))
    }

    /// The word rules of the masked-node layout: the A-buffer's on the nodes (no empty marker
    /// below the counter, no key above 1.0, with `filled` nothing past it), and each counted
    /// node's mask within the pixel's samples and not empty; with `filled`, a mask past the
    /// counter is 0.
    pub(super) fn check_masked_words(&self) -> Result<WordCheck, DumpError> {
        let masked = self.masked_checked()?;
        // Decoding validates the arrays; the check then indexes them freely.
        self.masked_lists()?;
        let (counters, nodes, masks) = self.masked_words(&masked)?;
        let stored_nodes = self.widened("nodes", masked.dtype)?;
        let stored_masks = self.u32s("masks")?.unwrap_or_default();
        let capacity = masked.capacity as usize;
        let samples_mask = (1_u64 << masked.samples) - 1;
        let mut check = WordCheck {
            corrupt: vec![Vec::new(); counters.len()],
            ..WordCheck::default()
        };
        let mut all = Vec::with_capacity(counters.len());
        for (p, &count) in counters.iter().enumerate() {
            let stored = (count as usize).min(capacity);
            for slot in 0..capacity {
                let own = p * capacity + slot;
                let (node, mask) = (nodes[own], masks[own]);
                let (node_why, mask_why) = if slot < stored {
                    let node_why = if node == u64::MAX {
                        Some(Corruption::EmptyCounted)
                    } else {
                        ((node >> 32) as u32 > LARGEST_KEY).then_some(Corruption::ImpossibleKey)
                    };
                    let outside = mask == 0 || u64::from(mask) & !samples_mask != 0;
                    (node_why, outside.then_some(Corruption::ImpossibleMask))
                } else if self.header.filled {
                    (
                        (node != u64::MAX).then_some(Corruption::BeyondCounter),
                        (mask != 0).then_some(Corruption::BeyondCounter),
                    )
                } else {
                    check.unchecked += 2;
                    (None, None)
                };
                let at = masked.placement.stored(own);
                check.flag(p, slot, stored_nodes[at], node_why);
                check.flag(p, slot, u64::from(stored_masks[at]), mask_why);
            }
            all.push(Counter {
                count,
                capacity: masked.capacity,
            });
        }
        check.counters = Some(all);
        Ok(check)
    }

    /// Runs the masked-node A-buffer of `capacity` nodes a pixel serially over `view` (which
    /// rasterizes per sample, at the sample count `scene`'s conventions declare) and records its
    /// memory as a dump, `filled` (fragsim's storage starts empty).
    ///
    /// # Errors
    /// A view that does not rasterize per sample at the conventions' count, a capacity of 0.
    pub fn record_masked(
        view: &View<'_>,
        scene: SceneSpec,
        capacity: u32,
        producer: &str,
    ) -> Result<Self, DumpError> {
        let pixels = view.pixel_viewport();
        let samples = scene.conventions.samples;
        if view.samples().map(|p| p.count()) != Some(samples) {
            return err(format!(
                "the masked-node A-buffer needs a view rasterizing per sample at the \
                 conventions' {samples} samples"
            ));
        }
        let scheme = MaskedABuffer::new(pixels, samples, capacity, u64::MAX)?;
        let memory: SerialMemory = scheme.layout().allocate();
        scheme
            .insert_all(view, &memory)
            // The view's sample count was checked above: a refusal here is the dump's to report.
            .map_err(|e| DumpError::Invalid(e.to_string()))?;
        let u32s: Vec<u32> = (0..WordMemory::<u32>::len(&memory))
            .map(|i| WordMemory::<u32>::load(&memory, i))
            .collect();
        let u64s: Vec<u64> = (0..WordMemory::<u64>::len(&memory))
            .map(|i| WordMemory::<u64>::load(&memory, i))
            .collect();
        Self::masked_of_memory(view, scene, capacity, &u32s, u64s, producer)
    }

    /// Records the words a run of the masked-node A-buffer of `capacity` nodes a pixel over
    /// `view` left (`words32`: the counters, then the masks; `words64`: the nodes) as a dump:
    /// what `render --dump` writes of the run it reports, on whatever executor ran it.
    ///
    /// # Errors
    /// Words of another number than the scheme's layout holds.
    pub fn masked_of_memory(
        view: &View<'_>,
        scene: SceneSpec,
        capacity: u32,
        words32: &[u32],
        words64: Vec<u64>,
        producer: &str,
    ) -> Result<Self, DumpError> {
        let pixels = view.pixel_viewport();
        let n = pixels.pixels();
        let nodes = n * capacity as usize;
        if (words32.len(), words64.len()) != (n + nodes, nodes) {
            return err(format!(
                "{MASKED_SCHEME} of {n} pixels and {capacity} nodes a pixel holds {} u32 and {nodes} \
                 u64 words, the run left {} and {}",
                n + nodes,
                words32.len(),
                words64.len()
            ));
        }
        let u64s = words64;
        let (counters, masks) = words32.split_at(n);
        let slots = vec![n as u64, u64::from(capacity)];
        let mut dump = Self {
            header: Header {
                format: FORMAT.into(),
                version: VERSION,
                producer: producer.into(),
                scene,
                width: pixels.width,
                height: pixels.height,
                scheme: MASKED_SCHEME.into(),
                k: None,
                capacity: Some(capacity),
                sorted: false,
                filled: true,
                pool: None,
                layers: None,
                layout: None,
                word: "key<<32|prim".into(),
                arrays: std::collections::BTreeMap::new(),
                extra: serde_json::Value::Null,
            },
            arrays: std::collections::BTreeMap::new(),
        };
        dump.set_array("counters", Words::U32(counters.to_vec()), vec![n as u64]);
        dump.set_array("masks", Words::U32(masks.to_vec()), slots.clone());
        dump.set_array("nodes", Words::U64(u64s), slots);
        Ok(dump)
    }

    /// This masked-node dump (in fragsim's own encoding, as [`Dump::record_masked`] writes it)
    /// with both slot arrays placed in `order` and the nodes packed as `payload`.
    ///
    /// # Errors
    /// A primitive id that does not fit the payload.
    pub(super) fn masked_as(&self, spec: Option<LayoutSpec>) -> Result<Self, DumpError> {
        let masked = self.masked_checked()?;
        if self.header.layout.is_some() {
            return err("only fragsim's own encoding is re-encoded");
        }
        let Some(LayoutSpec::Slots { order, payload }) = spec else {
            return match spec {
                None => Ok(self.clone()),
                Some(other) => err(format!(
                    "scheme {MASKED_SCHEME} dumps as slots, not {}",
                    other.kind()
                )),
            };
        };
        let (_, nodes, masks) = self.masked_words(&masked)?;
        let placement = Placement::new(order, masked.placement.pixels(), masked.capacity as usize);
        let codec = SlotCodec::plain(payload);
        let (mut stored_nodes, mut stored_masks) = (vec![0; nodes.len()], vec![0; masks.len()]);
        for (i, (&node, &mask)) in nodes.iter().zip(&masks).enumerate() {
            stored_nodes[placement.stored(i)] = codec.stored(node)?;
            stored_masks[placement.stored(i)] = mask;
        }
        let shape = match order {
            SlotOrder::PixelMajor => self.shape_of("nodes"),
            SlotOrder::SlotMajor => {
                vec![u64::from(masked.capacity), masked.placement.pixels() as u64]
            }
        };
        let mut dump = self.clone();
        dump.header.layout = Some(LayoutSpec::Slots { order, payload });
        if payload.is_some() {
            dump.header.word = String::new();
        }
        let dtype = payload.map_or(Dtype::U64, |p| p.dtype);
        dump.set_array("nodes", words_of(dtype, stored_nodes), shape.clone());
        dump.set_array("masks", Words::U32(stored_masks), shape);
        Ok(dump)
    }
}

/// The header layout that writes a masked-node dump in `encoding` (`None`: fragsim's own), and
/// the fields of `encoding` its layout has no place for (`list numbering`).
#[must_use]
pub fn masked_spec(encoding: &Encoding) -> (Option<LayoutSpec>, Vec<&'static str>) {
    let ignored = if encoding.list_numbering.is_some() {
        vec!["list numbering"]
    } else {
        Vec::new()
    };
    let order = encoding.order.unwrap_or_default();
    let spec = (order != SlotOrder::PixelMajor || encoding.payload.is_some()).then_some(
        LayoutSpec::Slots {
            order,
            payload: encoding.payload,
        },
    );
    (spec, ignored)
}

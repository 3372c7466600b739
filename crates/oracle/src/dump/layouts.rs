//! The layouts a dump's words may have: which scheme's memory, with its parameters, and the rules
//! every word of that layout obeys ([`Dump::check_words`]).
//!
//! The layouts and the header names that select them are the catalog's
//! ([`fragsim_capture::catalog::DumpLayout`]): a header's `scheme` is the name of the catalog entry
//! that heads a layout, and [`DumpScheme`] is that layout with the parameters its arrays need.

use std::collections::BTreeMap;

use fragsim_capture::catalog::{
    Build, DumpLayout, SchemeName, SchemeVisitor, SlotWord, Storage, CATALOG,
};
use fragsim_capture::schemes::mdts::Direction;
use fragsim_capture::{Capacity, Capture, Identity, Keeps};
use fragsim_raster::Viewport;
use serde::Serialize;

use super::lists::{layer_major, linked_lists, ListArrays, Translated};
use super::spec::{
    DepthFormat, Encoding, LayoutSpec, ListNumbering, Payload, SlotOrder, LARGEST_KEY,
};
use super::{err, Dtype, Dump, DumpError, Header, Words};

/// Which scheme's memory a dump holds, with its parameters.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DumpScheme {
    /// MDTS on u64 words `key << 32 | prim`: `slots` `[pixels, k]`.
    Mdts {
        /// Slots per pixel.
        k: u32,
        /// Ascending (`mdts`, empty = all ones) or descending (`mdts-desc`, word + 1, empty = 0).
        direction: Direction,
    },
    /// MDTS on u32 depth keys (FreePipe's Table 1), ascending: `slots` `[pixels, k]`.
    Mdts32 {
        /// Slots per pixel.
        k: u32,
    },
    /// A-buffer with `capacity` slots per pixel: `counters` `[pixels]`, `slots`
    /// `[pixels, capacity]`.
    ABufferFixed {
        /// Slots per pixel.
        capacity: u32,
        /// Whether each pixel's slots were sorted in place.
        sorted: bool,
    },
    /// A-buffer sized by a counting pass: `counters` `[pixels]`, `offsets` `[pixels + 1]`
    /// (prefix sums of `counts`), `slots` `[offsets[pixels]]`.
    ABufferExact {
        /// Slots of each pixel.
        counts: Vec<u32>,
        /// Whether each pixel's slots were sorted in place.
        sorted: bool,
    },
    /// Per-pixel linked lists (`linked-list`, `linked-list-nearest`): `heads` `[pixels]`,
    /// `next` and `nodes` `[pool]`, `counter` `[1]` ([`LayoutSpec::LinkedList`]).
    LinkedLists {
        /// Which of the two resolves decodes the lists.
        scheme: SchemeName,
        /// Nodes the resolve keeps (`--k`).
        k: u32,
        /// Nodes in the pool.
        pool: u32,
        /// The terminator, the first node's number and the payload.
        spec: LayoutSpec,
    },
    /// Bevy's layer counter (`layer-counter`): `counters` `[pixels]`, `layers` `[k, pixels]`
    /// layer-major ([`LayoutSpec::LayerMajor`]).
    LayerMajor {
        /// Layers per pixel.
        k: u32,
        /// The payload.
        payload: Payload,
    },
    /// A k-buffer's slots (`kbuffer`, `kbuffer-stores`, `kbuffer-interlock*`,
    /// `kbuffer-spinlock*`): `slots` `[pixels, k]` as MDTS's, under the scheme's own name, rebuilt
    /// and resolved as `scheme` (its promise, its resolve), its u32 words left at their initial
    /// values ([`DumpLayout::KBufferSlots`]).
    KBuffer {
        /// The k-buffer.
        scheme: SchemeName,
        /// Slots per pixel.
        k: u32,
    },
    /// Any other scheme's own memory after its last pass: `words32`, `words64`
    /// ([`LayoutSpec::Memory`]), rebuilt and resolved as `scheme` sized so.
    Memory {
        /// The scheme.
        scheme: SchemeName,
        /// Its `--k`.
        k: u32,
        /// Its `--capacity`.
        capacity: u32,
        /// The scene's maximum depth complexity it was sized to (schemes that record every layer).
        layers: u32,
    },
}

/// Catalog names as an alternative for an error message: `mdts, mdts32, mdts-desc or abuffer`.
fn either<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.collect();
    match names.split_last() {
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// Names of the memory's two word arrays in a dump (`None`: the scheme uses no such words).
pub(super) struct ArrayNames {
    pub(super) words32: Option<&'static str>,
    pub(super) words64: Option<&'static str>,
}

impl DumpScheme {
    /// The catalog's layout of these words.
    #[must_use]
    pub fn layout(&self) -> DumpLayout {
        match self {
            Self::Mdts {
                direction: Direction::Ascending,
                ..
            } => DumpLayout::SlotArray(SlotWord::Fragment),
            Self::Mdts {
                direction: Direction::Descending,
                ..
            } => DumpLayout::SlotArray(SlotWord::FragmentPlusOne),
            Self::Mdts32 { .. } => DumpLayout::SlotArray(SlotWord::Key),
            Self::ABufferFixed { .. } | Self::ABufferExact { .. } => DumpLayout::CountersAndSlots,
            Self::LinkedLists { .. } => DumpLayout::LinkedLists,
            Self::LayerMajor { .. } => DumpLayout::LayerMajor,
            Self::KBuffer { .. } => DumpLayout::KBufferSlots,
            Self::Memory { .. } => DumpLayout::Memory,
        }
    }

    /// The header's `scheme` field: the catalog name of the scheme that heads the layout, or of
    /// the scheme itself where the layout names its scheme.
    #[must_use]
    pub fn name(&self) -> &'static str {
        self.scheme_name().name()
    }

    /// The catalog scheme the dump's words are rebuilt as.
    fn scheme_name(&self) -> SchemeName {
        match self {
            Self::LinkedLists { scheme, .. }
            | Self::KBuffer { scheme, .. }
            | Self::Memory { scheme, .. } => *scheme,
            _ => self.layout().scheme(),
        }
    }

    /// The header's `"layout"`: the description of the new layouts (`None` for the slot and
    /// A-buffer layouts, which their name fixes).
    #[must_use]
    pub fn spec(&self) -> Option<LayoutSpec> {
        match self {
            Self::LinkedLists { spec, .. } => Some(*spec),
            Self::LayerMajor { payload, .. } => Some(LayoutSpec::LayerMajor { payload: *payload }),
            Self::Memory { .. } => Some(LayoutSpec::Memory),
            _ => None,
        }
    }

    /// The header layout that writes this scheme's words in `encoding` (`None`: fragsim's own
    /// slot encoding), and the fields of `encoding` its layout has no place for (`order`,
    /// `payload`, `list numbering`), which it leaves out.
    #[must_use]
    pub fn spec_in(&self, encoding: &Encoding) -> (Option<LayoutSpec>, Vec<&'static str>) {
        let mut ignored = Vec::new();
        let mut ignore = |field: &'static str, given: bool| {
            if given {
                ignored.push(field);
            }
        };
        ignore(
            "list numbering",
            !matches!(self, Self::LinkedLists { .. }) && encoding.list_numbering.is_some(),
        );
        let spec = match self {
            Self::Mdts { .. }
            | Self::Mdts32 { .. }
            | Self::KBuffer { .. }
            | Self::ABufferFixed { .. }
            | Self::ABufferExact { .. } => {
                let keys = matches!(self, Self::Mdts32 { .. });
                ignore("payload", keys && encoding.payload.is_some());
                let payload = encoding.payload.filter(|_| !keys);
                let ranges = matches!(self, Self::ABufferExact { .. });
                ignore(
                    "order",
                    ranges && encoding.order == Some(SlotOrder::SlotMajor),
                );
                let order = encoding.order.filter(|_| !ranges).unwrap_or_default();
                (order != SlotOrder::PixelMajor || payload.is_some())
                    .then_some(LayoutSpec::Slots { order, payload })
            }
            Self::LinkedLists { spec, .. } => {
                ignore("order", encoding.order.is_some());
                match *spec {
                    LayoutSpec::LinkedList {
                        payload,
                        null,
                        node_base,
                    } => {
                        let own = ListNumbering { null, node_base };
                        let numbering = encoding.list_numbering.unwrap_or(own);
                        Some(LayoutSpec::LinkedList {
                            payload: encoding.payload.unwrap_or(payload),
                            null: numbering.null,
                            node_base: numbering.node_base,
                        })
                    }
                    // Lists always carry a list description (`DumpScheme::from_header`).
                    other => Some(other),
                }
            }
            Self::LayerMajor { payload, .. } => {
                ignore("order", encoding.order.is_some());
                Some(LayoutSpec::LayerMajor {
                    payload: encoding.payload.unwrap_or(*payload),
                })
            }
            Self::Memory { .. } => {
                ignore("order", encoding.order.is_some());
                ignore("payload", encoding.payload.is_some());
                Some(LayoutSpec::Memory)
            }
        };
        (spec, ignored)
    }

    /// The layout scheme `name`'s memory has after a run of it built with `sizes`, with `slots`
    /// slots per pixel (K, or the capacity) and the per-pixel `counts` of its counting pass,
    /// where one ran ([`NamedRun`](fragsim_capture::catalog::NamedRun) holds all three).
    ///
    /// # Errors
    /// A scheme the catalog gives no dump layout (the error lists those it gives one), storage
    /// sized by a counting pass without its counts, or a pool past 2^32 nodes.
    pub fn for_run(
        name: SchemeName,
        slots: u32,
        sizes: &Build<'_>,
        counts: Option<&[u32]>,
    ) -> Result<Self, DumpError> {
        let entry = name.entry();
        let Some(layout) = entry.dump else {
            let dumpable = CATALOG.iter().filter(|e| e.dump.is_some());
            return err(format!(
                "scheme {name} has no dump layout; these have one: {}",
                either(dumpable.map(|e| e.name))
            ));
        };
        Ok(match layout {
            DumpLayout::SlotArray(SlotWord::Fragment) => Self::Mdts {
                k: slots,
                direction: Direction::Ascending,
            },
            DumpLayout::SlotArray(SlotWord::FragmentPlusOne) => Self::Mdts {
                k: slots,
                direction: Direction::Descending,
            },
            DumpLayout::SlotArray(SlotWord::Key) => Self::Mdts32 { k: slots },
            DumpLayout::CountersAndSlots if entry.storage == Storage::Counted => {
                Self::ABufferExact {
                    counts: counts
                        .ok_or_else(|| DumpError(format!("{name} ran without its counting pass")))?
                        .to_vec(),
                    sorted: false,
                }
            }
            DumpLayout::CountersAndSlots => Self::ABufferFixed {
                capacity: slots,
                sorted: false,
            },
            DumpLayout::LinkedLists => Self::LinkedLists {
                scheme: name,
                k: sizes.k,
                pool: u32::try_from(sizes.pool)
                    .map_err(|_| DumpError(format!("{name}: a pool past 2^32 nodes")))?,
                spec: LayoutSpec::FRAGSIM_LISTS,
            },
            DumpLayout::LayerMajor => Self::LayerMajor {
                k: slots,
                payload: Payload::FRAGMENT,
            },
            DumpLayout::KBufferSlots => Self::KBuffer {
                scheme: name,
                k: slots,
            },
            DumpLayout::Memory => Self::Memory {
                scheme: name,
                k: sizes.k,
                capacity: sizes.capacity,
                layers: sizes.layers,
            },
        })
    }

    /// The header's `word` field (informative).
    pub(super) fn word(&self) -> &'static str {
        match self.layout() {
            DumpLayout::SlotArray(SlotWord::FragmentPlusOne) => "(key<<32|prim)+1",
            DumpLayout::SlotArray(SlotWord::Key) => "key",
            DumpLayout::SlotArray(SlotWord::Fragment)
            | DumpLayout::KBufferSlots
            | DumpLayout::CountersAndSlots => "key<<32|prim",
            // The description is in `"layout"`.
            DumpLayout::LinkedLists | DumpLayout::LayerMajor | DumpLayout::Memory => "",
        }
    }

    pub(super) fn names(&self) -> ArrayNames {
        match self.layout() {
            DumpLayout::SlotArray(SlotWord::Key) => ArrayNames {
                words32: Some("slots"),
                words64: None,
            },
            // A k-buffer's u32 words are its locks, which are not dumped (`Resolve`).
            DumpLayout::SlotArray(_) | DumpLayout::KBufferSlots => ArrayNames {
                words32: None,
                words64: Some("slots"),
            },
            DumpLayout::CountersAndSlots => ArrayNames {
                words32: Some("counters"),
                words64: Some("slots"),
            },
            DumpLayout::LayerMajor => ArrayNames {
                words32: Some("counters"),
                words64: Some("layers"),
            },
            // Linked lists split the u32 words three ways (`Dump::record`).
            DumpLayout::LinkedLists | DumpLayout::Memory => ArrayNames {
                words32: Some("words32"),
                words64: Some("words64"),
            },
        }
    }

    /// Builds fragsim's scheme for a viewport through the catalog entry that heads the layout
    /// (no memory cap: the words exist already).
    pub(super) fn with_scheme<V: SchemeVisitor>(
        &self,
        viewport: Viewport,
        visitor: V,
    ) -> Result<V::Output, DumpError> {
        let slots = match self {
            Self::Mdts { k, .. }
            | Self::Mdts32 { k }
            | Self::LayerMajor { k, .. }
            | Self::KBuffer { k, .. } => *k,
            Self::ABufferFixed { capacity, .. } => *capacity,
            Self::ABufferExact { .. } => 0,
            Self::LinkedLists { k, .. } => *k,
            Self::Memory { capacity, .. } => *capacity,
        };
        let mut build = Build::fixed(viewport, slots, slots, 1, u64::MAX);
        match *self {
            Self::LinkedLists { pool, .. } => build.pool = pool as usize,
            Self::Memory { k, layers, .. } => (build.k, build.layers) = (k, layers.max(1)),
            _ => {}
        }
        let mut scheme = self.scheme_name();
        if let Self::ABufferExact { counts, .. } = self {
            if counts.len() != viewport.pixels() {
                return err(format!(
                    "offsets cover {} pixels, the viewport has {}",
                    counts.len(),
                    viewport.pixels()
                ));
            }
            build.counts = Some(counts);
            scheme = SchemeName::AbufferExact;
        }
        Ok(scheme.build(&build, visitor)?)
    }

    /// Reads the scheme and its parameters from a header.
    ///
    /// # Errors
    /// An unknown scheme, or a missing or zero parameter.
    pub fn from_header(header: &Header, offsets: Option<&[u32]>) -> Result<Self, DumpError> {
        let k = || match header.k {
            Some(k) if k > 0 => Ok(k),
            _ => err(format!("scheme {} needs \"k\" ≥ 1", header.scheme)),
        };
        let Some(layout) = DumpLayout::named(&header.scheme) else {
            return err(format!(
                "unknown scheme {:?}: expected {}",
                header.scheme,
                either(DumpLayout::names())
            ));
        };
        let name = &header.scheme;
        let spec = match (header.layout, layout) {
            (None, DumpLayout::LinkedLists) => Some(LayoutSpec::FRAGSIM_LISTS),
            (None, DumpLayout::LayerMajor) => Some(LayoutSpec::FRAGSIM_LAYERS),
            (None, DumpLayout::Memory) => Some(LayoutSpec::Memory),
            (None, _) => None,
            (Some(spec), _) => {
                let expected = match layout {
                    DumpLayout::LinkedLists => "linked-list",
                    DumpLayout::LayerMajor => "layer-major",
                    DumpLayout::Memory => "memory",
                    DumpLayout::SlotArray(_)
                    | DumpLayout::KBufferSlots
                    | DumpLayout::CountersAndSlots => "slots",
                };
                if spec.kind() != expected {
                    return err(format!(
                        "scheme {name} dumps as {expected}, the header's layout is {}",
                        spec.kind()
                    ));
                }
                Some(spec)
            }
        };
        let scheme = SchemeName::from_name(name).unwrap_or(layout.scheme());
        match (layout, spec) {
            (DumpLayout::LinkedLists, Some(spec)) => {
                if let LayoutSpec::LinkedList { payload, .. } = spec {
                    payload.check()?;
                }
                let pool = match header.pool {
                    Some(pool) if (1..=u64::from(u32::MAX)).contains(&pool) => pool as u32,
                    _ => return err(format!("{name} needs \"pool\" of 1 to 2^32 − 1 nodes")),
                };
                return Ok(Self::LinkedLists {
                    scheme,
                    k: k()?,
                    pool,
                    spec,
                });
            }
            (DumpLayout::LayerMajor, Some(LayoutSpec::LayerMajor { payload })) => {
                payload.check()?;
                return Ok(Self::LayerMajor { k: k()?, payload });
            }
            (DumpLayout::Memory, _) => {
                // Each size defaults to 1, as a scheme that does not use it is built. A scheme
                // holds at least one word per slot or layer, so a size past the dump's words is
                // refused before the scheme is built (its storage would not fit a u64 count).
                let words = header.arrays.iter().try_fold(0u64, |sum, (name, spec)| {
                    sum.checked_add(super::header::elements(name, &spec.shape)?)
                        .ok_or_else(|| DumpError("the arrays' elements overflow 64 bits".into()))
                })?;
                let size = |field: &str, value: Option<u32>| match value {
                    Some(0) => err(format!("{name} \"{field}\" must be at least 1")),
                    Some(v) if u64::from(v) > words.max(1) => err(format!(
                        "{name} \"{field}\" {v} is more than the dump's {words} words"
                    )),
                    v => Ok(v.unwrap_or(1)),
                };
                return Ok(Self::Memory {
                    scheme,
                    k: size("k", header.k)?,
                    capacity: size("capacity", header.capacity)?,
                    layers: size("layers", header.layers)?,
                });
            }
            _ => {}
        }
        let slots = match layout {
            DumpLayout::SlotArray(SlotWord::Fragment) => Self::Mdts {
                k: k()?,
                direction: Direction::Ascending,
            },
            DumpLayout::SlotArray(SlotWord::FragmentPlusOne) => Self::Mdts {
                k: k()?,
                direction: Direction::Descending,
            },
            DumpLayout::SlotArray(SlotWord::Key) => Self::Mdts32 { k: k()? },
            DumpLayout::KBufferSlots => Self::KBuffer { scheme, k: k()? },
            DumpLayout::CountersAndSlots => match (header.capacity, offsets) {
                (Some(0), _) => return err(format!("{name} \"capacity\" must be at least 1")),
                (Some(capacity), _) => Self::ABufferFixed {
                    capacity,
                    sorted: header.sorted,
                },
                (None, Some(offsets)) => {
                    if offsets.first() != Some(&0) || offsets.windows(2).any(|w| w[0] > w[1]) {
                        return err(format!("{name} offsets must start at 0 and never decrease"));
                    }
                    Self::ABufferExact {
                        counts: offsets.windows(2).map(|w| w[1] - w[0]).collect(),
                        sorted: header.sorted,
                    }
                }
                (None, None) => {
                    return err(format!("{name} needs \"capacity\" or an \"offsets\" array"))
                }
            },
            DumpLayout::LinkedLists | DumpLayout::LayerMajor | DumpLayout::Memory => {
                unreachable!("handled above")
            }
        };
        if let Some(LayoutSpec::Slots { order, payload }) = spec {
            slots.check_slot_spec(order, payload)?;
        }
        Ok(slots)
    }

    /// Refuses a slot layout description that this slot scheme cannot have.
    fn check_slot_spec(&self, order: SlotOrder, payload: Option<Payload>) -> Result<(), DumpError> {
        let name = self.name();
        match (self, payload) {
            (Self::Mdts32 { .. }, Some(_)) => {
                return err(format!(
                    "{name} slots hold bare depth keys: its layout takes no \"payload\""
                ))
            }
            (_, Some(payload)) => payload.check()?,
            (_, None) => {}
        }
        if order == SlotOrder::SlotMajor && matches!(self, Self::ABufferExact { .. }) {
            return err(format!(
                "{name} with \"offsets\" keeps each pixel's slots together: \"order\" must be \
                 pixel-major"
            ));
        }
        Ok(())
    }
}

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

/// An A-buffer pixel's counter and how many slots it has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counter {
    /// The counter's value: how many fragments took a slot number.
    pub count: u32,
    /// The pixel's slots (the fixed capacity, or its share of exact storage).
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
    /// Words the layout leaves undefined and so were not checked: A-buffer slots past the counter
    /// when the header does not say they were filled, layers past a counter, pool nodes past the
    /// node counter, every word of a memory dump (its scheme's memory has no rules here).
    pub unchecked: u64,
    /// Linked lists: nodes the counter handed out that no list reaches (a lost node; its
    /// fragment is missing from the lists, which the comparison counts).
    pub unreachable: u64,
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
        let missing = |n: &str| DumpError(format!("missing array {n:?}"));
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
            }
            DumpScheme::Mdts32 { k } => {
                let slots = self.u32s("slots")?.ok_or_else(|| missing("slots"))?;
                let wide: Vec<u64> = slots.iter().map(|&w| u64::from(w)).collect();
                check_mdts(&mut check, &wide, *k as usize, u64::from(u32::MAX), |w| {
                    w as u32
                });
            }
            DumpScheme::ABufferFixed { .. } | DumpScheme::ABufferExact { .. } => {
                let counters = self.u32s("counters")?.ok_or_else(|| missing("counters"))?;
                let slots = self.u64s("slots")?.ok_or_else(|| missing("slots"))?;
                let at = pixel_slots(&scheme);
                let mut all = Vec::with_capacity(pixels);
                for (p, &count) in counters.iter().enumerate() {
                    let (first, capacity) = at(p);
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
                    all.push(Counter {
                        count,
                        capacity: capacity as u32,
                    });
                }
                check.counters = Some(all);
            }
            DumpScheme::LinkedLists { .. } | DumpScheme::LayerMajor { .. } => {
                let translated = self.translate(&scheme)?;
                check.corrupt = translated.corrupt;
                check.unchecked = translated.unchecked;
                check.unreachable = translated.unreachable;
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

/// Pixel `p`'s first slot and slot count in fragsim's pixel-major slot array of an MDTS or
/// A-buffer dump.
pub(super) fn pixel_slots(scheme: &DumpScheme) -> impl Fn(usize) -> (usize, usize) + '_ {
    let offsets: Vec<usize> = match scheme {
        DumpScheme::ABufferExact { counts, .. } => std::iter::once(0)
            .chain(counts.iter().scan(0usize, |sum, &c| {
                *sum += c as usize;
                Some(*sum)
            }))
            .collect(),
        _ => Vec::new(),
    };
    move |p| match scheme {
        DumpScheme::ABufferFixed {
            capacity: slots, ..
        }
        | DumpScheme::Mdts { k: slots, .. }
        | DumpScheme::KBuffer { k: slots, .. }
        | DumpScheme::Mdts32 { k: slots } => (p * *slots as usize, *slots as usize),
        _ => (offsets[p], offsets[p + 1] - offsets[p]),
    }
}

/// A-buffer lists as the GPU's sort kernel left them: `min(counter, capacity)` slots, unsorted.
pub(super) fn stored_lists(scheme: &DumpScheme, counters: &[u32], slots: &[u64]) -> Capture {
    let at = pixel_slots(scheme);
    let capacity = match scheme {
        DumpScheme::ABufferFixed { capacity, .. } => Capacity::PerPixel(*capacity),
        _ => Capacity::Unbounded,
    };
    let mut overflow = Vec::with_capacity(counters.len());
    let mut capture = Capture::with_pixels(
        counters.len(),
        Identity::KeyAndPrim,
        Keeps::All {
            capacity,
            overflow: Vec::new(),
        },
    );
    for (p, &count) in counters.iter().enumerate() {
        let (first, capacity) = at(p);
        let stored = (count as usize).min(capacity);
        capture.push_pixel(slots[first..first + stored].iter().copied());
        overflow.push(count - stored as u32);
    }
    capture.keeps = Keeps::All { capacity, overflow };
    capture
}

/// What a GPU's post-sort kernel does to an A-buffer's memory: each pixel's stored slots sorted.
pub(super) fn sort_abuffer_in_place(arrays: &mut BTreeMap<String, Words>, scheme: &DumpScheme) {
    let counters = match arrays.get("counters") {
        Some(Words::U32(c)) => c.clone(),
        _ => return,
    };
    let at = pixel_slots(scheme);
    if let Some(Words::U64(slots)) = arrays.get_mut("slots") {
        for (p, &count) in counters.iter().enumerate() {
            let (first, capacity) = at(p);
            slots[first..first + (count as usize).min(capacity)].sort_unstable();
        }
    }
}

impl Dump {
    /// How the dump's words store depth: its layout's payload's format, f32 keys where the
    /// layout has no payload (fragsim's own words, `mdts32`'s keys, a scheme's memory).
    #[must_use]
    pub fn depth_format(&self) -> DepthFormat {
        self.header
            .layout
            .and_then(|layout| layout.payload())
            .map_or(DepthFormat::F32, |payload| payload.depth)
    }

    /// An array's words widened to u64, which must have `dtype`.
    pub(super) fn widened(&self, name: &str, dtype: Dtype) -> Result<Vec<u64>, DumpError> {
        match (self.arrays.get(name), dtype) {
            (Some(Words::U32(w)), Dtype::U32) => Ok(w.iter().map(|&w| u64::from(w)).collect()),
            (Some(Words::U64(w)), Dtype::U64) => Ok(w.clone()),
            (Some(_), _) => err(format!("array {name:?} must be {dtype:?}, as its payload")),
            (None, _) => err(format!("missing array {name:?}")),
        }
    }

    /// A u32 array of `len` words.
    pub(super) fn u32s_of(&self, name: &str, len: usize) -> Result<&[u32], DumpError> {
        let words = self
            .u32s(name)?
            .ok_or_else(|| DumpError(format!("missing array {name:?}")))?;
        if words.len() == len {
            Ok(words)
        } else {
            err(format!(
                "array {name:?} has {} words, {len} expected",
                words.len()
            ))
        }
    }

    /// A linked-list or layer-major dump as fragsim's memory of its scheme.
    pub(super) fn translate(&self, scheme: &DumpScheme) -> Result<Translated, DumpError> {
        let pixels = self.viewport()?.pixels();
        match scheme {
            DumpScheme::LinkedLists {
                pool,
                spec:
                    LayoutSpec::LinkedList {
                        payload,
                        null,
                        node_base,
                    },
                ..
            } => {
                let pool = *pool as usize;
                let nodes = self.widened("nodes", payload.dtype)?;
                if nodes.len() != pool {
                    return err(format!(
                        "array \"nodes\" has {} words, the pool {pool}",
                        nodes.len()
                    ));
                }
                Ok(linked_lists(&ListArrays {
                    heads: self.u32s_of("heads", pixels)?,
                    next: self.u32s_of("next", pool)?,
                    nodes: &nodes,
                    counter: self.u32s_of("counter", 1)?[0],
                    null: *null,
                    node_base: *node_base,
                    payload: *payload,
                }))
            }
            DumpScheme::LayerMajor { k, payload } => {
                let layers = self.widened("layers", payload.dtype)?;
                if layers.len() as u64 != pixels as u64 * u64::from(*k) {
                    return err(format!(
                        "array \"layers\" has {} words, {k} layers of {pixels} pixels expected",
                        layers.len()
                    ));
                }
                Ok(layer_major(
                    self.u32s_of("counters", pixels)?,
                    &layers,
                    *k,
                    *payload,
                ))
            }
            _ => err(format!("{} dumps are read as they are", scheme.name())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dump::{FORMAT, VERSION};
    use crate::scene::SceneAndCamera;

    fn header(scheme: &str) -> Header {
        Header {
            format: FORMAT.into(),
            version: VERSION,
            producer: String::new(),
            scene: SceneAndCamera::named("quads:1", 0.0, 0.0),
            width: 1,
            height: 1,
            scheme: scheme.into(),
            k: Some(2),
            capacity: Some(2),
            sorted: false,
            filled: false,
            pool: Some(4),
            layers: None,
            layout: None,
            word: String::new(),
            // Memory dumps' sizes are bounded by their words.
            arrays: [(
                "words32".to_string(),
                crate::dump::ArraySpec {
                    file: "words32.u32".into(),
                    dtype: Dtype::U32,
                    shape: vec![8],
                },
            )]
            .into_iter()
            .collect(),
            extra: serde_json::Value::Null,
        }
    }

    #[test]
    fn header_names_are_the_catalogs_layouts() {
        for name in DumpLayout::names() {
            let scheme = DumpScheme::from_header(&header(name), None).unwrap();
            assert_eq!(scheme.name(), name);
            assert_eq!(Some(scheme.layout()), DumpLayout::named(name));
        }
        // A scheme that dumps under another's name is no header name of its own.
        let unknown = DumpScheme::from_header(&header("abuffer-exact"), None).unwrap_err();
        assert!(
            unknown.0.starts_with(
                "unknown scheme \"abuffer-exact\": expected mdts, mdts32, mdts-desc, "
            ) && !unknown.0.contains("abuffer-exact,"),
            "{unknown}"
        );
        // A layout description of another kind than the scheme's is refused.
        let mut lists = header("linked-list");
        lists.layout = Some(LayoutSpec::Memory);
        let refused = DumpScheme::from_header(&lists, None).unwrap_err();
        assert_eq!(
            refused.0,
            "scheme linked-list dumps as linked-list, the header's layout is memory"
        );
    }

    #[test]
    fn every_catalog_entry_with_a_layout_dumps_in_it() {
        let sizes = Build::fixed(Viewport::new(2, 1).unwrap(), 3, 3, 1, u64::MAX);
        for entry in CATALOG {
            let dumped = DumpScheme::for_run(entry.scheme, 3, &sizes, Some(&[1, 2]));
            match entry.dump {
                Some(layout) => assert_eq!(dumped.unwrap().layout(), layout, "{}", entry.name),
                None => {
                    let error = dumped.unwrap_err().0;
                    let expected = format!(
                        "scheme {} has no dump layout; these have one: mdts, ",
                        entry.name
                    );
                    assert!(error.starts_with(&expected), "{error}");
                }
            }
        }
        let exact =
            DumpScheme::for_run(SchemeName::AbufferExact, 1, &sizes, Some(&[1, 2])).unwrap();
        assert_eq!(
            exact,
            DumpScheme::ABufferExact {
                counts: vec![1, 2],
                sorted: false
            }
        );
        assert!(DumpScheme::for_run(SchemeName::AbufferExact, 1, &sizes, None).is_err());
        let fixed =
            DumpScheme::for_run(SchemeName::AbufferBitonic, 4, &sizes, Some(&[1, 2])).unwrap();
        assert_eq!(
            fixed,
            DumpScheme::ABufferFixed {
                capacity: 4,
                sorted: false
            }
        );
    }
}

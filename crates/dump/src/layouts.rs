//! The layouts a dump's words may have: which scheme's memory, with its parameters (the rules
//! every word of a layout obeys are checked in `word_check.rs`, [`Dump::check_words`]; its
//! arrays are read in `arrays.rs`).
//!
//! The layouts and the header names that select them are the catalog's
//! ([`fragsim_catalog::DumpLayout`]): a header's `scheme` is the name of the catalog entry
//! that heads a layout, and [`DumpScheme`] is that layout with the parameters its arrays need.

use fragsim_catalog::{Build, DumpLayout, SchemeName, SchemeVisitor, SlotWord, Storage, CATALOG};
use fragsim_raster::Viewport;

use crate::spec::{DepthFormat, Encoding, LayoutSpec, ListNumbering, Payload, SlotOrder};
use crate::{err, Dump, DumpError, Header};

/// Which way an MDTS slot array of fragment words is sorted, as its header's scheme names it:
/// the format's own word for what the scheme's `atomicMin` or `atomicMax` left, so that the
/// format names no scheme's internals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// `mdts`: ascending words `key << 32 | prim`, empty = all ones (the `K` nearest).
    Ascending,
    /// `mdts-desc`: descending words `(key << 32 | prim) + 1`, empty = 0 (the `K` farthest).
    Descending,
}

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
    /// where one ran ([`NamedRun`](fragsim_catalog::NamedRun) holds all three).
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
            DumpLayout::MaskedNodes => return err(masked_apart(name.name())),
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
                        .ok_or_else(|| {
                            DumpError::Invalid(format!("{name} ran without its counting pass"))
                        })?
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
                    .map_err(|_| DumpError::Invalid(format!("{name}: a pool past 2^32 nodes")))?,
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
            // The description is in `"layout"` (no dump scheme is masked: `masked_apart`).
            DumpLayout::LinkedLists
            | DumpLayout::LayerMajor
            | DumpLayout::Memory
            | DumpLayout::MaskedNodes => "",
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
            // Linked lists split the u32 words three ways (`Dump::record`); no dump scheme is
            // masked (`masked_apart`).
            DumpLayout::LinkedLists | DumpLayout::Memory | DumpLayout::MaskedNodes => ArrayNames {
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
                    | DumpLayout::CountersAndSlots
                    | DumpLayout::MaskedNodes => "slots",
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
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "the guard holds the pool to 1..=u32::MAX"
                )]
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
                let words = header
                    .arrays
                    .iter()
                    .try_fold(0_u64, |sum, (array, array_spec)| {
                        sum.checked_add(super::header::elements(array, &array_spec.shape)?)
                            .ok_or_else(|| {
                                DumpError::Invalid("the arrays' elements overflow 64 bits".into())
                            })
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
            DumpLayout::MaskedNodes => return err(masked_apart(name)),
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

    /// Pixel `p`'s first slot and slot count in fragsim's pixel-major slot array of an MDTS or
    /// A-buffer dump.
    pub(super) fn pixel_slots(&self) -> impl Fn(usize) -> (usize, usize) + '_ {
        let offsets: Vec<usize> = match self {
            Self::ABufferExact { counts, .. } => std::iter::once(0)
                .chain(counts.iter().scan(0_usize, |sum, &c| {
                    *sum += c as usize;
                    Some(*sum)
                }))
                .collect(),
            _ => Vec::new(),
        };
        move |p| match self {
            Self::ABufferFixed {
                capacity: slots, ..
            }
            | Self::Mdts { k: slots, .. }
            | Self::KBuffer { k: slots, .. }
            | Self::Mdts32 { k: slots } => (p * *slots as usize, *slots as usize),
            _ => (offsets[p], offsets[p + 1] - offsets[p]),
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
}

#[cfg(test)]
mod tests;

/// Why a masked-node dump has no [`DumpScheme`]: its nodes carry masks, and `masked.rs` reads,
/// checks and writes them apart from the layouts of fragments.
fn masked_apart(name: &str) -> String {
    format!("{name} dumps masked nodes, read and written apart from the layouts of fragments")
}

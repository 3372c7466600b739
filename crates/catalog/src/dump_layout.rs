//! What a scheme's memory looks like in a dump (`docs/dump-format.md`): the layout each catalog
//! entry states, so that the dump reader and writer take the schemes they know, and the names a
//! dump header may carry, from the catalog. Every entry has one.

use super::{SchemeName, CATALOG};

/// How a scheme's memory is laid out in a dump.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DumpLayout {
    /// `slots` `[pixels, k]`: each pixel's `k` slots of one word each, pixel-major, full slots
    /// first (MDTS; the z-buffer is its `k` = 1; loop64 keeps the same array slot-major, the
    /// order a header may describe, with the same promise, the K nearest).
    SlotArray(SlotWord),
    /// The A-buffer's `counters` `[pixels]` (fetch-and-add counts, u32) and `slots` of fragment
    /// words (u64): `[pixels, capacity]` for fixed storage, or `[total]` beside `offsets`
    /// `[pixels + 1]` for storage sized by a counting pass ([`super::Storage::Counted`]).
    CountersAndSlots,
    /// Per-pixel linked lists: `heads` `[pixels]`, the pool's `next` and `nodes` `[pool]` and
    /// its `counter` `[1]`, the terminator and the first node's number in the header. Each entry
    /// with it dumps under its own name: the words are the same, the resolves differ.
    LinkedLists,
    /// Layer-major layers (Bevy's `layers[layer * pixels + pixel]`) beside per-pixel `counters`.
    LayerMajor,
    /// A k-buffer's `slots` `[pixels, k]`: MDTS's slot array of fragment words
    /// ([`SlotWord::Fragment`]), which is what its K render targets or slot arrays hold, without
    /// the scheme's u32 words (locks, tickets, sections done), which its resolve never reads.
    /// Each entry dumps under its own name, so that the reader holds the words to the scheme's
    /// own promise (the K nearest; `kbuffer-interlock-ordered-first` the first K in primitive
    /// order) and decodes them with its own resolve (which keeps the gaps, duplicates and
    /// disorder a hazard leaves, for the diff to see).
    KBufferSlots,
    /// The masked-node A-buffer's `counters` `[pixels]`, node words `[pixels, capacity]` and
    /// their coverage `masks` `[pixels, capacity]`: the layout of `fragsim_dump`'s masked-node
    /// dumps, judged node by node, masks included.
    MaskedNodes,
    /// The scheme's own words as they are after its last pass (`words32`, `words64`), decoded by
    /// its own resolve: schemes whose memory is no list per pixel (bucket histograms, peeling's
    /// layer records, stencil-routed samples). Each entry dumps under its own name.
    Memory,
}

/// The word a [`DumpLayout::SlotArray`] slot holds, and so its order and its empty marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlotWord {
    /// u64 `key << 32 | prim`, ascending (`atomicMin`); empty: all ones.
    Fragment,
    /// u64 `(key << 32 | prim) + 1`, descending (`atomicMax`); empty: 0.
    FragmentPlusOne,
    /// u32 depth key, ascending (FreePipe's Table 1); empty: all ones.
    Key,
}

impl DumpLayout {
    /// Whether a dump of this layout carries the name of the scheme that wrote it (its words
    /// need that scheme's own resolve) rather than the name of the layout's first entry.
    #[must_use]
    pub fn names_its_scheme(self) -> bool {
        matches!(self, Self::LinkedLists | Self::KBufferSlots | Self::Memory)
    }

    /// The scheme whose name a dump of this layout carries in its header, for a layout that
    /// does not name its scheme ([`DumpLayout::names_its_scheme`]): the first catalog entry with
    /// the layout. Other entries with it leave the same words (`abuffer-bitonic` and
    /// `abuffer-exact` dump as `abuffer`, `mdts-probe`, `zbuffer` and `loop64` as `mdts`), so a
    /// reader rebuilds them as that one.
    ///
    /// # Panics
    /// If no catalog entry has the layout (a unit test checks that every layout has one).
    #[must_use]
    pub fn scheme(self) -> SchemeName {
        CATALOG
            .iter()
            .find(|e| e.dump == Some(self))
            .map(|e| e.scheme)
            .expect("every dump layout is some catalog entry's")
    }

    /// The scheme whose name a dump of `scheme`'s memory carries (`None`: it has no layout).
    #[must_use]
    pub fn header_scheme(scheme: SchemeName) -> Option<SchemeName> {
        let layout = scheme.entry().dump?;
        Some(if layout.names_its_scheme() {
            scheme
        } else {
            layout.scheme()
        })
    }

    /// The layout a dump header's `scheme` names: `name` must be the catalog name that a dump of
    /// the layout carries ([`DumpLayout::header_scheme`]).
    #[must_use]
    pub fn named(name: &str) -> Option<Self> {
        let scheme = SchemeName::from_name(name)?;
        (Self::header_scheme(scheme)? == scheme).then(|| scheme.entry().dump)?
    }

    /// The names a dump header may carry, in catalog order.
    pub fn names() -> impl Iterator<Item = &'static str> {
        CATALOG
            .iter()
            .filter(|e| Self::header_scheme(e.scheme) == Some(e.scheme))
            .map(|e| e.name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_layout_is_named_by_the_entry_that_heads_it() {
        let layouts = [
            DumpLayout::SlotArray(SlotWord::Fragment),
            DumpLayout::SlotArray(SlotWord::FragmentPlusOne),
            DumpLayout::SlotArray(SlotWord::Key),
            DumpLayout::CountersAndSlots,
            DumpLayout::LinkedLists,
            DumpLayout::LayerMajor,
            DumpLayout::KBufferSlots,
            DumpLayout::MaskedNodes,
            DumpLayout::Memory,
        ];
        for layout in layouts {
            let name = layout.scheme().name();
            assert_eq!(DumpLayout::named(name), Some(layout), "{name}");
        }
        // Every entry dumps, and each header name is a catalog entry's.
        assert!(CATALOG.iter().all(|e| e.dump.is_some()));
        let own = CATALOG
            .iter()
            .filter(|e| e.dump.is_some_and(DumpLayout::names_its_scheme))
            .count();
        assert_eq!(DumpLayout::names().count(), 6 + own);
    }

    #[test]
    fn schemes_that_share_a_layout_dump_under_its_heads_name() {
        for entry in CATALOG {
            match entry.dump {
                Some(layout) if !layout.names_its_scheme() && layout.scheme() != entry.scheme => {
                    assert_eq!(DumpLayout::named(entry.name), None, "{}", entry.name);
                    assert_eq!(DumpLayout::named(layout.scheme().name()), Some(layout));
                }
                Some(layout) => assert_eq!(DumpLayout::named(entry.name), Some(layout)),
                None => assert_eq!(DumpLayout::named(entry.name), None, "{}", entry.name),
            }
        }
        assert_eq!(DumpLayout::named("no-such-scheme"), None);
    }
}

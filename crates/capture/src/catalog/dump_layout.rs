//! What a scheme's memory looks like in a dump (`docs/dump-format.md`): the layout each catalog
//! entry states, so that the dump reader and writer take the schemes they know, and the names a
//! dump header may carry, from the catalog.

use super::{SchemeName, CATALOG};

/// How a scheme's memory is laid out in a dump.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DumpLayout {
    /// `slots` `[pixels, k]`: each pixel's `k` slots of one word each, pixel-major, full slots
    /// first (MDTS).
    SlotArray(SlotWord),
    /// The A-buffer's `counters` `[pixels]` (fetch-and-add counts, u32) and `slots` of fragment
    /// words (u64): `[pixels, capacity]` for fixed storage, or `[total]` beside `offsets`
    /// `[pixels + 1]` for storage sized by a counting pass ([`super::Storage::Counted`]).
    CountersAndSlots,
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
    /// The scheme whose name a dump of this layout carries in its header: the first catalog entry
    /// with the layout. Other entries with it leave the same words (`abuffer-bitonic` and
    /// `abuffer-exact` dump as `abuffer`), so a reader rebuilds them as that one.
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

    /// The layout a dump header's `scheme` names: `name` must be the catalog name of the scheme
    /// that heads a layout ([`DumpLayout::scheme`]).
    #[must_use]
    pub fn named(name: &str) -> Option<DumpLayout> {
        let layout = SchemeName::from_name(name)?.entry().dump?;
        (layout.scheme().name() == name).then_some(layout)
    }

    /// The names a dump header may carry, in catalog order.
    pub fn names() -> impl Iterator<Item = &'static str> {
        CATALOG
            .iter()
            .filter(|e| e.dump.is_some_and(|layout| layout.scheme() == e.scheme))
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
        ];
        for layout in layouts {
            let name = layout.scheme().name();
            assert_eq!(DumpLayout::named(name), Some(layout), "{name}");
        }
        // Four layouts, four header names: the format's (docs/dump-format.md).
        assert_eq!(DumpLayout::names().count(), layouts.len());
    }

    #[test]
    fn schemes_that_share_a_layout_dump_under_its_heads_name() {
        for entry in CATALOG {
            match entry.dump {
                Some(layout) if layout.scheme() != entry.scheme => {
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

//! Linked-list and layer-major dumps turned into fragsim's memory of the scheme, every word
//! checked on the way: the node numbers and payload packing a header describes
//! ([`LayoutSpec`](super::LayoutSpec)) become fragsim's (node 0 ends a list, nodes from 1,
//! `depth_key << 32 | prim`), so that the scheme's own resolve decodes them.
//!
//! **Guarantee**: the words handed to the resolve form well-formed lists whatever the dump
//! holds. A list is walked from its head with one visited mark per pool node, so the walk of
//! every list together takes at most `pool + pixels` steps; a link that leaves the pool, points
//! at a node the counter never handed out, or reaches a node already visited (a cycle, or two
//! lists sharing a node) is cut there and named a [`CorruptWord`] of its pixel.

use crate::slots::words_of;
use crate::spec::{LayoutSpec, ListNumbering, Payload};
use crate::word_check::{outside_fields, CorruptWord, Corruption};
use crate::{err, Dump, DumpError, Words};

/// Fragsim's memory of a scheme built from a dump's arrays, and what the translation found.
#[derive(Debug, Default)]
pub(super) struct Translated {
    /// The scheme's u32 words.
    pub(super) words32: Vec<u32>,
    /// The scheme's u64 words.
    pub(super) words64: Vec<u64>,
    /// Per pixel, its corrupt words.
    pub(super) corrupt: Vec<Vec<CorruptWord>>,
    /// Words of room no counter handed out, so not read ([`super::WordCheck::spare`]).
    pub(super) spare: u64,
    /// Linked lists: nodes the counter handed out that no list reaches.
    pub(super) unreachable: u64,
}

/// A linked-list dump's arrays, as the header describes them.
pub(super) struct ListArrays<'a> {
    pub(super) heads: &'a [u32],
    pub(super) next: &'a [u32],
    /// The node payloads, widened to u64.
    pub(super) nodes: &'a [u64],
    pub(super) counter: u32,
    pub(super) null: u32,
    pub(super) node_base: u32,
    pub(super) payload: Payload,
}

/// fragsim's linked-list memory (`heads`, the counter, the `next` of nodes `1..=pool`; the node
/// words) from a dump's lists, each cut at its first bad link.
pub(super) fn linked_lists(lists: &ListArrays<'_>) -> Translated {
    let pixels = lists.heads.len();
    let pool = lists.next.len();
    let allocated = (lists.counter as usize).min(pool);
    let mut out = Translated {
        words32: vec![0; pixels + 1 + pool],
        words64: vec![u64::MAX; pool],
        corrupt: vec![Vec::new(); pixels],
        ..Translated::default()
    };
    out.words32[pixels] = lists.counter;
    let mut visited = vec![false; pool];
    let mut reached = 0_u64;
    for (p, &head) in lists.heads.iter().enumerate() {
        // Where the link to the current node goes in fragsim's memory: the head, then the
        // previous node's `next`.
        let mut link = p;
        let mut node = head;
        let mut slot = 0;
        while node != lists.null {
            let index = node.checked_sub(lists.node_base).map(|i| i as usize);
            let why = match index {
                Some(i) if i < allocated && visited[i] => Some(Corruption::Revisited),
                Some(i) if i < allocated => None,
                Some(i) if i < pool => Some(Corruption::Unallocated),
                _ => Some(Corruption::OutOfPool),
            };
            if let Some(why) = why {
                out.corrupt[p].push(CorruptWord {
                    pixel: p,
                    slot,
                    word: u64::from(node),
                    why,
                });
                break;
            }
            let i = index.unwrap_or_default();
            visited[i] = true;
            reached += 1;
            #[expect(
                clippy::cast_possible_truncation,
                reason = "node indices are below the pool, at most 2^32 − 1 (the header's \"pool\")"
            )]
            let number = i as u32 + 1;
            out.words32[link] = number;
            let (fragment, payload_why) = read_payload(lists.payload, lists.nodes[i]);
            if let Some(payload_why) = payload_why {
                out.corrupt[p].push(CorruptWord {
                    pixel: p,
                    slot,
                    word: lists.nodes[i],
                    why: payload_why,
                });
            }
            out.words64[i] = fragment;
            link = pixels + 1 + i;
            node = lists.next[i];
            slot += 1;
        }
    }
    out.unreachable = allocated as u64 - reached;
    // Nodes past the counter hold whatever the pool held: no list may reach them.
    out.spare = 2 * (pool - allocated) as u64;
    out
}

/// The fragment word a payload word read as a fragment holds, and what is wrong with it: a depth
/// key above 1.0's, or a bit set outside the payload's fields.
fn read_payload(payload: Payload, word: u64) -> (u64, Option<Corruption>) {
    let (fragment, possible) = payload.fragment(word);
    let why = if !possible {
        Some(Corruption::ImpossibleKey)
    } else if word & outside_fields(&payload) != 0 {
        Some(Corruption::OutsideFields)
    } else {
        None
    };
    (fragment, why)
}

/// fragsim's layer-counter memory (counters, then the layers layer-major) from a layer-major
/// dump: `k` layers of `counters.len()` pixels in `layers`, widened to u64.
pub(super) fn layer_major(
    counters: &[u32],
    layers: &[u64],
    k: u32,
    payload: Payload,
) -> Translated {
    let pixels = counters.len();
    let mut out = Translated {
        words32: counters.to_vec(),
        words64: layers.iter().map(|&w| payload.fragment(w).0).collect(),
        corrupt: vec![Vec::new(); pixels],
        ..Translated::default()
    };
    for (p, &count) in counters.iter().enumerate() {
        // Bevy's clamp stores `k` back over any counter that passed it, and the last operation
        // on a counter is that store or an increment below `k`: a final counter above `k` is no
        // run's.
        if count > k {
            out.corrupt[p].push(CorruptWord {
                pixel: p,
                slot: k as usize,
                word: u64::from(count),
                why: Corruption::CounterPastStorage,
            });
        }
        let stored = count.min(k) as usize;
        for layer in 0..stored {
            let word = layers[layer * pixels + p];
            if let (_, Some(why)) = read_payload(payload, word) {
                out.corrupt[p].push(CorruptWord {
                    pixel: p,
                    slot: layer,
                    word,
                    why,
                });
            }
        }
        out.spare += u64::from(k) - stored as u64;
    }
    out
}

impl Dump {
    /// This linked-list dump (fragsim's numbering and words, as [`Dump::record`] writes it) with
    /// its nodes numbered as `numbering` and packed as `payload`.
    ///
    /// # Errors
    /// A terminator that is some node's number, node numbers past 2^32, or a primitive id that
    /// does not fit the payload.
    pub(super) fn lists_as(
        &self,
        payload: Payload,
        numbering: ListNumbering,
    ) -> Result<Self, DumpError> {
        let ListNumbering { null, node_base } = numbering;
        let pool = self.header.pool.unwrap_or_default();
        let numbers = u64::from(node_base)..u64::from(node_base) + pool;
        if numbers.end > 1 << 32 {
            return err(format!(
                "list numbering: {pool} nodes from \"node_base\" {node_base} pass 2^32"
            ));
        }
        if numbers.contains(&u64::from(null)) {
            return err(format!(
                "list numbering: \"null\" {null} is a node's number ({node_base} to {})",
                numbers.end - 1
            ));
        }
        // fragsim's link 0 ends a list and link `n` is node `n − 1`.
        let renumber = |links: &[u32]| -> Words {
            Words::U32(
                links
                    .iter()
                    .map(|&link| link.checked_sub(1).map_or(null, |i| i + node_base))
                    .collect(),
            )
        };
        let pixels = self.viewport()?.pixels();
        let heads = renumber(self.u32s_of("heads", pixels)?);
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the pool fits u32: node numbers past 2^32 are refused above"
        )]
        let next = renumber(self.u32s_of("next", pool as usize)?);
        let nodes = self
            .widened("nodes", Payload::FRAGMENT.dtype)?
            .into_iter()
            .map(|word| payload.pack(word))
            .collect::<Result<Vec<u64>, DumpError>>()?;
        let mut dump = self.clone();
        dump.header.layout = Some(LayoutSpec::LinkedList {
            payload,
            null,
            node_base,
        });
        dump.set_array("heads", heads, vec![pixels as u64]);
        dump.set_array("next", next, vec![pool]);
        dump.set_array("nodes", words_of(payload.dtype, nodes), vec![pool]);
        Ok(dump)
    }

    /// This layer-major dump (fragsim's words) with its layers packed as `payload`.
    ///
    /// # Errors
    /// A primitive id that does not fit the payload.
    pub(super) fn layers_as(&self, payload: Payload) -> Result<Self, DumpError> {
        let layers = self
            .widened("layers", Payload::FRAGMENT.dtype)?
            .into_iter()
            .map(|word| payload.pack(word))
            .collect::<Result<Vec<u64>, DumpError>>()?;
        let shape = self.shape_of("layers");
        let mut dump = self.clone();
        dump.header.layout = Some(LayoutSpec::LayerMajor { payload });
        dump.set_array("layers", words_of(payload.dtype, layers), shape);
        Ok(dump)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lists<'a>(
        heads: &'a [u32],
        next: &'a [u32],
        nodes: &'a [u64],
        counter: u32,
    ) -> ListArrays<'a> {
        ListArrays {
            heads,
            next,
            nodes,
            counter,
            null: u32::MAX,
            node_base: 0,
            payload: Payload::FRAGMENT,
        }
    }

    #[test]
    fn a_cycle_is_cut_and_named_in_one_walk_of_the_pool() {
        // Pixel 0: node 0 → 1 → 0 → …; pixel 1: empty.
        let got = linked_lists(&lists(&[0, u32::MAX], &[1, 0], &[5, 6], 2));
        assert_eq!(got.corrupt[0].len(), 1);
        assert_eq!(got.corrupt[0][0].why, Corruption::Revisited);
        assert_eq!(got.corrupt[0][0].slot, 2);
        // fragsim's memory: head → node 1 → node 2 → end.
        assert_eq!(got.words32, vec![1, 0, 2, 2, 0]);
        assert_eq!(got.unreachable, 0);
    }

    #[test]
    fn links_out_of_the_pool_or_past_the_counter_are_cut() {
        let got = linked_lists(&lists(&[1, 7], &[u32::MAX, u32::MAX], &[5, 6], 1));
        assert_eq!(got.corrupt[0][0].why, Corruption::Unallocated);
        assert_eq!(got.corrupt[1][0].why, Corruption::OutOfPool);
        // Node 0 was handed out and no list reaches it.
        assert_eq!(got.unreachable, 1);
    }

    #[test]
    fn a_layer_counter_past_its_layers_is_corrupt() {
        let got = layer_major(&[3, 1], &[0, 0, 0, 0], 2, Payload::FRAGMENT);
        assert_eq!(got.corrupt[0][0].why, Corruption::CounterPastStorage);
        assert!(got.corrupt[1].is_empty());
        assert_eq!(got.spare, 1);
    }
}

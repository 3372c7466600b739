//! A layout's arrays as the decoders read them: each pixel's run of a pixel-major slot array,
//! A-buffer lists as stored (and as a GPU's sort kernel leaves them), an array of a required
//! type or length, and linked-list and layer-major arrays translated into fragsim's lists.

use std::collections::BTreeMap;

use fragsim_capture::{Capacity, Capture, Identity, Keeps};

use crate::layouts::DumpScheme;
use crate::lists::{layer_major, linked_lists, ListArrays, Translated};
use crate::spec::LayoutSpec;
use crate::{err, Dtype, Dump, DumpError, Words};

/// A-buffer lists as the GPU's sort kernel left them: `min(counter, capacity)` slots, unsorted.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a pixel's stored slots are at most its counter, a u32"
)]
pub(super) fn stored_lists(scheme: &DumpScheme, counters: &[u32], slots: &[u64]) -> Capture {
    let at = scheme.pixel_slots();
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
        let (first, slot_count) = at(p);
        let stored = (count as usize).min(slot_count);
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
    let at = scheme.pixel_slots();
    if let Some(Words::U64(slots)) = arrays.get_mut("slots") {
        for (p, &count) in counters.iter().enumerate() {
            let (first, capacity) = at(p);
            slots[first..first + (count as usize).min(capacity)].sort_unstable();
        }
    }
}

impl Dump {
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
            .ok_or_else(|| DumpError::Invalid(format!("missing array {name:?}")))?;
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

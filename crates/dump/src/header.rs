//! A dump's JSON header (`dump.json`), its array specs and the words of one array file, with the
//! checks every header passes before its arrays are read or written.

use std::collections::BTreeMap;

use fragsim_raster::Viewport;
use serde::{Deserialize, Serialize};

use crate::{err, DumpError, LayoutSpec};
use fragsim_catalog::DumpLayout;
use fragsim_raster::scene_spec::SceneSpec;

/// The element type of an array file: always little-endian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Dtype {
    /// 32-bit unsigned (NumPy `<u4`).
    #[serde(rename = "u32", alias = "<u4", alias = "uint32")]
    U32,
    /// 64-bit unsigned (NumPy `<u8`).
    #[serde(rename = "u64", alias = "<u8", alias = "uint64")]
    U64,
}

impl Dtype {
    /// The element's width in bits.
    #[must_use]
    pub fn bits(self) -> u32 {
        match self {
            Self::U32 => 32,
            Self::U64 => 64,
        }
    }
}

/// Where an array lives and what it holds. An unknown field is refused by name.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArraySpec {
    /// File name, relative to the dump directory.
    pub file: String,
    /// Element type.
    pub dtype: Dtype,
    /// Dimensions, row-major; the file holds their product of elements and nothing else.
    pub shape: Vec<u64>,
}

/// The JSON header of a dump (`dump.json`). An unknown field is refused by name, so that a
/// misspelt one (`"capacty"`) cannot silently change how the dump is judged; anything else the
/// producer keeps goes in [`Header::extra`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Always [`FORMAT`](super::FORMAT).
    pub format: String,
    /// [`VERSION`](super::VERSION).
    pub version: u32,
    /// Who wrote it (`fragsim 0.1.0`, `fragsim-cuda`, …): informative.
    #[serde(default)]
    pub producer: String,
    /// The scene and camera.
    pub scene: SceneSpec,
    /// Viewport width in pixels.
    pub width: u32,
    /// Viewport height in pixels.
    pub height: u32,
    /// The layout's name: the catalog name of the scheme that heads it (`docs/dump-format.md`,
    /// [`DumpLayout::scheme`](fragsim_catalog::DumpLayout::scheme)).
    pub scheme: String,
    /// MDTS slots per pixel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<u32>,
    /// A-buffer slots per pixel (fixed storage); absent with an `offsets` array (exact storage).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capacity: Option<u32>,
    /// A-buffer: whether each pixel's slots were sorted in place (the post-sort kernel ran).
    #[serde(default)]
    pub sorted: bool,
    /// A-buffer: whether every slot was set to the empty marker (`u64::MAX`) before the pass, so
    /// that a slot past its pixel's counter holding anything else is a stray write. Without it
    /// those slots may hold anything (FreePipe leaves them uninitialised) and are not checked.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub filled: bool,
    /// Linked lists: nodes in the pool (`next` and `nodes` hold this many).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pool: Option<u64>,
    /// Memory dumps of schemes that record every layer (peeling, ADP, the multi-pass k-buffer):
    /// the scene's maximum depth complexity they were sized to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers: Option<u32>,
    /// How the arrays hold the scheme's memory (linked lists, layer-major layers, a scheme's own
    /// memory: [`LayoutSpec`]); absent for the slot and A-buffer layouts, which `scheme` fixes,
    /// and in headers written before it, which read as fragsim's own encoding.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layout: Option<LayoutSpec>,
    /// The word layout, informative: `key<<32|prim`, `key`, or `(key<<32|prim)+1`.
    #[serde(default)]
    pub word: String,
    /// The arrays by name: `slots`, and for the A-buffer `counters` and maybe `offsets`.
    pub arrays: BTreeMap<String, ArraySpec>,
    /// Anything else the producer wants to keep (timings, device): the one field whose contents
    /// the reader ignores.
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub extra: serde_json::Value,
}

impl Header {
    /// The render target in pixels: `width` × `height`.
    ///
    /// # Errors
    /// A zero or oversized side.
    pub fn pixel_viewport(&self) -> Result<Viewport, DumpError> {
        Viewport::new(self.width, self.height).map_err(|e| DumpError::Invalid(e.to_string()))
    }

    /// Samples a pixel (`scene.conventions.samples`, 1 when absent).
    ///
    /// # Errors
    /// A count other than 1, 2, 4, 8 or 16, naming the field.
    pub fn samples(&self) -> Result<u32, DumpError> {
        self.scene
            .conventions
            .pattern()
            .map_err(|e| DumpError::Invalid(e.to_string()))?;
        Ok(self.scene.conventions.samples)
    }

    /// The sample-expanded framebuffer a per-sample layout indexes (`docs/semantics.md`,
    /// "Multisampling"): `width · samples` columns, sample `s` of pixel `p` at `p · samples + s`;
    /// at one sample, the viewport itself.
    ///
    /// # Errors
    /// A bad viewport or sample count, or an expanded width past the largest side.
    pub fn framebuffer(&self) -> Result<Viewport, DumpError> {
        Self::framebuffer_of(&self.scene, self.pixel_viewport()?)
    }

    /// The sample-expanded framebuffer of `pixels` at `scene`'s sample count.
    pub(super) fn framebuffer_of(
        scene: &SceneSpec,
        pixels: Viewport,
    ) -> Result<Viewport, DumpError> {
        let pattern = scene
            .conventions
            .pattern()
            .map_err(|e| DumpError::Invalid(e.to_string()))?;
        match pattern {
            Some(pattern) => pattern
                .expand(pixels)
                .map_err(|e| DumpError::Invalid(e.to_string())),
            None => Ok(pixels),
        }
    }
}

impl Header {
    /// Refuses the fields that contradict one another or the layout, before any array is read,
    /// each by name: a header cannot say two things and have one of them silently win.
    ///
    /// - An array the layout does not use (`junk`, or `heads` on an `mdts` dump): its words would
    ///   be read and never judged.
    /// - An A-buffer's `capacity` beside an `offsets` array: fixed storage or storage sized by a
    ///   counting pass, not both.
    /// - A scene with both `name` and `mesh`.
    /// - Linked-list numbering out of range: nodes numbered past 2^32 (`node_base + pool`), or a
    ///   `null` that is some node's number, which would end a list at that node.
    ///
    /// A scheme this format does not name is left to decoding, which lists those it does.
    ///
    /// # Errors
    /// The first contradiction, naming the fields.
    pub(super) fn check_fields(&self) -> Result<(), DumpError> {
        if let (Some(name), Some(mesh)) = (&self.scene.name, &self.scene.mesh) {
            return err(format!(
                "scene: both \"name\" {name:?} and \"mesh\" {mesh:?}; a scene is a named scene \
                 or a mesh file, not both"
            ));
        }
        let layout = DumpLayout::named(&self.scheme);
        let used: &[&str] = match layout {
            None => return Ok(()),
            Some(DumpLayout::MaskedNodes) => &["counters", "nodes", "masks"],
            Some(DumpLayout::SlotArray(_) | DumpLayout::KBufferSlots) => &["slots"],
            Some(DumpLayout::CountersAndSlots) => &["counters", "slots", "offsets"],
            Some(DumpLayout::LinkedLists) => &["heads", "next", "nodes", "counter"],
            Some(DumpLayout::LayerMajor) => &["counters", "layers"],
            Some(DumpLayout::Memory) => &["words32", "words64"],
        };
        if let Some(unused) = self
            .arrays
            .keys()
            .find(|name| !used.contains(&name.as_str()))
        {
            return err(format!(
                "array {unused:?}: a {} dump has no such array (its arrays: {})",
                self.scheme,
                used.join(", ")
            ));
        }
        if layout == Some(DumpLayout::CountersAndSlots) && self.arrays.contains_key("offsets") {
            if let Some(capacity) = self.capacity {
                return err(format!(
                    "\"capacity\" {capacity} beside an \"offsets\" array: an A-buffer has fixed \
                     storage (capacity) or storage sized by its counting pass (offsets), not both"
                ));
            }
        }
        if let (
            Some(LayoutSpec::LinkedList {
                null, node_base, ..
            }),
            Some(pool),
        ) = (self.layout, self.pool)
        {
            let end = u64::from(node_base) + pool;
            if end > 1 << 32 {
                return err(format!(
                    "layout: {pool} nodes (\"pool\") numbered from \"node_base\" {node_base} pass \
                     2^32: node numbers are u32"
                ));
            }
            if (u64::from(node_base)..end).contains(&u64::from(null)) {
                return err(format!(
                    "layout: \"null\" {null} is the number of a node (\"node_base\" {node_base} to \
                     {}): a list would end at that node",
                    end - 1
                ));
            }
        }
        Ok(())
    }
}

/// The contents of one array file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Words {
    /// `u32` elements.
    U32(Vec<u32>),
    /// `u64` elements.
    U64(Vec<u64>),
}

impl Words {
    pub(super) fn dtype(&self) -> Dtype {
        match self {
            Self::U32(_) => Dtype::U32,
            Self::U64(_) => Dtype::U64,
        }
    }

    pub(super) fn len(&self) -> usize {
        match self {
            Self::U32(w) => w.len(),
            Self::U64(w) => w.len(),
        }
    }

    pub(super) fn to_le_bytes(&self) -> Vec<u8> {
        match self {
            Self::U32(w) => w.iter().flat_map(|v| v.to_le_bytes()).collect(),
            Self::U64(w) => w.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }

    pub(super) fn from_le_bytes(dtype: Dtype, bytes: &[u8]) -> Self {
        match dtype {
            Dtype::U32 => Self::U32(
                bytes
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            ),
            Dtype::U64 => Self::U64(
                bytes
                    .chunks_exact(8)
                    .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                    .collect(),
            ),
        }
    }
}

/// Refuses an array file name with a directory part (`/`, `\\`, a drive's `:`), `.`, `..` or
/// nothing: a dump's arrays lie in its own directory.
/// Refuses two arrays that name the same file: one file cannot hold both, so encoding would keep
/// one array's words under both names (found by `dump_parse`).
pub(super) fn check_distinct_files(arrays: &BTreeMap<String, ArraySpec>) -> Result<(), DumpError> {
    let mut owner: BTreeMap<&str, &str> = BTreeMap::new();
    for (name, spec) in arrays {
        if let Some(first) = owner.insert(&spec.file, name) {
            return err(format!(
                "arrays {first:?} and {name:?} both name file {:?}",
                spec.file
            ));
        }
    }
    Ok(())
}

pub(super) fn check_file_name(name: &str, file: &str) -> Result<(), DumpError> {
    let plain =
        !file.is_empty() && file != "." && file != ".." && !file.contains(['/', '\\', ':', '\0']);
    if plain {
        Ok(())
    } else {
        err(format!(
            "array {name:?}: file {file:?} must be a plain file name in the dump's directory"
        ))
    }
}

/// The bytes of array `name`'s file: its shape's elements times its dtype's width, refused when
/// either overflows 64 bits.
pub(super) fn array_bytes(name: &str, spec: &ArraySpec) -> Result<u64, DumpError> {
    elements(name, &spec.shape)?
        .checked_mul(u64::from(spec.dtype.bits() / 8))
        .ok_or_else(|| {
            DumpError::Invalid(format!(
                "array {name:?}: shape {:?} of {:?} words is more than 2^64 bytes",
                spec.shape, spec.dtype
            ))
        })
}

/// The element count of a shape, refused when it overflows 64 bits.
pub(super) fn elements(name: &str, shape: &[u64]) -> Result<u64, DumpError> {
    shape
        .iter()
        .try_fold(1_u64, |n, &d| n.checked_mul(d))
        .ok_or_else(|| {
            DumpError::Invalid(format!(
                "array {name:?}: shape {shape:?} has more than 2^64 elements"
            ))
        })
}

pub(super) fn check_array(
    name: &str,
    spec: &ArraySpec,
    dtype: Dtype,
    len: u64,
) -> Result<(), DumpError> {
    let expected = elements(name, &spec.shape)?;
    if spec.dtype != dtype {
        return err(format!("array {name:?}: dtype {:?} expected", spec.dtype));
    }
    if expected != len {
        return err(format!(
            "array {name:?}: shape {:?} is {expected} elements, the data has {len}",
            spec.shape
        ));
    }
    Ok(())
}

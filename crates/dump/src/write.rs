//! Recording: fragsim's scheme run serially over a view, its memory copied out as a dump, and the
//! dump encoded and written to a directory.

use std::collections::BTreeMap;
use std::path::Path;

use fragsim_capture::Scheme;
use fragsim_catalog::DumpLayout;
use fragsim_memory::{SerialMemory, WordMemory};
use fragsim_raster::View;

use crate::arrays::sort_abuffer_in_place;
use crate::header::{check_array, check_distinct_files, check_file_name};
use crate::{err, io_err, ArraySpec, Dtype, Dump, DumpError, DumpScheme, Header, Words};
use crate::{LayoutSpec, ListNumbering};
use crate::{FORMAT, HEADER_FILE, VERSION};
use fragsim_catalog::SchemeVisitor;
use fragsim_raster::scene_spec::SceneSpec;

/// Runs a scheme serially over a view and copies its memory out.
struct Record<'a, 'm> {
    view: &'a View<'m>,
}

impl SchemeVisitor for Record<'_, '_> {
    type Output = (Vec<u32>, Vec<u64>);
    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) -> Self::Output {
        let memory: SerialMemory = scheme.layout().allocate();
        fragsim_capture::executors::serial_passes(self.view, scheme, &memory);
        (read_all(&memory), read_all(&memory))
    }
}

/// The spec of array `name` as fragsim writes it: file `name.u32` or `name.u64`.
fn array_spec(name: &str, dtype: Dtype, shape: Vec<u64>) -> ArraySpec {
    let suffix = match dtype {
        Dtype::U32 => "u32",
        Dtype::U64 => "u64",
    };
    ArraySpec {
        file: format!("{name}.{suffix}"),
        dtype,
        shape,
    }
}

fn read_all<W: fragsim_memory::Word>(memory: &impl WordMemory<W>) -> Vec<W> {
    (0..memory.len()).map(|i| memory.load(i)).collect()
}

/// The numbers of u32 and u64 words of a scheme's memory.
struct LayoutOf;

impl SchemeVisitor for LayoutOf {
    type Output = (usize, usize);
    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) -> Self::Output {
        let layout = scheme.layout();
        (layout.words32, layout.words64)
    }
}

impl Dump {
    /// Runs fragsim's `scheme` serially over `view` and records its memory as a dump.
    ///
    /// # Errors
    /// Scheme parameters out of range.
    pub fn record(
        view: &View<'_>,
        scene: SceneSpec,
        scheme: &DumpScheme,
        producer: &str,
    ) -> Result<Self, DumpError> {
        let (words32, words64) = scheme.with_scheme(view.viewport(), Record { view })?;
        Self::of_memory(view, scene, scheme, words32, words64, producer)
    }

    /// Records the memory a run of `scheme` over `view` left after its last pass (`words32` and
    /// `words64`, in its layout's order) as a dump: what `render --dump` writes, the words of the
    /// very run it reports on whatever executor ran it.
    ///
    /// # Errors
    /// Scheme parameters out of range, a view whose framebuffer is not the one `scene`'s sample
    /// count declares, or words of another number than the scheme's memory holds.
    pub fn of_memory(
        view: &View<'_>,
        scene: SceneSpec,
        scheme: &DumpScheme,
        words32: Vec<u32>,
        words64: Vec<u64>,
        producer: &str,
    ) -> Result<Self, DumpError> {
        // The arrays index the view's framebuffer (sample-expanded at more than one sample), the
        // header names the pixels and the sample count.
        let viewport = view.viewport();
        let declared = Header::framebuffer_of(&scene, view.pixel_viewport())?;
        if declared != viewport {
            return err(format!(
                "the view rasterizes a {}x{} framebuffer, the scene's conventions ({} samples) \
                 declare {}x{}",
                viewport.width,
                viewport.height,
                scene.conventions.samples,
                declared.width,
                declared.height
            ));
        }
        let (len32, len64) = scheme.with_scheme(viewport, LayoutOf)?;
        if (words32.len(), words64.len()) != (len32, len64) {
            return err(format!(
                "{} over this viewport holds {len32} u32 and {len64} u64 words, the memory given \
                 {} and {}",
                scheme.name(),
                words32.len(),
                words64.len()
            ));
        }
        let pixels = viewport.pixels() as u64;
        let mut arrays = BTreeMap::new();
        let mut shapes: BTreeMap<&str, Vec<u64>> = BTreeMap::new();
        let (mut k, mut capacity, mut sorted) = (None, None, false);
        let (mut pool, mut layers) = (None, None);
        // fragsim's memory starts at the layout's initial words: the A-buffer's slots empty.
        let filled = scheme.layout() == DumpLayout::CountersAndSlots;
        match scheme {
            DumpScheme::LinkedLists { k: n, pool: p, .. } => {
                (k, pool) = (Some(*n), Some(u64::from(*p)));
                // fragsim's u32 words: the heads, the node counter, the `next` of each node.
                #[expect(
                    clippy::shadow_unrelated,
                    reason = "the same pixel count as `pixels` above, as a usize to split the words by"
                )]
                let pixels = viewport.pixels();
                let (heads, rest) = words32.split_at(pixels);
                let (counter, next) = rest.split_at(1);
                for (name, words) in [("heads", heads), ("counter", counter), ("next", next)] {
                    shapes.insert(name, vec![words.len() as u64]);
                    arrays.insert(name.to_string(), Words::U32(words.to_vec()));
                }
                shapes.insert("nodes", vec![words64.len() as u64]);
                arrays.insert("nodes".into(), Words::U64(words64));
            }
            DumpScheme::LayerMajor { k: n, .. } => {
                k = Some(*n);
                shapes.insert("counters", vec![pixels]);
                shapes.insert("layers", vec![u64::from(*n), pixels]);
                arrays.insert("counters".into(), Words::U32(words32));
                arrays.insert("layers".into(), Words::U64(words64));
            }
            DumpScheme::Memory {
                k: n,
                capacity: c,
                layers: l,
                ..
            } => {
                (k, capacity, layers) = (Some(*n), Some(*c), Some(*l));
                shapes.insert("words32", vec![words32.len() as u64]);
                shapes.insert("words64", vec![words64.len() as u64]);
                arrays.insert("words32".into(), Words::U32(words32));
                arrays.insert("words64".into(), Words::U64(words64));
            }
            _ => {
                let names = scheme.names();
                if let Some(name) = names.words32 {
                    arrays.insert(name.to_string(), Words::U32(words32));
                }
                if let Some(name) = names.words64 {
                    arrays.insert(name.to_string(), Words::U64(words64));
                }
                let slots_shape = match scheme {
                    DumpScheme::ABufferFixed {
                        capacity: c,
                        sorted: s,
                    } => {
                        (capacity, sorted) = (Some(*c), *s);
                        vec![pixels, u64::from(*c)]
                    }
                    DumpScheme::ABufferExact { counts, sorted: s } => {
                        sorted = *s;
                        let mut offsets = Vec::with_capacity(counts.len() + 1);
                        offsets.push(0_u32);
                        for &c in counts {
                            offsets.push(offsets[offsets.len() - 1] + c);
                        }
                        let total = u64::from(offsets[counts.len()]);
                        arrays.insert("offsets".into(), Words::U32(offsets));
                        vec![total]
                    }
                    // The slot layouts: MDTS on either word, a k-buffer's slots.
                    DumpScheme::Mdts { k: n, .. }
                    | DumpScheme::Mdts32 { k: n }
                    | DumpScheme::KBuffer { k: n, .. } => {
                        k = Some(*n);
                        vec![pixels, u64::from(*n)]
                    }
                    DumpScheme::LinkedLists { .. }
                    | DumpScheme::LayerMajor { .. }
                    | DumpScheme::Memory { .. } => Vec::new(),
                };
                shapes.insert("slots", slots_shape);
                shapes.insert("counters", vec![pixels]);
                shapes.insert("offsets", vec![pixels + 1]);
            }
        }
        if sorted {
            sort_abuffer_in_place(&mut arrays, scheme);
        }
        let specs = arrays
            .iter()
            .map(|(name, words)| {
                let spec = array_spec(name, words.dtype(), shapes[name.as_str()].clone());
                (name.clone(), spec)
            })
            .collect();
        Ok(Self {
            header: Header {
                format: FORMAT.into(),
                version: VERSION,
                producer: producer.into(),
                scene,
                width: view.pixel_viewport().width,
                height: view.pixel_viewport().height,
                scheme: scheme.name().into(),
                k,
                capacity,
                sorted,
                filled,
                pool,
                layers,
                layout: scheme.spec(),
                word: scheme.word().into(),
                arrays: specs,
                extra: serde_json::Value::Null,
            },
            arrays,
        })
    }

    /// This dump, as [`Dump::record`] writes it (fragsim's own encoding), with its words as
    /// `spec` describes (`None`: fragsim's own slot encoding, unchanged): what `render --dump`
    /// writes for an engine's layout ([`DumpScheme::spec_in`]).
    ///
    /// # Errors
    /// A dump in another encoding than fragsim's, a description its scheme cannot have (the
    /// reader's own checks), a primitive id that does not fit the payload, or a list numbering
    /// whose terminator is a node's number.
    pub fn in_layout(&self, spec: Option<LayoutSpec>) -> Result<Self, DumpError> {
        if self.is_masked() {
            return self.masked_as(spec);
        }
        let scheme = self.scheme()?;
        if self.header.layout != scheme.spec() {
            return err(format!(
                "only fragsim's own encoding is re-encoded; this dump's layout is {:?}",
                self.header.layout
            ));
        }
        let mut described = self.header.clone();
        described.layout = spec;
        DumpScheme::from_header(&described, self.u32s("offsets")?)?;
        match spec {
            Some(LayoutSpec::Slots { order, payload }) => self.slots_as(&scheme, order, payload),
            Some(LayoutSpec::LinkedList {
                payload,
                null,
                node_base,
            }) => self.lists_as(payload, ListNumbering { null, node_base }),
            Some(LayoutSpec::LayerMajor { payload }) => self.layers_as(payload),
            Some(LayoutSpec::Memory) | None => Ok(self.clone()),
        }
    }

    /// The shape of array `name`: the header's, or its length where the header has none.
    pub(super) fn shape_of(&self, name: &str) -> Vec<u64> {
        match self.header.arrays.get(name) {
            Some(spec) => spec.shape.clone(),
            None => vec![self.arrays.get(name).map_or(0, |w| w.len() as u64)],
        }
    }

    /// Puts array `name` in the dump: its words, and in the header its file (`name.u32` or
    /// `name.u64`), dtype and shape.
    pub fn set_array(&mut self, name: &str, words: Words, shape: Vec<u64>) {
        let spec = array_spec(name, words.dtype(), shape);
        self.header.arrays.insert(name.into(), spec);
        self.arrays.insert(name.into(), words);
    }

    /// The header as `dump.json` text and each array file's bytes, by file name: what
    /// [`Dump::write`] puts in a directory, and [`Dump::parse`] reads back.
    ///
    /// # Errors
    /// Arrays that disagree with the header, a file name that is not a plain name, or a scene
    /// number that is not finite ([`SceneSpec::check_finite`]).
    pub fn encode(&self) -> Result<(String, BTreeMap<String, Vec<u8>>), DumpError> {
        check_distinct_files(&self.header.arrays)?;
        let mut files = BTreeMap::new();
        for (name, spec) in &self.header.arrays {
            check_file_name(name, &spec.file)?;
            let words = self.arrays.get(name).ok_or_else(|| {
                DumpError::Invalid(format!("the header names array {name:?}, absent"))
            })?;
            check_array(name, spec, words.dtype(), words.len() as u64)?;
            files.insert(spec.file.clone(), words.to_le_bytes());
        }
        self.header.scene.check_finite()?;
        let text = serde_json::to_string_pretty(&self.header)
            .map_err(|e| DumpError::Invalid(format!("cannot encode the header: {e}")))?;
        Ok((text + "\n", files))
    }

    /// Writes `dump.json` and the array files into `dir`, creating it.
    ///
    /// # Errors
    /// I/O failures, or arrays that disagree with the header.
    pub fn write(&self, dir: &Path) -> Result<(), DumpError> {
        let (text, files) = self.encode()?;
        std::fs::create_dir_all(dir).map_err(|e| io_err("create", dir, e))?;
        for (file, bytes) in files {
            let path = dir.join(file);
            std::fs::write(&path, bytes).map_err(|e| io_err("write", &path, e))?;
        }
        let path = dir.join(HEADER_FILE);
        std::fs::write(&path, text).map_err(|e| io_err("write", &path, e))
    }
}

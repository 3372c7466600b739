//! The interchange with GPU backends (`docs/dump-format.md`): the **dump**, what a backend's
//! per-pixel memory held after its passes, and the **triangle export**, the scene after fragsim's
//! vertex stage, so that a backend can test its scan and atomics alone.
//!
//! A dump is a directory: `dump.json` (format, version, the scene and camera that produced it,
//! viewport, scheme, K or capacity, the names, dtypes and shapes of the arrays) and one file of
//! little-endian words per array beside it. [`Dump::capture`] decodes the words into a
//! [`Capture`] through the named scheme's own post pass (`Scheme::resolve`): fragsim's MDTS reads
//! each pixel's slots until the first empty one, the A-buffer reads `min(counter, capacity)` slots
//! and sorts them. A dump whose A-buffer lists were already sorted on the GPU (`"sorted": true`)
//! is taken in stored order, so a broken sort kernel shows up as misordered pixels.
//! [`compare`] then diffs a capture against an [`Oracle`] pixel by pixel with [`Oracle::diff`]
//! and names each pixel's verdict. Decoding stops where the layout says a list ends, so
//! [`Dump::check_words`] reads every word against the layout's rules (nothing after an empty MDTS
//! slot, no empty marker below an A-buffer counter, no key above 1.0) and [`Dump::compare`] adds
//! what it finds: [`verdict::CORRUPT`], and [`verdict::MISCOUNTED`] for an A-buffer counter other
//! than the pixel's fragment count, which the oracle knows.
//!
//! ```
//! use fragsim_capture::mdts::Direction;
//! use fragsim_oracle::dump::{self, Dump, DumpScheme, SceneSpec};
//! use fragsim_oracle::Oracle;
//! use fragsim_raster::Viewport;
//!
//! let spec = SceneSpec::named("spheres:2", 30.0, 15.0);
//! let scene = spec.load(None).unwrap();
//! let view = scene.view(Viewport::new(32, 24).unwrap(), &spec.orbit()).unwrap();
//! let oracle = Oracle::build(&view);
//! let k = oracle.max_depth_complexity();
//! let scheme = DumpScheme::Mdts { k, direction: Direction::Ascending };
//! let dump = Dump::record(&view, spec, &scheme, "doc").unwrap();
//! let options = dump::CompareOptions { examples: 4, ..Default::default() };
//! let comparison = dump.compare(&oracle, &options).unwrap();
//! assert!(comparison.is_equal() && comparison.words_checked);
//! ```
//!
//! Unlike the GPU, which leaves its words in device memory, [`Dump::record`] runs fragsim's scheme
//! serially on [`SerialMemory`] and copies every word out; for MDTS the words are the same under
//! any interleaving (the sortedness proof), for the A-buffer the slot order within a pixel is the
//! serial one.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use fragsim_capture::abuffer::{ABuffer, PostSort};
use fragsim_capture::mdts::{Direction, Mdts};
use fragsim_capture::WordMemory;
use fragsim_capture::{Capacity, Capture, CaptureError, Identity, Keeps, Scheme, SerialMemory};
use fragsim_raster::{OrbitCamera, Scene, ScreenTriangle, View, Viewport, SUBPIXEL_BITS};
use serde::{Deserialize, Serialize};

use crate::{Diff, Oracle, PixelMismatch};

/// The `format` field of every dump header.
pub const FORMAT: &str = "fragsim-dump";
/// The dump format version this code reads and writes.
pub const VERSION: u32 = 1;
/// The header's file name inside a dump directory.
pub const HEADER_FILE: &str = "dump.json";

/// Why a dump or a triangle export could not be read, written or decoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DumpError(pub String);

impl fmt::Display for DumpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DumpError {}

impl From<CaptureError> for DumpError {
    fn from(e: CaptureError) -> Self {
        Self(e.to_string())
    }
}

fn err<T>(message: impl Into<String>) -> Result<T, DumpError> {
    Err(DumpError(message.into()))
}

fn io_err(what: &str, path: &Path, e: impl fmt::Display) -> DumpError {
    DumpError(format!("cannot {what} {}: {e}", path.display()))
}

/// The scene and orbit camera that produced a dump: enough to rebuild the view and its oracle.
///
/// Its numbers are exact across the file: serde_json is built with `float_roundtrip`, so a
/// decimal parses to the nearest f64, and writes the shortest decimal that parses back to the same
/// bits (ryu), so encode then parse gives every finite value back bit for bit. JSON has no NaN or
/// infinity: [`SceneSpec::check_finite`] refuses them before a header is written (serde_json would
/// write `null`), and a decimal past the f64 range is a parse error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneSpec {
    /// A named scene (`Scene::procedural`: `bunny`, `spheres:8`, …); absent when `mesh` is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A mesh file (OBJ or PLY), as given to `--mesh`; a relative path is looked up from the working
    /// directory, then from the dump's directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Orbit angle around the model, degrees (`--view`).
    pub view_degrees: f64,
    /// Elevation above the model's equator, degrees (`--elevation`).
    pub elevation_degrees: f64,
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov_y_degrees: f64,
    /// Eye distance as a multiple of the distance at which the bounding sphere fits.
    #[serde(default = "default_distance")]
    pub distance_scale: f64,
}

fn default_fov() -> f64 {
    OrbitCamera::default().fov_y_degrees
}

fn default_distance() -> f64 {
    OrbitCamera::default().distance_scale
}

impl SceneSpec {
    /// A named scene seen from the default orbit at `view_degrees` and `elevation_degrees`.
    #[must_use]
    pub fn named(name: &str, view_degrees: f64, elevation_degrees: f64) -> Self {
        Self {
            name: Some(name.into()),
            mesh: None,
            view_degrees,
            elevation_degrees,
            fov_y_degrees: default_fov(),
            distance_scale: default_distance(),
        }
    }

    /// A mesh file seen from the default orbit at `view_degrees` and `elevation_degrees`.
    #[must_use]
    pub fn mesh(path: &Path, view_degrees: f64, elevation_degrees: f64) -> Self {
        Self {
            mesh: Some(path.display().to_string()),
            name: None,
            ..Self::named("", view_degrees, elevation_degrees)
        }
    }

    /// The orbit camera.
    #[must_use]
    pub fn orbit(&self) -> OrbitCamera {
        OrbitCamera {
            angle_degrees: self.view_degrees,
            elevation_degrees: self.elevation_degrees,
            fov_y_degrees: self.fov_y_degrees,
            distance_scale: self.distance_scale,
        }
    }

    /// Loads the scene; a relative mesh path missing from the working directory is looked up in
    /// `beside` (the dump's directory).
    ///
    /// # Errors
    /// Neither a name nor a mesh, or a scene that cannot be loaded.
    pub fn load(&self, beside: Option<&Path>) -> Result<Scene, DumpError> {
        let scene = match (&self.mesh, &self.name) {
            (Some(mesh), _) => {
                let mut path = PathBuf::from(mesh);
                if let Some(dir) = beside.filter(|_| path.is_relative() && !path.exists()) {
                    path = dir.join(path);
                }
                Scene::from_file(&path)
            }
            (None, Some(name)) => Scene::procedural(name),
            (None, None) => return err("the scene names neither a mesh nor a named scene"),
        };
        scene.map_err(|e| DumpError(format!("scene: {e}")))
    }

    /// Refuses a NaN or infinite number, which JSON cannot hold (serde_json would silently write
    /// `null`, which then fails to parse as a number far from its cause).
    ///
    /// # Errors
    /// The first field that is not finite, by name.
    pub fn check_finite(&self) -> Result<(), DumpError> {
        for (field, value) in [
            ("view_degrees", self.view_degrees),
            ("elevation_degrees", self.elevation_degrees),
            ("fov_y_degrees", self.fov_y_degrees),
            ("distance_scale", self.distance_scale),
        ] {
            if !value.is_finite() {
                return err(format!(
                    "scene {field} is {value}: numbers in a header must be finite (JSON has no NaN or infinity)"
                ));
            }
        }
        Ok(())
    }

    /// A short description for reports.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{}, view {}°, elevation {}°",
            self.mesh.as_deref().or(self.name.as_deref()).unwrap_or("?"),
            self.view_degrees,
            self.elevation_degrees
        )
    }
}

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

/// Where an array lives and what it holds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ArraySpec {
    /// File name, relative to the dump directory.
    pub file: String,
    /// Element type.
    pub dtype: Dtype,
    /// Dimensions, row-major; the file holds their product of elements and nothing else.
    pub shape: Vec<u64>,
}

/// The JSON header of a dump (`dump.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
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
    /// `mdts`, `mdts32`, `mdts-desc` or `abuffer` (see `docs/dump-format.md`).
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
    /// The word layout, informative: `key<<32|prim`, `key`, or `(key<<32|prim)+1`.
    #[serde(default)]
    pub word: String,
    /// The arrays by name: `slots`, and for the A-buffer `counters` and maybe `offsets`.
    pub arrays: BTreeMap<String, ArraySpec>,
    /// Anything else the producer wants to keep (timings, device): ignored by the reader.
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub extra: serde_json::Value,
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
    fn dtype(&self) -> Dtype {
        match self {
            Self::U32(_) => Dtype::U32,
            Self::U64(_) => Dtype::U64,
        }
    }

    fn len(&self) -> usize {
        match self {
            Self::U32(w) => w.len(),
            Self::U64(w) => w.len(),
        }
    }

    fn to_le_bytes(&self) -> Vec<u8> {
        match self {
            Self::U32(w) => w.iter().flat_map(|v| v.to_le_bytes()).collect(),
            Self::U64(w) => w.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }

    fn from_le_bytes(dtype: Dtype, bytes: &[u8]) -> Self {
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
}

/// Names of the memory's two word arrays in a dump (`None`: the scheme uses no such words).
struct ArrayNames {
    words32: Option<&'static str>,
    words64: Option<&'static str>,
}

/// Something done with the concrete scheme a [`DumpScheme`] names (Rust has no generic closures).
trait SchemeVisitor {
    type Output;
    fn visit<S: Scheme>(self, scheme: &S) -> Self::Output;
}

impl DumpScheme {
    /// The header's `scheme` field.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::Mdts {
                direction: Direction::Ascending,
                ..
            } => "mdts",
            Self::Mdts {
                direction: Direction::Descending,
                ..
            } => "mdts-desc",
            Self::Mdts32 { .. } => "mdts32",
            Self::ABufferFixed { .. } | Self::ABufferExact { .. } => "abuffer",
        }
    }

    fn word(&self) -> &'static str {
        match self {
            Self::Mdts {
                direction: Direction::Descending,
                ..
            } => "(key<<32|prim)+1",
            Self::Mdts32 { .. } => "key",
            _ => "key<<32|prim",
        }
    }

    fn names(&self) -> ArrayNames {
        match self {
            Self::Mdts { .. } => ArrayNames {
                words32: None,
                words64: Some("slots"),
            },
            Self::Mdts32 { .. } => ArrayNames {
                words32: Some("slots"),
                words64: None,
            },
            Self::ABufferFixed { .. } | Self::ABufferExact { .. } => ArrayNames {
                words32: Some("counters"),
                words64: Some("slots"),
            },
        }
    }

    /// Builds fragsim's scheme for a viewport (no memory cap: the words exist already).
    fn with_scheme<V: SchemeVisitor>(
        &self,
        viewport: Viewport,
        visitor: V,
    ) -> Result<V::Output, DumpError> {
        let cap = u64::MAX;
        Ok(match self {
            Self::Mdts { k, direction } => {
                visitor.visit(&Mdts::<u64>::new(viewport, *k, *direction, cap)?)
            }
            Self::Mdts32 { k } => {
                visitor.visit(&Mdts::<u32>::new(viewport, *k, Direction::Ascending, cap)?)
            }
            Self::ABufferFixed { capacity, .. } => visitor.visit(&ABuffer::fixed(
                viewport,
                *capacity,
                PostSort::Insertion,
                cap,
            )?),
            Self::ABufferExact { counts, .. } => {
                if counts.len() != viewport.pixels() {
                    return err(format!(
                        "offsets cover {} pixels, the viewport has {}",
                        counts.len(),
                        viewport.pixels()
                    ));
                }
                visitor.visit(&ABuffer::exact(counts, PostSort::Insertion, cap)?)
            }
        })
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
        match header.scheme.as_str() {
            "mdts" => Ok(Self::Mdts {
                k: k()?,
                direction: Direction::Ascending,
            }),
            "mdts-desc" => Ok(Self::Mdts {
                k: k()?,
                direction: Direction::Descending,
            }),
            "mdts32" => Ok(Self::Mdts32 { k: k()? }),
            "abuffer" => match (header.capacity, offsets) {
                (Some(0), _) => err("abuffer \"capacity\" must be at least 1"),
                (Some(capacity), _) => Ok(Self::ABufferFixed {
                    capacity,
                    sorted: header.sorted,
                }),
                (None, Some(offsets)) => {
                    if offsets.first() != Some(&0) || offsets.windows(2).any(|w| w[0] > w[1]) {
                        return err("abuffer offsets must start at 0 and never decrease");
                    }
                    Ok(Self::ABufferExact {
                        counts: offsets.windows(2).map(|w| w[1] - w[0]).collect(),
                        sorted: header.sorted,
                    })
                }
                (None, None) => err("abuffer needs \"capacity\" or an \"offsets\" array"),
            },
            other => err(format!(
                "unknown scheme {other:?}: expected mdts, mdts32, mdts-desc or abuffer"
            )),
        }
    }
}

/// A dump: the header and the arrays it names.
#[derive(Clone, Debug, PartialEq)]
pub struct Dump {
    /// The header.
    pub header: Header,
    /// The arrays by name.
    pub arrays: BTreeMap<String, Words>,
}

/// Runs a scheme serially over a view and copies its memory out.
struct Record<'a, 'm> {
    view: &'a View<'m>,
}

impl SchemeVisitor for Record<'_, '_> {
    type Output = (Vec<u32>, Vec<u64>);
    fn visit<S: Scheme>(self, scheme: &S) -> Self::Output {
        let memory: SerialMemory = scheme.layout().allocate();
        fragsim_capture::executors::serial_passes(self.view, scheme, &memory);
        (read_all(&memory), read_all(&memory))
    }
}

fn read_all<W: fragsim_capture::Word>(memory: &impl WordMemory<W>) -> Vec<W> {
    (0..memory.len()).map(|i| memory.load(i)).collect()
}

fn write_all<W: fragsim_capture::Word>(memory: &impl WordMemory<W>, words: &[W]) {
    for (i, &w) in words.iter().enumerate() {
        memory.store(i, w);
    }
}

/// Loads the words into the scheme's memory and runs its post pass; a sorted A-buffer's lists
/// are taken as stored instead.
struct Resolve<'a> {
    scheme: &'a DumpScheme,
    words32: &'a [u32],
    words64: &'a [u64],
}

impl SchemeVisitor for Resolve<'_> {
    type Output = Result<Capture, DumpError>;
    fn visit<S: Scheme>(self, scheme: &S) -> Self::Output {
        let layout = scheme.layout();
        if layout.words32 != self.words32.len() || layout.words64 != self.words64.len() {
            return err(format!(
                "{} over this viewport holds {} u32 and {} u64 words; the dump has {} and {}",
                scheme.name(),
                layout.words32,
                layout.words64,
                self.words32.len(),
                self.words64.len()
            ));
        }
        if let DumpScheme::ABufferFixed { sorted: true, .. }
        | DumpScheme::ABufferExact { sorted: true, .. } = self.scheme
        {
            return Ok(stored_lists(self.scheme, self.words32, self.words64));
        }
        let memory: SerialMemory = layout.allocate();
        write_all(&memory, self.words32);
        write_all(&memory, self.words64);
        Ok(scheme.resolve(&memory))
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
        let viewport = view.viewport();
        let (words32, words64) = scheme.with_scheme(viewport, Record { view })?;
        let pixels = viewport.pixels() as u64;
        let mut arrays = BTreeMap::new();
        let names = scheme.names();
        if let Some(name) = names.words32 {
            arrays.insert(name.to_string(), Words::U32(words32));
        }
        if let Some(name) = names.words64 {
            arrays.insert(name.to_string(), Words::U64(words64));
        }
        let (mut k, mut capacity, mut sorted) = (None, None, false);
        // fragsim's memory starts at the layout's initial words: the A-buffer's slots empty.
        let filled = matches!(
            scheme,
            DumpScheme::ABufferFixed { .. } | DumpScheme::ABufferExact { .. }
        );
        let slots_shape = match scheme {
            DumpScheme::Mdts { k: n, .. } | DumpScheme::Mdts32 { k: n } => {
                k = Some(*n);
                vec![pixels, u64::from(*n)]
            }
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
                offsets.push(0u32);
                for &c in counts {
                    offsets.push(offsets[offsets.len() - 1] + c);
                }
                let total = u64::from(offsets[counts.len()]);
                arrays.insert("offsets".into(), Words::U32(offsets));
                vec![total]
            }
        };
        if sorted {
            sort_abuffer_in_place(&mut arrays, scheme);
        }
        let shapes: BTreeMap<&str, Vec<u64>> = [
            ("slots", slots_shape),
            ("counters", vec![pixels]),
            ("offsets", vec![pixels + 1]),
        ]
        .into_iter()
        .collect();
        let specs = arrays
            .iter()
            .map(|(name, words)| {
                let suffix = match words.dtype() {
                    Dtype::U32 => "u32",
                    Dtype::U64 => "u64",
                };
                let spec = ArraySpec {
                    file: format!("{name}.{suffix}"),
                    dtype: words.dtype(),
                    shape: shapes[name.as_str()].clone(),
                };
                (name.clone(), spec)
            })
            .collect();
        Ok(Self {
            header: Header {
                format: FORMAT.into(),
                version: VERSION,
                producer: producer.into(),
                scene,
                width: viewport.width,
                height: viewport.height,
                scheme: scheme.name().into(),
                k,
                capacity,
                sorted,
                filled,
                word: scheme.word().into(),
                arrays: specs,
                extra: serde_json::Value::Null,
            },
            arrays,
        })
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
            let words = self
                .arrays
                .get(name)
                .ok_or_else(|| DumpError(format!("the header names array {name:?}, absent")))?;
            check_array(name, spec, words.dtype(), words.len() as u64)?;
            files.insert(spec.file.clone(), words.to_le_bytes());
        }
        self.header.scene.check_finite()?;
        let text = serde_json::to_string_pretty(&self.header)
            .map_err(|e| DumpError(format!("cannot encode the header: {e}")))?;
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

    /// Reads a dump from its directory (or from the path of its `dump.json`).
    ///
    /// # Errors
    /// Missing files, a malformed header, another format or version, or array files whose size
    /// disagrees with their shape.
    pub fn read(path: &Path) -> Result<Self, DumpError> {
        let (dir, header_path) = if path.is_dir() {
            (path.to_path_buf(), path.join(HEADER_FILE))
        } else {
            (
                path.parent().unwrap_or(Path::new(".")).to_path_buf(),
                path.to_path_buf(),
            )
        };
        let text = std::fs::read(&header_path).map_err(|e| io_err("read", &header_path, e))?;
        Self::parse(&header_path.display().to_string(), &text, |file| {
            let path = dir.join(file);
            std::fs::read(&path).map_err(|e| io_err("read", &path, e))
        })
    }

    /// Decodes a dump from its header's bytes (`dump.json`, named `header_name` in errors) and
    /// `read_file`, which returns an array file's bytes by its name in the header. Never touches
    /// the file system itself: [`Dump::read`] passes a reader of the dump's directory, the
    /// `dump_parse` fuzz target one over its input.
    ///
    /// Array file names must be plain names (no directory part, not `.` or `..`), so that a
    /// header cannot make the reader open a file outside the dump's directory; shapes whose
    /// element count overflows 64 bits are refused before anything is read.
    ///
    /// # Errors
    /// A malformed header, another format or version, a bad viewport, an array file name that is
    /// not plain, a shape that overflows, `read_file`'s own errors, or array files whose size
    /// disagrees with their shape.
    pub fn parse(
        header_name: &str,
        header_bytes: &[u8],
        mut read_file: impl FnMut(&str) -> Result<Vec<u8>, DumpError>,
    ) -> Result<Self, DumpError> {
        let header: Header = serde_json::from_slice(header_bytes)
            .map_err(|e| DumpError(format!("{header_name}: {e}")))?;
        if header.format != FORMAT {
            return err(format!(
                "{header_name}: format {:?}, expected {FORMAT:?}",
                header.format
            ));
        }
        if header.version != VERSION {
            return err(format!(
                "{header_name}: dump format version {}, this fragsim reads version {VERSION}",
                header.version
            ));
        }
        Viewport::new(header.width, header.height).map_err(DumpError)?;
        check_distinct_files(&header.arrays)?;
        let mut arrays = BTreeMap::new();
        for (name, spec) in &header.arrays {
            check_file_name(name, &spec.file)?;
            elements(name, &spec.shape)?;
            let bytes = read_file(&spec.file)?;
            let width = match spec.dtype {
                Dtype::U32 => 4,
                Dtype::U64 => 8,
            };
            if bytes.len() % width != 0 {
                return err(format!(
                    "{}: {} bytes is not a whole number of {width}-byte words",
                    spec.file,
                    bytes.len()
                ));
            }
            check_array(name, spec, spec.dtype, (bytes.len() / width) as u64)?;
            arrays.insert(name.clone(), Words::from_le_bytes(spec.dtype, &bytes));
        }
        Ok(Self { header, arrays })
    }

    /// The viewport.
    ///
    /// # Errors
    /// A zero or oversized side.
    pub fn viewport(&self) -> Result<Viewport, DumpError> {
        Viewport::new(self.header.width, self.header.height).map_err(DumpError)
    }

    fn u32s(&self, name: &str) -> Result<Option<&[u32]>, DumpError> {
        match self.arrays.get(name) {
            None => Ok(None),
            Some(Words::U32(w)) => Ok(Some(w)),
            Some(Words::U64(_)) => err(format!("array {name:?} must be u32")),
        }
    }

    fn u64s(&self, name: &str) -> Result<Option<&[u64]>, DumpError> {
        match self.arrays.get(name) {
            None => Ok(None),
            Some(Words::U64(w)) => Ok(Some(w)),
            Some(Words::U32(_)) => err(format!("array {name:?} must be u64")),
        }
    }

    /// The scheme the header names.
    ///
    /// # Errors
    /// See [`DumpScheme::from_header`].
    pub fn scheme(&self) -> Result<DumpScheme, DumpError> {
        DumpScheme::from_header(&self.header, self.u32s("offsets")?)
    }

    /// Decodes the words into per-pixel lists with the scheme's own post pass (sorted A-buffer
    /// dumps: in stored order).
    ///
    /// # Errors
    /// A header that names no known scheme, or arrays missing or of the wrong size or type.
    pub fn capture(&self) -> Result<Capture, DumpError> {
        let scheme = self.scheme()?;
        let names = scheme.names();
        let fetch32 = |name: Option<&str>| -> Result<&[u32], DumpError> {
            match name {
                None => Ok(&[]),
                Some(n) => self
                    .u32s(n)?
                    .ok_or_else(|| DumpError(format!("missing array {n:?}"))),
            }
        };
        let fetch64 = |name: Option<&str>| -> Result<&[u64], DumpError> {
            match name {
                None => Ok(&[]),
                Some(n) => self
                    .u64s(n)?
                    .ok_or_else(|| DumpError(format!("missing array {n:?}"))),
            }
        };
        let (words32, words64) = (fetch32(names.words32)?, fetch64(names.words64)?);
        let resolve = Resolve {
            scheme: &scheme,
            words32,
            words64,
        };
        scheme.with_scheme(self.viewport()?, resolve)?
    }
}

/// The largest depth key of a fragment: depth 1.0 (fragments outside `[0, 1]` are dropped, and
/// `-0.0` is stored as `+0.0`), so a stored key above it is no fragment's.
const LARGEST_KEY: u32 = 0x3F80_0000;

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
    /// when the header does not say they were filled.
    pub unchecked: u64,
}

impl WordCheck {
    /// How many words are corrupt.
    #[must_use]
    pub fn corrupt_words(&self) -> u64 {
        self.corrupt.iter().map(|c| c.len() as u64).sum()
    }

    /// Records `word` in `slot` of pixel `pixel` as corrupt, when a rule gave a reason.
    fn flag(&mut self, pixel: usize, slot: usize, word: u64, why: Option<Corruption>) {
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
        // Decoding validates the arrays against the scheme's layout; the check then indexes them
        // freely.
        self.capture()?;
        let scheme = self.scheme()?;
        let pixels = self.viewport()?.pixels();
        let mut check = WordCheck {
            corrupt: vec![Vec::new(); pixels],
            ..WordCheck::default()
        };
        let missing = |n: &str| DumpError(format!("missing array {n:?}"));
        match &scheme {
            DumpScheme::Mdts { k, direction } => {
                let slots = self.u64s("slots")?.ok_or_else(|| missing("slots"))?;
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
                let at = abuffer_slots(&scheme);
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

/// Pixel `p`'s slot range in an A-buffer's flat slot array.
fn abuffer_slots(scheme: &DumpScheme) -> impl Fn(usize) -> (usize, usize) + '_ {
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
        DumpScheme::ABufferFixed { capacity, .. } => (p * *capacity as usize, *capacity as usize),
        _ => (offsets[p], offsets[p + 1] - offsets[p]),
    }
}

/// A-buffer lists as the GPU's sort kernel left them: `min(counter, capacity)` slots, unsorted.
fn stored_lists(scheme: &DumpScheme, counters: &[u32], slots: &[u64]) -> Capture {
    let at = abuffer_slots(scheme);
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
fn sort_abuffer_in_place(arrays: &mut BTreeMap<String, Words>, scheme: &DumpScheme) {
    let counters = match arrays.get("counters") {
        Some(Words::U32(c)) => c.clone(),
        _ => return,
    };
    let at = abuffer_slots(scheme);
    if let Some(Words::U64(slots)) = arrays.get_mut("slots") {
        for (p, &count) in counters.iter().enumerate() {
            let (first, capacity) = at(p);
            slots[first..first + (count as usize).min(capacity)].sort_unstable();
        }
    }
}

/// Refuses an array file name with a directory part (`/`, `\\`, a drive's `:`), `.`, `..` or
/// nothing: a dump's arrays lie in its own directory.
/// Refuses two arrays that name the same file: one file cannot hold both, so encoding would keep
/// one array's words under both names (found by `dump_parse`).
fn check_distinct_files(arrays: &BTreeMap<String, ArraySpec>) -> Result<(), DumpError> {
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

fn check_file_name(name: &str, file: &str) -> Result<(), DumpError> {
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

/// The element count of a shape, refused when it overflows 64 bits.
fn elements(name: &str, shape: &[u64]) -> Result<u64, DumpError> {
    shape
        .iter()
        .try_fold(1u64, |n, &d| n.checked_mul(d))
        .ok_or_else(|| {
            DumpError(format!(
                "array {name:?}: shape {shape:?} has more than 2^64 elements"
            ))
        })
}

fn check_array(name: &str, spec: &ArraySpec, dtype: Dtype, len: u64) -> Result<(), DumpError> {
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

impl Oracle {
    /// An oracle whose per-pixel lists are a capture's (each sorted to canonical order): a dump
    /// used as the reference of a comparison.
    #[must_use]
    pub fn from_capture(capture: &Capture) -> Self {
        let mut entries = capture.entries.clone();
        for p in 0..capture.pixels() {
            entries[capture.offsets[p]..capture.offsets[p + 1]].sort_unstable();
        }
        Self {
            offsets: capture.offsets.clone(),
            entries,
        }
    }
}

/// A capture reduced to a coarser identity (e.g. to compare a u64 dump with a u32 reference).
#[must_use]
pub fn with_identity(capture: &Capture, identity: Identity) -> Capture {
    let mask = match identity {
        Identity::KeyAndPrim => u64::MAX,
        Identity::KeyOnly => u64::MAX << 32,
        Identity::PrimOnly => u64::from(u32::MAX),
    };
    Capture {
        entries: capture.entries.iter().map(|e| e & mask).collect(),
        identity,
        ..capture.clone()
    }
}

/// Per-pixel verdict flags of a comparison (a pixel with none of [`verdict::DIFFERS`] is equal).
pub mod verdict {
    /// Fragments the reference has and the candidate should have kept are missing.
    pub const MISSING: u8 = 1;
    /// The candidate has fragments the reference does not.
    pub const EXTRA: u8 = 2;
    /// The candidate's list is out of canonical order.
    pub const MISORDERED: u8 = 4;
    /// Storage overflowed by design (beyond K, past a capacity): counted, not an error by itself.
    pub const OVERFLOWED: u8 = 8;
    /// An A-buffer counter that is not the pixel's fragment count: larger than the pixel could
    /// have, or an overflow `counter − capacity` other than `max(0, n − capacity)`.
    pub const MISCOUNTED: u8 = 16;
    /// A stored word that the layout says cannot be there ([`super::Corruption`]).
    pub const CORRUPT: u8 = 32;
    /// Flags that make a pixel differ.
    pub const DIFFERS: u8 = MISSING | EXTRA | MISORDERED | MISCOUNTED | CORRUPT;

    /// Each flag with its name in reports, in report order.
    pub const NAMES: [(u8, &str); 6] = [
        (MISSING, "missing"),
        (EXTRA, "extra"),
        (MISORDERED, "misordered"),
        (OVERFLOWED, "overflowed"),
        (MISCOUNTED, "overflow-miscounted"),
        (CORRUPT, "corrupt"),
    ];

    /// The names of the flags set in `flags`.
    #[must_use]
    pub fn names(flags: u8) -> Vec<&'static str> {
        NAMES
            .iter()
            .filter(|(flag, _)| flags & flag != 0)
            .map(|&(_, name)| name)
            .collect()
    }
}

/// Pixel counts per verdict; the JSON keys are the verdicts' names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct VerdictCounts {
    /// Pixels equal to the reference (possibly with overflow by design).
    pub equal: u64,
    /// Pixels missing fragments.
    pub missing: u64,
    /// Pixels with extra fragments.
    pub extra: u64,
    /// Pixels out of order.
    pub misordered: u64,
    /// Pixels whose storage overflowed by design.
    pub overflowed: u64,
    /// Pixels whose A-buffer counter is not their fragment count.
    #[serde(rename = "overflow-miscounted")]
    pub miscounted: u64,
    /// Pixels holding a word their layout says cannot be there.
    pub corrupt: u64,
}

impl VerdictCounts {
    /// Counts one pixel's flags.
    fn add(&mut self, flags: u8) {
        let counters = [
            (verdict::MISSING, &mut self.missing),
            (verdict::EXTRA, &mut self.extra),
            (verdict::MISORDERED, &mut self.misordered),
            (verdict::OVERFLOWED, &mut self.overflowed),
            (verdict::MISCOUNTED, &mut self.miscounted),
            (verdict::CORRUPT, &mut self.corrupt),
        ];
        for (flag, count) in counters {
            *count += u64::from(flags & flag != 0);
        }
        self.equal += u64::from(flags & verdict::DIFFERS == 0);
    }
}

/// The result of [`compare`] and [`compare_with`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Comparison {
    /// Totals over every pixel (the sum of one [`Oracle::diff`] per pixel), with the first
    /// `examples` differing pixels. `overflowed` is the overflow the reference predicts where it
    /// knows the pixel's fragment count (`max(0, n − capacity)`), not what counters claim;
    /// `mismatched_pixels` counts every pixel with a [`verdict::DIFFERS`] flag.
    pub diff: Diff,
    /// Per pixel, `verdict` flags.
    pub verdicts: Vec<u8>,
    /// Pixels per verdict.
    pub counts: VerdictCounts,
    /// The overflow the candidate claims: its A-buffer counters' `Σ (counter − stored)`, or for
    /// MDTS what lies beyond K (its promise); equal to `diff.overflowed` unless a counter is
    /// miscounted.
    pub claimed_overflow: u64,
    /// Words that the layout says cannot be there (0 when no words were checked).
    pub corrupt_words: u64,
    /// Words the layout leaves undefined, not checked ([`WordCheck::unchecked`]).
    pub unchecked_words: u64,
    /// Whether the candidate's words were checked at all ([`compare_with`] with a
    /// [`WordCheck`]), not only its decoded lists.
    pub words_checked: bool,
    /// The corrupt words of the pixels in `diff.first_mismatches`.
    pub first_corrupt: Vec<CorruptWord>,
}

impl Comparison {
    /// Whether every pixel is equal (overflow by design allowed).
    #[must_use]
    pub fn is_equal(&self) -> bool {
        self.diff.is_exact()
    }
}

/// How [`compare_with`] judges.
#[derive(Clone, Copy, Debug, Default)]
pub struct CompareOptions<'a> {
    /// Accept a candidate key within this many f32 ulps of an otherwise unmatched reference
    /// fragment of the same primitive (any, for key-only words); 0: bit for bit.
    pub depth_ulps: u32,
    /// How many differing pixels to keep as examples.
    pub examples: usize,
    /// Per pixel, whether the reference knows every fragment there; `None`: everywhere, as the
    /// oracle does. An A-buffer counter is checked against the pixel's fragment count only
    /// where the reference knows it ([`complete_pixels`] of a dump used as the reference).
    pub complete: Option<&'a [bool]>,
}

/// Per pixel, whether a capture holds every fragment of the pixel: fewer than K in an MDTS
/// pixel, no overflow in an A-buffer one. Where it does not, a comparison against it cannot
/// know the pixel's fragment count.
#[must_use]
pub fn complete_pixels(capture: &Capture) -> Vec<bool> {
    (0..capture.pixels())
        .map(|p| match &capture.keeps {
            Keeps::Nearest(k) | Keeps::Farthest(k) => capture.pixel(p).len() < *k as usize,
            Keeps::All { overflow, .. } => overflow[p] == 0,
        })
        .collect()
}

/// Compares `candidate`'s decoded lists with `reference` pixel by pixel under the candidate's
/// promise ([`compare_with`] with no word check and a reference that knows every fragment).
///
/// # Panics
/// If the capture and the reference cover different numbers of pixels.
#[must_use]
pub fn compare(
    reference: &Oracle,
    candidate: &Capture,
    depth_ulps: u32,
    examples: usize,
) -> Comparison {
    let options = CompareOptions {
        depth_ulps,
        examples,
        complete: None,
    };
    compare_with(reference, candidate, None, &options)
}

impl Dump {
    /// Compares this dump with `reference`: its decoded lists ([`Dump::capture`]) and every one
    /// of its words ([`Dump::check_words`]), with [`compare_with`].
    ///
    /// # Errors
    /// As [`Dump::capture`].
    ///
    /// # Panics
    /// If the dump and the reference cover different numbers of pixels.
    pub fn compare(
        &self,
        reference: &Oracle,
        options: &CompareOptions<'_>,
    ) -> Result<Comparison, DumpError> {
        let capture = self.capture()?;
        let words = self.check_words()?;
        Ok(compare_with(reference, &capture, Some(&words), options))
    }
}

/// An A-buffer pixel's counter as a capture alone shows it: `stored + overflow`, and a capacity
/// of `stored` when it overflowed (storage ran out), unknown (at least `stored`) when not.
fn inferred_counter(stored: usize, overflow: u32) -> Counter {
    Counter {
        count: stored as u32 + overflow,
        capacity: if overflow > 0 {
            stored as u32
        } else {
            u32::MAX
        },
    }
}

/// Compares `candidate` with `reference` pixel by pixel under the candidate's promise, with
/// [`Oracle::diff`] on each pixel, and adds what `words` (the candidate dump's
/// [`WordCheck`]) found: a pixel with a corrupt word is [`verdict::CORRUPT`] whatever its list,
/// and an A-buffer slot holding the empty marker is taken out of the list (it is no fragment,
/// so it is corrupt, not extra).
///
/// An A-buffer counter must equal its pixel's fragment count `n`, which the reference knows
/// (where `options.complete` says so): every fragment adds one and the counter never wraps. A
/// counter that differs is [`verdict::MISCOUNTED`]: larger than the pixel could have, or an
/// overflow `counter − capacity` other than `max(0, n − capacity)`. The overflow allowed to be
/// missing is then `max(0, n − capacity)`, never what the counter claims; without `words` the
/// counter and capacity are inferred from the capture ([`Keeps::All`]'s overflow).
///
/// With `options.depth_ulps > 0`, a candidate fragment whose key lies within that many f32 ulps
/// of an otherwise unmatched reference fragment of the same primitive (any, for key-only words)
/// counts as that fragment; a list the candidate stored in order stays in order.
///
/// # Panics
/// If the capture, the reference, `words` or `options.complete` cover different numbers of
/// pixels.
#[must_use]
pub fn compare_with(
    reference: &Oracle,
    candidate: &Capture,
    words: Option<&WordCheck>,
    options: &CompareOptions<'_>,
) -> Comparison {
    let pixels = candidate.pixels();
    assert_eq!(
        reference.pixels(),
        pixels,
        "capture and reference cover different viewports"
    );
    if let Some(words) = words {
        assert_eq!(
            words.corrupt.len(),
            pixels,
            "word check of another viewport"
        );
    }
    if let Some(complete) = options.complete {
        assert_eq!(complete.len(), pixels, "completeness of another viewport");
    }
    let mut comparison = Comparison {
        diff: Diff::default(),
        verdicts: Vec::with_capacity(pixels),
        counts: VerdictCounts::default(),
        claimed_overflow: 0,
        corrupt_words: words.map_or(0, WordCheck::corrupt_words),
        unchecked_words: words.map_or(0, |w| w.unchecked),
        words_checked: words.is_some(),
        first_corrupt: Vec::new(),
    };
    let total = &mut comparison.diff;
    let mut one_ref = Oracle {
        offsets: vec![0, 0],
        entries: Vec::new(),
    };
    let mut one = Capture::with_pixels(1, candidate.identity, Keeps::Nearest(0));
    one.offsets.push(0);
    for p in 0..pixels {
        let all = reference.pixel(p);
        let n = all.len();
        let knows_n = options.complete.is_none_or(|c| c[p]);
        one_ref.entries.clear();
        one_ref.entries.extend_from_slice(all);
        one_ref.offsets[1] = n;
        let got = candidate.pixel(p);
        one.entries.clear();
        let mut flags = 0;
        one.keeps = match &candidate.keeps {
            Keeps::All { overflow, .. } => {
                let counter = match words.and_then(|w| w.counters.as_ref()) {
                    Some(counters) => counters[p],
                    None => inferred_counter(got.len(), overflow[p]),
                };
                comparison.claimed_overflow += u64::from(overflow[p]);
                // The marker is no fragment: its word check calls it corrupt.
                let marker_is_corrupt = words.is_some();
                one.entries
                    .extend(got.iter().filter(|&&e| !marker_is_corrupt || e != u64::MAX));
                let (capacity, allowed) = if knows_n {
                    if counter.count as usize != n {
                        flags |= verdict::MISCOUNTED;
                    }
                    let allowed = n.saturating_sub(counter.capacity as usize) as u32;
                    (Capacity::PerPixel(counter.capacity), allowed)
                } else {
                    // The reference does not know the count: the claimed overflow stands, as
                    // the capacity that predicts exactly it from the fragments the reference has.
                    let stands = n.saturating_sub(overflow[p] as usize) as u32;
                    (Capacity::PerPixel(stands), overflow[p])
                };
                Keeps::All {
                    capacity,
                    overflow: vec![allowed],
                }
            }
            keeps => {
                one.entries.extend_from_slice(got);
                keeps.clone()
            }
        };
        let counted = matches!(candidate.keeps, Keeps::All { .. });
        if options.depth_ulps > 0 {
            snap_to_reference(
                &mut one.entries,
                all,
                candidate.identity,
                options.depth_ulps,
            );
        }
        one.offsets[1] = one.entries.len();
        let d = one_ref.diff(&one);
        if words.is_some_and(|w| !w.corrupt[p].is_empty()) {
            flags |= verdict::CORRUPT;
        }
        if d.lost > 0 {
            flags |= verdict::MISSING;
        }
        if d.extra > 0 {
            flags |= verdict::EXTRA;
        }
        if d.misordered_pixels > 0 {
            flags |= verdict::MISORDERED;
        }
        if d.overflowed > 0 {
            flags |= verdict::OVERFLOWED;
        }
        // A pixel the diff rejects for no other reason has fewer fragments missing than the
        // overflow it was allowed. Where the reference knows the count that cannot happen (the
        // allowance is `n − capacity` and at most `capacity` are held), so it is named a miscount
        // rather than left unnamed; where the reference does not know the count, the claimed
        // overflow is all there is and a reference holding no more than the candidate is no gap.
        if d.mismatched_pixels > 0 && flags & verdict::DIFFERS == 0 && knows_n {
            flags |= verdict::MISCOUNTED;
        }
        comparison.counts.add(flags);
        if !counted {
            // MDTS claims nothing: what lies beyond K is its promise.
            comparison.claimed_overflow += d.overflowed;
        }
        total.captured += d.captured;
        total.overflowed += d.overflowed;
        total.lost += d.lost;
        total.extra += d.extra;
        total.misordered_pixels += d.misordered_pixels;
        if flags & verdict::DIFFERS != 0 {
            total.mismatched_pixels += 1;
            if total.first_mismatches.len() < options.examples {
                let example = d.first_mismatches.into_iter().next().unwrap_or_else(|| {
                    // Equal lists, wrong words: both sides are the list the pixel holds.
                    PixelMismatch {
                        pixel: p,
                        expected: one.entries.clone(),
                        got: one.entries.clone(),
                    }
                });
                total.first_mismatches.push(PixelMismatch {
                    pixel: p,
                    ..example
                });
                if let Some(words) = words {
                    comparison
                        .first_corrupt
                        .extend_from_slice(&words.corrupt[p]);
                }
            }
        }
        comparison.verdicts.push(flags);
    }
    comparison
}

/// Replaces each candidate fragment that has no exact match in `reference` by the nearest
/// unmatched reference fragment of the same primitive within `ulps` (the depth key is the f32's
/// bit pattern, so a key difference is a distance in ulps).
fn snap_to_reference(got: &mut [u64], reference: &[u64], identity: Identity, ulps: u32) {
    if identity == Identity::PrimOnly {
        return;
    }
    let mask = if identity == Identity::KeyOnly {
        u64::MAX << 32
    } else {
        u64::MAX
    };
    let was_sorted = got.windows(2).all(|w| w[0] <= w[1]);
    let mut used = vec![false; reference.len()];
    let mut unmatched = Vec::new();
    for (i, g) in got.iter().enumerate() {
        match (0..reference.len()).find(|&j| !used[j] && reference[j] & mask == *g) {
            Some(j) => used[j] = true,
            None => unmatched.push(i),
        }
    }
    for i in unmatched {
        let (key, prim) = ((got[i] >> 32) as u32, got[i] as u32);
        let nearest = (0..reference.len())
            .filter(|&j| !used[j])
            .filter(|&j| identity == Identity::KeyOnly || reference[j] as u32 == prim)
            .map(|j| (((reference[j] >> 32) as u32).abs_diff(key), j))
            .filter(|&(distance, _)| distance <= ulps)
            .min();
        if let Some((_, j)) = nearest {
            used[j] = true;
            got[i] = reference[j] & mask;
        }
    }
    if was_sorted {
        got.sort_unstable();
    }
}

/// The magic bytes that open a triangle export.
pub const TRIANGLES_MAGIC: [u8; 8] = *b"FRAGTRI1";
/// The triangle export's version.
pub const TRIANGLES_VERSION: u32 = 1;
/// Bytes per triangle record.
pub const TRIANGLE_RECORD_BYTES: usize = 56;
const TRIANGLES_HEADER_BYTES: usize = 40;

/// A view's screen triangles: fragsim's vertex stage, clipping, snapping and orientation done.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleExport {
    /// The scene and camera (copied verbatim into a backend's dump header).
    pub scene: SceneSpec,
    /// Viewport width.
    pub width: u32,
    /// Viewport height.
    pub height: u32,
    /// Triangles in the mesh (primitive ids are below this).
    pub mesh_triangles: u32,
    /// The oriented pieces, in primitive order then fan order: scanning each with
    /// `View::scan` gives exactly the view's fragments.
    pub triangles: Vec<ScreenTriangle>,
}

impl TriangleExport {
    /// Every screen triangle of `view`.
    #[must_use]
    pub fn from_view(view: &View<'_>, scene: SceneSpec) -> Self {
        let mut triangles = Vec::new();
        for prim in 0..view.triangle_count() {
            view.screen_triangles(prim, &mut |t| triangles.push(t));
        }
        let viewport = view.viewport();
        Self {
            scene,
            width: viewport.width,
            height: viewport.height,
            mesh_triangles: view.triangle_count(),
            triangles,
        }
    }

    /// The file's bytes (`docs/dump-format.md`).
    ///
    /// # Errors
    /// A coordinate outside i32 (impossible within the guard band), too many triangles, or a
    /// scene number that is not finite ([`SceneSpec::check_finite`]).
    pub fn to_bytes(&self) -> Result<Vec<u8>, DumpError> {
        self.scene.check_finite()?;
        let json = serde_json::to_string(&self.scene)
            .map_err(|e| DumpError(format!("cannot encode the scene: {e}")))?;
        let padded = json.len().next_multiple_of(8);
        let count = u32::try_from(self.triangles.len())
            .map_err(|_| DumpError("more than 2^32 screen triangles".into()))?;
        let mut bytes = Vec::with_capacity(
            TRIANGLES_HEADER_BYTES + padded + self.triangles.len() * TRIANGLE_RECORD_BYTES,
        );
        bytes.extend_from_slice(&TRIANGLES_MAGIC);
        for field in [
            TRIANGLES_VERSION,
            self.width,
            self.height,
            SUBPIXEL_BITS,
            self.mesh_triangles,
            count,
            json.len() as u32,
            TRIANGLE_RECORD_BYTES as u32,
        ] {
            bytes.extend_from_slice(&field.to_le_bytes());
        }
        bytes.extend_from_slice(json.as_bytes());
        bytes.resize(TRIANGLES_HEADER_BYTES + padded, b' ');
        for t in &self.triangles {
            bytes.extend_from_slice(&t.prim.to_le_bytes());
            for v in t.xy.iter().flatten() {
                let v = i32::try_from(*v).map_err(|_| {
                    DumpError(format!("triangle {}: coordinate {v} outside i32", t.prim))
                })?;
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            bytes.extend_from_slice(&0u32.to_le_bytes());
            for z in t.z {
                bytes.extend_from_slice(&z.to_le_bytes());
            }
        }
        Ok(bytes)
    }

    /// Parses a triangle export.
    ///
    /// # Errors
    /// Wrong magic or version, a truncated file, a malformed scene.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DumpError> {
        let u32_at = |at: usize| -> Result<u32, DumpError> {
            bytes
                .get(at..at + 4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .ok_or_else(|| DumpError("triangle export truncated".into()))
        };
        if bytes.get(..8) != Some(&TRIANGLES_MAGIC[..]) {
            return err("not a fragsim triangle export (bad magic)");
        }
        let version = u32_at(8)?;
        if version != TRIANGLES_VERSION {
            return err(format!(
                "triangle export version {version}, expected {TRIANGLES_VERSION}"
            ));
        }
        let (width, height, bits) = (u32_at(12)?, u32_at(16)?, u32_at(20)?);
        if bits != SUBPIXEL_BITS {
            return err(format!(
                "{bits} subpixel bits, fragsim uses {SUBPIXEL_BITS}"
            ));
        }
        let (mesh_triangles, count) = (u32_at(24)?, u32_at(28)? as usize);
        let (json_len, record) = (u32_at(32)? as usize, u32_at(36)? as usize);
        if record != TRIANGLE_RECORD_BYTES {
            return err(format!(
                "record size {record}, expected {TRIANGLE_RECORD_BYTES}"
            ));
        }
        let start = TRIANGLES_HEADER_BYTES + json_len.next_multiple_of(8);
        let json = bytes
            .get(TRIANGLES_HEADER_BYTES..TRIANGLES_HEADER_BYTES + json_len)
            .ok_or_else(|| DumpError("triangle export truncated".into()))?;
        let scene: SceneSpec = serde_json::from_slice(json)
            .map_err(|e| DumpError(format!("triangle export scene: {e}")))?;
        if bytes.len() != start + count * TRIANGLE_RECORD_BYTES {
            return err(format!(
                "triangle export of {} bytes, expected {} for {count} triangles",
                bytes.len(),
                start + count * TRIANGLE_RECORD_BYTES
            ));
        }
        let triangles = bytes[start..]
            .chunks_exact(TRIANGLE_RECORD_BYTES)
            .map(|r| {
                let i32_at = |at: usize| {
                    i64::from(i32::from_le_bytes([r[at], r[at + 1], r[at + 2], r[at + 3]]))
                };
                let f64_at =
                    |at: usize| f64::from_le_bytes(r[at..at + 8].try_into().unwrap_or([0; 8]));
                ScreenTriangle {
                    prim: u32::from_le_bytes([r[0], r[1], r[2], r[3]]),
                    xy: [
                        [i32_at(4), i32_at(8)],
                        [i32_at(12), i32_at(16)],
                        [i32_at(20), i32_at(24)],
                    ],
                    z: [f64_at(32), f64_at(40), f64_at(48)],
                }
            })
            .collect();
        Ok(Self {
            scene,
            width,
            height,
            mesh_triangles,
            triangles,
        })
    }

    /// Writes the export to `path`, creating parent directories.
    ///
    /// # Errors
    /// I/O failures; see [`TriangleExport::to_bytes`].
    pub fn write(&self, path: &Path) -> Result<(), DumpError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| io_err("create", dir, e))?;
        }
        std::fs::write(path, self.to_bytes()?).map_err(|e| io_err("write", path, e))
    }

    /// Reads an export from `path`.
    ///
    /// # Errors
    /// I/O failures; see [`TriangleExport::from_bytes`].
    pub fn read(path: &Path) -> Result<Self, DumpError> {
        Self::from_bytes(&std::fs::read(path).map_err(|e| io_err("read", path, e))?)
    }
}

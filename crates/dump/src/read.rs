//! Parsing a dump (from bytes or a directory) and decoding its words into per-pixel lists through
//! the scheme's own post pass.

use std::collections::BTreeMap;
use std::path::Path;

use fragsim_capture::{Capture, Scheme};

use fragsim_memory::{SerialMemory, WordMemory};
use fragsim_raster::Viewport;

use crate::arrays::stored_lists;
use crate::header::{array_bytes, check_array, check_distinct_files, check_file_name};
use crate::shapes::check_shapes;
use crate::{err, io_err, Dtype, Dump, DumpError, DumpScheme, Header, Words};
use crate::{FORMAT, HEADER_FILE, VERSION};
use fragsim_capture::MEMORY_CAP_DEFAULT;
use fragsim_catalog::{SchemeName, SchemeVisitor};
use fragsim_raster::files::{read_regular, FileError};

/// The most bytes a dump header may have: a header is a few kilobytes, its `extra` included.
pub const HEADER_BYTES_LIMIT: u64 = 4 << 20;

/// The UTF-8 byte-order mark some editors and Windows tools put before JSON text: skipped.
const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// A file refused or unreadable, as a dump error: the system's refusal stays [`DumpError::Io`].
fn file_error(e: FileError) -> DumpError {
    match e {
        FileError::Io { path, source } => io_err("read", &path, source),
        e => DumpError::Invalid(e.to_string()),
    }
}

fn write_all<W: fragsim_memory::Word>(memory: &impl WordMemory<W>, words: &[W]) {
    for (i, &w) in words.iter().enumerate() {
        memory.store(i, w);
    }
}

/// Loads the words into the scheme's memory and runs its post pass; a sorted A-buffer's lists
/// are taken as stored instead.
struct Resolve<'a> {
    scheme: &'a DumpScheme,
    /// `None`: the dump has none of the scheme's u32 words (a k-buffer's locks and tickets, which
    /// its resolve never reads), so they keep their initial values.
    words32: Option<&'a [u32]>,
    words64: &'a [u64],
}

impl SchemeVisitor for Resolve<'_> {
    type Output = Result<Capture, DumpError>;
    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) -> Self::Output {
        let layout = scheme.layout();
        let words32 = self.words32.map_or(layout.words32, <[u32]>::len);
        if layout.words32 != words32 || layout.words64 != self.words64.len() {
            return err(format!(
                "{} over this viewport holds {} u32 and {} u64 words; the dump has {words32} and {}",
                scheme.name(),
                layout.words32,
                layout.words64,
                self.words64.len()
            ));
        }
        if let DumpScheme::ABufferFixed { sorted: true, .. }
        | DumpScheme::ABufferExact { sorted: true, .. } = self.scheme
        {
            return Ok(stored_lists(
                self.scheme,
                self.words32.unwrap_or_default(),
                self.words64,
            ));
        }
        let memory: SerialMemory = layout.allocate();
        write_all(&memory, self.words32.unwrap_or_default());
        write_all(&memory, self.words64);
        Ok(scheme.resolve(&memory))
    }
}

impl Dump {
    /// Reads a dump from its directory (or from the path of its `dump.json`), its arrays holding
    /// at most fragsim's default memory cap ([`Dump::read_within`]).
    ///
    /// # Errors
    /// As [`Dump::read_within`].
    pub fn read(path: &Path) -> Result<Self, DumpError> {
        Self::read_within(path, MEMORY_CAP_DEFAULT)
    }

    /// Reads a dump from its directory (or from the path of its `dump.json`) whose arrays hold
    /// at most `limit` bytes together (`--memory-cap`). Only regular files are read (links
    /// followed; a FIFO or a device is refused by its kind, unopened: [`fragsim_raster::files`]),
    /// the header at most [`HEADER_BYTES_LIMIT`] bytes, and each array file only once its size
    /// (the file's metadata) is what its shape makes.
    ///
    /// # Errors
    /// Missing, irregular or oversized files, a malformed header, another format or version,
    /// array files whose size disagrees with their shape, or arrays over `limit` bytes.
    pub fn read_within(path: &Path, limit: u64) -> Result<Self, DumpError> {
        let (dir, header_path) = if path.is_dir() {
            (path.to_path_buf(), path.join(HEADER_FILE))
        } else {
            (
                path.parent().unwrap_or(Path::new(".")).to_path_buf(),
                path.to_path_buf(),
            )
        };
        let text = read_regular(&header_path, HEADER_BYTES_LIMIT, "a dump header may have")
            .map_err(file_error)?;
        Self::parse_within(
            &header_path.display().to_string(),
            &text,
            limit,
            |file, bytes| {
                read_regular(&dir.join(file), bytes, "its array's shape makes").map_err(file_error)
            },
        )
    }

    /// Decodes a dump from its header's bytes (`dump.json`, named `header_name` in errors) and
    /// `read_file`, which returns an array file's bytes by its name in the header. Never touches
    /// the file system itself: [`Dump::read`] passes a reader of the dump's directory, the
    /// `dump_parse` fuzz target one over its input. [`Dump::parse_within`] with no limit.
    ///
    /// # Errors
    /// As [`Dump::parse_within`].
    pub fn parse(
        header_name: &str,
        header_bytes: &[u8],
        mut read_file: impl FnMut(&str) -> Result<Vec<u8>, DumpError>,
    ) -> Result<Self, DumpError> {
        Self::parse_within(header_name, header_bytes, u64::MAX, |file, _| {
            read_file(file)
        })
    }

    /// Decodes a dump from its header's bytes and `read_file`, which is handed each array
    /// file's name and the bytes its shape makes (so that a reader of files can refuse one of
    /// another size before reading it), the arrays holding at most `limit` bytes together.
    ///
    /// Everything the header alone can contradict is refused before any array is read: a
    /// UTF-8 byte-order mark is skipped; array file names must be plain names (no directory part,
    /// not `.` or `..`), so that a header cannot make the reader open a file outside the dump's
    /// directory; shapes whose element count or bytes overflow 64 bits are refused, and so are
    /// the fields that contradict one another or the layout (`Header::check_fields`: an array
    /// the layout does not use, `capacity` beside `offsets`, a scene with both `name` and `mesh`,
    /// list numbering out of range) and shapes the header's fields contradict (`check_shapes`,
    /// where the header alone fixes them).
    ///
    /// # Errors
    /// A malformed header, another format or version, a bad viewport, an array file name that is
    /// not plain, a shape that overflows, contradictory fields, arrays over `limit` bytes,
    /// `read_file`'s own errors, or array files whose size disagrees with their shape.
    pub fn parse_within(
        header_name: &str,
        header_bytes: &[u8],
        limit: u64,
        mut read_file: impl FnMut(&str, u64) -> Result<Vec<u8>, DumpError>,
    ) -> Result<Self, DumpError> {
        let header_bytes = header_bytes.strip_prefix(UTF8_BOM).unwrap_or(header_bytes);
        let header: Header = serde_json::from_slice(header_bytes)
            .map_err(|e| DumpError::Invalid(format!("{header_name}: {e}")))?;
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
        header.framebuffer()?;
        check_distinct_files(&header.arrays)?;
        let mut sizes = Vec::with_capacity(header.arrays.len());
        let mut total = 0_u64;
        for (name, spec) in &header.arrays {
            check_file_name(name, &spec.file)?;
            let bytes = array_bytes(name, spec)?;
            total = total.saturating_add(bytes);
            sizes.push(bytes);
        }
        header.check_fields()?;
        check_shapes(&header)?;
        if total > limit {
            return err(format!(
                "{header_name}: the arrays' shapes make {total} bytes, over the memory cap of \
                 {limit} bytes (--memory-cap raises it)"
            ));
        }
        let mut arrays = BTreeMap::new();
        for ((name, spec), expected) in header.arrays.iter().zip(sizes) {
            let bytes = read_file(&spec.file, expected)?;
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

    /// The framebuffer the arrays index, one list each: the pixels of the masked-node layout
    /// ([`Dump::is_masked`]), else the sample-expanded framebuffer ([`Header::framebuffer`]),
    /// which at one sample is the viewport.
    ///
    /// # Errors
    /// A zero or oversized side, or a sample count without a standard pattern.
    pub fn viewport(&self) -> Result<Viewport, DumpError> {
        if self.is_masked() {
            self.header.pixel_viewport()
        } else {
            self.header.framebuffer()
        }
    }

    pub(super) fn u32s(&self, name: &str) -> Result<Option<&[u32]>, DumpError> {
        match self.arrays.get(name) {
            None => Ok(None),
            Some(Words::U32(w)) => Ok(Some(w)),
            Some(Words::U64(_)) => err(format!("array {name:?} must be u32")),
        }
    }

    pub(super) fn u64s(&self, name: &str) -> Result<Option<&[u64]>, DumpError> {
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

    /// Decodes the words into the per-pixel lists the verdict judges, with the scheme's own post
    /// pass (sorted A-buffer dumps: in stored order). Linked lists are decoded whole: every node
    /// a pixel's list reaches, sorted, all of them owed (the resolve's `k` limits what shading
    /// reads, not what is judged).
    ///
    /// # Errors
    /// A header that names no known scheme, or arrays missing or of the wrong size or type.
    pub fn capture(&self) -> Result<Capture, DumpError> {
        if self.is_masked() {
            return self.masked_capture();
        }
        let scheme = Self::judged_lists(self.scheme()?);
        self.check_shapes(&scheme)?;
        if let Some(own) = self.own_slots(&scheme)? {
            return own.capture();
        }
        let translated;
        let (words32, words64) = match scheme {
            DumpScheme::LinkedLists { .. } | DumpScheme::LayerMajor { .. } => {
                translated = self.translate(&scheme)?;
                (Some(&translated.words32[..]), &translated.words64[..])
            }
            DumpScheme::KBuffer { .. } => (None, required(Some("slots"), self.u64s("slots"))?),
            _ => {
                let names = scheme.names();
                (
                    Some(required(
                        names.words32,
                        self.u32s(names.words32.unwrap_or_default()),
                    )?),
                    required(names.words64, self.u64s(names.words64.unwrap_or_default()))?,
                )
            }
        };
        let resolve = Resolve {
            scheme: &scheme,
            words32,
            words64,
        };
        scheme.with_scheme(self.viewport()?, resolve)?
    }
}

impl Dump {
    /// The scheme whose post pass decodes the lists the verdict judges: the header's, except that
    /// a linked list is judged on every node its lists reach. The resolve's `k` (keep the first
    /// or the nearest `k` nodes) limits what shading reads, not what the lists hold: a node cut
    /// out of a list of more than `k` is a lost fragment wherever the resolve would have dropped
    /// it anyway. So the lists are read by the keep-first resolve with room for the whole pool,
    /// which keeps every node reached, sorted, and promises each of the pixel's fragments.
    fn judged_lists(scheme: DumpScheme) -> DumpScheme {
        match scheme {
            DumpScheme::LinkedLists { pool, spec, .. } => DumpScheme::LinkedLists {
                scheme: SchemeName::LinkedList,
                k: pool,
                pool,
                spec,
            },
            other => other,
        }
    }
}

/// The words of array `name` the layout uses, which must exist (`None`: the layout uses none).
fn required<'a, W>(
    name: Option<&str>,
    found: Result<Option<&'a [W]>, DumpError>,
) -> Result<&'a [W], DumpError> {
    match name {
        None => Ok(&[]),
        Some(n) => found?.ok_or_else(|| DumpError::Invalid(format!("missing array {n:?}"))),
    }
}

//! Triangle meshes and OBJ loading.

use std::io::{BufRead, Read};
use std::path::Path;

use crate::files::{read_regular, FileError};

/// The first two bytes of every gzip stream (RFC 1952): files are decompressed by content, so a
/// gzipped mesh loads whatever its name.
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// The most bytes a mesh file, or its text once decompressed, may hold: fragsim's default memory
/// cap, so that a file (or a gzip stream that inflates without end) cannot exhaust memory.
pub const MESH_BYTES_LIMIT: u64 = 4 << 30;

impl From<FileError> for MeshError {
    /// A file the system cannot read keeps [`MeshError::Io`]'s message; one refused unread
    /// (no regular file, too large) says why.
    fn from(e: FileError) -> Self {
        match e {
            FileError::Io { path, source } => Self::Io {
                path: path.display().to_string(),
                source,
            },
            e => Self::Unreadable(e),
        }
    }
}

/// A name that is no up axis ([`UpAxis::parse`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{text:?} is not an axis: x, y, z, -x, -y or -z")]
pub struct UpAxisError {
    /// The text given.
    pub text: String,
}

/// Why a mesh could not be loaded or used.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("cannot read mesh file {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The reason the OS gave.
        source: std::io::Error,
    },
    /// The path is no regular file, or the file (or its decompressed text) is larger than
    /// [`MESH_BYTES_LIMIT`]: refused before it is read.
    #[error("mesh file {0}")]
    Unreadable(FileError),
    /// The file starts as gzip but does not decompress.
    #[error("cannot decompress gzipped mesh file {path}: {source}")]
    Gzip {
        /// The file.
        path: String,
        /// What the decoder reported.
        source: std::io::Error,
    },
    /// The OBJ parser rejected the file (or it is not text at all).
    #[error("malformed OBJ {path}: {reason}")]
    Obj {
        /// The file.
        path: String,
        /// What is wrong, with the line where there is one.
        reason: String,
    },
    /// The PLY parser rejected the file.
    #[error("malformed PLY {path}: {reason}")]
    Ply {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The file parsed but holds no triangle.
    #[error("{format} {path} has no triangles")]
    Empty {
        /// `OBJ`, `PLY`, or `mesh` for one built in memory.
        format: &'static str,
        /// The file.
        path: String,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("{format} {path}: vertex {vertex} has a non-finite coordinate {value}")]
    NonFinite {
        /// `OBJ`, `PLY`, or `mesh` for one built in memory.
        format: &'static str,
        /// The file.
        path: String,
        /// Index of the vertex.
        vertex: usize,
        /// The coordinate.
        value: f32,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "{format} {path}: triangle {triangle} refers to vertex {index}, but there are only {vertices}"
    )]
    BadIndex {
        /// `OBJ`, `PLY`, or `mesh` for one built in memory.
        format: &'static str,
        /// The file.
        path: String,
        /// Index of the triangle.
        triangle: usize,
        /// The bad vertex index.
        index: u32,
        /// How many vertices the mesh has.
        vertices: usize,
    },
}

/// An indexed triangle mesh. Triangle `i` has primitive id `i`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in model space.
    pub positions: Vec<[f32; 3]>,
    /// Vertex indices, three per triangle, in the order the file gave them.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Checks that every coordinate is finite and every index in range.
    ///
    /// # Errors
    /// The first problem found, naming `source` (a file name or a scene name).
    pub fn validate(&self, source: &str) -> Result<(), MeshError> {
        self.validate_as("mesh", source)
    }

    /// [`Mesh::validate`] for a mesh read from a file of `format` (`OBJ`, `PLY`), which the
    /// errors name.
    ///
    /// # Errors
    /// As [`Mesh::validate`].
    pub fn validate_as(&self, format: &'static str, source: &str) -> Result<(), MeshError> {
        for (vertex, p) in self.positions.iter().enumerate() {
            if let Some(&value) = p.iter().find(|c| !c.is_finite()) {
                return Err(MeshError::NonFinite {
                    format,
                    path: source.into(),
                    vertex,
                    value,
                });
            }
        }
        for (triangle, tri) in self.triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= self.positions.len()) {
                return Err(MeshError::BadIndex {
                    format,
                    path: source.into(),
                    triangle,
                    index,
                    vertices: self.positions.len(),
                });
            }
        }
        Ok(())
    }

    /// Loads an OBJ file, triangulating polygons, all of its models merged into one mesh.
    ///
    /// # Errors
    /// A missing or unreadable file, a file tobj rejects, a face of fewer than 3 vertices or one
    /// referring to texture coordinates or normals the file lacks, a mesh with no triangle, a
    /// non-finite coordinate or an out-of-range index: each names the file.
    pub fn load_obj(path: &Path) -> Result<Self, MeshError> {
        let name = path.display().to_string();
        Self::read_obj(&mut read_mesh_file(path)?.as_slice(), &name)
    }

    /// Parses OBJ text from a reader; `name` is used in error messages.
    ///
    /// # Errors
    /// As [`Mesh::load_obj`].
    pub fn read_obj(reader: &mut impl BufRead, name: &str) -> Result<Self, MeshError> {
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ..Default::default()
        };
        // Read once, parse twice: the face checks tobj leaves out, then tobj.
        let mut text = Vec::new();
        reader
            .read_to_end(&mut text)
            .map_err(|source| MeshError::Io {
                path: name.into(),
                source,
            })?;
        let obj = |reason| MeshError::Obj {
            path: name.into(),
            reason,
        };
        let text = String::from_utf8(text).map_err(|e| obj(not_text(e.as_bytes())))?;
        if text.contains('\0') {
            return Err(obj(not_text(text.as_bytes())));
        }
        check_faces(&text).map_err(|e| obj(e.to_string()))?;
        let text = text.into_bytes();
        let (models, _materials) = tobj::load_obj_buf(&mut text.as_slice(), &options, |_| {
            // Materials are irrelevant to depth; an absent .mtl must not fail the load.
            Ok(Default::default())
        })
        .map_err(|e| MeshError::Obj {
            path: name.into(),
            reason: e.to_string(),
        })?;
        let mut mesh = Self::default();
        for model in models {
            let m = model.mesh;
            if m.positions.len() % 3 != 0 || m.indices.len() % 3 != 0 {
                return Err(MeshError::Obj {
                    path: name.into(),
                    reason: "ragged position or index array".into(),
                });
            }
            let base = u32::try_from(mesh.positions.len()).map_err(|_| MeshError::Obj {
                path: name.into(),
                reason: "more than 2^32 vertices".into(),
            })?;
            mesh.positions
                .extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
            for t in m.indices.chunks_exact(3) {
                let shifted = [t[0], t[1], t[2]].map(|i| i.saturating_add(base));
                mesh.triangles.push(shifted);
            }
        }
        if mesh.triangles.is_empty() {
            return Err(MeshError::Empty {
                format: "OBJ",
                path: name.into(),
            });
        }
        mesh.validate_as("OBJ", name)?;
        Ok(mesh)
    }

    /// Axis-aligned bounds `(min, max)` of the vertices that triangles use.
    #[must_use]
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        use rayon::prelude::*;
        if self.triangles.is_empty() {
            return ([0.0; 3], [0.0; 3]);
        }
        let empty = || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let merge = |(lo, hi): ([f64; 3], [f64; 3]), (lo2, hi2): ([f64; 3], [f64; 3])| {
            (
                [0, 1, 2].map(|axis| lo[axis].min(lo2[axis])),
                [0, 1, 2].map(|axis| hi[axis].max(hi2[axis])),
            )
        };
        // A reduction over triangles (not positions: unused vertices must not widen the view),
        // in parallel because the full dragon's 2.6 M random reads dominate the vertex stage.
        self.triangles
            .par_iter()
            .with_min_len(4096)
            .fold(empty, |bounds, tri| {
                tri.iter().fold(bounds, |bounds, &i| {
                    let p = self.positions[i as usize].map(f64::from);
                    merge(bounds, (p, p))
                })
            })
            .reduce(empty, merge)
    }
}

/// The axis a model points up along in its file. fragsim's orbit camera circles the +y axis
/// (OBJ's custom); scanners and CAD tools often model z up, so such a mesh would lie on its
/// side. Turning the model onto +y is a signed permutation of its axes: exact in any
/// precision, its bounds the permuted bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UpAxis {
    /// +x up.
    X,
    /// −x up.
    MinusX,
    /// +y up: the model as the file has it.
    #[default]
    Y,
    /// −y up (a model upside down).
    MinusY,
    /// +z up (the horse, most CAD and scanner files).
    Z,
    /// −z up.
    MinusZ,
}

impl UpAxis {
    /// Every axis, in the order `--help` lists them.
    pub const ALL: [Self; 6] = [
        Self::Y,
        Self::Z,
        Self::X,
        Self::MinusY,
        Self::MinusZ,
        Self::MinusX,
    ];

    /// The axis's name: `x`, `y`, `z`, `-x`, `-y` or `-z`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::X => "x",
            Self::MinusX => "-x",
            Self::Y => "y",
            Self::MinusY => "-y",
            Self::Z => "z",
            Self::MinusZ => "-z",
        }
    }

    /// The axis named `text` (`x`, `+x`, `-x`, … case-insensitive).
    ///
    /// # Errors
    /// Any other text, with the names accepted.
    pub fn parse(text: &str) -> Result<Self, UpAxisError> {
        let lower = text.trim().to_ascii_lowercase();
        let name = lower.strip_prefix('+').unwrap_or(&lower);
        Self::ALL
            .into_iter()
            .find(|axis| axis.name() == name)
            .ok_or_else(|| UpAxisError { text: text.into() })
    }

    /// The rotation turning this axis onto +y, row by row (`p' = R · p`): a quarter or half turn
    /// about x or z, so a proper rotation (determinant 1) that keeps the model's handedness.
    #[must_use]
    pub fn rows(self) -> [[f64; 3]; 3] {
        match self {
            Self::Y => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            Self::MinusY => [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
            Self::Z => [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
            Self::MinusZ => [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
            Self::X => [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            Self::MinusX => [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        }
    }

    /// `p` turned so that this axis points along +y.
    #[must_use]
    pub fn turn(self, p: [f64; 3]) -> [f64; 3] {
        self.rows()
            .map(|row| row[0] * p[0] + row[1] * p[1] + row[2] * p[2])
    }

    /// The bounds `(min, max)` of a model of `bounds` once turned ([`UpAxis::turn`]).
    #[must_use]
    pub fn turn_bounds(self, (lo, hi): ([f64; 3], [f64; 3])) -> ([f64; 3], [f64; 3]) {
        let (a, b) = (self.turn(lo), self.turn(hi));
        (
            [0, 1, 2].map(|i| a[i].min(b[i])),
            [0, 1, 2].map(|i| a[i].max(b[i])),
        )
    }
}

/// The bytes of a mesh file, decompressed when they start with the gzip magic (whatever the
/// file's name: fragsim's own `stanford-bunny.obj.gz` is gzipped OBJ).
///
/// # Errors
/// The file cannot be read ([`MeshError::Io`]), is no regular file or too large
/// ([`MeshError::Unreadable`], before a byte is read), or its gzip stream is corrupt
/// ([`MeshError::Gzip`]), naming the file.
pub(crate) fn read_mesh_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    let name = || path.display().to_string();
    let bytes = read_regular(path, MESH_BYTES_LIMIT, "a mesh file may have")?;
    if !bytes.starts_with(&GZIP_MAGIC) {
        return Ok(bytes);
    }
    let mut text = Vec::new();
    // Multi-member: `cat a.gz b.gz` is valid gzip, and gzip(1) decompresses it whole. One byte
    // past the limit is read, to tell a stream that inflates past it.
    flate2::read::MultiGzDecoder::new(bytes.as_slice())
        .take(MESH_BYTES_LIMIT + 1)
        .read_to_end(&mut text)
        .map_err(|source| MeshError::Gzip {
            path: name(),
            source,
        })?;
    if text.len() as u64 > MESH_BYTES_LIMIT {
        return Err(MeshError::Unreadable(FileError::TooLarge {
            path: path.to_path_buf(),
            bytes: text.len() as u64,
            limit: MESH_BYTES_LIMIT,
            what: "a mesh file's decompressed text may have".into(),
        }));
    }
    Ok(text)
}

/// Whether `bytes` (decompressed) are a PLY file: its first line is `ply` (ASCII and binary
/// PLY alike start with a text header).
#[must_use]
pub(crate) fn is_ply(bytes: &[u8]) -> bool {
    bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")
}

/// What a file that is not UTF-8 text without NUL bytes is, for the error: UTF-16 text (by its
/// byte-order mark or its NUL high bytes) or binary data, naming the first offending byte.
fn not_text(bytes: &[u8]) -> String {
    const WHAT: &str = "not OBJ text (nor a PLY file, which starts with a `ply` line)";
    let head = &bytes[..bytes.len().min(64)];
    if head.starts_with(&[0xFF, 0xFE]) || head.starts_with(&[0xFE, 0xFF]) {
        return format!(
            "{WHAT}: it is UTF-16 text (byte-order mark {:02X} {:02X}); save it as ASCII or UTF-8",
            head[0], head[1]
        );
    }
    // ASCII in UTF-16 without a byte-order mark: every other byte is NUL.
    let nul_halves =
        |parity: usize| head.len() >= 4 && head.iter().skip(parity).step_by(2).all(|&b| b == 0);
    if nul_halves(0) || nul_halves(1) {
        return format!("{WHAT}: it looks like UTF-16 text (every other byte is NUL); save it as ASCII or UTF-8");
    }
    let nul = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    let invalid = std::str::from_utf8(bytes).map_or_else(|e| e.valid_up_to(), |_| bytes.len());
    let offset = nul.min(invalid);
    format!(
        "{WHAT}: it is binary data (byte 0x{:02X} at offset {offset} is not text)",
        bytes.get(offset).copied().unwrap_or(0)
    )
}

/// A line of OBJ text that tobj would misread, or panic on, found by [`check_faces`]; lines
/// numbered from 1. It becomes [`MeshError::Obj`]'s reason.
#[derive(Debug, thiserror::Error)]
enum ObjLineError {
    /// A face of fewer than 3 vertices.
    #[error("line {line}: a face needs at least 3 vertices, got {corners}")]
    TooFewCorners { line: usize, corners: usize },
    /// A face or line element refers to an element that is not defined (before it, for a
    /// negative index).
    #[error(
        "line {line}: {element} refers to {kind} {index}, but {available} {kinds} are \
         defined{whence}"
    )]
    IndexOutOfRange {
        line: usize,
        /// `a face` or `a line`.
        element: &'static str,
        /// `vertex`, `texture coordinate` or `normal`.
        kind: &'static str,
        index: i64,
        available: usize,
        /// `kind` in the plural.
        kinds: &'static str,
        /// ` before it` for a negative (relative) index, else empty.
        whence: &'static str,
    },
    /// A `v`, `vt` or `vn` line with a word that is no `f32`.
    #[error("line {line}: {what} parse error: {word:?} is not a number")]
    NotANumber {
        line: usize,
        /// `position`, `texture coordinate` or `normal`.
        what: &'static str,
        word: String,
    },
    /// A `v` or `vn` line with fewer than 3 numbers.
    #[error("line {line}: {what} parse error: needs 3 numbers, got {count}")]
    TooFewNumbers {
        line: usize,
        /// `position` or `normal`.
        what: &'static str,
        count: usize,
    },
}

/// Face checks made before tobj parses: a face of fewer than 3 vertices (tobj makes it a
/// degenerate triangle), and every vertex, texture-coordinate and normal index of a face or line
/// element in range. tobj drops references to attributes the file has none of, and its index
/// arithmetic overflows on a relative index reaching before the first element (a panic where
/// overflow checks are on, as in `cargo test`), so indices are bounded here first: positive ones
/// by the file's total, negative (relative) ones by the elements defined before the line, as tobj
/// resolves them. Parts that are not integers are left for tobj to reject.
fn check_faces(text: &str) -> Result<(), ObjLineError> {
    const KINDS: [(&str, &str, &str); 3] = [
        ("v", "vertex", "vertices"),
        ("vt", "texture coordinate", "texture coordinates"),
        ("vn", "normal", "normals"),
    ];
    let kind_of = |tag: &str| KINDS.iter().position(|&(t, _, _)| t == tag);
    let mut totals = [0_usize; 3];
    for line in text.lines() {
        if let Some(k) = line.split_whitespace().next().and_then(kind_of) {
            totals[k] += 1;
        }
    }
    let mut before = [0_usize; 3];
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        if let Some(k) = kind_of(tag) {
            before[k] += 1;
            check_numbers(number + 1, k, words)?;
            continue;
        }
        if tag != "f" && tag != "l" {
            continue;
        }
        let corners: Vec<&str> = words.collect();
        if tag == "f" && corners.len() < 3 {
            return Err(ObjLineError::TooFewCorners {
                line: number + 1,
                corners: corners.len(),
            });
        }
        for corner in corners {
            for (k, part) in corner.split('/').take(3).enumerate() {
                let Ok(index) = part.parse::<i64>() else {
                    continue;
                };
                let (_, kind, kinds) = KINDS[k];
                let (available, whence) = if index < 0 {
                    (before[k], " before it")
                } else {
                    (totals[k], "")
                };
                if index == 0 || index.unsigned_abs() > available as u64 {
                    return Err(ObjLineError::IndexOutOfRange {
                        line: number + 1,
                        element: if tag == "f" { "a face" } else { "a line" },
                        kind,
                        index,
                        available,
                        kinds,
                        whence,
                    });
                }
            }
        }
    }
    Ok(())
}

/// The numbers of a `v` (`k` = 0), `vt` (1) or `vn` (2) line, checked as tobj parses them (the
/// first three as `f32`; positions and normals need three) so that the error can give the line
/// (`line`, from 1), which tobj's does not.
fn check_numbers<'a>(
    line: usize,
    k: usize,
    words: impl Iterator<Item = &'a str>,
) -> Result<(), ObjLineError> {
    const WHAT: [&str; 3] = ["position", "texture coordinate", "normal"];
    let numbers: Vec<&str> = words.take(3).collect();
    if let Some(word) = numbers.iter().find(|w| w.parse::<f32>().is_err()) {
        return Err(ObjLineError::NotANumber {
            line,
            what: WHAT[k],
            word: (*word).into(),
        });
    }
    if k != 1 && numbers.len() < 3 {
        return Err(ObjLineError::TooFewNumbers {
            line,
            what: WHAT[k],
            count: numbers.len(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Mesh, MeshError> {
        Mesh::read_obj(&mut text.as_bytes(), "test.obj")
    }

    #[test]
    fn quads_are_triangulated() {
        let mesh = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(mesh.triangles.len(), 2);
    }

    #[test]
    fn bad_index_is_an_error_naming_the_file() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("test.obj"), "{err}");
    }

    #[test]
    fn nan_coordinate_is_an_error() {
        let err = parse("v nan 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap_err();
        assert!(
            matches!(err, MeshError::NonFinite { .. } | MeshError::Obj { .. }),
            "{err}"
        );
    }

    #[test]
    #[expect(
        clippy::shadow_unrelated,
        reason = "each `err` is the message of the case just parsed"
    )]
    fn a_face_referring_to_a_normal_in_a_file_without_normals_is_an_error() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1//5 2//5 3//5\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 4") && err.contains("normal 5"), "{err}");
        let err = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/2 2/2 3/2\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("texture coordinate 2"), "{err}");
    }

    #[test]
    #[expect(
        clippy::shadow_unrelated,
        reason = "each `err` is the message of the case just parsed"
    )]
    fn a_relative_index_before_the_first_element_is_an_error_not_an_overflow() {
        // Found by the obj_load fuzz target: tobj computed `vt * 2 + 1` on the wrapped index.
        let err = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nf 1/-11 2/-1 3/-1\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("texture coordinate -11, but 2 texture coordinates are defined before it"),
            "{err}"
        );
        for face in ["f -4 1 2", "f 0 1 2", "f 1 2 4", "l 1 9"] {
            let err = parse(&format!("v 0 0 0\nv 1 0 0\nv 1 1 0\n{face}\n")).unwrap_err();
            assert!(err.to_string().contains("line 4"), "{face}: {err}");
        }
        assert!(parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\n").is_ok());
    }

    #[test]
    fn a_face_with_two_vertices_is_an_error_not_a_degenerate_triangle() {
        let err = parse("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err().to_string();
        assert!(err.contains("at least 3 vertices, got 2"), "{err}");
    }

    #[test]
    fn empty_file_is_an_error() {
        assert!(matches!(
            parse(""),
            Err(MeshError::Empty { .. }) | Err(MeshError::Obj { .. })
        ));
    }
}

//! PLY loading (ASCII and binary, plain or gzipped), for the Stanford repository's own format.
//!
//! Parsing is `ply-rs-bw`'s (a maintained fork of `ply-rs`); gzip is `flate2`'s. Read are the
//! `vertex` element's `x`, `y`, `z`, the `face` element's `vertex_indices` (polygons split into
//! fans `(v0, vi, vi+1)` as the OBJ loader's triangulation does) and the `tristrips` element's
//! `vertex_indices` (triangle strips, `-1` restarting a strip, as the Stanford scans and the
//! common test-model collections store them); any other element (edges, materials) is read past.

use std::io::{BufReader, Read};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Encoding, PropertyAccess, PropertyAccessResult};

use crate::mesh::{Mesh, MeshError};

#[derive(Debug, Default)]
struct PlyVertex([f32; 3]);

impl PlyVertex {
    #[expect(
        clippy::cast_possible_truncation,
        reason = "narrowing a double coordinate to f32 is what the rasterizer's input is made of"
    )]
    fn set(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        // Narrowing a double coordinate to f32 is what the rasterizer's input is made of.
        self.0[axis] = value as f32;
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, f64::from(value))
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set(name, value)
    }
}

#[derive(Debug, Default)]
struct PlyFace(Vec<i64>);

impl PlyFace {
    fn set(&mut self, name: &str, indices: Vec<i64>) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        self.0 = indices;
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_list_char(&mut self, name: &str, value: Vec<i8>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
    fn set_list_uchar(&mut self, name: &str, value: Vec<u8>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
    fn set_list_short(&mut self, name: &str, value: Vec<i16>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
    fn set_list_ushort(&mut self, name: &str, value: Vec<u16>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
    fn set_list_int(&mut self, name: &str, value: Vec<i32>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
    fn set_list_uint(&mut self, name: &str, value: Vec<u32>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
}

/// An element fragsim does not use, read past property by property.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Self
    }
}

/// The triangles of a triangle strip `indices` (`-1` ends a strip and starts the next), in
/// `emit`: triangle `i` of a strip is `(s_i, s_i+1, s_i+2)`, its odd ones turned to
/// `(s_i+1, s_i, s_i+2)` so that every triangle keeps the strip's winding; a triangle that
/// repeats a vertex (the degenerate joins strips are stitched with) covers nothing and is left
/// out.
fn strip_triangles(indices: &[i64], emit: &mut impl FnMut([i64; 3])) {
    for strip in indices.split(|&i| i == -1) {
        for (i, w) in strip.windows(3).enumerate() {
            let [a, b, c] = [w[0], w[1], w[2]];
            if a == b || b == c || a == c {
                continue;
            }
            emit(if i % 2 == 0 { [a, b, c] } else { [b, a, c] });
        }
    }
}

/// `ply-rs-bw`'s error on one line. Its text is `Line N: message` with tab-indented detail
/// lines; a binary payload has no lines (N counts elements read), so there the prefix goes.
fn one_line(error: &ply_rs_bw::parser::ParseError, binary: bool) -> String {
    let text = error.to_string();
    let text = match error.line() {
        Some(line) if binary => text
            .strip_prefix(&format!("Line {line}: "))
            .unwrap_or(&text)
            .to_string(),
        Some(line) => format!(
            "line {line}: {}",
            text.strip_prefix(&format!("Line {line}: "))
                .unwrap_or(&text)
        ),
        None => text,
    };
    text.split(['\n', '\t'])
        .map(str::trim)
        .filter(|part| !part.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

impl Mesh {
    /// Loads a PLY file, ASCII or binary, gzipped or not (told by content, not by name).
    ///
    /// # Errors
    /// A missing or unreadable file, a file the PLY parser rejects (one line; a binary file's
    /// error names no line, a truncated one says so), no triangles (neither faces nor strips), a
    /// negative or out-of-range index, a non-finite coordinate: each names the file.
    pub fn load_ply(path: &Path) -> Result<Self, MeshError> {
        let name = path.display().to_string();
        Self::read_ply(crate::mesh::read_mesh_file(path)?.as_slice(), &name)
    }

    /// Parses PLY from a reader; `name` is used in error messages.
    ///
    /// # Errors
    /// As [`Mesh::load_ply`].
    pub fn read_ply(source: impl Read, name: &str) -> Result<Self, MeshError> {
        let bad = |reason: String| MeshError::Ply {
            path: name.into(),
            reason,
        };
        let mut reader = Reader::new(BufReader::new(source));
        let vertex_parser = Parser::<PlyVertex>::new();
        let header = vertex_parser
            .read_header(&mut reader)
            .map_err(|e| bad(format!("header: {}", one_line(&e, false))))?;
        let binary = header.encoding != Encoding::Ascii;
        let payload = |what: &str, e: ply_rs_bw::parser::ParseError, count: usize| {
            if binary && e.kind() == std::io::ErrorKind::UnexpectedEof {
                bad(format!(
                    "the file ends inside its {count} {what} (the header declares more bytes \
                     than the file holds: a truncated download?)"
                ))
            } else {
                bad(format!("{what}: {}", one_line(&e, binary)))
            }
        };
        let mut mesh = Self::default();
        let mut faces: Vec<Vec<i64>> = Vec::new();
        let mut strips: Vec<Vec<i64>> = Vec::new();
        // Elements come in header order; each must be read (or skipped) in turn.
        for (element_name, element) in &header.elements {
            match element_name.as_str() {
                "vertex" => {
                    let vertices = vertex_parser
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| payload("vertices", e, element.count))?;
                    mesh.positions = vertices.into_iter().map(|v| v.0).collect();
                }
                "face" => faces.extend(
                    Parser::<PlyFace>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| payload("faces", e, element.count))?
                        .into_iter()
                        .map(|PlyFace(indices)| indices),
                ),
                "tristrips" => strips.extend(
                    Parser::<PlyFace>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| payload("triangle strips", e, element.count))?
                        .into_iter()
                        .map(|PlyFace(indices)| indices),
                ),
                other => {
                    Parser::<Skipped>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| payload(&format!("{other:?} elements"), e, element.count))?;
                }
            }
        }
        let index = |what: &str, n: usize, i: i64| {
            u32::try_from(i).map_err(|_| bad(format!("{what} {n} has vertex index {i}")))
        };
        for (face, indices) in faces.iter().enumerate() {
            for k in 1..indices.len().saturating_sub(1) {
                mesh.triangles.push([
                    index("face", face, indices[0])?,
                    index("face", face, indices[k])?,
                    index("face", face, indices[k + 1])?,
                ]);
            }
        }
        for (strip, indices) in strips.iter().enumerate() {
            let mut triangles = Vec::new();
            strip_triangles(indices, &mut |t| triangles.push(t));
            for [a, b, c] in triangles {
                mesh.triangles.push([
                    index("triangle strip", strip, a)?,
                    index("triangle strip", strip, b)?,
                    index("triangle strip", strip, c)?,
                ]);
            }
        }
        if mesh.triangles.is_empty() {
            return Err(MeshError::Empty {
                format: "PLY",
                path: name.into(),
            });
        }
        mesh.validate_as("PLY", name)?;
        Ok(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_quad_becomes_two_triangles() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let mesh = Mesh::read_ply(text.as_bytes(), "quad.ply").unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.positions[2], [1.0, 1.0, 0.0]);
    }

    #[test]
    fn out_of_range_index_names_the_file() {
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0\n3 0 1 2\n";
        let err = Mesh::read_ply(text.as_bytes(), "bad.ply")
            .unwrap_err()
            .to_string();
        assert!(err.contains("bad.ply"), "{err}");
    }
}

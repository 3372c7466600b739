//! PLY loading (ASCII and binary, plain or gzipped), for the Stanford repository's own format.
//!
//! Parsing is `ply-rs-bw`'s (a maintained fork of `ply-rs`); gzip is `flate2`'s. Only the `vertex`
//! element's `x`, `y`, `z` and the `face` element's `vertex_indices` are read; polygons are split
//! into fans `(v0, vi, vi+1)` as the OBJ loader's triangulation does.

use std::io::{BufReader, Read};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{PropertyAccess, PropertyAccessResult};

use crate::mesh::{Mesh, MeshError};

#[derive(Debug, Default)]
struct PlyVertex([f32; 3]);

impl PlyVertex {
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
    fn set_list_int(&mut self, name: &str, value: Vec<i32>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
    fn set_list_uint(&mut self, name: &str, value: Vec<u32>) -> PropertyAccessResult {
        self.set(name, value.into_iter().map(i64::from).collect())
    }
}

impl Mesh {
    /// Loads a PLY file, ASCII or binary, gzipped or not (told by content, not by name).
    ///
    /// # Errors
    /// A missing or unreadable file, a file the PLY parser rejects, no `vertex` or `face`
    /// element, a negative or out-of-range index, a non-finite coordinate: each names the file.
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
            .map_err(|e| bad(format!("header: {e}")))?;
        let mut mesh = Mesh::default();
        // Elements come in header order; each must be read (or skipped) in turn.
        for (element_name, element) in &header.elements {
            match element_name.as_str() {
                "vertex" => {
                    let vertices = vertex_parser
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| bad(format!("vertices: {e}")))?;
                    mesh.positions = vertices.into_iter().map(|v| v.0).collect();
                }
                "face" => {
                    let faces = Parser::<PlyFace>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| bad(format!("faces: {e}")))?;
                    for (face, PlyFace(indices)) in faces.into_iter().enumerate() {
                        let index = |i: i64| {
                            u32::try_from(i)
                                .map_err(|_| bad(format!("face {face} has vertex index {i}")))
                        };
                        for k in 1..indices.len().saturating_sub(1) {
                            mesh.triangles.push([
                                index(indices[0])?,
                                index(indices[k])?,
                                index(indices[k + 1])?,
                            ]);
                        }
                    }
                }
                other => {
                    return Err(bad(format!(
                        "unsupported PLY element {other:?} (only vertex and face are read)"
                    )));
                }
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

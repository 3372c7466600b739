//! The triangle export (`FRAGTRI1`): a view's screen triangles after fragsim's vertex stage, so
//! that a backend can test its scan and atomics alone.

use std::path::Path;

use fragsim_raster::{ScreenTriangle, View, SUBPIXEL_BITS};

use crate::{err, io_err, DumpError};
use fragsim_raster::scene_spec::SceneSpec;

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
            .map_err(|e| DumpError::Invalid(format!("cannot encode the scene: {e}")))?;
        let padded = json.len().next_multiple_of(8);
        let count = u32::try_from(self.triangles.len())
            .map_err(|_| DumpError::Invalid("more than 2^32 screen triangles".into()))?;
        let json_len = u32::try_from(json.len())
            .map_err(|_| DumpError::Invalid("a scene of more than 2^32 bytes of JSON".into()))?;
        let mut bytes = Vec::with_capacity(
            TRIANGLES_HEADER_BYTES + padded + self.triangles.len() * TRIANGLE_RECORD_BYTES,
        );
        bytes.extend_from_slice(&TRIANGLES_MAGIC);
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the record size is 56 bytes"
        )]
        for field in [
            TRIANGLES_VERSION,
            self.width,
            self.height,
            SUBPIXEL_BITS,
            self.mesh_triangles,
            count,
            json_len,
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
                    DumpError::Invalid(format!("triangle {}: coordinate {v} outside i32", t.prim))
                })?;
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            bytes.extend_from_slice(&0_u32.to_le_bytes());
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
                .ok_or_else(|| DumpError::Invalid("triangle export truncated".into()))
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
            .ok_or_else(|| DumpError::Invalid("triangle export truncated".into()))?;
        let scene: SceneSpec = serde_json::from_slice(json)
            .map_err(|e| DumpError::Invalid(format!("triangle export scene: {e}")))?;
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

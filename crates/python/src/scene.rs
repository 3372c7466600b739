//! [`SceneCore`]: a scene on a viewport, as the Python `fragsim.Scene` holds it, with what a
//! kernel under test needs from it (screen triangles, the fragment stream, the exact reference)
//! and the oracle's verdict on arrays in memory; and dump directories read and written.
//!
//! A scene is named the way a dump header names it (`fragsim_raster::SceneSpec`: a named scene
//! or a mesh file, the orbit or an engine's `view_projection`, the conventions), or by vertex and
//! index arrays: those become a mesh whose OBJ text ([`obj_text`]) is written as `mesh.obj`
//! beside every dump of the scene, with its hash in the header, so `fragsim compare oracle DIR`
//! rebuilds the very same mesh. The oracle of the scene is built once, on first use, and kept.
//!
//! A verdict on arrays takes the same path as `fragsim compare oracle DUMP`: the header (built
//! by the Python side from keyword arguments, `dump.json`'s JSON) and the arrays' little-endian
//! bytes go through `Dump::parse`, every check of a dump read from files included, and the dump
//! is judged by `fragsim_oracle::verdict::judge` against this scene's oracle (`Reference::of_view`,
//! as the conformance battery judges a backend; the per-pixel view of the per-sample oracle for a
//! masked-node dump, as `judge_sides` does).

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::OnceLock;

use fragsim_catalog::CATALOG;
use fragsim_dump::triangles::TriangleExport;
use fragsim_dump::{Dump, Words};
use fragsim_measure::hazard::{hazard_in_view, machine_named, Campaign};
use fragsim_measure::Silent;
use fragsim_oracle::samples::SampleOracle;
use fragsim_oracle::verdict::{
    self, Candidate, Options, Reference, Side, SideReport, VerdictError,
};
use fragsim_oracle::Oracle;
use fragsim_raster::scene_spec::{mesh_hash, SceneSpec};
use fragsim_raster::{Conventions, Fragment, Mesh, Scene, UpAxis, VertexPrecision, View, Viewport};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::errors::{dump_error, mesh_error, scene_error, scene_spec_error, JudgeError};
use crate::errors::{DumpError, FragsimError, SceneError};

/// The file name an array scene's mesh is written under, beside each of its dumps.
pub const ARRAY_MESH_FILE: &str = "mesh.obj";

/// A scene on a viewport: what the Python class `fragsim.Scene` wraps.
#[pyclass(module = "fragsim._fragsim", frozen)]
#[derive(Debug)]
pub struct SceneCore {
    /// The spec a dump header records (an array scene's names [`ARRAY_MESH_FILE`] and its hash).
    spec: SceneSpec,
    /// The loaded scene.
    scene: Scene,
    /// The render target.
    viewport: Viewport,
    /// An array scene's mesh as OBJ text, written beside its dumps.
    obj: Option<String>,
    /// The oracle under the spec's own vertex stage, and under an f64 one (the reference a
    /// vertex stage judged within f32 precision is held to), each built on first use.
    oracles: [OnceLock<Oracle>; 2],
}

/// An array scene's mesh as OBJ text: every coordinate the shortest decimal that reads back to
/// the same f32 (Rust's `Display`), faces numbered from 1.
#[must_use]
pub fn obj_text(mesh: &Mesh) -> String {
    let mut text = String::from("# a mesh given to fragsim as arrays\n");
    for [x, y, z] in &mesh.positions {
        text.push_str(&format!("v {x} {y} {z}\n"));
    }
    for [a, b, c] in &mesh.triangles {
        text.push_str(&format!("f {} {} {}\n", a + 1, b + 1, c + 1));
    }
    text
}

impl SceneCore {
    /// The scene `scene` (loaded from `spec`, or made of arrays whose OBJ text is `obj`) on
    /// `viewport`, its view checked once so that a bad matrix or conventions fail here.
    ///
    /// # Errors
    /// The view cannot be built.
    pub fn from_parts(
        spec: SceneSpec,
        scene: Scene,
        viewport: Viewport,
        obj: Option<String>,
    ) -> PyResult<Self> {
        let core = Self {
            spec,
            scene,
            viewport,
            obj,
            oracles: [OnceLock::new(), OnceLock::new()],
        };
        let view = core.view(false)?;
        let recorded = core.spec.recorded(&view);
        drop(view);
        Ok(Self {
            spec: recorded,
            ..core
        })
    }

    /// The view; with `f64_stage`, under an f64 vertex stage whatever the spec declares.
    fn view(&self, f64_stage: bool) -> PyResult<View<'_>> {
        let mut spec = self.spec.clone();
        if f64_stage {
            spec.conventions.vertex_precision = VertexPrecision::F64;
        }
        spec.view(&self.scene, self.viewport)
            .map_err(scene_spec_error)
    }

    /// The oracle of [`SceneCore::view`], built once.
    fn oracle(&self, f64_stage: bool) -> PyResult<&Oracle> {
        match self.oracles[usize::from(f64_stage)].get() {
            Some(oracle) => Ok(oracle),
            None => Ok(self.oracle_of(&self.view(f64_stage)?, f64_stage)),
        }
    }

    /// The oracle of `view` (this scene's [`SceneCore::view`] of `f64_stage`), built once.
    fn oracle_of(&self, view: &View<'_>, f64_stage: bool) -> &Oracle {
        self.oracles[usize::from(f64_stage)].get_or_init(|| Oracle::build(view))
    }

    /// Parses a header and the arrays' bytes as a dump read from files would be.
    fn dump(header: &str, files: &HashMap<String, Bound<'_, PyBytes>>) -> PyResult<Dump> {
        Dump::parse("the arrays' header", header.as_bytes(), |file| {
            files
                .get(file)
                .map(|bytes| bytes.as_bytes().to_vec())
                .ok_or_else(|| {
                    fragsim_dump::DumpError::Invalid(format!(
                        "the header names file {file:?}, and no array was given for it"
                    ))
                })
        })
        .map_err(dump_error)
    }

    /// The scene's fragments in submission order (primitive by primitive, each triangle's in
    /// the rasterizer's order), as a fragment shader would be invoked.
    fn fragment_stream(&self) -> PyResult<Vec<Fragment>> {
        let view = self.view(false)?;
        let mut fragments = Vec::new();
        for prim in 0..view.triangle_count() {
            view.rasterize(prim, &mut |f| fragments.push(f));
        }
        Ok(fragments)
    }

    /// The verdict on `dump` against this scene's oracle, owed by a vertex stage of
    /// `vertex_precision` (`f64`: every bit; `f32`: within the bounds derived for it).
    fn verdict<'py>(
        &self,
        py: Python<'py>,
        dump: &Dump,
        vertex_precision: &str,
        options: Options,
    ) -> PyResult<Bound<'py, PyDict>> {
        let stage = match vertex_precision {
            "f64" => VertexPrecision::F64,
            "f32" => VertexPrecision::F32,
            other => {
                return Err(JudgeError::new_err(format!(
                    "vertex_precision {other:?}: f64 or f32"
                )))
            }
        };
        let f32_stage = stage == VertexPrecision::F32;
        let view = self.view(f32_stage)?;
        let size = (self.viewport.width, self.viewport.height);
        let reference = if dump.is_masked() {
            let sampled =
                SampleOracle::build(&view).map_err(|e| SceneError::new_err(e.to_string()))?;
            let reference = Reference::masked(sampled.per_pixel(), size);
            if f32_stage {
                let conventions = Conventions {
                    vertex_precision: VertexPrecision::F32,
                    ..view.conventions()
                };
                let precision = fragsim_oracle::precision::Precision::derive(&view, &conventions);
                reference.masked_within(sampled.oracle().clone(), precision)
            } else {
                reference
            }
        } else {
            Reference::of_view(self.oracle_of(&view, f32_stage), &view, stage)
        };
        let verdict =
            verdict::judge(&reference, Candidate::Dump(dump), &options).map_err(verdict_error)?;
        let candidate = SideReport {
            source: "arrays".into(),
            scheme: dump.header.scheme.clone(),
            producer: dump.header.producer.clone(),
            k: dump.header.k,
            capacity: dump.header.capacity,
        };
        crate::reference::verdict_dict(py, &verdict, Side::Oracle.describe(), candidate)
    }
}

#[pymethods]
impl SceneCore {
    /// A scene from `spec_json` (a dump header's scene object) on a `width` × `height`
    /// viewport, the orbit around the model's `up` axis (`y`, `-z`, …); with `vertices` (float32, `[n, 3]`) and `indices` (uint32, `[m, 3]`) the mesh
    /// is those arrays and the spec names neither a scene nor a mesh. A relative mesh path is
    /// looked up from the working directory, then in `beside`.
    #[new]
    #[pyo3(signature = (spec_json, width, height, up="y", vertices=None, indices=None, beside=None))]
    fn new(
        spec_json: &str,
        width: u32,
        height: u32,
        up: &str,
        vertices: Option<PyReadonlyArray2<'_, f32>>,
        indices: Option<PyReadonlyArray2<'_, u32>>,
        beside: Option<PathBuf>,
    ) -> PyResult<Self> {
        let mut spec: SceneSpec = serde_json::from_str(spec_json)
            .map_err(|e| SceneError::new_err(format!("scene: {e}")))?;
        spec.up = UpAxis::parse(up).map_err(|e| SceneError::new_err(e.to_string()))?;
        let viewport =
            Viewport::new(width, height).map_err(|e| SceneError::new_err(e.to_string()))?;
        let (scene, obj) = match (vertices, indices) {
            (Some(vertices), Some(indices)) => {
                let rows = |shape: &[usize], what: &str| match shape {
                    [_, 3] => Ok(()),
                    _ => Err(SceneError::new_err(format!(
                        "{what} must have shape [n, 3], not {shape:?}"
                    ))),
                };
                rows(vertices.as_array().shape(), "vertices")?;
                rows(indices.as_array().shape(), "indices")?;
                let flat = |v: &[f32]| -> Vec<[f32; 3]> {
                    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
                };
                let mesh = Mesh {
                    positions: flat(&vertices.as_array().iter().copied().collect::<Vec<_>>()),
                    triangles: indices
                        .as_array()
                        .iter()
                        .copied()
                        .collect::<Vec<_>>()
                        .chunks_exact(3)
                        .map(|c| [c[0], c[1], c[2]])
                        .collect(),
                };
                mesh.validate("the vertex and index arrays")
                    .map_err(mesh_error)?;
                let obj = obj_text(&mesh);
                (spec.name, spec.mesh) = (None, Some(ARRAY_MESH_FILE.into()));
                spec.mesh_hash = Some(mesh_hash(obj.as_bytes()));
                let scene = Scene {
                    name: "arrays".into(),
                    mesh,
                };
                (scene, Some(obj))
            }
            (None, None) => {
                if spec.mesh.is_some() && spec.mesh_hash.is_none() {
                    spec = spec.hashed().map_err(scene_spec_error)?;
                }
                (
                    spec.load(beside.as_deref()).map_err(scene_spec_error)?,
                    None,
                )
            }
            _ => {
                return Err(SceneError::new_err(
                    "vertices and indices are given together, or neither",
                ))
            }
        };
        if scene.mesh.triangles.is_empty() {
            return Err(scene_error(fragsim_raster::SceneError::BadParameter {
                name: scene.name.clone(),
                reason: "no triangles".into(),
            }));
        }
        Self::from_parts(spec, scene, viewport, obj)
    }

    /// The scene object a dump header records for this scene (JSON).
    fn spec_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.spec).map_err(|e| SceneError::new_err(e.to_string()))
    }

    /// Viewport width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.viewport.width
    }

    /// Viewport height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.viewport.height
    }

    /// Samples a pixel (the conventions' `samples`): the lists per pixel of every layout but
    /// the masked nodes.
    #[getter]
    fn samples(&self) -> u32 {
        self.spec.conventions.samples
    }

    /// Triangles in the mesh.
    #[getter]
    fn mesh_triangles(&self) -> usize {
        self.scene.mesh.triangles.len()
    }

    /// The screen triangles after fragsim's vertex stage, as `export-scene` writes them:
    /// `prim` (uint32 `[n]`), `xy` (int32 `[n, 3, 2]`, 1/256 pixel, y down), `z` (float64
    /// `[n, 3]`, window depth).
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let view = self.view(false)?;
        let export = TriangleExport::from_view(&view, self.spec.clone());
        let n = export.triangles.len();
        let mut xy = Vec::with_capacity(n * 6);
        for t in &export.triangles {
            for v in t.xy.iter().flatten() {
                xy.push(i32::try_from(*v).map_err(|_| {
                    SceneError::new_err(format!("triangle {}: coordinate {v} outside i32", t.prim))
                })?);
            }
        }
        let dict = PyDict::new(py);
        let prim: Vec<u32> = export.triangles.iter().map(|t| t.prim).collect();
        let z: Vec<f64> = export.triangles.iter().flat_map(|t| t.z).collect();
        dict.set_item("prim", PyArray1::from_vec(py, prim))?;
        dict.set_item("xy", PyArray1::from_vec(py, xy).reshape([n, 3, 2])?)?;
        dict.set_item("z", PyArray1::from_vec(py, z).reshape([n, 3])?)?;
        Ok(dict)
    }

    /// The fragments in submission order: `list` (uint32, the pixel `y · width + x`, or its
    /// sample's list `pixel · samples + s`), `key` (uint32 depth key), `prim` (uint32).
    fn fragments<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let fragments = self.fragment_stream()?;
        let column = |f: fn(&Fragment) -> u32| fragments.iter().map(f).collect::<Vec<u32>>();
        let dict = PyDict::new(py);
        dict.set_item("list", PyArray1::from_vec(py, column(|f| f.pixel)))?;
        dict.set_item("key", PyArray1::from_vec(py, column(|f| f.depth_key)))?;
        dict.set_item("prim", PyArray1::from_vec(py, column(|f| f.prim)))?;
        Ok(dict)
    }

    /// The exact reference: every list's fragment words (`key << 32 | prim`) in canonical order
    /// as `counts` (uint32 `[lists]`), `offsets` (uint64 `[lists + 1]`) and `words` (uint64);
    /// with `k`, also `nearest` (uint64 `[lists, k]`, the K nearest, empty slots all ones).
    #[pyo3(signature = (k=None))]
    fn reference<'py>(&self, py: Python<'py>, k: Option<usize>) -> PyResult<Bound<'py, PyDict>> {
        crate::reference::reference_arrays(py, self.oracle(false)?, k)
    }

    /// The oracle's verdict on a dump given as its header (`dump.json`'s JSON) and its arrays'
    /// little-endian bytes by file name; `vertex_precision` `f32` judges within the bounds of
    /// an f32 vertex stage. Returns the verdict's summary (JSON), its word, and the per-list
    /// flags and reference fragment counts.
    #[pyo3(signature = (header, files, vertex_precision="f64", depth_ulps=0, examples=8))]
    fn judge<'py>(
        &self,
        py: Python<'py>,
        header: &str,
        files: HashMap<String, Bound<'py, PyBytes>>,
        vertex_precision: &str,
        depth_ulps: u32,
        examples: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let dump = Self::dump(header, &files)?;
        let options = Options {
            depth_ulps,
            examples,
        };
        self.verdict(py, &dump, vertex_precision, options)
    }

    /// [`SceneCore::judge`] on the dump directory (or `dump.json`) at `path`, read as `fragsim
    /// compare` reads it.
    #[pyo3(signature = (path, vertex_precision="f64", depth_ulps=0, examples=8))]
    fn judge_dir<'py>(
        &self,
        py: Python<'py>,
        path: PathBuf,
        vertex_precision: &str,
        depth_ulps: u32,
        examples: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let dump = Dump::read(&path).map_err(dump_error)?;
        let options = Options {
            depth_ulps,
            examples,
        };
        self.verdict(py, &dump, vertex_precision, options)
    }

    /// The k-buffer's hazard rate on this scene (`fragsim_measure::hazard`, as `fragsim hazard`
    /// measures it): K slots a pixel, each number of threads in flight of `threads_in_flight`
    /// under both scheduling policies, `seeds` seeds a row, on each machine of `write_back`
    /// (`render-target`, `separate-stores`). Returns the report as JSON.
    ///
    /// # Errors
    /// An unknown machine, no machine or seed, zero threads in flight, or a view beyond the
    /// memory cap: a [`FragsimError`].
    #[pyo3(signature = (k, threads_in_flight, seeds, write_back))]
    fn hazard(
        &self,
        k: u32,
        threads_in_flight: Vec<usize>,
        seeds: u64,
        write_back: Vec<String>,
    ) -> PyResult<String> {
        let machines = write_back
            .iter()
            .map(|name| {
                machine_named(name).ok_or_else(|| {
                    FragsimError::new_err(format!(
                        "no k-buffer machine {name:?} (render-target, separate-stores)"
                    ))
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let campaign = Campaign::Rates {
            k,
            threads_in_flight,
            seeds,
        };
        let scene = fragsim_measure::scene_name(&self.spec);
        let report = hazard_in_view(&self.view(false)?, scene, &machines, &campaign, &Silent)
            .map_err(FragsimError::new_err)?;
        serde_json::to_string(&report).map_err(|e| FragsimError::new_err(e.to_string()))
    }

    /// Writes a dump (its header's JSON and arrays' bytes, as for [`SceneCore::judge`]) into
    /// directory `dir`, with an array scene's mesh beside it.
    fn write_dump(
        &self,
        dir: PathBuf,
        header: &str,
        files: HashMap<String, Bound<'_, PyBytes>>,
    ) -> PyResult<()> {
        let dump = Self::dump(header, &files)?;
        dump.write(&dir).map_err(dump_error)?;
        if let Some(obj) = &self.obj {
            let path = dir.join(ARRAY_MESH_FILE);
            std::fs::write(&path, obj).map_err(|e| {
                dump_error(fragsim_dump::DumpError::Io {
                    action: "write".into(),
                    path,
                    reason: e.to_string(),
                })
            })?;
        }
        Ok(())
    }
}

/// The exception for a verdict the oracle could not give: the dump's own [`DumpError`] where
/// decoding it failed (a malformed dump, not a refusal to compare), else a [`JudgeError`].
fn verdict_error(error: VerdictError) -> PyErr {
    match error {
        VerdictError::Dump(e) => dump_error(e),
        other => JudgeError::new_err(other.to_string()),
    }
}

/// Reads a dump directory (or its `dump.json`): the header's JSON, and each array's words as a
/// flat numpy array (uint32 or uint64) by array name.
#[pyfunction]
pub fn read_dump<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(String, Bound<'py, PyDict>)> {
    let dump = Dump::read(&path).map_err(dump_error)?;
    let header =
        serde_json::to_string(&dump.header).map_err(|e| DumpError::new_err(e.to_string()))?;
    let arrays = PyDict::new(py);
    for (name, words) in dump.arrays {
        match words {
            Words::U32(w) => arrays.set_item(name, PyArray1::from_vec(py, w))?,
            Words::U64(w) => arrays.set_item(name, PyArray1::from_vec(py, w))?,
        }
    }
    Ok((header, arrays))
}

/// Every scheme of fragsim's catalog by name, in the order its tables list them.
#[pyfunction]
pub fn scheme_names() -> Vec<&'static str> {
    CATALOG.iter().map(|e| e.name).collect()
}

//! The conformance battery on a Python callable: `fragsim_testkit::Battery` in process, its cases
//! generated and a failure shrunk by proptest and the battery's own crop, the callable standing
//! where a GPU backend stands.
//!
//! [`PythonBackend`] implements the testkit's `Backend`: each case becomes a [`SceneCore`] (the
//! case's triangles as an array scene under the identity matrix, so a kernel gets its fragments
//! or screen triangles as from any scene) handed to the callable, which returns a dump as its
//! header's JSON and its arrays' bytes; the battery judges it with the verdict `fragsim compare`
//! gives. A Python exception in the callable, or arrays that are no dump, fail the case (shrunk
//! like any other): the message carries the exception.

use fragsim_capture::executors::Executor;
use fragsim_capture::Guarantee;
use fragsim_catalog::SchemeName;
use fragsim_dump::Dump;
use fragsim_raster::scene_spec::mesh_hash;
use fragsim_raster::VertexPrecision;
use fragsim_testkit::Case;
use fragsim_testkit::{
    Backend, BackendError, Battery, CatalogBackend, Failure, GuaranteeError, Input, Limits, Output,
    Params,
};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::collections::HashMap;

use crate::errors::BatteryRefused;
use crate::scene::{SceneCore, ARRAY_MESH_FILE};

/// A Python callable as a backend: `callable(scene, scheme, k, capacity)` returns
/// `(header_json, {file: bytes})`.
#[derive(Debug)]
pub struct PythonBackend<'py> {
    /// The callable.
    callable: Bound<'py, PyAny>,
    /// Its name in reports.
    name: String,
    /// The precision its vertex stage declares.
    vertex_precision: VertexPrecision,
}

impl PythonBackend<'_> {
    /// The case's scene as the callable sees it.
    fn scene(case: &Case) -> Result<SceneCore, BackendError> {
        let obj = case.obj();
        let spec = Case::scene_and_camera(ARRAY_MESH_FILE, mesh_hash(obj.as_bytes()));
        SceneCore::from_parts(spec, case.scene(), case.viewport, Some(obj))
            .map_err(|e| BackendError::Setup(format!("the case's scene: {e}")))
    }
}

impl Backend for PythonBackend<'_> {
    fn name(&self) -> String {
        self.name.clone()
    }

    /// The catalog scheme's own guarantee at these sizes (a claim of the caller's replaces it).
    fn guarantee(&self, params: &Params) -> Result<Guarantee, GuaranteeError> {
        CatalogBackend::on(Executor::Parallel).guarantee(params)
    }

    fn vertex_precision(&self) -> VertexPrecision {
        self.vertex_precision
    }

    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError> {
        let py = self.callable.py();
        let scene = Py::new(py, Self::scene(input.case)?)
            .map_err(|e| BackendError::Setup(e.to_string()))?;
        let params = input.params;
        let returned = self
            .callable
            .call1((scene, params.scheme.name(), params.k, params.capacity))
            .map_err(|e| BackendError::Failed(format!("the callable raised {e}")))?;
        let (header, files): (String, HashMap<String, Bound<'_, PyBytes>>) = returned
            .extract()
            .map_err(|e| BackendError::Failed(format!("the callable returned no dump: {e}")))?;
        let dump = Dump::parse("the callable's header", header.as_bytes(), |file| {
            files
                .get(file)
                .map(|b| b.as_bytes().to_vec())
                .ok_or_else(|| {
                    fragsim_dump::DumpError::Invalid(format!(
                        "the header names file {file:?}, and no array was given for it"
                    ))
                })
        })
        .map_err(|e| BackendError::Failed(e.to_string()))?;
        Ok(Output::Dump(Box::new(dump)))
    }
}

/// The guarantee spelled `claim` (`exact`, `exact-within-capacity`, …: as reports print them,
/// a capacity taken from `capacity`).
fn parse_claim(claim: &str, capacity: u32) -> PyResult<Guarantee> {
    let all = [
        Guarantee::Exact,
        Guarantee::ExactWithinCapacity(capacity),
        Guarantee::ExactDistinctDepths,
        Guarantee::ExactWithoutHazards,
        Guarantee::ExactInArrivalOrder,
        Guarantee::Approximate,
    ];
    let spelled = |g: &Guarantee| {
        let text = g.to_string();
        text.split('(').next().unwrap_or_default().to_string()
    };
    all.iter()
        .find(|g| spelled(g) == claim || g.to_string() == claim)
        .copied()
        .ok_or_else(|| {
            let names: Vec<String> = all.iter().map(spelled).collect();
            BatteryRefused::new_err(format!("claim {claim:?}: one of {}", names.join(", ")))
        })
}

/// Runs the battery on `callable` for catalog scheme `scheme` at `k` and `capacity`: `cases`
/// cases from `seed` within `max_side` × `max_side` pixels and `max_triangles` triangles,
/// checking `claim` (default: the scheme's own guarantee). Returns a dict: `passed`, `cases`,
/// `claim`, and on a failure the shrunk counterexample (`property`, `message`, `width`,
/// `height`, `triangles`, `obj`, `mismatches`, `cases_run`, `case_number`, `shrink_steps`).
///
/// # Errors
/// [`BatteryRefused`] when nothing could be checked (an unknown scheme or claim, a claim that
/// owes nothing, a backend that cannot run).
#[pyfunction]
#[pyo3(signature = (callable, scheme, k, capacity, name, cases=64, seed=0, claim=None,
                    vertex_precision="f64", max_side=8, max_triangles=6, shrink_steps=2048))]
pub fn run_battery<'py>(
    py: Python<'py>,
    callable: Bound<'py, PyAny>,
    scheme: &str,
    k: u32,
    capacity: u32,
    name: String,
    cases: u32,
    seed: u64,
    claim: Option<&str>,
    vertex_precision: &str,
    max_side: u32,
    max_triangles: usize,
    shrink_steps: u32,
) -> PyResult<Bound<'py, PyDict>> {
    let scheme = SchemeName::from_name(scheme)
        .ok_or_else(|| BatteryRefused::new_err(format!("no scheme {scheme:?} in the catalog")))?;
    let vertex_precision = match vertex_precision {
        "f64" => VertexPrecision::F64,
        "f32" => VertexPrecision::F32,
        other => {
            return Err(BatteryRefused::new_err(format!(
                "vertex_precision {other:?}: f64 or f32"
            )))
        }
    };
    let backend = PythonBackend {
        callable,
        name,
        vertex_precision,
    };
    let params = Params {
        scheme,
        k,
        capacity,
    };
    let limits = Limits {
        max_side,
        max_triangles,
        ..Limits::default()
    };
    let mut battery = Battery::new(&backend, params)
        .cases(cases)
        .seed(seed)
        .limits(limits)
        .shrink_steps(shrink_steps);
    if let Some(claim) = claim {
        battery = battery.claiming(parse_claim(claim, capacity)?);
    }
    let out = PyDict::new(py);
    match battery.run() {
        Ok(passed) => {
            out.set_item("passed", true)?;
            out.set_item("cases", passed.cases)?;
            out.set_item("claim", passed.claim.to_string())?;
        }
        Err(Failure::Refused(why)) => return Err(BatteryRefused::new_err(why)),
        Err(Failure::Counterexample(c)) => {
            out.set_item("passed", false)?;
            out.set_item("property", c.property.to_string())?;
            out.set_item("message", &c.message)?;
            out.set_item("width", c.case.viewport.width)?;
            out.set_item("height", c.case.viewport.height)?;
            let triangles = PyList::empty(py);
            for t in &c.submitted.triangles {
                let d = PyDict::new(py);
                d.set_item("corners_half_pixels", t.corners.to_vec())?;
                d.set_item("depths", t.depths.to_vec())?;
                triangles.append(d)?;
            }
            out.set_item("triangles", triangles)?;
            out.set_item("obj", c.submitted.obj())?;
            let mismatches = PyList::empty(py);
            let width = c.case.viewport.width as usize;
            for m in c.mismatches() {
                let d = PyDict::new(py);
                d.set_item("pixel", m.pixel)?;
                d.set_item("x", m.pixel % width)?;
                d.set_item("y", m.pixel / width)?;
                d.set_item("expected", m.expected.clone())?;
                d.set_item("found", m.got.clone())?;
                mismatches.append(d)?;
            }
            out.set_item("mismatches", mismatches)?;
            out.set_item("fragments", c.fragments)?;
            out.set_item("cases_run", c.cases_run)?;
            out.set_item("case_number", c.case_number)?;
            out.set_item("shrink_steps", c.shrink_steps)?;
        }
    }
    Ok(out)
}

//! The exceptions the package raises, one per kind of failure, and the mapping from the library
//! crates' typed errors onto them.
//!
//! Python callers branch on the class: a file that cannot be read or written
//! ([`DumpIoError`], from `DumpError::Io`) is not a dump or a set of arrays that contradicts the
//! format ([`DumpError`], from `DumpError::Invalid` and `DumpError::Capture`), which is not a
//! scene that cannot be loaded ([`SceneError`], from `SceneSpecError` and `SceneError`), which
//! is not a verdict the oracle refuses to give ([`JudgeError`]: the sides cannot be compared)
//! nor a battery that checked nothing ([`BatteryRefused`]). All derive from [`FragsimError`];
//! the message is the library's own, which names the field, array or file at fault.

use fragsim_dump::DumpError as FormatDumpError;
use fragsim_raster::{MeshError, SceneError as RasterSceneError, SceneSpecError};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    fragsim,
    FragsimError,
    PyException,
    "The base of every error fragsim raises."
);
create_exception!(
    fragsim,
    DumpError,
    FragsimError,
    "A dump, its header or the arrays given as one contradict the dump format: the message names \
     the field or array at fault."
);
create_exception!(
    fragsim,
    DumpIoError,
    DumpError,
    "A dump's file or directory cannot be read or written."
);
create_exception!(
    fragsim,
    SceneError,
    FragsimError,
    "The scene cannot be loaded or viewed: an unknown scene name, a mesh file missing or of \
     another hash, bad vertex or index arrays, a viewport or conventions fragsim cannot \
     rasterize."
);
create_exception!(
    fragsim,
    JudgeError,
    FragsimError,
    "The oracle cannot judge these sides: the arrays cover another viewport or number of lists \
     than the scene, or a layout needs a reference this call cannot give."
);
create_exception!(
    fragsim,
    BatteryRefused,
    FragsimError,
    "The conformance battery checked nothing: the claim owes nothing on the backend, or the \
     backend cannot run at all."
);

/// Adds the exception classes to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("FragsimError", py.get_type::<FragsimError>())?;
    m.add("DumpError", py.get_type::<DumpError>())?;
    m.add("DumpIoError", py.get_type::<DumpIoError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("JudgeError", py.get_type::<JudgeError>())?;
    m.add("BatteryRefused", py.get_type::<BatteryRefused>())?;
    Ok(())
}

/// A dump error as its Python class: [`DumpIoError`] for a file, [`DumpError`] otherwise.
pub(crate) fn dump_error(e: FormatDumpError) -> PyErr {
    match e {
        FormatDumpError::Io { .. } => DumpIoError::new_err(e.to_string()),
        FormatDumpError::Invalid(_) | FormatDumpError::Capture(_) => {
            DumpError::new_err(e.to_string())
        }
    }
}

/// A scene spec that names no scene fragsim can view.
pub(crate) fn scene_spec_error(e: SceneSpecError) -> PyErr {
    SceneError::new_err(e.to_string())
}

/// A scene that cannot be viewed.
pub(crate) fn scene_error(e: RasterSceneError) -> PyErr {
    SceneError::new_err(e.to_string())
}

/// Vertex or index arrays that make no mesh.
pub(crate) fn mesh_error(e: MeshError) -> PyErr {
    SceneError::new_err(e.to_string())
}

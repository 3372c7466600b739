//! The wgpu backend as an in-process [`Backend`] of fragsim's conformance battery
//! (`fragsim_testkit::battery`): each generated case is drawn by a scheme's WGSL shader on the
//! adapter, in replay or engine mode, optionally with a planted bug, and its dump is judged
//! against the oracle.
//!
//! Algorithm: the case's view (fragsim's vertex stage, under the reference conventions) goes to
//! [`capture_planted`] as any scene's would; the dump comes back in memory, never written. The
//! scheme's claim is the catalog's ([`CatalogBackend`]), so the battery holds the shader to what
//! fragsim's own scheme of that name promises.
//!
//! Guarantee: the dump is judged within the precision of an f32 vertex stage
//! ([`VertexPrecision::F32`]) in both modes: engine mode's vertex shader computes in f32, and in
//! both modes depth is the GPU's own interpolation of f32 vertex depths, a few ulps from
//! fragsim's f64 plane (replay mode's coverage is still fragsim's exactly: its snapped positions
//! are inside every bound). Replay mode takes only power-of-two viewports (its clip coordinates
//! are exact only then), so the battery generates and shrinks to those alone
//! ([`Backend::power_of_two_viewports`]).
//!
//! Departures: a scheme the adapter lacks a feature for, or a plant that does not apply to the
//! scheme, is refused before any case runs (the battery's `Refused`), not failed case by case.

use fragsim_capture::executors::Executor;
use fragsim_capture::Guarantee;
use fragsim_raster::scene_spec::mesh_hash;
use fragsim_raster::VertexPrecision;
use fragsim_testkit::{
    Backend, BackendError, Case, CatalogBackend, GuaranteeError, Input, Output, Params,
};

use crate::capture::{capture_planted, Mode};
use crate::device::{Gpu, GpuError};
use crate::plant::Plant;
use crate::shaders::GpuScheme;

/// The wgpu backend on one adapter, in one mode, with the correct shaders or one planted bug.
#[derive(Debug)]
pub struct WgpuBackend<'g> {
    /// The device the cases are drawn on.
    pub gpu: &'g Gpu,
    /// Replay (fragsim's snapped triangles) or engine (the mesh through the f32 vertex shader).
    pub mode: Mode,
    /// A planted bug's shader variant, or `None` for the correct shader.
    pub plant: Option<Plant>,
}

impl WgpuBackend<'_> {
    /// The GPU scheme for the catalog scheme and sizes of `params`.
    fn scheme(params: &Params) -> Result<GpuScheme, String> {
        GpuScheme::parse(params.scheme.name(), params.k, params.capacity).map_err(|e| e.to_string())
    }
}

impl Backend for WgpuBackend<'_> {
    fn name(&self) -> String {
        format!(
            "the wgpu backend on {} ({} mode{})",
            self.gpu.info.name,
            self.mode.name(),
            self.plant
                .map_or(String::new(), |p| format!(", planted {}", p.name()))
        )
    }

    /// The catalog scheme's own claim, once the adapter and the plant are known to run it.
    fn guarantee(&self, params: &Params) -> Result<Guarantee, GuaranteeError> {
        let unsupported = |e: &dyn std::fmt::Display| GuaranteeError::Unsupported(e.to_string());
        let scheme = Self::scheme(params).map_err(|e| unsupported(&e))?;
        self.gpu
            .check(scheme.name(), scheme.needs())
            .map_err(|e| unsupported(&e))?;
        if let Some(plant) = self.plant {
            plant.check(&scheme).map_err(|e| unsupported(&e))?;
        }
        CatalogBackend::on(Executor::Parallel).guarantee(params)
    }

    fn vertex_precision(&self) -> VertexPrecision {
        VertexPrecision::F32
    }

    fn power_of_two_viewports(&self) -> bool {
        self.mode == Mode::Replay
    }

    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError> {
        let scheme = Self::scheme(input.params).map_err(BackendError::Setup)?;
        // The dump names the case's mesh as `fragsim conform` writes it (`mesh.obj` beside the
        // dump): only the judge reads it here, from the view itself.
        let obj = input.case.obj();
        let scene = Case::scene_and_camera("mesh.obj", mesh_hash(obj.as_bytes()));
        capture_planted(self.gpu, input.view, scene, &scheme, self.mode, self.plant)
            .map(|captured| Output::Dump(Box::new(captured.dump)))
            .map_err(battery_error)
    }
}

/// What the battery makes of a GPU error: a run the device failed is this case's failure, shrunk
/// like any other; no GPU, an adapter without what the case needs, or a request it refuses means
/// the backend cannot run the case at all, which shrinking would only hide.
fn battery_error(e: GpuError) -> BackendError {
    match e {
        GpuError::Device(message) => BackendError::Failed(message),
        GpuError::NoGpu(message) | GpuError::Unsupported(message) | GpuError::Refused(message) => {
            BackendError::Setup(message)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_failed_run_is_a_failing_case_the_rest_stop_the_battery() {
        let failed = battery_error(GpuError::Device("read-back: lost".into()));
        assert!(
            matches!(&failed, BackendError::Failed(m) if m == "read-back: lost"),
            "{failed}"
        );
        for e in [
            GpuError::NoGpu("no Vulkan adapter".into()),
            GpuError::Unsupported("no 64-bit atomics".into()),
            GpuError::Refused("unknown scheme".into()),
        ] {
            let message = e.to_string();
            let mapped = battery_error(e);
            assert!(
                matches!(&mapped, BackendError::Setup(m) if *m == message),
                "{mapped}"
            );
        }
    }
}

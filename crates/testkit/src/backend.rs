//! The [`Backend`] trait: a case in, a dump or per-pixel lists out; and [`CatalogBackend`], every
//! scheme of fragsim's catalog on any of its executors, so that the battery tests fragsim itself.
//!
//! Guarantee: a backend sees only the case's view (fragsim's vertex stage already applied; a
//! backend that rasterizes itself reads the case's mesh) and the scheme's sizes; what it returns
//! is judged by [`crate::judge`], the code `fragsim compare` judges dumps with. Source: the
//! catalog (`fragsim_catalog`) and the dump format (`docs/dump-format.md`).

use fragsim_capture::executors::scheduled::run_scheduled;
use fragsim_capture::executors::Executor;
use fragsim_capture::{Capture, CaptureError, Guarantee, Scheme, MEMORY_CAP_DEFAULT};
use fragsim_catalog::{Build, Count, SchemeName, SchemeRunner, SchemeVisitor, Sizing};
use fragsim_dump::Dump;
use fragsim_raster::{VertexPrecision, View, Viewport};

use crate::case::Case;

/// The scheme a backend runs and its sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Params {
    /// The catalog scheme (its layout names the dump's arrays).
    pub scheme: SchemeName,
    /// Slots per pixel of K-sized schemes (MDTS, the k-buffers).
    pub k: u32,
    /// Slots per pixel of capacity-sized schemes (the fixed A-buffer).
    pub capacity: u32,
}

/// What a backend is given: the case, fragsim's view of it, and the scheme's sizes.
#[derive(Clone, Copy, Debug)]
pub struct Input<'a> {
    /// The case (its triangles, viewport and schedule).
    pub case: &'a Case,
    /// The case's view: fragsim's vertex stage applied, ready to scan.
    pub view: &'a View<'a>,
    /// The scheme and its sizes.
    pub params: &'a Params,
}

/// What a backend returns.
#[derive(Clone, Debug)]
pub enum Output {
    /// A dump (`docs/dump-format.md`): judged by its decoded lists and every one of its words.
    Dump(Box<Dump>),
    /// Per-pixel lists under the scheme's promise: judged by the lists alone.
    Capture(Capture),
}

/// Why a backend returned no output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BackendError {
    /// The backend cannot run at all (a command not found, a size the scheme rejects): the
    /// battery stops and reports it, shrinking nothing.
    Setup(String),
    /// The backend failed on this case (a crash, a timeout, no readable dump): a failing case,
    /// shrunk like any other.
    Failed(String),
}

impl std::fmt::Display for BackendError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Setup(m) | Self::Failed(m) => f.write_str(m),
        }
    }
}

/// Why a backend cannot run some parameters ([`Backend::guarantee`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GuaranteeError {
    /// The catalog scheme cannot be built at these sizes.
    #[error("{scheme}: {source}")]
    Build {
        /// The scheme.
        scheme: SchemeName,
        /// Why it cannot be built.
        source: CaptureError,
    },
    /// The backend cannot run the scheme, for a reason of its own (a GPU without a feature the
    /// scheme needs), in its words.
    #[error("{0}")]
    Unsupported(String),
}

/// A backend under test.
pub trait Backend {
    /// A short description for reports.
    fn name(&self) -> String;

    /// What the backend claims for `params`: the battery checks what the claim owes
    /// ([`crate::battery`]).
    ///
    /// # Errors
    /// The backend cannot run `params` (a size the scheme rejects).
    fn guarantee(&self, params: &Params) -> Result<Guarantee, GuaranteeError>;

    /// Whether the backend runs each pixel's fragments one at a time in primitive order (then
    /// the guarantees that exclude hazards are owed). `false` for a GPU.
    fn serialises_pixels(&self) -> bool {
        false
    }

    /// The precision of the backend's vertex stage and depth interpolation, as it declares it:
    /// [`VertexPrecision::F64`] (the default) owes the oracle every bit; [`VertexPrecision::F32`]
    /// (a GPU's vertex shader and interpolator) is judged within the bounds derived for an f32
    /// vertex stage (`docs/semantics.md`, "Precision of a conforming implementation").
    fn vertex_precision(&self) -> VertexPrecision {
        VertexPrecision::F64
    }

    /// Whether the backend takes only viewports whose sides are powers of two (a replay of
    /// fragsim's snapped triangles through clip coordinates that are exact only then): the
    /// battery then generates and shrinks to such viewports alone.
    fn power_of_two_viewports(&self) -> bool {
        false
    }

    /// Captures one case.
    ///
    /// # Errors
    /// [`BackendError::Failed`] when it failed on the case, [`BackendError::Setup`] when it
    /// cannot run at all.
    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError>;
}

/// A catalog scheme on one of fragsim's executors. On the scheduled executor it runs under each
/// case's own schedule (so a hazard found shrinks with its interleaving); it then takes only
/// schemes sized without a counting pass and not following the primitive order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CatalogBackend {
    /// The executor.
    pub executor: Executor,
}

impl CatalogBackend {
    /// The catalog on `executor`.
    #[must_use]
    pub fn on(executor: Executor) -> Self {
        Self { executor }
    }
}

/// The sizes of `params` as the command line gives them (fixed K and capacity).
fn sizing(params: &Params) -> Sizing {
    Sizing {
        k: Count::Fixed(params.k),
        capacity: Count::Fixed(params.capacity),
        memory_cap: MEMORY_CAP_DEFAULT,
    }
}

/// The visitor reading a built scheme's guarantee.
struct GuaranteeOf;

impl SchemeVisitor for GuaranteeOf {
    type Output = Guarantee;
    fn visit<S: Scheme>(self, scheme: &S, _: Option<u32>) -> Guarantee {
        scheme.guarantee()
    }
}

/// The visitor running a built scheme on the scheduled executor under a case's schedule.
struct Scheduled<'v, 'm> {
    view: &'v View<'m>,
    case: &'v Case,
}

impl SchemeVisitor for Scheduled<'_, '_> {
    type Output = Capture;
    fn visit<S: Scheme>(self, scheme: &S, _: Option<u32>) -> Capture {
        run_scheduled(self.view, scheme, &self.case.schedule, false)
            .run
            .capture
    }
}

impl Backend for CatalogBackend {
    fn name(&self) -> String {
        format!("fragsim's catalog on the {} executor", self.executor.name())
    }

    fn guarantee(&self, params: &Params) -> Result<Guarantee, GuaranteeError> {
        // The guarantee of the scheme built at these sizes on one pixel (the sizes decide it:
        // a capacity is part of `exact-within-capacity`).
        let one = Viewport {
            width: 1,
            height: 1,
        };
        let build = Build {
            counts: Some(&[1]),
            ..Build::fixed(one, params.k, params.capacity, 1, MEMORY_CAP_DEFAULT)
        };
        params
            .scheme
            .build(&build, GuaranteeOf)
            .map_err(|source| GuaranteeError::Build {
                scheme: params.scheme,
                source,
            })
    }

    fn serialises_pixels(&self) -> bool {
        self.executor.serialises_pixels()
    }

    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError> {
        let params = input.params;
        let sizing = sizing(params);
        if self.executor != Executor::Scheduled {
            let run = SchemeRunner::default()
                .run(params.scheme, self.executor, input.view, &sizing)
                .map_err(|e| BackendError::Setup(e.to_string()))?;
            return Ok(Output::Capture(run.run.capture));
        }
        let entry = params.scheme.entry();
        if params.scheme.needs_count_pass(&sizing) || entry.primitive_order {
            return Err(BackendError::Setup(format!(
                "{}: the battery runs the scheduled executor under each case's schedule only for \
                 schemes sized without a counting pass and not following the primitive order",
                entry.name
            )));
        }
        let build = Build::fixed(
            input.view.viewport(),
            params.k,
            params.capacity,
            1,
            MEMORY_CAP_DEFAULT,
        );
        params
            .scheme
            .build(
                &build,
                Scheduled {
                    view: input.view,
                    case: input.case,
                },
            )
            .map(Output::Capture)
            .map_err(|e| BackendError::Setup(format!("{}: {e}", entry.name)))
    }
}

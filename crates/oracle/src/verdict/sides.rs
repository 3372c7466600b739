//! The two sides of `fragsim compare`, as the command line names them (a dump directory or its
//! `dump.json`, or `oracle`): their headers checked against each other, the oracle rebuilt from
//! the scene a dump names when a side asks for it, and the verdict of [`super::judge`].

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use fragsim_raster::{Conventions, VertexPrecision, Viewport};
use serde::Serialize;

use super::{judge, Candidate, Options, Reference, Verdict, VerdictError};
use crate::precision::Precision;
use crate::samples::SampleOracle;
use crate::Oracle;
use fragsim_dump::{Dump, DumpError, Header};

/// One side of a comparison.
#[derive(Debug)]
pub enum Side {
    /// fragsim's serial oracle on the scene the other side's header names.
    Oracle,
    /// A dump, read from `path`.
    Dump(Box<Dump>, PathBuf),
}

/// A side as a report names it.
#[derive(Clone, Debug, Serialize)]
pub struct SideReport {
    /// The path given, or `oracle`.
    pub source: String,
    /// The dump's scheme, or `oracle`.
    pub scheme: String,
    /// What wrote it.
    pub producer: String,
    /// The K of a K-list dump.
    pub k: Option<u32>,
    /// The capacity of a fixed-capacity dump.
    pub capacity: Option<u32>,
}

impl SideReport {
    /// The side in one line: `fragsim oracle`, or the dump's path, scheme, size and producer.
    #[must_use]
    pub fn describe(&self) -> String {
        let size = match (self.k, self.capacity) {
            (Some(k), _) => format!(" K={k}"),
            (None, Some(c)) => format!(" capacity={c}"),
            _ => String::new(),
        };
        if self.source == "oracle" {
            "fragsim oracle".to_string()
        } else {
            let (source, scheme, producer) = (&self.source, &self.scheme, &self.producer);
            format!("{source} ({scheme}{size}, by {producer})")
        }
    }
}

impl Side {
    /// The side `text` names: `oracle`, or a dump directory (or its `dump.json`), read.
    ///
    /// # Errors
    /// A dump that cannot be read.
    pub fn open(text: &str) -> Result<Self, VerdictError> {
        Self::open_within(text, fragsim_capture::MEMORY_CAP_DEFAULT)
    }

    /// [`Side::open`] with the dump's arrays holding at most `limit` bytes together
    /// ([`Dump::read_within`]).
    ///
    /// # Errors
    /// A dump that cannot be read, or arrays over `limit`.
    pub fn open_within(text: &str, limit: u64) -> Result<Self, VerdictError> {
        if text == "oracle" {
            return Ok(Self::Oracle);
        }
        let path = PathBuf::from(text);
        let dump = Dump::read_within(&path, limit)?;
        Ok(Self::Dump(Box::new(dump), path))
    }

    fn header(&self) -> Option<&Header> {
        match self {
            Self::Oracle => None,
            Self::Dump(dump, _) => Some(&dump.header),
        }
    }

    fn is_masked(&self) -> bool {
        matches!(self, Self::Dump(dump, _) if dump.is_masked())
    }

    /// The side as a report names it.
    #[must_use]
    pub fn describe(&self) -> SideReport {
        match self {
            Self::Oracle => SideReport {
                source: "oracle".into(),
                scheme: "oracle".into(),
                producer: format!("fragsim {}", env!("CARGO_PKG_VERSION")),
                k: None,
                capacity: None,
            },
            Self::Dump(dump, path) => SideReport {
                source: path.display().to_string(),
                scheme: dump.header.scheme.clone(),
                producer: dump.header.producer.clone(),
                k: dump.header.k,
                capacity: dump.header.capacity,
            },
        }
    }
}

/// How [`judge_sides`] judges: [`Options`] and what the command line adds.
#[derive(Clone, Copy, Debug, Default)]
pub struct SidesOptions<'a> {
    /// Tolerance and examples.
    pub options: Options,
    /// How the candidate's vertex stage is judged against the oracle: f64 owes every bit to the
    /// oracle rebuilt under the dump's declared conventions; f32 judges within the bounds derived
    /// for an f32 vertex stage against the exact f64 one.
    pub vertex_precision: VertexPrecision,
    /// The mesh file to rebuild the oracle from instead of the one the dump names.
    pub mesh: Option<&'a Path>,
    /// Compare two dumps that name different scenes (a note) instead of refusing them.
    pub allow_different_scenes: bool,
    /// The most bytes the scene and the oracle may take (`--memory-cap`), bounded before either
    /// is made ([`crate::memory_cap`]); `None`: no bound.
    pub memory_cap: Option<u64>,
}

/// Judges `candidate` against `reference` ([`super::judge`]), the oracle rebuilt from the scene
/// the dump names (`--mesh` replaces its mesh) where a side is [`Side::Oracle`].
///
/// # Errors
/// Both sides the oracle; dumps of different viewports, or of different scenes unless allowed;
/// `--vertex-precision f32` against a reference dump; a masked-node dump anywhere but as the
/// candidate against the oracle, or under f32 one whose nodes overflowed; a scene that cannot be
/// rebuilt; a dump that cannot be decoded.
pub fn judge_sides(
    reference: &Side,
    candidate: &Side,
    options: &SidesOptions<'_>,
) -> Result<Verdict, VerdictError> {
    let (mut header, beside) = match (reference, candidate) {
        (Side::Dump(dump, path), _) | (Side::Oracle, Side::Dump(dump, path)) => {
            (dump.header.clone(), dump_dir(path))
        }
        (Side::Oracle, Side::Oracle) => return Err(VerdictError::NoDump),
    };
    if let Some(mesh) = options.mesh {
        (header.scene.mesh, header.scene.name) = (Some(mesh.display().to_string()), None);
    }
    let mut notes = Vec::new();
    if let (Some(a), Some(b)) = (reference.header(), candidate.header()) {
        if (a.width, a.height) != (b.width, b.height) {
            return Err(VerdictError::DumpViewports {
                a: (a.width, a.height),
                b: (b.width, b.height),
            });
        }
        if a.scene != b.scene {
            let (a, b) = (a.scene.describe(), b.scene.describe());
            if !options.allow_different_scenes {
                return Err(VerdictError::DifferentScenes { a, b });
            }
            notes.push(format!("the dumps name different scenes: {a} and {b}"));
        }
    }
    let judged_f32 = options.vertex_precision == VertexPrecision::F32;
    // The precision bounds are derived per sample; the sample count is checked here all the same.
    header.samples()?;
    // A masked-node dump is judged against the per-pixel view of the per-sample oracle, which
    // only the oracle side can give.
    let masked = candidate.is_masked();
    if reference.is_masked() || (masked && !matches!(reference, Side::Oracle)) {
        return Err(VerdictError::MaskedSide);
    }
    let size = (header.width, header.height);
    // The oracle is built only when a side asks for it (the scene may be a large mesh). Without
    // f32 it is rebuilt under the conventions the dump declares, its vertex stage included, and
    // owes every bit; with f32 it takes the exact f64 vertex stage under the declared
    // conventions, and the candidate is judged within the bounds derived for an f32 one: they
    // measure an implementation's distance from the exact positions, not from another f32 order.
    let needs_oracle = matches!(reference, Side::Oracle) || matches!(candidate, Side::Oracle);
    let mut spec = header.scene.clone();
    if judged_f32 {
        spec.conventions.vertex_precision = VertexPrecision::F64;
    }
    if let (true, Some(cap), Some(name), None) =
        (needs_oracle, options.memory_cap, &spec.name, &spec.mesh)
    {
        let lists = header.framebuffer()?.pixels() as u64;
        crate::memory_cap::check_named_scene(name, lists, cap)?;
    }
    let loaded = if needs_oracle {
        Some(spec.load(Some(&beside)).map_err(DumpError::from)?)
    } else {
        None
    };
    let view = match &loaded {
        Some(loaded) => {
            let viewport = Viewport::new(header.width, header.height)?;
            Some(spec.view(loaded, viewport).map_err(DumpError::from)?)
        }
        None => None,
    };
    if let (true, Some(view)) = (judged_f32, &view) {
        // The f32 stage judged is not the view's (f64 here): its range is checked all the same.
        view.check_f32_range()?;
    }
    if let (Some(view), Some(cap)) = (&view, options.memory_cap) {
        crate::memory_cap::check(view, cap)?;
    }
    let oracle = match &view {
        None => None,
        Some(view) if masked => {
            let sampled = SampleOracle::of_view(view);
            #[expect(
                clippy::shadow_unrelated,
                reason = "the masked reference, the one this arm builds"
            )]
            let reference = Reference::masked(sampled.per_pixel(), size);
            Some(if judged_f32 {
                // The exact per-sample oracle (the view's vertex stage is f64 here) and the
                // bounds of an f32 one at every sample, as for a per-sample dump.
                let conventions = Conventions {
                    vertex_precision: VertexPrecision::F32,
                    ..view.conventions()
                };
                let precision = Precision::derive(view, &conventions);
                reference.masked_within(sampled.oracle().clone(), precision)
            } else {
                reference
            })
        }
        Some(view) => {
            let stage = options.vertex_precision;
            let conventions = Conventions {
                vertex_precision: stage,
                ..view.conventions()
            };
            let precision = Precision::derive(view, &conventions);
            Some(
                Reference::new(
                    Cow::Owned(Oracle::build(view)),
                    Cow::Owned(precision),
                    stage,
                    size,
                )
                .with_edge_ties(view),
            )
        }
    };
    if judged_f32 && !matches!(reference, Side::Oracle) {
        return Err(VerdictError::F32NeedsOracle);
    }
    // The oracle is the reference, or (against a reference dump) the candidate.
    let (mut reference, oracle) = match (reference, oracle) {
        (Side::Dump(dump, _), oracle) => (Reference::dump(dump)?, oracle),
        (Side::Oracle, Some(oracle)) => (oracle, None),
        (Side::Oracle, None) => unreachable!("the oracle is built when a side names it"),
    };
    reference.notes = notes;
    let candidate = match (candidate, &oracle) {
        (Side::Dump(dump, _), _) => Candidate::Dump(dump),
        (Side::Oracle, Some(oracle)) => Candidate::Oracle(oracle.oracle()),
        (Side::Oracle, None) => unreachable!("the oracle is built when a side names it"),
    };
    let mut verdict = judge(&reference, candidate, &options.options)?;
    verdict.scene = Some(header.scene);
    Ok(verdict)
}

/// The directory a dump's relative paths are taken from.
fn dump_dir(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.to_path_buf()
    } else {
        path.parent().unwrap_or(Path::new(".")).to_path_buf()
    }
}

//! `fragsim conform` as a library: the battery ([`Battery`]) against a [`CommandBackend`] on
//! generated cases, its `conform` record, and the smallest failing case saved with the commands
//! that replay it. The command line parses the options and prints what [`conform`] returns.
//!
//! The report claims only what the cases exercised ([`Exercised::claims`]); a backend that
//! fails to run on the smallest case too fails whatever the case, and is not shrunk.

use std::path::{Path, PathBuf};
use std::time::Duration;

use fragsim_catalog::{SchemeName, CATALOG};
use fragsim_oracle::PixelMismatch;
use fragsim_raster::{depth_from_key, Conventions, VertexPrecision};
use serde::Serialize;

use crate::battery::{Battery, Counterexample, Event, Exercised, Failure};
use crate::case::{Case, Limits};
use crate::command::{quoted, write_case, CommandBackend};
use crate::{Input, Params};

/// What `conform` runs: the backend's command, the scheme and its sizes, the cases.
#[derive(Debug, Clone)]
pub struct ConformParams {
    /// The backend's command line (`{scene}`, `{out}`, `{scheme}`, `{k}`, `{capacity}`
    /// replaced per case: [`CommandBackend::template`]).
    pub backend: String,
    /// The catalog scheme the backend runs, by name.
    pub scheme: String,
    /// Slots per pixel of K-sized schemes.
    pub k: u32,
    /// Slots per pixel of the fixed A-buffer.
    pub capacity: u32,
    /// How many cases the seed generates.
    pub cases: u32,
    /// The seed the cases are generated from.
    pub seed: u64,
    /// The shard checked, `(index, count)` with the index from 1 (`None`: every case).
    pub shard: Option<(u32, u32)>,
    /// How long one run of the command may take.
    pub timeout: Duration,
    /// The largest viewport side of a case.
    pub max_side: u32,
    /// The most triangles a case holds (`None`: 7, or 4 more than the larger of K and the
    /// capacity where that is more).
    pub max_triangles: Option<u32>,
    /// The most simplifications proptest tries on a failing case.
    pub shrink_steps: u32,
    /// Where the smallest failing case is saved (`case/`) and the cases run (`work/`).
    pub save: PathBuf,
    /// How the backend's vertex stage is judged.
    pub vertex_precision: VertexPrecision,
    /// Whether the backend takes only viewports whose sides are powers of two.
    pub power_of_two: bool,
    /// The `fragsim` program the replay script runs `compare` with.
    pub fragsim: PathBuf,
}

impl ConformParams {
    /// The shard, `(index, count)` (`(1, 1)`: the whole).
    fn shard_or_whole(&self) -> (u32, u32) {
        self.shard.unwrap_or((1, 1))
    }

    /// The cases this shard checks: those numbered `index`, `index + count`, … of all.
    #[must_use]
    pub fn shard_cases(&self) -> u32 {
        let (index, count) = self.shard_or_whole();
        (self.cases + count - index) / count
    }
}

/// A fragment as the report shows it.
#[derive(Debug, Serialize)]
pub struct Entry {
    /// The depth key, 8 hex digits (as `compare` prints keys).
    pub key: String,
    /// The depth the key encodes.
    pub depth: f32,
    /// The primitive id.
    pub prim: u32,
}

/// The entries of a list of fragment words (depth key high, primitive id low).
#[expect(
    clippy::cast_possible_truncation,
    reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn entries(words: &[u64]) -> Vec<Entry> {
    words
        .iter()
        .map(|&w| Entry {
            key: format!("{:08x}", w >> 32),
            depth: depth_from_key((w >> 32) as u32),
            prim: w as u32,
        })
        .collect()
}

/// What the checked cases exercised, as the `conform` record carries it.
#[derive(Debug, Serialize)]
struct ExercisedRecord {
    /// Cases counted: those that passed.
    exercised_cases: u32,
    exercised_fragments: u64,
    deepest_pixel: u32,
    k_cut_cases: u32,
    over_capacity_cases: u32,
    overflow_cases: u32,
    overflow_fragments: u64,
    tie_cases: u32,
    empty_cases: u32,
}

impl From<Exercised> for ExercisedRecord {
    fn from(e: Exercised) -> Self {
        Self {
            exercised_cases: e.cases,
            exercised_fragments: e.fragments,
            deepest_pixel: e.deepest_pixel,
            k_cut_cases: e.k_cut_cases,
            over_capacity_cases: e.over_capacity_cases,
            overflow_cases: e.overflow_cases,
            overflow_fragments: e.overflow_fragments,
            tie_cases: e.tie_cases,
            empty_cases: e.empty_cases,
        }
    }
}

/// The `conform` record's own fields (`docs/json-schema.md`).
#[derive(Debug, Serialize)]
pub struct ConformRecord {
    passed: bool,
    backend: String,
    conform_scheme: String,
    cases: u32,
    seed: u64,
    vertex_precision: String,
    /// `I/N` under a shard (`null` unsharded).
    shard: Option<String>,
    /// Cases checked (a shard's own).
    cases_run: u32,
    /// The failing case's number among the seed's `cases` (the same in a shard as unsharded).
    case_number: Option<u32>,
    shrink_steps: Option<u32>,
    property: Option<String>,
    message: Option<String>,
    triangles: Option<usize>,
    fragments: Option<usize>,
    saved: Option<String>,
    replay: Option<Vec<String>>,
    /// On a failure, whether the backend failed to run on the smallest case too (not shrunk).
    case_independent: Option<bool>,
    #[serde(flatten)]
    exercised: ExercisedRecord,
}

/// One differing pixel of the counterexample, both lists (the `counterexample_pixel` record).
#[derive(Debug, Serialize)]
pub struct PixelRecord {
    /// The pixel's index.
    pub pixel: usize,
    /// Its column.
    pub x: u32,
    /// Its row.
    pub y: u32,
    /// The oracle's list.
    pub reference: Vec<Entry>,
    /// The backend's list.
    pub candidate: Vec<Entry>,
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
)]
fn pixel_record(m: &PixelMismatch, width: u32) -> PixelRecord {
    PixelRecord {
        pixel: m.pixel,
        x: m.pixel as u32 % width,
        y: m.pixel as u32 / width,
        reference: entries(&m.expected),
        candidate: entries(&m.got),
    }
}

/// The smallest failing case, saved.
#[derive(Debug)]
pub struct Found {
    /// The counterexample the battery shrunk to.
    pub counterexample: Box<Counterexample>,
    /// Its first differing pixels.
    pub pixels: Vec<PixelRecord>,
    /// The directory it is saved in (`scene/`, `out/`, `replay.sh`).
    pub saved: PathBuf,
    /// The commands that replay it.
    pub replay: Vec<String>,
}

/// What `conform` found: the record, and the counterexample where a case failed.
#[derive(Debug)]
pub struct Conformance {
    /// The scheme checked.
    pub scheme: SchemeName,
    /// The battery's sizes.
    pub params: Params,
    /// The `conform` record.
    pub record: ConformRecord,
    /// What the cases that passed exercised.
    pub exercised: Exercised,
    /// The smallest failing case (`None`: every case passed).
    pub found: Option<Found>,
}

/// Runs the battery against the command of `params`, telling `on_event` of each case and
/// shrinking step; saves the smallest failing case in `params.save/case/` (an older one is
/// removed when every case passes).
///
/// # Errors
/// An unknown scheme, a command without `{out}` or one that cannot run, files that cannot be
/// written.
pub fn conform(
    params: &ConformParams,
    on_event: &mut dyn FnMut(Event),
) -> Result<Conformance, String> {
    let scheme = SchemeName::from_name(&params.scheme).ok_or_else(|| {
        let names: Vec<&str> = CATALOG.iter().map(|e| e.name).collect();
        format!(
            "unknown scheme {}: one of {}",
            params.scheme,
            names.join(", ")
        )
    })?;
    if !params.backend.contains("{out}") {
        return Err(format!(
            "--backend `{}` has no {{out}}: the command must be told where to write its dump",
            params.backend
        ));
    }
    let (index, count) = params.shard_or_whole();
    let sizes = Params {
        scheme,
        k: params.k,
        capacity: params.capacity,
    };
    let work = params.save.join("work");
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let backend = CommandBackend {
        template: params.backend.clone(),
        timeout: params.timeout,
        work: work.clone(),
        vertex_precision: params.vertex_precision,
        power_of_two: params.power_of_two,
    };
    let max_triangles = params
        .max_triangles
        .unwrap_or((params.k.max(params.capacity) + 4).clamp(7, 64));
    let battery = Battery::new(&backend, sizes)
        .cases(params.cases)
        .seed(params.seed)
        .shard(index, count)
        .shrink_steps(params.shrink_steps)
        .limits(Limits {
            max_side: params.max_side,
            max_triangles: max_triangles as usize,
            power_of_two: params.power_of_two,
            ..Limits::default()
        });
    let result = battery.run_with(on_event);
    // The cases' files are scratch; the saved case is written afresh below.
    let _ = std::fs::remove_dir_all(&work);
    let record = ConformRecord {
        passed: true,
        backend: params.backend.clone(),
        conform_scheme: scheme.name().to_string(),
        cases: params.cases,
        seed: params.seed,
        vertex_precision: precision_name(params.vertex_precision).into(),
        shard: params.shard.map(|(i, n)| format!("{i}/{n}")),
        cases_run: params.shard_cases(),
        case_number: None,
        shrink_steps: None,
        property: None,
        message: None,
        triangles: None,
        fragments: None,
        saved: None,
        replay: None,
        case_independent: None,
        exercised: Exercised::default().into(),
    };
    let saved = params.save.join("case");
    let found = match result {
        Ok(passed) => {
            // A failing case saved by an earlier run no longer describes this backend.
            if saved.exists() {
                std::fs::remove_dir_all(&saved)
                    .map_err(|e| format!("cannot remove {}: {e}", saved.display()))?;
            }
            return Ok(Conformance {
                scheme,
                params: sizes,
                record: ConformRecord {
                    exercised: passed.exercised.into(),
                    ..record
                },
                exercised: passed.exercised,
                found: None,
            });
        }
        Err(Failure::Refused(message)) => return Err(message),
        Err(Failure::Counterexample(found)) => found,
    };
    let replay = save(&backend, &found, &sizes, &saved, &params.fragsim)?;
    let viewport = found.submitted.viewport;
    let pixels = found
        .mismatches()
        .iter()
        .map(|m| pixel_record(m, viewport.width))
        .collect();
    Ok(Conformance {
        scheme,
        params: sizes,
        record: ConformRecord {
            passed: false,
            cases_run: found.cases_run,
            case_number: Some(found.case_number),
            shrink_steps: Some(found.shrink_steps),
            property: Some(found.property.to_string()),
            message: Some(found.message.clone()),
            triangles: Some(found.submitted.triangles.len()),
            fragments: Some(found.fragments),
            saved: Some(saved.display().to_string()),
            replay: Some(replay.clone()),
            case_independent: Some(found.case_independent),
            exercised: found.exercised.into(),
            ..record
        },
        exercised: found.exercised,
        found: Some(Found {
            counterexample: found,
            pixels,
            saved,
            replay,
        }),
    })
}

/// How options and records spell a vertex precision.
fn precision_name(precision: VertexPrecision) -> &'static str {
    match precision {
        VertexPrecision::F32 => "f32",
        VertexPrecision::F64 => "f64",
    }
}

/// Runs the backend once more on the shrunk case inside `dir` (`dir/scene`, `dir/out`), and
/// writes `dir/replay.sh`, whose `compare` runs `fragsim`; returns the replay's command lines.
fn save(
    backend: &CommandBackend,
    found: &Counterexample,
    params: &Params,
    dir: &Path,
    fragsim: &Path,
) -> Result<Vec<String>, String> {
    let case = &found.submitted;
    let scene = case.scene();
    let view = scene
        .view_under(case.viewport, &Case::camera(), Conventions::REFERENCE)
        .map_err(|e| e.to_string())?;
    let input = Input {
        case,
        view: &view,
        params,
    };
    // The dump may be missing when the failure is the backend's own (a crash, a timeout):
    // the scene files are saved all the same. A backend that fails whatever the case is not run
    // again (a timeout would cost its whole length once more).
    let rerun = if found.case_independent {
        #[expect(
            clippy::shadow_unrelated,
            reason = "the scene file's path in the counterexample's directory"
        )]
        let scene = dir.join("scene");
        if dir.exists() {
            std::fs::remove_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        for d in [&scene, &dir.join("out")] {
            std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
        }
        write_case(case, &view, params, &scene).map_err(|e| e.to_string())?;
        Err(found.message.clone())
    } else {
        backend.run_in(&input, dir).map_err(|e| e.to_string())
    };
    let absolute = std::fs::canonicalize(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    // Every path absolute, so that the script runs from any directory: the backend's command
    // from the directory conform ran in (its own paths may be relative to it), and this very
    // fragsim (which need not be on PATH).
    let here = std::env::current_dir().map_err(|e| format!("the working directory: {e}"))?;
    let replay = vec![
        format!("cd {} || exit 2", quoted(&here)),
        backend.command_line(&absolute.join("scene"), &absolute.join("out"), params),
        format!(
            "{} compare oracle {}{}",
            quoted(fragsim),
            quoted(&absolute.join("out")),
            match backend.vertex_precision {
                VertexPrecision::F32 => " --vertex-precision f32",
                VertexPrecision::F64 => "",
            }
        ),
    ];
    let mut script = String::from(
        "#!/bin/sh\n# Replays fragsim conform's smallest failing case (from any directory).\n",
    );
    if let Err(e) = rerun {
        script.push_str(&if found.case_independent {
            format!("# The backend failed whatever the case, this one too: {e}\n")
        } else {
            format!("# On saving, the backend failed again: {e}\n")
        });
    }
    for line in &replay {
        script.push_str(line);
        script.push('\n');
    }
    let path = dir.join("replay.sh");
    std::fs::write(&path, script).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(replay)
}

impl Exercised {
    /// What the cases exercised, in lines: each claim of a pass with the cases that exercised
    /// it, or said never to have been exercised (`k` and `capacity`: the battery's sizes).
    #[must_use]
    pub fn claims(&self, k: u32, capacity: u32) -> Vec<String> {
        let e = self;
        let of = |n: u32| format!("{n} of {}", e.cases);
        let mut lines = vec![format!(
            "equal to the oracle and order-independent in {} cases ({} fragments, {} empty cases)",
            e.cases, e.fragments, e.empty_cases
        )];
        lines.push(if e.overflow_cases > 0 {
            format!(
                "overflow as predicted in {} cases ({} fragments overflowed)",
                of(e.overflow_cases),
                e.overflow_fragments
            )
        } else {
            format!(
                "overflow: never exercised (no case exceeded the scheme's storage: deepest pixel \
                 {}, k {k}, capacity {capacity})",
                e.deepest_pixel
            )
        });
        lines.push(format!(
            "deepest pixel {} fragments; deeper than K ({k}) in {} cases, than the capacity \
             ({capacity}) in {}",
            e.deepest_pixel,
            of(e.k_cut_cases),
            of(e.over_capacity_cases)
        ));
        lines.push(if e.tie_cases > 0 {
            format!("ties (fragments at one depth) in {} cases", of(e.tie_cases))
        } else {
            "ties: never exercised (no pixel held two fragments at one depth)".to_string()
        });
        lines
    }
}

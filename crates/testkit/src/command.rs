//! [`CommandBackend`]: a backend in any language, run as a shell command on a case's files.
//!
//! For each case the command line's placeholders are replaced and the line is run by `sh -c`:
//! `{scene}` is a directory holding the case ([`write_case`]), `{out}` the directory the backend
//! writes its dump into (`docs/dump-format.md`; it exists and is empty), `{scheme}`, `{k}` and
//! `{capacity}` the scheme's name and sizes. The case's directory holds
//! - `scene.tri`: the triangle export (`FRAGTRI1`), for backends that scan fragsim's screen
//!   triangles;
//! - `mesh.obj` and `camera.json`: the mesh and the scene object of a dump header (its
//!   `view_projection` is the identity, so model x and y are normalised device coordinates), for
//!   backends that run their own vertex stage;
//! - `case.json`: `{"width", "height", "scheme", "k", "capacity", "triangles"}`.
//!
//! Guarantee: a command that exits non-zero, runs past its timeout (it is killed, with its whole
//! process group) or leaves no readable dump fails the case; its stderr's last lines are in the
//! message. Source: the dump format and the triangle export (`fragsim_dump`,
//! `fragsim_dump::triangles`).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use fragsim_capture::Guarantee;
use fragsim_dump::triangles::TriangleExport;
use fragsim_dump::{Dump, DumpError};
use fragsim_raster::scene_spec::mesh_hash;
use fragsim_raster::{VertexPrecision, View};

use crate::backend::{Backend, BackendError, GuaranteeError, Input, Output, Params};
use crate::case::Case;

/// The exit status `sh` gives a command it cannot find or run.
const NOT_FOUND: [i32; 2] = [126, 127];

/// A backend run as a command line on each case's files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CommandBackend {
    /// The command line, with `{scene}` and `{out}` (and optionally `{scheme}`, `{k}`,
    /// `{capacity}`) to be replaced.
    pub template: String,
    /// How long one case may run.
    pub timeout: Duration,
    /// Where the cases are written (`current/` inside it, replaced at every case).
    pub work: PathBuf,
    /// The precision of the command's vertex stage ([`Backend::vertex_precision`]): `F32` for a
    /// GPU's vertex shader and interpolator, judged within the bounds derived for it.
    pub vertex_precision: VertexPrecision,
    /// Whether the command takes only viewports whose sides are powers of two
    /// ([`Backend::power_of_two_viewports`]).
    pub power_of_two: bool,
}

/// A path as one shell word.
pub(crate) fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', "'\\''"))
}

/// Why a case could not be written for a command ([`write_case`]).
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// A file of the case could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The case's directory could not be made absolute (it does not exist, say).
    #[error("{}: {source}", path.display())]
    Directory {
        /// The directory.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The scene and camera could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The triangle export could not be written.
    #[error(transparent)]
    Export(#[from] DumpError),
}

/// Writes `case` (its view `view`, to be run with `params`) into `dir`, which must exist:
/// `scene.tri`, `mesh.obj`, `camera.json`, `case.json` (see the module docs). The scene object
/// names the mesh by its absolute path, so the files can be read from anywhere.
///
/// # Errors
/// A file that cannot be written.
pub fn write_case(
    case: &Case,
    view: &View<'_>,
    params: &Params,
    dir: &Path,
) -> Result<(), CaseError> {
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        fs::write(&path, bytes).map_err(|source| CaseError::Write { path, source })
    };
    let obj = case.obj();
    write("mesh.obj", obj.as_bytes())?;
    let dir = fs::canonicalize(dir).map_err(|source| CaseError::Directory {
        path: dir.to_path_buf(),
        source,
    })?;
    let mesh = dir.join("mesh.obj");
    let scene = Case::scene_and_camera(&mesh.display().to_string(), mesh_hash(obj.as_bytes()));
    let camera = serde_json::to_string_pretty(&scene)?;
    write("camera.json", camera.as_bytes())?;
    TriangleExport::from_view(view, scene).write(&dir.join("scene.tri"))?;
    let about = serde_json::json!({
        "width": case.viewport.width,
        "height": case.viewport.height,
        "scheme": params.scheme.name(),
        "k": params.k,
        "capacity": params.capacity,
        "triangles": case.triangles.len(),
    });
    write("case.json", about.to_string().as_bytes())
}

impl CommandBackend {
    /// The command line for a case in `scene` whose dump goes to `out`, run with `params`.
    #[must_use]
    pub fn command_line(&self, scene: &Path, out: &Path, params: &Params) -> String {
        self.template
            .replace("{scene}", &quoted(scene))
            .replace("{out}", &quoted(out))
            .replace("{scheme}", params.scheme.name())
            .replace("{k}", &params.k.to_string())
            .replace("{capacity}", &params.capacity.to_string())
    }

    /// Runs the command on `input`'s case inside `dir`: the case in `dir/scene`, the dump in
    /// `dir/out` (both made afresh), the command's output in `dir/stdout.txt` and
    /// `dir/stderr.txt`.
    ///
    /// # Errors
    /// [`BackendError::Setup`] when the command cannot be started or found, [`BackendError::Failed`]
    /// when it fails on the case.
    pub fn run_in(&self, input: &Input<'_>, dir: &Path) -> Result<Dump, BackendError> {
        let setup = |e: String| BackendError::Setup(e);
        if dir.exists() {
            fs::remove_dir_all(dir).map_err(|e| setup(format!("{}: {e}", dir.display())))?;
        }
        let (scene, out) = (dir.join("scene"), dir.join("out"));
        for d in [&scene, &out] {
            fs::create_dir_all(d).map_err(|e| setup(format!("{}: {e}", d.display())))?;
        }
        write_case(input.case, input.view, input.params, &scene)
            .map_err(|e| setup(e.to_string()))?;
        let line = self.command_line(
            &fs::canonicalize(&scene).map_err(|e| setup(e.to_string()))?,
            &fs::canonicalize(&out).map_err(|e| setup(e.to_string()))?,
            input.params,
        );
        let stderr_path = dir.join("stderr.txt");
        let status = self.run_line(&line, &dir.join("stdout.txt"), &stderr_path)?;
        let stderr_tail = || {
            let text = fs::read_to_string(&stderr_path).unwrap_or_default();
            let lines: Vec<&str> = text.lines().collect();
            lines[lines.len().saturating_sub(5)..].join(" | ")
        };
        if !status.success() {
            let message = format!(
                "`{line}` exited with {status}{}",
                match stderr_tail() {
                    tail if tail.is_empty() => String::new(),
                    tail => format!(": {tail}"),
                }
            );
            return Err(if status.code().is_some_and(|c| NOT_FOUND.contains(&c)) {
                BackendError::Setup(message)
            } else {
                BackendError::Failed(message)
            });
        }
        // A command that succeeds and writes nothing at all is not failing on this case: it is
        // not writing where `{out}` says (every case would fail alike, and shrinking would only
        // run it again and again).
        if fs::read_dir(&out).map_or(true, |mut entries| entries.next().is_none()) {
            return Err(BackendError::Setup(format!(
                "`{line}` exited 0 but wrote nothing into {} (its {{out}}): a backend writes its \
                 dump there, header.json and its arrays (docs/dump-format.md)",
                out.display()
            )));
        }
        Dump::read(&out).map_err(|e| BackendError::Failed(format!("the backend's dump: {e}")))
    }

    /// Runs `line` with `sh -c` in a process group of its own, its output into the two files;
    /// kills the group past the timeout.
    fn run_line(
        &self,
        line: &str,
        stdout: &Path,
        stderr: &Path,
    ) -> Result<ExitStatus, BackendError> {
        let file = |path: &Path| {
            fs::File::create(path)
                .map_err(|e| BackendError::Setup(format!("{}: {e}", path.display())))
        };
        let mut command = Command::new("sh");
        command
            .arg("-c")
            .arg(line)
            .stdin(Stdio::null())
            .stdout(file(stdout)?)
            .stderr(file(stderr)?);
        #[cfg(unix)]
        std::os::unix::process::CommandExt::process_group(&mut command, 0);
        let mut child = command
            .spawn()
            .map_err(|e| BackendError::Setup(format!("cannot run sh -c `{line}`: {e}")))?;
        let deadline = Instant::now() + self.timeout;
        loop {
            match child.try_wait() {
                Ok(Some(status)) => return Ok(status),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(2));
                }
                Ok(None) => {
                    // The whole group: `sh` and whatever it started. `-s KILL --` spells the
                    // group as an operand: procps-ng 4.0.2 (Debian 12) reads `kill -KILL -PGID`
                    // as `kill(-<first digit of PGID>)`, which for a group such as 12345 is
                    // kill(-1): every process the user may signal (seen under strace).
                    let _ = Command::new("kill")
                        .args(["-s", "KILL", "--", &format!("-{}", child.id())])
                        .status();
                    let _ = child.kill();
                    let _ = child.wait();
                    return Err(BackendError::Failed(format!(
                        "`{line}` ran past its timeout of {:.1} s and was killed",
                        self.timeout.as_secs_f64()
                    )));
                }
                Err(e) => return Err(BackendError::Setup(format!("waiting for `{line}`: {e}"))),
            }
        }
    }
}

impl Backend for CommandBackend {
    fn name(&self) -> String {
        format!("`{}`", self.template)
    }

    /// Exactness under the scheme's promise: what `fragsim compare` holds a dump to.
    fn guarantee(&self, _: &Params) -> Result<Guarantee, GuaranteeError> {
        Ok(Guarantee::Exact)
    }

    fn vertex_precision(&self) -> VertexPrecision {
        self.vertex_precision
    }

    fn power_of_two_viewports(&self) -> bool {
        self.power_of_two
    }

    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError> {
        self.run_in(input, &self.work.join("current"))
            .map(|dump| Output::Dump(Box::new(dump)))
    }
}

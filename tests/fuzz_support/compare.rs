//! The `compare` target: two arbitrary dumps through `fragsim compare REFERENCE CANDIDATE`
//! ([`fragsim_cli::compare`], the command's own code, run on two dump directories), never a
//! panic. The input is a little-endian `u32` length, then that many bytes of the reference's
//! [`Blob`] (as `dump_parse` reads one), then the candidate's; the length's top bit set
//! ([`ORACLE`]), the candidate is also compared with the oracle. Each is written out as a
//! directory, the header as `dump.json` and each array file the parser asks for beside it, so
//! that the command reads them as it reads a backend's.
//!
//! What is written for a file is chosen by its name, so that the fuzzer reaches the reader's
//! refusals through the header's text: an array file whose name starts `zero` is a link to
//! `/dev/zero`, `fifo` a FIFO, `sock` a socket, `dir` a directory; a mesh the scene names is a
//! small regular OBJ file beside the dump, or the same kinds by the same prefixes. The command
//! runs under `--memory-cap` [`MEMORY_CAP`], so that scenes and arrays past it are refused rather
//! than made (a runaway read or a wait on a FIFO is a fuzz crash: libFuzzer's RSS and time
//! limits).
//!
//! Checked against what the library makes of each directory ([`Dump::read`], then
//! [`Dump::capture`] and [`Dump::check_words`]): the command fails (exit code 2) with a message
//! exactly when a side does not read or decode, the two cover different viewports or name
//! different scenes, or the memory cap refuses the work; otherwise it gives a verdict (exit code
//! 0 or 1), and "equal" (0) only when neither side holds a word its layout says cannot be there.
//! A dump that decodes to lists in canonical order, with no overflow, no corrupt word and (a
//! linked list) a node counter equal to its lists' fragments, compared with itself is equal.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use clap::{Args, Command, FromArgMatches};
use fragsim::capture::Capture;
use fragsim::dump::{Dump, WordCheck, HEADER_FILE};
use fragsim_cli::CompareArgs;

use super::dump::{is_canonical, Blob};

/// Splits `data` into the two dumps, writes them out and checks the command on them.
pub(crate) fn check(data: &[u8]) {
    let (length, rest) = data.split_at(data.len().min(4));
    let mut word = [0; 4];
    word[..length.len()].copy_from_slice(length);
    let word = u32::from_le_bytes(word);
    let (reference, candidate) = rest.split_at(((word & !ORACLE) as usize).min(rest.len()));
    let scratch = Scratch::new();
    let (a, b) = (scratch.0.join("reference"), scratch.0.join("candidate"));
    write_out(reference, &a);
    write_out(candidate, &b);
    check_pair(&a, &b);
    if decoded(&a).is_ok() {
        check_pair(&a, &a);
    }
    if word & ORACLE != 0 {
        check_against_oracle(&b);
    }
}

/// The length word's top bit: the candidate is also compared with the oracle of its scene,
/// which makes the scene (its mesh beside the dump, or a named scene within the memory cap).
const ORACLE: u32 = 1 << 31;

/// `fragsim compare oracle CANDIDATE`: a verdict only for a candidate that decodes, "equal"
/// only without a corrupt word; any refusal with a message.
fn check_against_oracle(candidate: &Path) {
    let got = run(Path::new("oracle"), candidate);
    match (got, decoded(candidate)) {
        (Ok(true), Ok((_, _, words))) => assert_eq!(
            words.corrupt_words(),
            0,
            "compare called a dump with corrupt words equal to the oracle"
        ),
        (Ok(_), Ok(_)) => {}
        (Ok(_), Err(error)) => panic!("compare judged a dump that does not decode: {error}"),
        (Err(error), _) => assert!(!error.is_empty(), "an error without a message"),
    }
}

/// A directory of its own for one input, removed afterwards (targets run in parallel threads in
/// the corpus replay, and in several processes under libFuzzer's `-jobs`).
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Self {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("fragsim-fuzz-compare-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes the dump `blob` holds into `dir`: its header, and each array file the parser asks for
/// (one that the file system refuses, or named as the header, is left out: reading it fails, or
/// reads the header, as a backend's directory would).
fn write_out(blob: &[u8], dir: &Path) {
    std::fs::create_dir_all(dir).expect("a dump directory");
    let mut blob = Blob::new(blob);
    let header = blob.header;
    let mut files = Vec::new();
    let _ = Dump::parse("fuzz/compare.json", header, |file| {
        let bytes = blob.file(file);
        files.push((file.to_string(), bytes.clone()));
        Ok(bytes)
    });
    for (file, bytes) in files.iter().filter(|(file, _)| file != HEADER_FILE) {
        write_file(&dir.join(file), bytes);
    }
    // The scene's mesh, where the header names one by a plain name.
    let scene = serde_json::from_slice::<serde_json::Value>(header).ok();
    let mesh = scene.as_ref().and_then(|h| h["scene"]["mesh"].as_str());
    let plain =
        |m: &&str| !m.is_empty() && *m != "." && *m != ".." && !m.contains(['/', '\\', '\0']);
    if let Some(mesh) = mesh.filter(plain) {
        write_file(&dir.join(mesh), TETRAHEDRON.as_bytes());
    }
    std::fs::write(dir.join(HEADER_FILE), header).expect("the header is written");
}

/// A small closed mesh, the mesh file of a header that names one.
const TETRAHEDRON: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/// Writes `bytes` to `path`, or the kind of file its name's prefix asks for (the module's doc);
/// one the file system refuses is left out: reading it fails, as a backend's directory would.
fn write_file(path: &Path, bytes: &[u8]) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    #[cfg(unix)]
    {
        if name.starts_with("zero") {
            let _ = std::os::unix::fs::symlink("/dev/zero", path);
            return;
        }
        if name.starts_with("fifo") {
            let _ = std::process::Command::new("mkfifo").arg(path).status();
            return;
        }
        if name.starts_with("sock") {
            // The socket file stays when the listener is dropped.
            let _ = std::os::unix::net::UnixListener::bind(path);
            return;
        }
    }
    if name.starts_with("dir") {
        let _ = std::fs::create_dir(path);
        return;
    }
    let _ = std::fs::write(path, bytes);
}

/// The memory cap `compare` runs under: 64 MiB.
const MEMORY_CAP: &str = "67108864";

/// A dump directory as the library reads and decodes it.
fn decoded(dir: &Path) -> Result<(Dump, Capture, WordCheck), String> {
    let dump = Dump::read(dir).map_err(|e| e.to_string())?;
    let capture = dump.capture().map_err(|e| e.to_string())?;
    let words = dump.check_words().map_err(|e| e.to_string())?;
    Ok((dump, capture, words))
}

/// `fragsim compare REFERENCE CANDIDATE --no-images --show 0`, parsed as the command line parses
/// it: `Ok(equal)` is exit code 0 or 1, `Err` exit code 2.
fn run(reference: &Path, candidate: &Path) -> Result<bool, String> {
    let command = CompareArgs::augment_args(Command::new("compare"));
    let argv = [
        "compare".as_ref(),
        reference.as_os_str(),
        candidate.as_os_str(),
        "--no-images".as_ref(),
        "--show".as_ref(),
        "0".as_ref(),
        "--memory-cap".as_ref(),
        MEMORY_CAP.as_ref(),
    ];
    let matches = command
        .try_get_matches_from(argv)
        .expect("the arguments parse");
    let args = CompareArgs::from_arg_matches(&matches).expect("the arguments are compare's");
    fragsim_cli::compare(&args)
}

/// Runs the command on one pair and checks its outcome against the library's.
fn check_pair(reference: &Path, candidate: &Path) {
    let got = run(reference, candidate);
    let sides = (decoded(reference), decoded(candidate));
    let (Ok((a, capture, words_a)), Ok((b, _, words_b))) = &sides else {
        let error = got.expect_err("compare accepted a dump that does not read or decode");
        assert!(!error.is_empty(), "an error without a message");
        return;
    };
    let same_viewport = (a.header.width, a.header.height) == (b.header.width, b.header.height);
    if !same_viewport || a.header.scene != b.header.scene {
        let error = got.expect_err("compare accepted dumps of different viewports or scenes");
        assert!(
            error.contains("different"),
            "the error does not say the dumps differ: {error}"
        );
        return;
    }
    let equal = match got {
        Ok(equal) => equal,
        // The scene, or its oracle, could exceed the cap: refused before it is made.
        Err(error) if error.contains("memory cap") => return,
        Err(error) => panic!("compare refused two dumps that decode: {error}"),
    };
    if equal {
        assert_eq!(
            words_a.corrupt_words() + words_b.corrupt_words(),
            0,
            "compare called dumps with corrupt words equal"
        );
    }
    // A memory dump may hold the empty marker in a list, which the comparison takes for no
    // fragment: no promise is made of such lists.
    let no_marker = (0..capture.pixels()).all(|p| !capture.pixel(p).contains(&u64::MAX));
    // A list's node counter is held to the fragments its reference holds (docs/semantics.md §6):
    // a dump whose counter disagrees with its own lists differs from itself, by that rule.
    let stored: u64 = (0..capture.pixels())
        .map(|p| capture.pixel(p).len() as u64)
        .sum();
    let counter_agrees = words_a
        .list_counter
        .is_none_or(|counter| u64::from(counter) == stored);
    if reference == candidate
        && words_a.corrupt_words() == 0
        && is_canonical(capture)
        && no_marker
        && counter_agrees
    {
        assert!(equal, "a dump in canonical order differs from itself");
    }
}

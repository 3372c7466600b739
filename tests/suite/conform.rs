//! `fragsim conform` against the Python backend of `crates/testkit/python/backend.py`: the
//! correct backend passes and the report says what its cases exercised; its planted bugs (a scan
//! missing pixel centres exactly on a top edge, an A-buffer dropping the 3rd fragment of a pixel,
//! an MDTS walk stopping one slot early) are found within 200 cases and shrunk to at most 3
//! triangles and 4×4 pixels, with the smallest case saved and its replay written; the clamped
//! and the racy A-buffer counters are caught within 100 cases; a backend that always fails stops
//! within 5 seconds.
//!
//! Each run launches Python once a case and submission order. The correct backend's test is
//! cheap (24 cases). The planted bugs are found in the first 7 cases of seed 0; proptest's
//! shrinking would then re-run the backend up to 2048 times (2 min 4 s to 2 min 16 s per bug on
//! this 2-core machine under load, 2026-12-02), so the planted-bug runs cap it with
//! `--shrink-steps 32` and leave the rest to conform's own crop and triangle dropping: the
//! bounds asserted below are the issue's, whatever did the shrinking.

use std::path::PathBuf;

use assert_cmd::Command;

/// The Python backend's command line, with `extra` arguments.
fn python(extra: &str) -> String {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("crates/testkit/python/backend.py");
    format!("python3 '{}' {{scene}} {{out}} {extra}", script.display())
}

/// `fragsim conform --json` with `backend` on `scheme`; the exit code and the records.
fn conform(
    name: &str,
    backend: &str,
    scheme: &str,
    cases: u32,
    shrink_steps: u32,
) -> (i32, Vec<serde_json::Value>) {
    let save = std::env::temp_dir().join(format!("fragsim-conform-{name}-{}", std::process::id()));
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "conform",
            "--json",
            "--scheme",
            scheme,
            "--backend",
            backend,
        ])
        .args(["--cases", &cases.to_string(), "--seed", "0"])
        .args(["--shrink-steps", &shrink_steps.to_string()])
        .arg("--save")
        .arg(&save)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    let records = crate::support::json_lines(&output.stdout);
    let code = output.status.code().unwrap_or(-1);
    if code == 1 {
        let saved = PathBuf::from(records[0]["saved"].as_str().unwrap());
        for file in [
            "scene/scene.tri",
            "scene/mesh.obj",
            "scene/camera.json",
            "replay.sh",
        ] {
            assert!(
                saved.join(file).is_file(),
                "{name}: no {file} in {}",
                saved.display()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&save);
    (code, records)
}

#[test]
fn the_correct_python_backend_passes_and_says_what_its_cases_exercised() {
    for scheme in ["mdts", "abuffer"] {
        let (code, records) = conform("correct", &python(""), scheme, 12, 2048);
        assert_eq!(code, 0, "{scheme}: {records:?}");
        let summary = &records[0];
        assert_eq!(summary["record"], "conform");
        assert_eq!(summary["passed"], true);
        assert_eq!(summary["exercised_cases"], 12, "{summary}");
        // Most cases are deeper than K (2) and the capacity (3), so they overflow.
        let count = |key: &str| summary[key].as_u64().unwrap();
        assert!(count("overflow_cases") > 0, "{scheme}: {summary}");
        assert!(count("over_capacity_cases") > 0, "{scheme}: {summary}");
        assert!(count("deepest_pixel") > 3, "{scheme}: {summary}");
        assert!(count("exercised_fragments") > 0, "{scheme}: {summary}");
    }
}

/// Plants of `docs/testing.md` written as a user would, through the binary with conform's
/// defaults but for the shrinking's cap (the full table over seeds 0 to 4 is measured in
/// `docs/testing.md`; `crates/testkit/tests/plants.rs` runs all four on those seeds in
/// process): caught within 100 cases, shrunk to at most 4 triangles (a capacity of 3 overflows
/// at 4 fragments) and 2 pixels.
#[test]
fn the_clamped_counters_and_the_racy_counter_are_caught_within_100_cases() {
    for bug in ["clamp-counters", "racy-counter"] {
        let (code, records) = conform(bug, &python(&format!("--bug {bug}")), "abuffer", 100, 32);
        assert_eq!(code, 1, "{bug}: {records:?}");
        let summary = &records[0];
        assert_eq!(summary["case_independent"], false, "{bug}: {summary}");
        assert!(
            summary["case_number"].as_u64().unwrap() <= 100,
            "{bug}: {summary}"
        );
        assert!(
            summary["triangles"].as_u64().unwrap() <= 4,
            "{bug}: {summary}"
        );
        let pixels = summary["width"].as_u64().unwrap() * summary["height"].as_u64().unwrap();
        assert!(pixels <= 2, "{bug}: {summary}");
    }
}

/// A backend that fails on every case (exit 3, or past its timeout) fails on the smallest case
/// too: the run stops at once, unshrunk, within 5 seconds. Control: the same run's report of a
/// backend that fails on a case's content is shrunk (`each_planted_bug_…` above).
///
/// The timeout kills the backend's whole process group (a child it left running in the
/// background included) and nothing else: a process outside the group, started before the run,
/// is still running after it. (A `kill` that misread the group once signalled every process.)
#[test]
fn a_backend_that_always_fails_stops_within_five_seconds_unshrunk() {
    let grandchild =
        std::env::temp_dir().join(format!("fragsim-conform-grandchild-{}", std::process::id()));
    let timeout_backend = format!(
        "sleep 23 & echo $! > {}; wait # {{out}}",
        grandchild.display()
    );
    for (name, backend, timeout) in [
        ("exit", "exit 3 # {out}", "30"),
        ("timeout", timeout_backend.as_str(), "1"),
    ] {
        let save = std::env::temp_dir().join(format!(
            "fragsim-conform-always-{name}-{}",
            std::process::id()
        ));
        let mut bystander = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        let output = Command::cargo_bin("fragsim")
            .unwrap()
            .args(["conform", "--json", "--scheme", "abuffer"])
            .args(["--backend", backend, "--timeout", timeout, "--save"])
            .arg(&save)
            .output()
            .unwrap();
        let elapsed = start.elapsed();
        let _ = std::fs::remove_dir_all(&save);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{name}: {stderr}");
        assert!(elapsed.as_secs_f64() < 5.0, "{name}: {elapsed:?}");
        let records = crate::support::json_lines(&output.stdout);
        let summary = &records[0];
        assert_eq!(summary["case_independent"], true, "{name}: {summary}");
        assert_eq!(summary["shrink_steps"], 0, "{name}: {summary}");
        assert_eq!(summary["case_number"], 1, "{name}: {summary}");
        assert_eq!(summary["property"], "runs", "{name}: {summary}");
        let bystander_running = bystander.try_wait().unwrap().is_none();
        let _ = bystander.kill();
        let _ = bystander.wait();
        assert!(
            bystander_running,
            "{name}: a process outside the backend's group was killed"
        );
    }
    let pid = std::fs::read_to_string(&grandchild).unwrap();
    let _ = std::fs::remove_file(&grandchild);
    // Killed: gone, or a zombie waiting for whichever process adopted it.
    let state = std::fs::read_to_string(format!("/proc/{}/stat", pid.trim())).unwrap_or_default();
    let running = state
        .rsplit(") ")
        .next()
        .is_some_and(|rest| !rest.starts_with('Z') && !rest.is_empty());
    assert!(
        !running,
        "the backend's background child {pid} outlived its timeout: {state}"
    );
}

#[test]
fn each_planted_bug_is_found_and_shrunk_to_three_triangles_and_four_by_four_pixels() {
    for (bug, scheme) in [
        ("top-edge", "mdts"),
        ("third-fragment", "abuffer"),
        ("early-break", "mdts"),
    ] {
        let (code, records) = conform(bug, &python(&format!("--bug {bug}")), scheme, 200, 32);
        assert_eq!(code, 1, "{bug}: {records:?}");
        let summary = &records[0];
        assert_eq!(summary["passed"], false, "{bug}");
        assert!(
            summary["cases_run"].as_u64().unwrap() <= 200,
            "{bug}: {summary}"
        );
        assert!(
            summary["triangles"].as_u64().unwrap() <= 3,
            "{bug}: {summary}"
        );
        let (w, h) = (
            summary["width"].as_u64().unwrap(),
            summary["height"].as_u64().unwrap(),
        );
        assert!(w <= 4 && h <= 4, "{bug}: {w}x{h}");
        // The failing pixels with both lists follow (a crash would have none).
        assert!(records.len() > 1, "{bug}: {records:?}");
        assert_eq!(records[1]["record"], "counterexample_pixel");
    }
}

#[test]
fn progress_lines_count_every_passed_case_on_stderr() {
    let save =
        std::env::temp_dir().join(format!("fragsim-conform-progress-{}", std::process::id()));
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["conform", "--scheme", "mdts", "--backend", &python("")])
        .args(["--cases", "4", "--seed", "0", "--progress-lines", "--save"])
        .arg(&save)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&save);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("conform: "))
        .collect();
    // One line as each case after the first starts (the one before it passed), one at the end.
    let expected: Vec<String> = (1..=4)
        .map(|n| format!("conform: {n} of 4 cases passed"))
        .collect();
    assert_eq!(lines, expected, "{stderr}");
}

/// Issue 36: a failing run's report and saved case read like the rest of fragsim and replay from
/// anywhere; proptest's own messages stay out of stderr; a passing run removes the stale case.
#[test]
fn a_counterexample_replays_from_any_directory_and_a_pass_removes_it() {
    let dir = std::env::temp_dir().join(format!("fragsim-conform-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The backend named relative to the directory conform runs in.
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("crates/testkit/python/backend.py");
    std::fs::copy(&script, dir.join("backend.py")).unwrap();
    let run = |backend: &str, cases: &str| {
        Command::cargo_bin("fragsim")
            .unwrap()
            .current_dir(&dir)
            .args([
                "conform",
                "--json",
                "--scheme",
                "mdts",
                "--backend",
                backend,
            ])
            .args([
                "--cases",
                cases,
                "--seed",
                "0",
                "--shrink-steps",
                "1",
                "--save",
                "saved",
            ])
            .output()
            .unwrap()
    };
    let failing = run("python3 backend.py {scene} {out} --bug top-edge", "100");
    let stderr = String::from_utf8_lossy(&failing.stderr);
    assert_eq!(failing.status.code(), Some(1), "{stderr}");
    assert!(
        !stderr.contains("proptest") && !stderr.contains("Aborting"),
        "{stderr}"
    );
    let records = crate::support::json_lines(&failing.stdout);
    let keys: Vec<&str> = records[1..]
        .iter()
        .flat_map(|r| r["reference"].as_array().unwrap())
        .map(|e| e["key"].as_str().unwrap())
        .collect();
    assert!(!keys.is_empty(), "{records:?}");
    for key in keys {
        assert!(
            key.len() == 8 && key.chars().all(|c| c.is_ascii_hexdigit()),
            "{key}"
        );
    }
    let case = dir.join("saved/case");
    let replay = Command::new("sh")
        .arg(case.join("replay.sh"))
        .current_dir("/")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&replay.stdout);
    // The backend ran and compare judged its dump: it differs (exit 1), nothing was missing.
    assert_eq!(
        replay.status.code(),
        Some(1),
        "{text}\n{}",
        String::from_utf8_lossy(&replay.stderr)
    );
    assert!(text.contains("candidate"), "{text}");
    // A pass of any length removes the stale case: 20 cases keep the test short.
    let passing = run("python3 backend.py {scene} {out}", "20");
    assert_eq!(passing.status.code(), Some(0));
    assert!(
        !case.exists(),
        "the stale failing case is still in {}",
        case.display()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A backend that exits 0 without writing a dump is not shrunk case after case: the run stops on
/// the first, saying where the dump was expected.
#[test]
fn a_backend_that_writes_no_dump_stops_the_run_at_once() {
    let save = std::env::temp_dir().join(format!("fragsim-conform-nodump-{}", std::process::id()));
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "conform",
            "--scheme",
            "mdts",
            "--backend",
            "true {out}",
            "--progress-lines",
        ])
        .args(["--cases", "20", "--save"])
        .arg(&save)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&save);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("wrote nothing into"), "{stderr}");
    assert!(!stderr.contains("shrinking"), "{stderr}");
}

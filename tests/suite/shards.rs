//! `--shard I/N`: `conform`, `sweep` and `bench` split a campaign over machines in
//! cargo-nextest's `count:I/N` convention; the shards are disjoint and their union is the
//! unsharded run, case for case (conform: the very cases the backend is given; sweep and bench:
//! their records, the measured times apart).

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use serde_json::Value;

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("shards", name)
}

fn run_in(dir: &Path, args: &[&str]) -> std::process::Output {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// A record without what varies from run to run: times and what is derived from them (rates
/// per second, time per item, the split of a frame, speed-ups).
fn without_times(mut record: Value) -> String {
    record.as_object_mut().unwrap().retain(|key, _| {
        !(key.ends_with("_ms")
            || key.contains("per_second")
            || key.starts_with("ns_per_")
            || key.starts_with("speedup")
            || ["fps", "shares"].contains(&key.as_str()))
    });
    record.to_string()
}

/// The records of `file`, timeless and sorted.
fn records(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap();
    let mut all: Vec<String> = crate::support::json_lines(text.as_bytes())
        .into_iter()
        .map(without_times)
        .collect();
    all.sort();
    all
}

/// Asserts that the shards' records (sorted) are the whole run's, none twice.
fn assert_union(whole: Vec<String>, shards: Vec<Vec<String>>, what: &str) {
    assert!(
        shards.iter().all(|s| !s.is_empty()),
        "{what}: an empty shard"
    );
    let mut union: Vec<String> = shards.into_iter().flatten().collect();
    union.sort();
    assert_eq!(union.len(), whole.len(), "{what}");
    assert_eq!(union, whole, "{what}");
}

#[test]
fn conform_shards_check_exactly_the_unsharded_cases() {
    let dir = scratch("conform");
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("crates/testkit/python/backend.py");
    // Each run of the backend logs a checksum of the case it was given, then runs it.
    let backend = |log: &str| {
        format!(
            "cat {{scene}}/case.json {{scene}}/mesh.obj {{scene}}/camera.json | cksum >> {log} \
             && python3 '{}' {{scene}} {{out}}",
            script.display()
        )
    };
    let conform = |log: &str, shard: Option<&str>| {
        let mut args = vec![
            "conform",
            "--scheme",
            "mdts",
            "--cases",
            "7",
            "--seed",
            "3",
            "--json",
            "--backend",
        ];
        let backend = backend(log);
        args.push(&backend);
        if let Some(shard) = shard {
            args.extend(["--shard", shard]);
        }
        let output = run_in(&dir, &args);
        let summary = crate::support::json_lines(&output.stdout).remove(0);
        assert_eq!(summary["passed"], true, "{summary}");
        let mut cases: Vec<String> = std::fs::read_to_string(dir.join(log))
            .unwrap()
            .lines()
            .map(str::to_owned)
            .collect();
        cases.sort();
        (summary["cases_run"].as_u64().unwrap(), cases)
    };
    let (all, whole) = conform("whole.log", None);
    assert_eq!(all, 7);
    let shards: Vec<(u64, Vec<String>)> = ["1/3", "2/3", "count:3/3"]
        .iter()
        .enumerate()
        .map(|(i, shard)| conform(&format!("shard{i}.log"), Some(shard)))
        .collect();
    // Cases 1, 4, 7; 2, 5; 3, 6.
    assert_eq!(shards.iter().map(|s| s.0).collect::<Vec<_>>(), [3, 2, 2]);
    assert_union(whole, shards.into_iter().map(|s| s.1).collect(), "conform");
}

#[test]
fn sweep_and_bench_shards_are_the_unsharded_run() {
    let dir = scratch("sweep-bench");
    let scene = [
        "--scene",
        "spheres:2",
        "--width",
        "24",
        "--height",
        "16",
        "--no-images",
    ];
    let sweep = |out: &str, shard: &[&str]| {
        run_in(
            &dir,
            &[
                &[
                    "sweep",
                    "--angles",
                    "7",
                    "--scheme",
                    "mdts,zbuffer",
                    "--out",
                    out,
                ][..],
                &scene,
                shard,
            ]
            .concat(),
        );
        records(&dir.join(out).join("sweep.jsonl"))
    };
    let whole = sweep("sweep-whole", &[]);
    assert_eq!(whole.len(), 14);
    let shards = (1..=3)
        .map(|i| sweep(&format!("sweep-{i}"), &["--shard", &format!("{i}/3")]))
        .collect();
    assert_union(whole, shards, "sweep");

    let bench = |out: &str, shard: &[&str]| {
        run_in(
            &dir,
            &[
                &[
                    "bench",
                    "--frames",
                    "1",
                    "--scheme",
                    "mdts,zbuffer,abuffer",
                    "--executor",
                    "all",
                ][..],
                &["--approximate", "wboit", "--out", out],
                &scene,
                shard,
            ]
            .concat(),
        );
        records(&dir.join(out).join("bench.jsonl"))
    };
    let bench_whole = bench("bench-whole", &[]);
    assert_eq!(bench_whole.len(), 10, "9 rows and the approximate one");
    let bench_shards = (1..=4)
        .map(|i| bench(&format!("bench-{i}"), &["--shard", &format!("{i}/4")]))
        .collect();
    assert_union(bench_whole, bench_shards, "bench");
}

#[test]
fn a_bad_shard_is_refused_naming_the_form() {
    for shard in ["0/3", "4/3", "1/0", "2", "a/b"] {
        let output = Command::cargo_bin("fragsim")
            .unwrap()
            .args(["sweep", "--shard", shard])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{shard}: {stderr}");
        assert!(stderr.contains("--shard"), "{shard}: {stderr}");
    }
}

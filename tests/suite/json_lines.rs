//! Issue 20, item 9: one output model. Every command's `--json` prints JSON Lines, one record a
//! line, each opening with the same context fields (`docs/json-schema.md`), and a quantity has one
//! name everywhere. Each command runs through the binary on a small scene, and its stdout is read
//! line by line with `serde_json`.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use serde_json::Value;

/// The fields every record carries (`null` allowed where the command has no such thing).
const CONTEXT: [&str; 13] = [
    "record",
    "fragsim_version",
    "command",
    "scene",
    "mesh_hash",
    "width",
    "height",
    "view_degrees",
    "elevation_degrees",
    "k",
    "capacity",
    "executor",
    "threads",
];

/// Names of today's quantities that the one model renamed: no record may carry them.
const RETIRED: [&str; 4] = ["mismatches", "median_ms", "rows", "first_differences"];

const SIZE: [&str; 4] = ["--width", "16", "--height", "16"];

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("json-lines", name)
}

/// `fragsim COMMAND ARGS --json [--out OUT]`, expecting exit code 0; its records, each checked
/// for the context fields.
fn records(command: &str, args: &[&str], out: Option<&Path>) -> Vec<Value> {
    let mut run = Command::cargo_bin("fragsim").unwrap();
    run.arg(command).args(args).arg("--json");
    if let Some(out) = out {
        run.arg("--out").arg(out);
    }
    let output = run.output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{command} {args:?}: {stderr}"
    );
    let records = crate::support::json_lines(&output.stdout);
    assert!(!records.is_empty(), "{command} printed no record");
    for r in &records {
        for field in CONTEXT {
            assert!(r.get(field).is_some(), "{command}: no {field} in {r}");
        }
        for field in RETIRED {
            assert!(r.get(field).is_none(), "{command}: {field} in {r}");
        }
        assert_eq!(r["fragsim_version"], env!("CARGO_PKG_VERSION"), "{r}");
        assert_eq!(r["command"], command, "{r}");
    }
    records
}

#[test]
fn every_command_prints_json_lines_with_the_common_fields() {
    let dir = scratch("all");
    let scene = ["--scene", "quads:3"];
    let render = records(
        "render",
        &[
            &scene[..],
            &SIZE,
            &[
                "--scheme",
                "mdts,abuffer",
                "--executor",
                "all",
                "--no-images",
            ],
        ]
        .concat(),
        Some(&dir),
    );
    // One record per scheme and executor, each naming its own executor.
    assert_eq!(render.len(), 6);
    for r in &render {
        assert_eq!(r["record"], "run");
        assert_eq!(
            (r["scene"].as_str(), r["width"].as_u64()),
            (Some("quads:3"), Some(16))
        );
        assert_eq!(
            (r["k"].as_u64(), r["capacity"].as_u64()),
            (Some(20), Some(20))
        );
        assert!(r["mesh_hash"].is_null());
        assert_eq!(r["mismatched_pixels"], 0, "{r}");
        assert!(
            r["time_ms"].is_f64() && r["threads"].as_u64() >= Some(1),
            "{r}"
        );
    }
    let executors: Vec<&str> = render
        .iter()
        .filter_map(|r| r["executor"].as_str())
        .collect();
    assert_eq!(executors, ["serial", "parallel", "tiled"].repeat(2));

    let bench = records(
        "bench",
        &[
            &scene[..],
            &SIZE,
            &["--frames", "1", "--scheme", "mdts,zbuffer", "--no-images"],
        ]
        .concat(),
        Some(&dir),
    );
    assert_eq!(bench.len(), 2);
    for r in &bench {
        assert_eq!(r["record"], "bench");
        // Rates are fractions in JSON.
        let rate = r["error_pixel_rate"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&rate), "{r}");
        assert!(
            r["time_ms"].is_f64() && r["mismatched_pixels"].is_u64(),
            "{r}"
        );
    }
    // bench.jsonl holds the same records.
    let file = std::fs::read(dir.join("bench.jsonl")).unwrap();
    assert_eq!(crate::support::json_lines(&file).len(), 2);

    let sweep = records(
        "sweep",
        &[
            &scene[..],
            &SIZE,
            &["--angles", "2", "--scheme", "mdts,bdp"],
        ]
        .concat(),
        Some(&dir),
    );
    // One record per scheme and angle, the angle in the context.
    assert_eq!(sweep.len(), 4);
    let angles: Vec<f64> = sweep
        .iter()
        .map(|r| r["view_degrees"].as_f64().unwrap())
        .collect();
    assert_eq!(angles, [0.0, 180.0, 0.0, 180.0]);
    assert!(sweep.iter().all(|r| r["time_ms"].is_f64()));

    let hazard = records(
        "hazard",
        &[
            &scene[..],
            &SIZE,
            &[
                "--threads-in-flight",
                "1,32",
                "--seeds",
                "1",
                "--write-back",
                "render-target",
            ],
        ]
        .concat(),
        Some(&dir.join("hazard")),
    );
    // Two policies × two widths; the width in flight is the record's threads.
    assert_eq!(hazard.len(), 4);
    let threads: Vec<u64> = hazard
        .iter()
        .map(|r| r["threads"].as_u64().unwrap())
        .collect();
    assert_eq!(threads, [1, 32, 1, 32]);
    assert!(hazard
        .iter()
        .all(|r| r["mismatched_pixel_rate"].is_f64() && r["k"] == 8));

    let explain = records("explain", &[], None);
    assert_eq!(explain.len(), 1);
    assert_eq!(explain[0]["shown"], true);
    assert_eq!(explain[0]["scheme"], "kbuffer");
}

#[test]
fn export_scene_and_compare_print_json_lines_with_the_mesh_hash() {
    let dir = scratch("mesh");
    let mesh = dir.join("two.obj");
    std::fs::write(
        &mesh,
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv -1 -1 0.5\nv 1 -1 0.5\nv 0 1 0.5\n\
         f 1 2 3\nf 1 3 4\nf 5 6 7\n",
    )
    .unwrap();
    let mesh = mesh.to_str().unwrap();
    let export = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["export-scene", "--mesh", mesh])
        .args(SIZE)
        .arg("--out")
        .arg(dir.join("triangles.json"))
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        export.status.success(),
        "{}",
        String::from_utf8_lossy(&export.stderr)
    );
    let export = crate::support::json_lines(&export.stdout);
    assert_eq!(export.len(), 1);
    // A mesh is named by its file, never its directory, and carries the hash of its bytes.
    assert_eq!(export[0]["scene"], "two.obj");
    let hash = export[0]["mesh_hash"].as_str().unwrap();
    assert!(hash.starts_with("fnv1a64:"), "{hash}");
    assert_eq!(export[0]["mesh_triangles"], 3);

    let dumps = dir.join("dumps");
    let made = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "render",
            "--mesh",
            mesh,
            "--scheme",
            "mdts",
            "--k",
            "1",
            "--no-images",
        ])
        .args(SIZE)
        .arg("--dump")
        .arg(&dumps)
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    // K = 1 keeps the nearest: against the oracle's lists the dump is compared as what it
    // promises, equal (exit 0).
    let compare = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["compare", "oracle"])
        .arg(dumps.join("mdts"))
        .args(["--json", "--no-images"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&compare.stderr);
    assert_eq!(compare.status.code(), Some(0), "{stderr}");
    let compare = crate::support::json_lines(&compare.stdout);
    let first = &compare[0];
    for field in CONTEXT {
        assert!(first.get(field).is_some(), "compare: no {field} in {first}");
    }
    assert_eq!(first["record"], "compare");
    assert_eq!(first["command"], "compare");
    assert_eq!(first["mesh_hash"], hash);
    assert_eq!(
        (first["k"].as_u64(), first["candidate_k"].as_u64()),
        (Some(1), Some(1))
    );
    assert_eq!(first["mismatched_pixels"], 0);
    assert_eq!(first["equal"], true);
    // Every group's fields are flat: no value of the record is an object.
    let object = first.as_object().unwrap();
    assert!(object.values().all(|v| !v.is_object()), "{first}");
}

//! Flags that do nothing in their context: a warning or a refusal naming the
//! flag, and every scheme's name as a run prints it the one it was given.

use std::process::Output;

use assert_cmd::Command;

use super::{assert_refused, fragsim};

/// `fragsim args` exactly as given (subcommands first).
fn fragsim_raw(args: &[&str]) -> Output {
    Command::cargo_bin("fragsim")
        .unwrap()
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn threads_on_a_one_thread_executor_is_a_warning() {
    for executor in ["serial", "scheduled"] {
        let output = fragsim(&[
            "--scene",
            "quads:2",
            "--threads",
            "2",
            "--executor",
            executor,
        ]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(0), "{stderr}");
        assert!(
            stderr.contains(&format!(
                "warning: --threads has no effect on the {executor} executor"
            )),
            "{stderr}"
        );
    }
    let output = fragsim(&[
        "--scene",
        "quads:2",
        "--threads",
        "2",
        "--executor",
        "parallel",
    ]);
    assert!(!String::from_utf8_lossy(&output.stderr).contains("warning"));
}

#[test]
fn sweep_view_is_refused() {
    let out = std::env::temp_dir().join(format!("fragsim-cli-sweep-{}", std::process::id()));
    let output = fragsim_raw(&[
        "sweep",
        "--scene",
        "quads:2",
        "--width",
        "8",
        "--height",
        "8",
        "--angles",
        "1",
        "--view",
        "10",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("sweep sets the view angle itself"),
        "{stderr}"
    );
}

#[test]
fn an_elevation_the_camera_would_clamp_is_refused() {
    for value in ["1000", "-90", "89.5"] {
        assert_refused(
            &["--elevation", value],
            &["--elevation", "between -89 and 89 degrees"],
        );
    }
    let output = fragsim(&["--scene", "quads:2", "--elevation", "-89"]);
    assert!(output.status.success());
}

#[test]
fn compare_image_with_no_image_is_refused() {
    let output = fragsim_raw(&["compare", "a", "b", "--image", "x.png", "--no-images"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cannot be used with"), "{stderr}");
}

#[test]
fn explain_negative_depths_are_values_refused_by_range() {
    let output = fragsim_raw(&["explain", "--depths", "-0.1,0.5"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("depth -0.1 is outside [0, 1]"), "{stderr}");
}

#[test]
fn help_with_help_prints_help() {
    for args in [&["help", "--help"][..], &["help", "render", "-h"]] {
        let output = fragsim_raw(args);
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{args:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        assert!(stdout.contains("Usage: fragsim"), "{args:?}: {stdout}");
    }
}

/// Issue 20, item 6: every scheme's name, as a run prints it, is the one `--scheme` takes (it
/// printed `srab-2pass` for `srab`), and `--capacity 1` does not turn `abuffer` into another
/// scheme (it ran `abuffer-fixed`).
#[test]
fn every_scheme_name_a_run_prints_is_the_name_it_was_given() {
    let names: Vec<&str> = fragsim::catalog::CATALOG.iter().map(|e| e.name).collect();
    let output = fragsim(&[
        "--scene",
        "quads:2",
        "--scheme",
        &names.join(","),
        "--capacity",
        "1",
        "--k",
        "2",
        "--json",
        "--out",
        &std::env::temp_dir()
            .join(format!("fragsim-names-{}", std::process::id()))
            .to_string_lossy(),
    ]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let printed: Vec<String> = stdout
        .lines()
        .map(|line| {
            let record: serde_json::Value = serde_json::from_str(line).unwrap();
            record["scheme"].as_str().unwrap().to_string()
        })
        .collect();
    assert_eq!(
        printed,
        names,
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

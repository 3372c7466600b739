//! `fragsim-wgpu`'s scene options are checked as `fragsim`'s are (the scene spec's own parsers):
//! an out-of-range value is refused by name, exit 2, before any adapter is asked for (no Vulkan
//! driver is needed: the driver is pointed nowhere, so a value that slipped through would fail
//! with "no Vulkan adapter" instead).

use std::process::Command;

/// Runs `fragsim-wgpu ARGS` with no Vulkan driver; returns its exit code and stderr.
fn fragsim_wgpu(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_fragsim-wgpu"))
        .args(args)
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// `args` is refused with exit 2 and every one of `phrases` on stderr.
fn assert_refused(args: &[&str], phrases: &[&str]) {
    let (code, stderr) = fragsim_wgpu(args);
    assert_eq!(code, Some(2), "{args:?}: {stderr}");
    for phrase in phrases {
        assert!(
            stderr.contains(phrase),
            "{args:?}: no {phrase:?} in {stderr}"
        );
    }
}

#[test]
fn capture_refuses_the_scene_values_fragsim_refuses() {
    assert_refused(
        &["capture", "--width", "0"],
        &["--width", "0 is not in 1..=16384"],
    );
    assert_refused(
        &["capture", "--height", "16385"],
        &["--height", "16385 is not in 1..=16384"],
    );
    assert_refused(
        &["capture", "--view", "nan"],
        &["--view", "expected a finite number of degrees"],
    );
    assert_refused(
        &["capture", "--elevation", "90"],
        &["--elevation", "between -89 and 89 degrees"],
    );
}

#[test]
fn msaa_count_refuses_the_scene_values_fragsim_refuses() {
    assert_refused(
        &["msaa-count", "--width", "-5"],
        &["--width", "-5 is not in 1..=16384"],
    );
    assert_refused(
        &["msaa-count", "--view", "30,inf"],
        &["--view", "expected a finite number of degrees"],
    );
    assert_refused(
        &["msaa-count", "--elevation", "-90"],
        &["--elevation", "between -89 and 89 degrees"],
    );
}

#[test]
fn a_case_directory_replaces_the_scene_options() {
    assert_refused(
        &["capture", "--case", "some-case", "--up", "z"],
        &["--case", "--up"],
    );
}

#[test]
fn values_in_range_reach_the_adapter() {
    // Accepted: the command goes on to ask for an adapter, which there is none of.
    let (code, stderr) = fragsim_wgpu(&[
        "capture",
        "--width",
        "16384",
        "--view",
        "-30",
        "--elevation",
        "-89",
        "--up",
        "z",
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("no Vulkan adapter"), "{stderr}");
}

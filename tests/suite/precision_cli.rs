//! `fragsim compare` through the binary: the bounds an f32 vertex stage is judged by, a reference
//! that cannot know (an MDTS K = 3 dump against an A-buffer: a note and exit 0), and dumps of
//! different scenes (exit 2 unless `--allow-different-scenes`).

use std::path::{Path, PathBuf};

use assert_cmd::Command;

fn fragsim() -> Command {
    Command::cargo_bin("fragsim").unwrap()
}

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("precision-cli", name)
}

fn run(cmd: &mut Command, code: i32) -> String {
    let output = cmd.output().unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    );
    assert_eq!(
        output.status.code(),
        Some(code),
        "stdout {out}\nstderr {err}"
    );
    out + &err
}

fn dump(dir: &Path, schemes: &str, view: &str) {
    run(
        fragsim()
            .args([
                "render",
                "--scene",
                "spheres:3",
                "--width",
                "48",
                "--height",
                "36",
            ])
            .args([
                "--view",
                view,
                "--k",
                "3",
                "--scheme",
                schemes,
                "--no-images",
                "--dump",
            ])
            .arg(dir),
        0,
    );
}

#[test]
fn a_k3_reference_against_an_abuffer_is_a_note_and_exit_0() {
    let dir = scratch("k3");
    dump(&dir, "mdts,abuffer", "30");
    let out = run(
        fragsim()
            .arg("compare")
            .arg(dir.join("mdts"))
            .arg(dir.join("abuffer"))
            .arg("--no-images"),
        0,
    );
    assert!(out.contains("cannot be judged"), "{out}");
    assert!(out.contains("verdict: EQUAL"), "{out}");
}

#[test]
fn dumps_of_different_scenes_exit_2_unless_asked_for() {
    let dir = scratch("scenes");
    dump(&dir.join("a"), "abuffer", "30");
    dump(&dir.join("b"), "abuffer", "75");
    let (a, b) = (dir.join("a/abuffer"), dir.join("b/abuffer"));
    let refused = run(
        fragsim().arg("compare").arg(&a).arg(&b).arg("--no-images"),
        2,
    );
    assert!(refused.contains("different scenes"), "{refused}");
    let asked = run(
        fragsim()
            .arg("compare")
            .arg(&a)
            .arg(&b)
            .args(["--no-images", "--allow-different-scenes"]),
        1,
    );
    assert!(asked.contains("verdict: DIFFERENT"), "{asked}");
}

#[test]
fn an_f32_vertex_stage_is_judged_within_printed_bounds() {
    let dir = scratch("f32");
    dump(&dir, "abuffer", "30");
    let out = run(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("abuffer"))
            .args(["--no-images", "--vertex-precision", "f32"]),
        0,
    );
    assert!(
        out.contains("precision (f32 vertex stage): vertex error up to"),
        "{out}"
    );
    let json = run(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("abuffer"))
            .args(["--no-images", "--json", "--vertex-precision", "f32"]),
        0,
    );
    let report = &crate::support::json_lines(json.as_bytes())[0];
    assert!(
        report["precision_max_depth_interval_ulps"]
            .as_u64()
            .unwrap()
            > 0
    );
    assert!(report["ambiguous_pixels"].is_u64(), "{json}");
    // The ambiguous pairs split by cause, and the pixels by cause, in the text and the JSON.
    assert!(
        out.contains("ambiguous") && out.contains("by cause: coverage"),
        "{out}"
    );
    let field = |key: &str| {
        report[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{key} in {json}"))
    };
    assert_eq!(
        field("precision_ambiguous_pairs"),
        field("precision_may_be_present_pairs")
            + field("precision_coverage_undecided_pairs")
            + field("precision_depth_undecided_pairs")
            + field("precision_clipped_pairs"),
        "{json}"
    );
    let by_cause: u64 = ["coverage", "depth", "order", "clipped"]
        .iter()
        .map(|c| field(&format!("ambiguous_by_cause_{c}")))
        .sum();
    assert!(by_cause >= field("ambiguous_pixels"), "{json}");
}

/// A per-sample capture of an f32 vertex stage (`render --vertex-precision f32 --samples N`: the
/// rasterizer's own f32 stage, its dump declaring both) judged under `--vertex-precision f32`,
/// which derives its bounds at each sample: EQUAL with no differing sample at 4 and 8 samples, for
/// MDTS keys and the A-buffer's ids; a sample dropped from the A-buffer (its counter and slot
/// as a capture that lost it) is DIFFERENT. A masked-node dump under the flag is refused by name.
#[test]
fn a_per_sample_f32_capture_is_judged_at_each_sample() {
    for samples in ["4", "8"] {
        let dir = scratch(&format!("f32-samples-{samples}"));
        run(
            fragsim()
                .args([
                    "render",
                    "--scene",
                    "spheres:3",
                    "--width",
                    "40",
                    "--height",
                    "30",
                ])
                .args([
                    "--vertex-precision",
                    "f32",
                    "--samples",
                    samples,
                    "--k",
                    "4",
                ])
                .args([
                    "--capacity",
                    "auto",
                    "--scheme",
                    "mdts,abuffer,abuffer-masked",
                    "--no-images",
                ])
                .arg("--dump")
                .arg(&dir),
            0,
        );
        let judge = |scheme: &str, code: i32| {
            let json = run(
                fragsim()
                    .args(["compare", "oracle"])
                    .arg(dir.join(scheme))
                    .args(["--no-images", "--json", "--vertex-precision", "f32"]),
                code,
            );
            // The report is the JSON line; a DIFFERENT verdict adds a line on stderr.
            let line = json
                .lines()
                .find(|l| l.starts_with('{'))
                .unwrap_or_default();
            crate::support::json_lines(line.as_bytes())[0].clone()
        };
        // The masked-node dump too: its nodes judged at each sample of their masks.
        for scheme in ["mdts", "abuffer", "abuffer-masked"] {
            let report = judge(scheme, 0);
            assert_eq!(report["equal"], true, "{samples}x {scheme}: {report}");
            assert_eq!(report["per_sample_differing_samples"], 0, "{report}");
            assert!(report["per_sample_compared"].as_u64().unwrap() > 0);
        }
        // Drop the first stored fragment of the first sample holding one: the counter one less
        // and the slot emptied, as an implementation that lost it would leave them.
        let abuffer = dir.join("abuffer");
        let header: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(abuffer.join("dump.json")).unwrap())
                .unwrap();
        let capacity = usize::try_from(header["capacity"].as_u64().unwrap()).unwrap();
        let counters_file = abuffer.join("counters.u32");
        let mut counters: Vec<u32> = std::fs::read(&counters_file)
            .unwrap()
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let sample = counters.iter().position(|&c| c > 0).unwrap();
        counters[sample] -= 1;
        let bytes: Vec<u8> = counters.iter().flat_map(|c| c.to_le_bytes()).collect();
        std::fs::write(&counters_file, bytes).unwrap();
        let slots_file = abuffer.join("slots.u64");
        let mut slots = std::fs::read(&slots_file).unwrap();
        let last = (sample * capacity + counters[sample] as usize) * 8;
        slots[last..last + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        std::fs::write(&slots_file, slots).unwrap();
        let report = judge("abuffer", 1);
        assert_eq!(report["per_sample_differing_samples"], 1, "{report}");
    }
}

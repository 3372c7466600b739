//! The acceptance check of the core: on the embedded default scene, both schemes on both
//! executors equal the serial oracle fragment for fragment.

use fragsim::capture::executors::{run_parallel, run_serial, Executor};
use fragsim::capture::MEMORY_CAP_DEFAULT;
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, Viewport};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::{Direction, Mdts};

#[test]
fn bunny_both_schemes_both_executors_equal_the_oracle() {
    let scene = Scene::default_scene();
    let view = scene
        .view(
            Viewport::new(256, 256).unwrap(),
            &OrbitCamera::default().at_angle(30.0),
        )
        .unwrap();
    let oracle = Oracle::build(&view);
    let k = oracle.max_depth_complexity();
    assert!(k >= 4, "the bunny has several layers somewhere, got {k}");
    let mdts = Mdts::<u64>::ascending(view.viewport(), k).unwrap();
    let abuffer = ABuffer::exact(
        &oracle.depth_complexity(),
        PostSort::Bitonic,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    for run in [run_serial(&view, &mdts), run_parallel(&view, &mdts)] {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(
            usize::try_from(run.stats.counters.fragments),
            Ok(oracle.fragments())
        );
        assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
    }
    for run in [run_serial(&view, &abuffer), run_parallel(&view, &abuffer)] {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
    }
    // With fewer slots than layers MDTS keeps exactly the nearest K, and says how many it dropped.
    let shallow =
        Mdts::<u32>::new(view.viewport(), 2, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let run = run_parallel(&view, &shallow);
    let diff = oracle.diff(&run.capture);
    assert!(diff.is_exact(), "{diff:?}");
    assert_eq!(diff.overflowed, run.stats.counters.dropped);
    assert!(diff.overflowed > 0);
    let descending = Mdts::<u64>::new(
        view.viewport(),
        3,
        Direction::Descending,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    let descending_diff = oracle.diff(&run_parallel(&view, &descending).capture);
    assert!(descending_diff.is_exact(), "{descending_diff:?}");
}

/// `fragsim render ARGS --json --no-images`: the exit status and the rows.
fn render_json(args: &[&str]) -> (i32, Vec<serde_json::Value>, String) {
    let output = assert_cmd::Command::cargo_bin("fragsim")
        .unwrap()
        .args(args)
        .args(["--json", "--no-images"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let rows = crate::support::json_lines(&output.stdout);
    (output.status.code().unwrap_or(-1), rows, stderr)
}

/// The row of `scheme` (its first executor).
fn row<'a>(rows: &'a [serde_json::Value], scheme: &str) -> &'a serde_json::Value {
    rows.iter()
        .find(|r| r["scheme"] == scheme)
        .unwrap_or_else(|| panic!("no row for {scheme}"))
}

/// FreePipe's A-buffer is one pass over fixed arrays; the exact-storage variant is two, and its
/// counting pass is timed and counted; MDTS with a fixed K is one pass.
#[test]
fn abuffer_is_one_pass_over_fixed_arrays_and_abuffer_exact_reports_its_count_pass() {
    let (code, rows, stderr) = render_json(&["--scheme", "abuffer,abuffer-exact,mdts"]);
    assert_eq!(code, 0, "{stderr}");
    let pixels = 512 * 512_u64;
    let fragments = row(&rows, "mdts")["fragments"].as_u64().unwrap();
    // The oracle's fragment count, computed here independently of any scheme's storage.
    let scene = Scene::default_scene();
    let view = scene
        .view(
            Viewport::new(512, 512).unwrap(),
            &OrbitCamera::default().at_angle(30.0),
        )
        .unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(usize::try_from(fragments), Ok(oracle.fragments()));

    let fixed = row(&rows, "abuffer");
    assert_eq!(fixed["passes"], 1);
    assert!(fixed["count_pass_ms"].is_null());
    assert_eq!(fixed["slots_per_pixel"], 20);
    // 20 slots of 8 bytes and a 4-byte counter per pixel, whatever the scene.
    assert_eq!(
        fixed["memory_bytes"].as_u64().unwrap(),
        pixels * (4 + 20 * 8)
    );
    assert_eq!(fixed["guarantee"], "exact-within-capacity(20)");

    let exact = row(&rows, "abuffer-exact");
    assert_eq!(exact["passes"], 2);
    assert!(exact["count_pass_ms"].as_f64().unwrap() > 0.0);
    assert!(exact["time_ms"].as_f64().unwrap() >= exact["count_pass_ms"].as_f64().unwrap());
    // Both passes rasterize every fragment.
    assert_eq!(exact["fragments"].as_u64().unwrap(), 2 * fragments);
    // Counters, slots and 32-bit offsets: sized to the fragments its own pass counted.
    assert_eq!(
        exact["memory_bytes"].as_u64().unwrap(),
        pixels * 4 + fragments * 8 + (pixels + 1) * 4
    );
    let mdts = row(&rows, "mdts");
    assert_eq!(mdts["passes"], 1);
    assert_eq!(mdts["memory_bytes"].as_u64().unwrap(), pixels * 20 * 8);
    for r in &rows {
        assert_eq!(r["keeps_guarantee"], true, "{r}");
        assert_eq!(r["lost"], 0, "{r}");
    }
}

/// No scheme's storage is sized by anything but the user's numbers and its own counting pass:
/// on two scenes of different depth complexity, a scheme whose memory differs must report a
/// counting pass. With fixed sizes, no scheme but those sized to the scene by design may differ.
/// A scheme sized from the oracle (which knows the scene without a pass) would fail this.
#[test]
fn no_scheme_is_sized_from_the_oracle() {
    let schemes_run = |scene: &str, sizes: &[&str]| {
        let mut args = vec![
            "--scene",
            scene,
            "--width",
            "24",
            "--height",
            "24",
            "--view",
            "0",
            "--elevation",
            "0",
            "--scheme",
            "all",
            "--executor",
            Executor::Serial.name(),
        ];
        args.extend_from_slice(sizes);
        let (code, rows, stderr) = render_json(&args);
        assert_eq!(code, 0, "{stderr}");
        rows
    };
    for sizes in [
        &["--k", "auto", "--capacity", "auto"][..],
        &["--k", "3", "--capacity", "3"],
    ] {
        let shallow = schemes_run("quads:2", sizes);
        let deep = schemes_run("quads:7", sizes);
        assert_eq!(shallow.len(), deep.len());
        let mut sized_by_scene = 0;
        for (a, b) in shallow.iter().zip(&deep) {
            assert_eq!(a["scheme"], b["scheme"]);
            if a["memory_bytes"] != b["memory_bytes"] {
                sized_by_scene += 1;
                for r in [a, b] {
                    assert!(
                        r["count_pass_ms"].is_f64(),
                        "{} is sized to the scene without a counting pass: {r}",
                        r["scheme"]
                    );
                }
            }
        }
        assert!(
            sized_by_scene > 0,
            "the scenes must differ in depth complexity"
        );
    }
}

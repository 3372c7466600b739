//! What `render` and `bench` report adds up, through the binary:
//! every row of `render` accounts for every fragment of the scene, and a run whose guarantee owes
//! nothing on its executor says so instead of `kept`.

use assert_cmd::Command;

/// The JSON Lines records of `fragsim ARGS --json` (which must exit 0) that are rows.
fn rows(args: &[&str], kind: &str) -> Vec<serde_json::Value> {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(args)
        .args(["--no-images", "--json"])
        .output()
        .unwrap();
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    crate::support::json_lines(&output.stdout)
        .into_iter()
        .filter(|r| r["record"] == kind)
        .collect()
}

const SMALL: [&str; 8] = [
    "--scene",
    "spheres:3",
    "--width",
    "48",
    "--height",
    "36",
    "--k",
    "2",
];

#[test]
fn every_render_row_accounts_for_every_fragment_with_its_extra_ones() {
    // A racy k-buffer run left duplicates (extra) beside its losses: without `extra` the row's
    // captured, overflow and lost did not add up to the scene's fragments.
    for executor in ["all", "scheduled"] {
        let rows = rows(
            &[
                &["render"],
                &SMALL[..],
                &["--scheme", "all", "--executor", executor, "--capacity", "3"],
            ]
            .concat(),
            "run",
        );
        assert!(rows.len() > 30, "{executor}: {} rows", rows.len());
        for r in &rows {
            let n = |field: &str| r[field].as_u64().unwrap_or_else(|| panic!("{field}: {r}"));
            assert_eq!(
                n("captured") + n("overflowed") + n("lost") - n("extra"),
                n("reference_fragments"),
                "{r}"
            );
        }
    }
}

#[test]
fn a_racy_run_whose_guarantee_owes_nothing_on_its_executor_is_not_called_kept() {
    // `render --scheme kbuffer --executor scheduled` printed `kept` beside `lost 94`.
    let args = [
        &["render"],
        &SMALL[..],
        &["--scheme", "kbuffer,mdts", "--executor", "scheduled"],
    ]
    .concat();
    let rows = rows(&args, "run");
    let kbuffer = rows.iter().find(|r| r["scheme"] == "kbuffer").unwrap();
    assert!(kbuffer["lost"].as_u64().unwrap() > 0, "{kbuffer}");
    assert_eq!(kbuffer["guarantee_owed"], false, "{kbuffer}");
    let mdts = rows.iter().find(|r| r["scheme"] == "mdts").unwrap();
    assert_eq!(mdts["guarantee_owed"], true, "{mdts}");
    let table = Command::cargo_bin("fragsim")
        .unwrap()
        .args(&args)
        .arg("--no-images")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&table.stdout);
    let line = |scheme: &str| {
        text.lines()
            .find(|l| l.starts_with(&format!("{scheme} ")))
            .unwrap_or_else(|| panic!("no {scheme} row in {text}"))
            .to_string()
    };
    assert!(line("kbuffer").contains("not owed"), "{text}");
    assert!(!line("kbuffer").contains("kept"), "{text}");
    assert!(line("mdts").contains("kept"), "{text}");
}

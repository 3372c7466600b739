//! `fragsim explain`: it finds and names a k-buffer loss on both write-back machines, shrinks
//! without growing the interleaving (to the 4 steps of render-target write-backs, the `4 K` of
//! separate stores), and shows MDTS's invariant holding at every step.

use assert_cmd::Command;

fn explain(args: &[&str]) -> (bool, String) {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .arg("explain")
        .args(args)
        .output()
        .unwrap();
    (
        output.status.success(),
        String::from_utf8(output.stdout).unwrap(),
    )
}

/// The step count on the line starting with `label`.
fn steps(text: &str, label: &str) -> usize {
    let line = text
        .lines()
        .find(|l| l.starts_with(label))
        .unwrap_or_else(|| panic!("no `{label}` line in:\n{text}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = words.iter().position(|w| w.starts_with("steps")).unwrap();
    words[at - 1].parse().unwrap()
}

#[test]
fn explain_finds_a_losing_kbuffer_interleaving_and_names_the_lost_value() {
    let (ok, text) = explain(&["--scheme", "kbuffer", "--depths", "0.3,0.5,0.1"]);
    assert!(ok, "{text}");
    let lost = text
        .lines()
        .find(|l| l.starts_with("LOST: "))
        .unwrap_or_else(|| panic!("no lost value named:\n{text}"));
    // The lost value is one of the inputs, by depth and fragment.
    assert!(
        ["0.3#", "0.5#", "0.1#"].iter().any(|d| lost.contains(d)),
        "{lost}"
    );
    // The table has a column per thread and a write-back over another fragment's value.
    assert!(text.contains("| T"), "{text}");
    assert!(
        text.contains("write [") && text.contains("(was ["),
        "{text}"
    );
}

#[test]
fn shrinking_yields_no_more_steps_than_the_unshrunk_interleaving() {
    for machine in ["render-target", "separate-stores"] {
        for depths in ["0.3,0.5,0.1", "0.3,0.5,0.1,0.2,0.7"] {
            let args = ["--depths", depths, "--write-back", machine];
            let (ok, shrunk) = explain(&args);
            let (ok_raw, raw) = explain(&[&args[..], &["--no-shrink"]].concat());
            assert!(ok && ok_raw, "{shrunk}\n{raw}");
            let found = steps(&raw, "k-buffer");
            assert_eq!(steps(&raw, "unshrunk"), found);
            assert!(steps(&shrunk, "shrunk") <= found, "{shrunk}\n{raw}");
            // Two fragments suffice for the hazard: shrinking finds them.
            assert!(shrunk.contains(", 2 threads,"), "{shrunk}");
        }
    }
}

#[test]
fn the_shortest_losing_interleaving_is_4_steps_on_render_targets_and_4k_with_separate_stores() {
    for (depths, k) in [
        ("0.3,0.5,0.1", 3),
        ("0.3,0.5,0.1,0.2,0.7", 5),
        ("0.2,0.6", 1),
    ] {
        let k_arg = k.to_string();
        let (ok, text) = explain(&["--depths", depths, "--k", &k_arg]);
        assert!(ok, "{text}");
        // Read, read, write-back, write-back: a read is one row, a write-back one row.
        assert_eq!(steps(&text, "shrunk"), 4, "{text}");
        assert!(
            text.starts_with("k-buffer (render-target write-backs)"),
            "{text}"
        );
        let rows = |prefix: &str| {
            text.lines()
                .filter(|l| l.split('|').any(|c| c.trim().starts_with(prefix)))
                .count()
        };
        assert_eq!((rows("read ["), rows("write [")), (2, 2), "{text}");
        // Render targets lose; they never duplicate.
        assert!(text.contains("LOST: "), "{text}");
        assert!(!text.contains("DUPLICATED"), "{text}");

        let (second_ok, second_text) = explain(&[
            "--depths",
            depths,
            "--k",
            &k_arg,
            "--write-back",
            "separate-stores",
        ]);
        assert!(second_ok, "{second_text}");
        assert_eq!(steps(&second_text, "shrunk"), 4 * k, "{second_text}");
        assert!(second_text.contains("store w"), "{second_text}");
    }
}

#[test]
fn explain_on_mdts_reports_the_invariant_holding_at_every_step() {
    let (ok, text) = explain(&[
        "--scheme",
        "mdts",
        "--depths",
        "0.3,0.5,0.1,0.2",
        "--k",
        "3",
    ]);
    assert!(ok, "{text}");
    let rows = text.lines().filter(|l| l.contains("fetch_min")).count();
    let checked = text
        .lines()
        .filter(|l| l.contains("fetch_min") && l.rsplit('|').nth(1).map(str::trim) == Some("✓"))
        .count();
    assert!(rows > 0);
    assert_eq!(rows, checked, "{text}");
    assert!(text.contains("✓ holds"), "{text}");
    assert!(!text.contains('✗'), "{text}");
}

#[test]
fn explain_rejects_depths_outside_the_unit_interval() {
    let (ok, _) = explain(&["--depths", "0.3,1.5"]);
    assert!(!ok);
}

#[test]
fn explain_offers_the_catalogs_kbuffer_stores_as_the_kbuffer_on_separate_stores() {
    let depths = ["--depths", "0.3,0.5,0.1"];
    let (ok, stores) = explain(&[&["--scheme", "kbuffer-stores"], &depths[..]].concat());
    let (ok_flag, flag) = explain(
        &[
            &["--scheme", "kbuffer", "--write-back", "separate-stores"],
            &depths[..],
        ]
        .concat(),
    );
    assert!(ok && ok_flag, "{stores}\n{flag}");
    assert!(stores.starts_with("k-buffer (separate stores)"), "{stores}");
    assert_eq!(stores, flag);
    // A `-stores` name fixes its machine: naming the other one is refused, not ignored.
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["explain", "--scheme", "kbuffer-stores", "--write-back"])
        .arg("render-target")
        .output()
        .unwrap();
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert!(!output.status.success());
    assert!(
        stderr.contains("kbuffer-stores runs on separate stores"),
        "{stderr}"
    );
    // A catalog scheme explain cannot build on one pixel is refused, naming those it can.
    let abuffer_output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["explain", "--scheme", "abuffer"])
        .output()
        .unwrap();
    let abuffer_stderr = String::from_utf8(abuffer_output.stderr).unwrap();
    assert!(!abuffer_output.status.success());
    assert!(
        abuffer_stderr.contains("mdts") && abuffer_stderr.contains("kbuffer-stores"),
        "{abuffer_stderr}"
    );
}

/// Every `DEPTH#PRIM` written in `text` (a thread's heading, a slot, a lost value).
fn fragments_named(text: &str) -> Vec<(f32, usize)> {
    text.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '#'))
        .filter_map(|word| {
            let (depth, prim) = word.split_once('#')?;
            Some((depth.parse().ok()?, prim.parse().ok()?))
        })
        .collect()
}

/// Issue 36: after shrinking, every fragment keeps the number the user gave it (fragment `i` is
/// the `i`-th of `--depths`, on thread `Ti`), and the key's example is one of the run's own.
#[test]
fn explain_keeps_the_users_fragment_numbering_after_shrinking() {
    let depths = [0.1_f32, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
    let list: Vec<String> = depths.iter().map(f32::to_string).collect();
    for machine in ["render-target", "separate-stores"] {
        let (ok, text) = explain(&["--depths", &list.join(","), "--write-back", machine]);
        assert!(ok, "{text}");
        let named = fragments_named(&text);
        assert!(!named.is_empty(), "{text}");
        for (depth, prim) in named {
            assert_eq!(depth, depths[prim], "{depth}#{prim} in\n{text}");
        }
        // A thread's column is headed by its fragment's own number.
        let heading = text.lines().find(|l| l.starts_with("| step")).unwrap();
        for column in heading.split('|').filter(|c| c.trim().starts_with('T')) {
            let (thread, fragment) = column.trim().split_once(" (").unwrap();
            let prim = fragment.split_once('#').unwrap().1.trim_end_matches(')');
            assert_eq!(thread, format!("T{prim}"), "{heading}");
        }
        let lost = text.lines().find(|l| l.starts_with("LOST: ")).unwrap();
        let (value, fragment) = lost["LOST: ".len()..].split_once(" (fragment ").unwrap();
        let prim: usize = fragment.split_once(',').unwrap().0.parse().unwrap();
        assert_eq!(value, format!("{}#{prim}", depths[prim]), "{lost}");
    }
    // The default run's key illustrates its own first fragment, 0.3 (primitive 0).
    let (ok, text) = explain(&[]);
    assert!(ok, "{text}");
    let key = text.lines().find(|l| l.starts_with("key: ")).unwrap();
    assert!(
        key.starts_with("key: 0.3#0 = a fragment: depth 0.3, primitive 0 (index 0 in --depths)"),
        "{key}"
    );
}

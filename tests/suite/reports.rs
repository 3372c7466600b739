//! What the reports tell a user, through the binary: each case a new user met that misled or
//! stopped them, redone as they did it.

use std::path::{Path, PathBuf};

use crate::support::prim_of;
use assert_cmd::Command;
use fragsim_dump::{Dump, Words};

/// A linked list's layout names its node word: a header without `payload` is refused naming the
/// field and the file (docs/dump-format.md says all three of `null`, `node_base` and `payload`
/// are required).
#[test]
fn a_linked_list_header_without_its_payload_is_refused_naming_the_field() {
    let dir = crate::support::scratch("reports", "list-without-payload");
    let render = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["--scheme", "linked-list", "--width", "16", "--height", "16"])
        .args(["--no-images", "--out"])
        .arg(&dir)
        .arg("--dump")
        .arg(dir.join("dumps"))
        .output()
        .unwrap();
    assert!(
        render.status.success(),
        "{}",
        String::from_utf8_lossy(&render.stderr)
    );
    let dump = dir.join("dumps/linked-list");
    let header_path = dump.join("dump.json");
    let mut header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&header_path).unwrap()).unwrap();
    let layout = header["layout"]
        .as_object_mut()
        .expect("a linked-list layout");
    assert!(
        layout.remove("payload").is_some(),
        "the render wrote a payload"
    );
    std::fs::write(&header_path, header.to_string()).unwrap();
    let compare = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["compare", "oracle"])
        .arg(&dump)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&compare.stderr);
    assert_eq!(compare.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("payload") && stderr.contains("dump.json"),
        "{stderr}"
    );
}

/// `fragsim ARGS…`, which must succeed; its output.
fn fragsim_ok(args: &[&str]) -> std::process::Output {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "fragsim {args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// `fragsim compare oracle DUMP ARGS…` (any exit code); its stdout.
fn compare_with_oracle(dump: &Path, args: &[&str]) -> String {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["compare", "oracle"])
        .arg(dump)
        .args(args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(
        matches!(output.status.code(), Some(0 | 1)),
        "{stdout}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    stdout
}

/// Renders `schemes` of eight stacked quads (deep lists, pixels inside and on the edge of each
/// triangle) at 24 × 24 pixels with `more` options into `dir/dumps/<scheme>`.
fn dumps(dir: &Path, schemes: &str, more: &[&str]) -> PathBuf {
    let (out, dumps) = (dir.join("out"), dir.join("dumps"));
    let mut args = vec![
        "--scene", "quads:8", "--scheme", schemes, "--width", "24", "--height", "24",
    ];
    args.extend_from_slice(more);
    args.extend(["--no-images", "--out", out.to_str().unwrap()]);
    args.extend(["--dump", dumps.to_str().unwrap()]);
    fragsim_ok(&args);
    dumps
}

/// A dump's u32 array `name`, to edit.
fn u32s<'d>(dump: &'d mut Dump, name: &str) -> &'d mut Vec<u32> {
    match dump.arrays.get_mut(name) {
        Some(Words::U32(words)) => words,
        _ => panic!("no u32 array {name}"),
    }
}

/// A fragsim linked-list dump's nodes (`depth key << 32 | primitive`), to edit.
fn nodes(dump: &mut Dump) -> &mut Vec<u64> {
    match dump.arrays.get_mut("nodes") {
        Some(Words::U64(words)) => words,
        _ => panic!("no u64 array nodes"),
    }
}

/// Each pixel's nodes of a fragsim linked-list dump (numbered from 1, 0 ending a list), head
/// first.
fn lists(dump: &mut Dump) -> Vec<Vec<u32>> {
    let next = u32s(dump, "next").clone();
    u32s(dump, "heads")
        .iter()
        .map(|&head| {
            std::iter::successors((head != 0).then_some(head), |&node| {
                Some(next[node as usize - 1]).filter(|&n| n != 0)
            })
            .collect()
        })
        .collect()
}

/// Unlinks `node` from `pixel`'s list: a lost node, its fragment missing at the pixel.
fn unlink(dump: &mut Dump, pixel: usize, node: u32) {
    let list = &lists(dump)[pixel];
    let at = list
        .iter()
        .position(|&n| n == node)
        .expect("the node is in the list");
    let after = u32s(dump, "next")[node as usize - 1];
    match at {
        0 => u32s(dump, "heads")[pixel] = after,
        _ => u32s(dump, "next")[list[at - 1] as usize - 1] = after,
    }
}

/// Issue 48, item 1: fragsim's own linked-list dump is `EQUAL (bit-identical)`: its pool past
/// the node counter is room no header defines, named in a note worded for lists (no A-buffer
/// slot, no `"filled"`), while an unfilled A-buffer's spare slots keep theirs and stop at `EQUAL
/// (lists bit-identical)`.
#[test]
fn every_note_on_unread_words_is_worded_for_its_layout() {
    let dir = crate::support::scratch("reports", "unread-words");
    let dumps = dumps(&dir, "linked-list,abuffer", &[]);
    let list = compare_with_oracle(&dumps.join("linked-list"), &[]);
    assert!(list.contains("verdict: EQUAL (bit-identical)"), "{list}");
    assert!(
        !list.contains("A-buffer") && !list.contains("filled"),
        "{list}"
    );
    let spare = list
        .lines()
        .find(|l| l.starts_with("words:"))
        .and_then(|l| l.split("spare room not read ").nth(1))
        .and_then(|rest| rest.split(',').next())
        .and_then(|n| n.parse::<u64>().ok())
        .expect("a words line with the spare room");
    assert!(spare > 0, "the pool has room past the counter: {list}");
    assert!(
        list.contains("nodes lie past the node counter and were not read"),
        "{list}"
    );
    // The same A-buffer dump, its header no longer promising filled slots.
    let abuffer = dumps.join("abuffer");
    let header_path = abuffer.join("dump.json");
    let mut header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&header_path).unwrap()).unwrap();
    header["filled"] = false.into();
    std::fs::write(&header_path, header.to_string()).unwrap();
    let unfilled = compare_with_oracle(&abuffer, &[]);
    assert!(
        unfilled.contains("verdict: EQUAL (lists bit-identical)"),
        "{unfilled}"
    );
    assert!(
        unfilled.contains("A-buffer slots past their pixel's counter were not checked")
            && unfilled.contains("(\"filled\": true)"),
        "{unfilled}"
    );
}

/// Issue 48, item 6: the report names conventions as a dump header spells them, and `compare
/// --help` names the alias that works.
#[test]
fn conventions_are_printed_in_the_headers_words() {
    let dir = crate::support::scratch("reports", "conventions-words");
    let dumps = dumps(
        &dir,
        "abuffer",
        &[
            "--window-origin",
            "lower-left",
            "--depth-range",
            "minus-one-to-one",
        ],
    );
    let report = compare_with_oracle(&dumps.join("abuffer"), &[]);
    assert!(
        report.contains(
            r#"conventions {"window_origin": "lower-left", "depth_range": "minus-one-to-one"}"#
        ),
        "{report}"
    );
    assert!(!report.contains("Conventions {"), "{report}");
    let help = fragsim_ok(&["compare", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("the older `--no-image` still works"),
        "{help}"
    );
    fragsim_ok(&[
        "compare",
        "oracle",
        dumps.join("abuffer").to_str().unwrap(),
        "--no-image",
    ]);
}

/// The example lines of a report's side-by-side lists that are marked as differing.
fn marked_rows(report: &str) -> Vec<&str> {
    report.lines().filter(|l| l.starts_with("* ")).collect()
}

/// The first pixel whose list has at least `fragments` fragments and one node that is not its
/// deepest (so that a list aligned by index would mark the rows after it), with that node.
fn deep_pixel(dump: &mut Dump, fragments: usize) -> (usize, u32) {
    let all = lists(dump);
    let nodes = nodes(dump).clone();
    all.iter()
        .enumerate()
        .filter(|(_, list)| list.len() >= fragments)
        .find_map(|(p, list)| {
            let deepest = list.iter().map(|&n| nodes[n as usize - 1]).max()?;
            let node = list.iter().find(|&&n| nodes[n as usize - 1] != deepest)?;
            Some((p, *node))
        })
        .expect("a pixel with that many fragments")
}

/// Issue 48, item 7: one missing fragment marks one row of the side-by-side lists (aligned by
/// fragment, not by index), and the difference image's legend counts pixels as the text does.
#[test]
fn one_missing_fragment_marks_one_row_and_the_legend_counts_as_the_text() {
    let dir = crate::support::scratch("reports", "aligned-rows");
    let dumps = dumps(&dir, "linked-list", &[]);
    let mut dump = Dump::read(&dumps.join("linked-list")).unwrap();
    let (p, node) = deep_pixel(&mut dump, 3);
    unlink(&mut dump, p, node);
    let edited = dir.join("edited");
    dump.write(&edited).unwrap();
    let image = dir.join("diff.png");
    let report = compare_with_oracle(&edited, &["--image", image.to_str().unwrap()]);
    assert!(report.contains("verdict: DIFFERENT"), "{report}");
    assert_eq!(marked_rows(&report).len(), 1, "{report}");
    // The same pixel also corrupt: a word past 1.0 at its head. The text counts it missing and
    // corrupt; so does the legend, saying the missing one is drawn in the corrupt colour.
    let head = lists(&mut dump)[p][0];
    nodes(&mut dump)[head as usize - 1] = u64::from(2.0_f32.to_bits()) << 32;
    dump.write(&edited).unwrap();
    let second_report = compare_with_oracle(&edited, &["--image", image.to_str().unwrap()]);
    let count = |line: &str, name: &str| -> u64 {
        line.split(name)
            .nth(1)
            .and_then(|rest| rest.split([',', ';', ' ']).find(|w| !w.is_empty()))
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no {name} in {line}"))
    };
    let pixels = second_report
        .lines()
        .find(|l| l.starts_with("pixels "))
        .expect("the verdicts line");
    let legend = second_report
        .lines()
        .find(|l| l.trim_start().starts_with("legend:"))
        .expect("the legend line");
    assert_eq!(count(pixels, ", missing "), 1, "{second_report}");
    assert_eq!(
        count(legend, "; missing: "),
        count(pixels, ", missing "),
        "{second_report}"
    );
    assert_eq!(
        count(legend, "corrupt word: "),
        count(pixels, "corrupt "),
        "{second_report}"
    );
    assert!(
        legend.contains("missing: 1 (1 drawn above)"),
        "{second_report}"
    );
}

/// Issue 48, item 7: a hint when the differences have a shape that names a cause, and none
/// otherwise: depth keys an ulp off (the precision options), fragments lost on their
/// triangle's edge (conventions and tie rules), the whole frame of another view (scene or
/// camera).
#[test]
fn a_mismatch_of_an_actionable_shape_gets_a_hint() {
    let dir = crate::support::scratch("reports", "hints");
    let dumps = dumps(&dir, "linked-list", &[]);
    let original = Dump::read(&dumps.join("linked-list")).unwrap();
    let edited = dir.join("edited");
    let judged = |dump: &Dump, args: &[&str]| {
        dump.write(&edited).unwrap();
        compare_with_oracle(&edited, args)
    };
    let hints = |report: &str| -> Vec<String> {
        report
            .lines()
            .filter_map(|l| l.strip_prefix("hint: "))
            .map(String::from)
            .collect()
    };
    // A few nodes one ulp deeper.
    let mut deeper = original.clone();
    let heads: Vec<u32> = lists(&mut deeper)
        .into_iter()
        .filter_map(|l| l.first().copied())
        .collect();
    for &node in heads.iter().take(3) {
        nodes(&mut deeper)[node as usize - 1] += 1 << 32;
    }
    let report = judged(&deeper, &[]);
    assert!(report.contains("verdict: DIFFERENT"), "{report}");
    let hint = hints(&report).join("\n");
    assert!(
        hint.contains("at most 1 f32 ulp from")
            && hint.contains("--vertex-precision f32")
            && hint.contains("--depth-ulps 1"),
        "{report}"
    );
    assert!(judged(&deeper, &["--depth-ulps", "1"]).contains("verdict: EQUAL"));
    // One fragment lost where its triangle's coverage ends, then one where it goes on.
    let mut edge = original.clone();
    let all = lists(&mut edge);
    let prims: Vec<Vec<u32>> = all
        .iter()
        .map(|list| {
            list.iter()
                .map(|&n| prim_of(nodes(&mut edge)[n as usize - 1]))
                .collect()
        })
        .collect();
    let width = 24;
    let beside = |p: usize, prim: u32, inside: bool| {
        let (x, y) = (p % width, p / width);
        let neighbours = [
            (x > 0).then(|| p - 1),
            (x + 1 < width).then(|| p + 1),
            (y > 0).then(|| p - width),
            (p + width < prims.len()).then(|| p + width),
        ];
        let mut neighbours = neighbours.into_iter().flatten();
        if inside {
            neighbours.all(|q| prims[q].contains(&prim))
        } else {
            neighbours.any(|q| !prims[q].contains(&prim))
        }
    };
    let lost_at = |inside: bool| {
        (0..all.len())
            .find_map(|p| {
                let i = (0..all[p].len()).find(|&i| beside(p, prims[p][i], inside))?;
                Some((p, all[p][i]))
            })
            .expect("such a fragment")
    };
    let (p, node) = lost_at(false);
    unlink(&mut edge, p, node);
    let edge_report = judged(&edge, &[]);
    assert!(
        hints(&edge_report)
            .join("\n")
            .contains("on the edge of its triangle's coverage"),
        "{edge_report}"
    );
    let mut inside = original.clone();
    let (inside_pixel, inside_node) = lost_at(true);
    unlink(&mut inside, inside_pixel, inside_node);
    let inside_report = judged(&inside, &[]);
    assert!(
        inside_report.contains("verdict: DIFFERENT"),
        "{inside_report}"
    );
    assert!(hints(&inside_report).is_empty(), "{inside_report}");
    // The header names another view than the one drawn.
    let mut turned = original;
    turned.header.scene.view_degrees += 180.0;
    let turned_report = judged(&turned, &[]);
    assert!(
        hints(&turned_report)
            .join("\n")
            .contains("another scene or view"),
        "{turned_report}"
    );
    // `--json` carries the same hint, and the linked list's spare pool apart from the words a
    // header could have had checked.
    let json = crate::support::json_lines(compare_with_oracle(&edited, &["--json"]).as_bytes());
    assert_eq!(json[0]["record"], "compare");
    assert!(
        json[0]["hints"][0]
            .as_str()
            .is_some_and(|h| h.contains("another scene or view")),
        "{}",
        json[0]
    );
    assert_eq!(json[0]["unchecked_words"], 0, "{}", json[0]);
    assert!(
        json[0]["spare_words"].as_u64().is_some_and(|n| n > 0),
        "{}",
        json[0]
    );
}

/// The width and height of the PNG at `path`.
fn png_size(path: &Path) -> (u32, u32) {
    image::image_dimensions(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Issue 48, items 2, 5 and 8: `render --samples 4` draws its pictures per pixel (as wide as the
/// single-sample ones), the line naming where they went names every option that changed them
/// (`--samples`, `--up`), and under `--json` that line goes to stderr.
#[test]
fn multisampled_and_turned_pictures_are_drawn_per_pixel_and_named() {
    let dir = crate::support::scratch("reports", "pictures");
    let render = |name: &str, more: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["--scene", "bunny", "--width", "40", "--height", "30"];
        args.extend_from_slice(more);
        args.extend(["--out", out.to_str().unwrap()]);
        (fragsim_ok(&args), out)
    };
    let (single, single_dir) = render("single", &[]);
    let (sampled, sampled_dir) = render("sampled", &["--samples", "4"]);
    for image in ["depth-complexity.png", "nearest-depth.png"] {
        let (one, four) = (
            png_size(&single_dir.join(image)),
            png_size(&sampled_dir.join(image)),
        );
        assert_eq!(one.0, four.0, "{image}: {one:?} at 1 sample, {four:?} at 4");
    }
    let line = |output: &std::process::Output| {
        String::from_utf8_lossy(&output.stdout)
            .lines()
            .find(|l| l.starts_with("images of "))
            .map(String::from)
            .expect("a line naming the images")
    };
    assert!(
        line(&single).contains("bunny, view 30°, elevation 15°, 40x30: "),
        "{}",
        line(&single)
    );
    assert!(
        line(&sampled).contains("40x30 at 4 samples"),
        "{}",
        line(&sampled)
    );
    let (turned, _) = render("turned", &["--up", "z"]);
    assert!(line(&turned).contains(", up z, "), "{}", line(&turned));
    let (json, json_dir) = render("json", &["--up", "z", "--json"]);
    let stderr = String::from_utf8_lossy(&json.stderr);
    let wrote = format!(
        "wrote {}: depth-complexity.png, nearest-depth.png (bunny, view 30°, elevation 15°, up z",
        json_dir.display()
    );
    assert!(stderr.contains(&wrote), "{stderr}");
    assert!(json_dir.join("depth-complexity.png").is_file());
    crate::support::json_lines(&json.stdout);
}

/// Issue 48, item 8: the sweep table says what its error-pixel rate and colour error count, and
/// a row whose colour is off somewhere (MDTS and the single-pass bucket scheme at K = 2) never
/// shows a rate of 0 beside it, in either table.
#[test]
fn the_sweep_table_says_what_epr_and_err_count() {
    let dir = crate::support::scratch("reports", "sweep");
    let out = fragsim_ok(&[
        "sweep",
        "--scheme",
        "bdp-single,mdts",
        "--k",
        "2",
        "--angles",
        "2",
        "--width",
        "96",
        "--height",
        "96",
        "--no-images",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("EPR: error-pixel rate, the % of covered pixels"),
        "{text}"
    );
    let (whole, buckets) = text
        .split_once("colour error per depth-complexity bucket")
        .expect("a table per bucket");
    // (the table, the columns of the largest rate and of the largest error)
    let mut errors = 0;
    for (table, rate, error) in [(whole, 2, 4), (buckets, 3, 5)] {
        for row in table
            .lines()
            .filter(|l| l.starts_with("mdts ") || l.starts_with("bdp-single "))
        {
            let cells: Vec<&str> = row.split_whitespace().collect();
            if cells[error].parse::<u32>().is_ok_and(|e| e > 0) {
                errors += 1;
                assert!(
                    cells[rate].parse::<f64>().map_or(true, |r| r > 0.0),
                    "{text}"
                );
            }
        }
    }
    assert!(errors > 0, "no row with a colour error: {text}");
}

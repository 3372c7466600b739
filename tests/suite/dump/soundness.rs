//! Captures no conforming implementation produces are DIFFERENT through the binary: each test
//! is named after what it caught, mutates a dump `render --dump` wrote and checks first that the
//! unmutated dump is equal, so that it can fail both ways.

use std::path::Path;

use assert_cmd::Command;

use super::binary::{fragsim, stdout_of};
use super::{scratch, SCENE};

/// `fragsim render` of `scene` (a named scene, or `--mesh FILE` in `source`) at `size`, serially,
/// running `schemes` with `options`, its dumps in `out`.
fn render(out: &Path, source: &[&str], size: u32, schemes: &str, options: &[&str]) {
    let side = size.to_string();
    stdout_of(
        fragsim()
            .arg("render")
            .args(source)
            .args(["--width", &side, "--height", &side, "--scheme", schemes])
            .args(["--executor", "serial", "--no-images", "--dump"])
            .arg(out)
            .args(options),
        0,
    );
}

/// `fragsim compare oracle DIR --json --no-image` with `options`, expecting exit `code`: the
/// `compare` record.
pub(super) fn compared(dir: &Path, options: &[&str], code: i32) -> serde_json::Value {
    let out = stdout_of(
        Command::cargo_bin("fragsim")
            .unwrap()
            .args(["compare", "oracle"])
            .arg(dir)
            .args(["--json", "--no-image"])
            .args(options),
        code,
    );
    crate::support::json_lines(out.as_bytes())[0].clone()
}

fn read_u32s(path: &Path) -> Vec<u32> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn write_u32s(path: &Path, words: &[u32]) {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// Sets every byte of the words of slot `slot` of each pixel (`k` slots of `width` bytes a
/// pixel, pixel-major) to `byte` (the empty slot: all ones, `0` for `mdts-desc`); `None`: every
/// slot.
fn empty_slots(file: &Path, width: usize, k: usize, slot: Option<usize>, byte: u8) {
    let mut bytes = std::fs::read(file).unwrap();
    for (i, word) in bytes.chunks_exact_mut(width).enumerate() {
        if slot.is_none_or(|s| i % k == s) {
            word.fill(byte);
        }
    }
    std::fs::write(file, bytes).unwrap();
}

#[test]
fn an_emptied_k_nearest_list_of_a_quad_drawn_twice_is_different_under_f32_precision() {
    // Two coplanar copies of a quad: every covered pixel holds two fragments of equal depth, and
    // the one K = 1 slot must hold the nearer in canonical order. An empty list was excused as
    // "ambiguous (order)" because another fragment could be nearer than each.
    let dir = scratch("sound-quad-twice");
    let mesh = dir.join("quad-twice.obj");
    std::fs::write(
        &mesh,
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let source = ["--mesh", mesh.to_str().unwrap()];
    let (own, unorm) = (dir.join("own"), dir.join("unorm"));
    render(&own, &source, 16, "mdts", &["--k", "1"]);
    render(
        &unorm,
        &source,
        16,
        "mdts",
        &["--k", "1", "--dump-payload", "u32:unorm24:8:8"],
    );
    let f32_stage = ["--vertex-precision", "f32"];
    assert_eq!(compared(&own.join("mdts"), &f32_stage, 0)["equal"], true);
    // A unorm payload is judged within the precision of its depth conversion by default.
    assert_eq!(compared(&unorm.join("mdts"), &[], 0)["equal"], true);
    empty_slots(&own.join("mdts").join("slots.u64"), 8, 1, None, 0xFF);
    empty_slots(&unorm.join("mdts").join("slots.u32"), 4, 1, None, 0xFF);
    for (dump, options) in [(own, &f32_stage[..]), (unorm, &[][..])] {
        let report = compared(&dump.join("mdts"), options, 1);
        assert_eq!(report["captured"], 0, "{report}");
        assert_eq!(report["ambiguous_pixels"], 0, "{report}");
        // One fragment lost a covered pixel; its copy lies past K, as the reference predicts.
        assert_eq!(report["lost"], report["overflowed"], "{report}");
        assert_eq!(report["missing_pixels"], report["lost"], "{report}");
    }
}

#[test]
fn a_k_nearest_list_short_of_k_is_different_under_f32_precision() {
    // A quad drawn three times, K = 2, the second slot of every pixel emptied: each covered pixel
    // holds one fragment where every conforming list holds two. The absent one was excused as
    // "ambiguous (order)" because two others (one of them absent too) could be nearer.
    let dir = scratch("sound-short-list");
    let mesh = dir.join("quad-thrice.obj");
    let quad = "f 1 2 3\nf 1 3 4\n";
    std::fs::write(
        &mesh,
        format!("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n{quad}{quad}{quad}"),
    )
    .unwrap();
    let source = ["--mesh", mesh.to_str().unwrap()];
    render(&dir, &source, 16, "mdts,mdts-desc", &["--k", "2"]);
    let f32_stage = ["--vertex-precision", "f32"];
    for (scheme, empty) in [("mdts", 0xFF), ("mdts-desc", 0)] {
        let path = dir.join(scheme);
        let before = compared(&path, &f32_stage, 0);
        assert_eq!(before["equal"], true, "{scheme}: {before}");
        empty_slots(&path.join("slots.u64"), 8, 2, Some(1), empty);
        let after = compared(&path, &f32_stage, 1);
        let covered = after["missing_pixels"].as_u64().unwrap();
        assert!(covered > 50, "{scheme}: {after}");
        // One fragment lost at each covered pixel, the third beyond K: every fragment counted.
        assert_eq!(after["lost"], covered, "{scheme}: {after}");
        let n = |field: &str| after[field].as_u64().unwrap();
        assert_eq!(
            n("captured") + n("lost") + n("overflowed"),
            n("reference_fragments"),
            "{scheme}: {after}"
        );
        assert_eq!(after["ambiguous_pixels"], 0, "{scheme}: {after}");
    }
}

/// A linked-list dump's lists: the heads, the `next` links and the node words, fragsim's
/// numbering (link 0 ends a list, link `n` is node `n − 1`).
struct Lists {
    heads: Vec<u32>,
    next: Vec<u32>,
    nodes: Vec<u64>,
}

impl Lists {
    fn read(dir: &Path) -> Self {
        let nodes = std::fs::read(dir.join("nodes.u64"))
            .unwrap()
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        Self {
            heads: read_u32s(&dir.join("heads.u32")),
            next: read_u32s(&dir.join("next.u32")),
            nodes,
        }
    }

    fn write(&self, dir: &Path) {
        write_u32s(&dir.join("heads.u32"), &self.heads);
        write_u32s(&dir.join("next.u32"), &self.next);
    }

    /// The links of pixel `p`'s list, head first.
    fn list(&self, p: usize) -> Vec<u32> {
        let mut links = Vec::new();
        let mut link = self.heads[p];
        while link != 0 {
            links.push(link);
            link = self.next[link as usize - 1];
        }
        links
    }

    /// Takes link `node` out of pixel `p`'s list.
    fn unlink(&mut self, p: usize, node: u32) {
        let after = self.next[node as usize - 1];
        match self.list(p).iter().position(|&n| n == node) {
            Some(0) => self.heads[p] = after,
            Some(i) => {
                let before = self.list(p)[i - 1];
                self.next[before as usize - 1] = after;
            }
            None => panic!("node {node} is not in pixel {p}'s list"),
        }
    }
}

#[test]
fn a_linked_list_node_cut_past_the_resolves_k_is_a_lost_fragment() {
    // K = 2: the resolve keeps two nodes of each list, so a node cut out of a list of three or
    // more was judged on what the resolve kept and called equal.
    let dir = scratch("sound-linked-lists");
    let options = ["--k", "2", "--capacity", "exact"];
    render(
        &dir,
        &["--scene", SCENE],
        48,
        "linked-list,linked-list-nearest",
        &options,
    );
    for (scheme, cut_nearest_first) in [("linked-list", true), ("linked-list-nearest", false)] {
        let path = dir.join(scheme);
        assert_eq!(compared(&path, &[], 0)["equal"], true, "{scheme}");
        let mut lists = Lists::read(&path);
        let mut cut = 0;
        for p in 0..lists.heads.len() {
            let list = lists.list(p);
            if list.len() < 3 {
                continue;
            }
            // The head (the last arrival, which keep-first keeps), or the farthest node (which
            // keep-nearest drops anyway).
            let node = if cut_nearest_first {
                list[0]
            } else {
                *list
                    .iter()
                    .max_by_key(|&&n| lists.nodes[n as usize - 1])
                    .unwrap()
            };
            lists.unlink(p, node);
            cut += 1;
        }
        assert!(cut > 50, "{scheme}: {cut} lists of three nodes or more");
        lists.write(&path);
        let report = compared(&path, &[], 1);
        assert_eq!(report["lost"], cut, "{scheme}: {report}");
        assert_eq!(report["missing_pixels"], cut, "{scheme}: {report}");
        assert_eq!(report["unreachable_words"], cut, "{scheme}: {report}");
    }
}

#[test]
fn a_linked_list_node_handed_out_and_never_linked_is_different() {
    // A pool larger than the scene's fragments: the counter claims one node more than the lists
    // reach, and every list is complete. No pixel differs; the node is still lost.
    let dir = scratch("sound-unlinked-node");
    render(
        &dir,
        &["--scene", SCENE],
        48,
        "linked-list",
        &["--k", "2", "--capacity", "4"],
    );
    let path = dir.join("linked-list");
    assert_eq!(compared(&path, &[], 0)["equal"], true);
    let counter = path.join("counter.u32");
    let count = read_u32s(&counter)[0];
    write_u32s(&counter, &[count + 1]);
    let report = compared(&path, &[], 1);
    assert_eq!(report["mismatched_pixels"], 0, "{report}");
    assert_eq!(report["unreachable_words"], 1, "{report}");
    assert_eq!(report["equal"], false, "{report}");
}

#[test]
fn render_dump_of_a_racy_kbuffer_run_holds_that_runs_words() {
    // The scheduled executor interleaves the k-buffer's read and write-back: the run loses
    // fragments, and its dump held a serial re-run's words, which compare called equal.
    let dir = scratch("sound-racy-dump");
    let out = stdout_of(
        fragsim()
            .args([
                "render", "--scene", SCENE, "--width", "48", "--height", "36",
            ])
            .args(["--scheme", "kbuffer", "--executor", "scheduled"])
            .args(["--no-images", "--json", "--dump"])
            .arg(&dir),
        0,
    );
    let run = &crate::support::json_lines(out.as_bytes())[0];
    let lost = run["lost"].as_u64().unwrap();
    assert!(lost > 0, "the scheduled run lost nothing: {run}");
    let report = compared(&dir.join("kbuffer"), &[], 1);
    for field in ["captured", "lost", "mismatched_pixels"] {
        assert_eq!(report[field], run[field], "{field}: {report}");
    }
}

#[test]
fn a_misspelt_header_field_is_refused_by_name() {
    // `"capacty"` was ignored, so a typo silently changed how a dump was judged.
    let dir = scratch("sound-unknown-fields");
    render(&dir, &["--scene", SCENE], 48, "mdts", &["--k", "2"]);
    let path = dir.join("mdts");
    let header_file = path.join("dump.json");
    let original: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&header_file).unwrap()).unwrap();
    let mut kept = original.clone();
    kept["extra"] = serde_json::json!({"capacty": 3, "anything": [1, 2]});
    std::fs::write(&header_file, kept.to_string()).unwrap();
    assert_eq!(
        compared(&path, &[], 0)["equal"],
        true,
        "extra holds anything"
    );
    let misspelt: [(&[&str], &str); 4] = [
        (&[], "capacty"),
        (&["scene"], "fov_y_degres"),
        (&["arrays", "slots"], "fileld"),
        (&["layout", "payload"], "prim_bit"),
    ];
    for (at, field) in misspelt {
        let mut header = original.clone();
        header["layout"] = serde_json::json!({"kind": "slots", "order": "pixel-major",
            "payload": {"dtype": "u64", "depth": "f32", "depth_shift": 32, "prim_bits": 32}});
        let mut object = &mut header;
        for key in at {
            object = &mut object[*key];
        }
        object[field] = serde_json::json!(1);
        std::fs::write(&header_file, header.to_string()).unwrap();
        let output = fragsim()
            .args(["compare", "oracle"])
            .arg(&path)
            .arg("--no-image")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{field}: {stderr}");
        assert!(
            stderr.contains(&format!("unknown field `{field}`")),
            "{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

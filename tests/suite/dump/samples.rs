//! Multisampled dumps: the sample count in `scene.conventions.samples`, per-sample
//! MDTS and A-buffer dumps over the sample-expanded framebuffer, and the masked-node A-buffer's
//! dump, through the binary: written by `render --samples 4 --dump`, judged by `compare`.

use std::path::Path;

use super::binary::{fragsim, json_report, stdout_of};
use super::scratch;
use super::soundness::compared;

/// `render --samples 4` of a small scene, with the dumps of `schemes` in `out` and `options`.
fn render_4x(out: &Path, schemes: &str, options: &[&str]) {
    stdout_of(
        fragsim()
            .args([
                "render",
                "--scene",
                "spheres:3",
                "--width",
                "24",
                "--height",
                "18",
            ])
            .args([
                "--samples",
                "4",
                "--k",
                "auto",
                "--capacity",
                "auto",
                "--no-images",
            ])
            .args(["--scheme", schemes, "--dump"])
            .arg(out)
            .args(options),
        0,
    );
}

fn read_words<const N: usize>(path: &Path) -> Vec<[u8; N]> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(N)
        .map(|c| c.try_into().unwrap())
        .collect()
}

fn write_words<const N: usize>(path: &Path, words: &[[u8; N]]) {
    std::fs::write(path, words.concat()).unwrap();
}

#[test]
fn per_sample_and_masked_dumps_round_trip_equal_at_4_samples() {
    let dir = scratch("samples-round-trip");
    render_4x(&dir, "mdts,abuffer,abuffer-masked", &[]);
    for scheme in ["mdts", "abuffer", "abuffer-masked"] {
        let header = std::fs::read_to_string(dir.join(scheme).join("dump.json")).unwrap();
        assert!(header.contains("\"samples\": 4"), "{header}");
        let report = &json_report(&dir.join(scheme), 0)[0];
        assert_eq!(report["equal"], true, "{scheme}: {report}");
        assert_eq!(report["corrupt_words"], 0, "{scheme}");
        assert_eq!(report["unchecked_words"], 0, "{scheme}");
        if scheme == "abuffer-masked" {
            // One list per pixel: 24 × 18.
            assert_eq!(report["pixels"], 432, "{scheme}");
            assert_eq!(report["wrong_masks"], 0, "{scheme}");
        } else {
            assert_eq!(report["pixels"], 432 * 4, "{scheme}");
            assert_eq!(report["per_sample_differing_samples"], 0, "{scheme}");
        }
    }
    // The engine's encodings read back as fragsim's own.
    let engine = dir.join("engine");
    render_4x(
        &engine,
        "mdts,abuffer-masked",
        &[
            "--dump-order",
            "slot-major",
            "--dump-payload",
            "u64:f32:24:24",
        ],
    );
    for scheme in ["mdts", "abuffer-masked"] {
        assert_eq!(
            json_report(&engine.join(scheme), 0)[0]["equal"],
            true,
            "{scheme}"
        );
    }
}

#[test]
fn a_dropped_sample_fragment_a_wrong_mask_bit_and_a_dropped_node_are_different() {
    let dir = scratch("samples-planted");
    render_4x(&dir, "mdts,abuffer-masked", &[]);
    // MDTS per sample: the nearest fragment of the first covered sample dropped (its slots
    // shift down, as if it never arrived: no word rule is broken).
    let k = 6;
    let slots = dir.join("mdts").join("slots.u64");
    let mut words = read_words::<8>(&slots);
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("mdts/dump.json")).unwrap())
            .unwrap();
    assert_eq!(header["k"], k);
    let first = words.iter().position(|w| w != &[0xff; 8]).unwrap();
    let sample = first / k;
    let row = &mut words[sample * k..(sample + 1) * k];
    row.rotate_left(1);
    row[k - 1] = [0xff; 8];
    write_words(&slots, &words);
    let report = &json_report(&dir.join("mdts"), 1)[0];
    assert_eq!(report["per_sample_differing_samples"], 1, "{report}");
    assert_eq!(report["per_sample_differing_pixels"], 1, "{report}");
    assert_eq!(report["lost"], 1, "{report}");

    let masked = dir.join("abuffer-masked");
    let arrays = MaskedArrays::read(&masked);
    arrays.write_wrong_mask();
    let records = json_report(&masked, 1);
    assert_eq!(records[0]["wrong_masks"], 1, "{:?}", records[0]);
    assert_eq!(records[0]["corrupt_words"], 0, "{:?}", records[0]);
    assert_eq!(records[1]["pixel"], arrays.pixel, "{:?}", records[1]);
    arrays.write_lost_node();
    let lost_report = &json_report(&masked, 1)[0];
    assert_eq!(lost_report["lost"], 1, "{lost_report}");
    assert_eq!(lost_report["missing_pixels"], 1, "{lost_report}");
}

/// A masked-node dump's arrays as written, and the first pixel that stored a node: the plants
/// of the tests, each written over the files from the arrays as written (one plant at a time).
struct MaskedArrays {
    dir: std::path::PathBuf,
    counters: Vec<[u8; 4]>,
    masks: Vec<[u8; 4]>,
    nodes: Vec<[u8; 8]>,
    capacity: usize,
    pixel: usize,
}

impl MaskedArrays {
    fn read(dir: &Path) -> Self {
        let counters = read_words::<4>(&dir.join("counters.u32"));
        let masks = read_words::<4>(&dir.join("masks.u32"));
        let nodes = read_words::<8>(&dir.join("nodes.u64"));
        let capacity = masks.len() / counters.len();
        let pixel = counters
            .iter()
            .position(|c| u32::from_le_bytes(*c) > 0)
            .unwrap();
        Self {
            dir: dir.to_path_buf(),
            counters,
            masks,
            nodes,
            capacity,
            pixel,
        }
    }

    /// The slot of the pixel's first node.
    fn first(&self) -> usize {
        self.pixel * self.capacity
    }

    fn write(&self, counters: &[[u8; 4]], masks: &[[u8; 4]], nodes: &[[u8; 8]]) {
        write_words(&self.dir.join("counters.u32"), counters);
        write_words(&self.dir.join("masks.u32"), masks);
        write_words(&self.dir.join("nodes.u64"), nodes);
    }

    /// A wrong mask: samples 0 and 1 swapped in the pixel's first node (a mask of one bit
    /// moves, of two or more changes, never empties).
    fn write_wrong_mask(&self) {
        let mut wrong = self.masks.clone();
        let mask = u32::from_le_bytes(wrong[self.first()]);
        wrong[self.first()] = (if mask == 0b11 { 0b01 } else { mask ^ 0b11 }).to_le_bytes();
        self.write(&self.counters, &wrong, &self.nodes);
    }

    /// A stray key: the pixel's first node at depth 0, in front of every depth the scene can
    /// reach.
    fn write_stray_key(&self) {
        let mut stray = self.nodes.clone();
        stray[self.first()][4..].copy_from_slice(&[0; 4]);
        self.write(&self.counters, &self.masks, &stray);
    }

    /// A lost node: the pixel's last node and mask cleared and its counter one less.
    fn write_lost_node(&self) {
        let count = u32::from_le_bytes(self.counters[self.pixel]);
        let last = self.first() + count as usize - 1;
        let (mut fewer, mut cleared, mut gone) = (
            self.counters.clone(),
            self.masks.clone(),
            self.nodes.clone(),
        );
        fewer[self.pixel] = (count - 1).to_le_bytes();
        cleared[last] = [0; 4];
        gone[last] = [0xff; 8];
        self.write(&fewer, &cleared, &gone);
    }
}

#[test]
fn a_header_with_a_sample_count_without_a_standard_pattern_is_refused_naming_the_field() {
    let dir = scratch("samples-bad-count");
    render_4x(&dir, "mdts", &[]);
    let header_path = dir.join("mdts").join("dump.json");
    let header = std::fs::read_to_string(&header_path).unwrap();
    for bad in ["3", "0", "32"] {
        std::fs::write(
            &header_path,
            header.replace("\"samples\": 4", &format!("\"samples\": {bad}")),
        )
        .unwrap();
        let output = fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("mdts"))
            .arg("--no-images")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{bad}: {stderr}");
        assert!(
            stderr.contains(&format!("conventions \"samples\" {bad}")),
            "{bad}: {stderr}"
        );
    }
    // The masked-node A-buffer at one sample: a node a fragment, each of mask 1, its dump
    // judged against the oracle itself (one sample at the centre).
    let one = scratch("samples-masked-one-sample");
    let output = fragsim()
        .args([
            "render",
            "--scene",
            "spheres:3",
            "--width",
            "8",
            "--height",
            "8",
        ])
        .args(["--scheme", "abuffer-masked", "--no-images", "--dump"])
        .arg(&one)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let compared = fragsim()
        .args(["compare", "oracle"])
        .arg(one.join("abuffer-masked"))
        .arg("--no-images")
        .output()
        .unwrap();
    assert_eq!(compared.status.code(), Some(0), "{compared:?}");
}

#[test]
fn an_f32_masked_node_dump_is_judged_a_sample_at_a_time_and_a_wrong_mask_a_lost_node_or_a_stray_key_is_different(
) {
    let dir = scratch("samples-masked-f32");
    let f32 = ["--vertex-precision", "f32"];
    render_4x(&dir, "abuffer-masked", &f32);
    let masked = dir.join("abuffer-masked");
    let record = compared(&masked, &f32, 0);
    assert_eq!(record["equal"], true, "{record}");
    // Judged a sample at a time, against the per-sample oracle.
    assert_eq!(record["pixels"], 432 * 4, "{record}");
    assert_eq!(record["per_sample_differing_samples"], 0, "{record}");
    assert_eq!(
        record["captured"], record["reference_fragments"],
        "{record}"
    );
    assert!(
        record["precision_max_vertex_error_subpixels"]
            .as_f64()
            .unwrap()
            > 0.0
    );

    let arrays = MaskedArrays::read(&masked);
    arrays.write_wrong_mask();
    let wrong_mask = compared(&masked, &f32, 1);
    assert_eq!(wrong_mask["per_sample_differing_pixels"], 1, "{wrong_mask}");
    arrays.write_stray_key();
    let stray_key = compared(&masked, &f32, 1);
    assert_eq!(stray_key["per_sample_differing_pixels"], 1, "{stray_key}");
    arrays.write_lost_node();
    let lost_node = compared(&masked, &f32, 1);
    assert_eq!(lost_node["per_sample_differing_pixels"], 1, "{lost_node}");
    assert!(lost_node["lost"].as_u64().unwrap() >= 1, "{lost_node}");
}

/// `render`'s row of the masked-node A-buffer and `compare oracle` on the dump of that run give
/// one verdict, at capacities that drop nodes (overflow by design, equal) and at `auto`.
#[test]
fn render_and_compare_agree_on_masked_node_runs_whose_nodes_overflow() {
    for capacity in ["1", "2", "auto"] {
        let dir = scratch(&format!("samples-masked-agree-{capacity}"));
        let stdout = stdout_of(
            fragsim()
                .args(["render", "--scene", "spheres:3", "--width", "24"])
                .args(["--height", "18", "--samples", "4", "--no-images", "--json"])
                .args(["--capacity", capacity, "--scheme", "abuffer-masked"])
                .arg("--dump")
                .arg(&dir),
            0,
        );
        let row = crate::support::json_lines(stdout.as_bytes())
            .into_iter()
            .find(|r| r["scheme"] == "abuffer-masked")
            .unwrap_or_else(|| panic!("no masked row:\n{stdout}"));
        let line = row.to_string();
        let overflowed = row["overflowed"].as_u64().unwrap();
        let compared = fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("abuffer-masked"))
            .arg("--no-images")
            .output()
            .unwrap();
        let equal = compared.status.code() == Some(0);
        let says_equal =
            row["keeps_guarantee"] == true && row["mismatched_pixels"].as_u64() == Some(0);
        assert_eq!(
            says_equal,
            equal,
            "render: {line}\ncompare: {}",
            String::from_utf8_lossy(&compared.stdout)
        );
        assert!(equal, "capacity {capacity}: {line}");
        assert_eq!(overflowed > 0, capacity != "auto", "{line}");
    }
}

//! One dialect of flags across commands: `--no-images` is spelled so everywhere (the
//! older `compare --no-image` still parses), sweep takes it, `sweep --help` lists no flag sweep
//! refuses, every `--help` that offers `--k` shows its default, and bench and sweep write into
//! their own folders and say where.

use std::path::{Path, PathBuf};
use std::process::Output;

use assert_cmd::Command;

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("flag-dialect", name)
}

/// `fragsim args` run in `dir`.
fn fragsim_in(dir: &Path, args: &[&str]) -> Output {
    Command::cargo_bin("fragsim")
        .unwrap()
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn help(command: &str) -> String {
    let output = fragsim_in(Path::new("."), &[command, "--help"]);
    assert!(output.status.success(), "the command failed: {output:?}");
    String::from_utf8(output.stdout).unwrap()
}

/// The files directly in `dir`, sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}

#[test]
fn every_command_that_writes_images_takes_no_images_and_help_shows_defaults() {
    for command in ["render", "bench", "sweep", "compare"] {
        let text = help(command);
        assert!(text.contains("--no-images"), "{command} --help:\n{text}");
        assert!(!text.contains("--no-image "), "{command} --help:\n{text}");
    }
    for command in ["render", "bench", "sweep", "hazard", "conform", "explain"] {
        let text = help(command);
        let k = text
            .split("\n\n")
            .chain(text.lines())
            .find(|block| block.trim_start().starts_with("--k "))
            .unwrap_or_else(|| panic!("{command} --help has no --k:\n{text}"));
        assert!(
            k.contains("default"),
            "{command}'s --k hides its default: {k}"
        );
    }
    // sweep sets the angle itself: --view is not offered, and still refused with the reason.
    let sweep = help("sweep");
    assert!(!sweep.contains("--view"), "{sweep}");
    let refused = fragsim_in(Path::new("."), &["sweep", "--view", "10"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("sweep sets the view angle"));
}

#[test]
fn bench_and_sweep_write_their_own_folders_and_say_where() {
    let dir = scratch("defaults");
    let tiny = [
        "--scene",
        "spheres:2",
        "--width",
        "24",
        "--height",
        "16",
        "--scheme",
        "mdts",
    ];
    let bench = fragsim_in(&dir, &[&["bench", "--frames", "1"], &tiny[..]].concat());
    let sweep = fragsim_in(&dir, &[&["sweep", "--angles", "2"], &tiny[..]].concat());
    for (name, output) in [("bench", &bench), ("sweep", &sweep)] {
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(
            output.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let wrote = format!("wrote {}", Path::new("out").join(name).display());
        assert!(
            stdout.contains(&wrote),
            "{name} does not say where it wrote:\n{stdout}"
        );
    }
    assert!(files(&dir.join("out/bench")).contains(&"bench.jsonl".to_string()));
    assert_eq!(
        files(&dir.join("out/sweep")),
        ["sweep-epr.png", "sweep-speed-accuracy.png", "sweep.jsonl"]
    );
    // sweep --no-images writes its JSON Lines only; under --json the path goes to stderr.
    let bare = dir.join("bare");
    let output = fragsim_in(
        &dir,
        &[
            &[
                "sweep",
                "--angles",
                "2",
                "--no-images",
                "--json",
                "--out",
                "bare",
            ],
            &tiny[..],
        ]
        .concat(),
    );
    assert!(output.status.success());
    assert_eq!(files(&bare), ["sweep.jsonl"]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("wrote bare: sweep.jsonl"));
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert_eq!(
        crate::support::json_lines(stdout.as_bytes()).len(),
        2,
        "{stdout}"
    );
}

#[test]
fn compare_still_takes_the_old_no_image_spelling() {
    let dir = scratch("alias");
    let render = fragsim_in(
        &dir,
        &[
            "render",
            "--scene",
            "spheres:2",
            "--width",
            "16",
            "--height",
            "12",
            "--no-images",
            "--scheme",
            "mdts",
            "--dump",
            "dumps",
        ],
    );
    assert!(render.status.success());
    for flag in ["--no-images", "--no-image"] {
        let output = fragsim_in(&dir, &["compare", "oracle", "dumps/mdts", flag]);
        assert!(
            output.status.success(),
            "{flag}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    assert!(!dir.join("out").exists(), "an image was written");
}

/// `hazard` speaks the others' dialect: percentages in its tables (JSON keeps the fractions, under
/// the JSON Lines' names), a key for every column, the viewport as `width` and `height` apart
/// from the threads in flight, hyphenated file names, and the files it wrote named.
#[test]
fn hazard_prints_percentages_with_a_key_and_names_what_it_wrote() {
    let dir = scratch("hazard");
    let output = fragsim_in(
        &dir,
        &[
            "hazard",
            "--scene",
            "spheres:3",
            "--width",
            "40",
            "--height",
            "30",
            "--threads-in-flight",
            "1,64",
            "--seeds",
            "2",
            "--write-back",
            "render-target",
        ],
    );
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let out = dir.join("out/hazard");
    assert_eq!(
        files(&out),
        [
            "hazard-vs-depth-complexity.png",
            "hazard-vs-width.png",
            "hazard.json",
            "hazard.md"
        ]
    );
    assert!(
        stdout.contains(&format!(
            "wrote {}: hazard.md, hazard.json, hazard-vs-width.png, hazard-vs-depth-complexity.png",
            Path::new("out/hazard").display()
        )),
        "{stdout}"
    );
    let md = std::fs::read_to_string(out.join("hazard.md")).unwrap();
    for key in [
        "**W** threads in flight",
        "**policy**",
        "**per seed**",
        "**write-back**",
        "**dc**",
    ] {
        assert!(md.contains(key), "no key for {key}:\n{md}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("hazard.json")).unwrap()).unwrap();
    assert_eq!(
        (json["width"].as_u64(), json["height"].as_u64()),
        (Some(40), Some(30))
    );
    assert!(json.get("size").is_none(), "{json}");
    // Each table row prints the JSON's fraction as a percentage, per seed too.
    for row in json["rows"].as_array().unwrap() {
        let w = row["threads_in_flight"].as_u64().unwrap();
        let per_seed: Vec<String> = row["mismatched_pixel_rate_per_seed"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| format!("{:.2}", 100.0 * x.as_f64().unwrap()))
            .collect();
        let line = format!(
            "| render-target | {} | {w} | {:.2} | {} |",
            row["policy"].as_str().unwrap(),
            100.0 * row["mismatched_pixel_rate"].as_f64().unwrap(),
            per_seed.join(" ")
        );
        assert!(md.contains(&line), "{line} not in\n{md}");
    }
    assert!(
        json["rows"]
            .as_array()
            .unwrap()
            .iter()
            .any(|r| r["mismatched_pixel_rate"].as_f64() > Some(0.0)),
        "no hazard at 64 threads in flight: the percentages check nothing\n{md}"
    );
}

/// Issue 36's smaller items: at several samples render's header names the pixels and the
/// samples, with the masked A-buffer's line after it; a long scheme name widens its column
/// rather than pushing the rest out of line; bench's terminal table fits a terminal; the figures
/// name their scene, view and scheme.
#[test]
fn tables_stay_aligned_and_name_pixels_and_samples() {
    let dir = scratch("tables");
    let output = fragsim_in(
        &dir,
        &[
            "render",
            "--scene",
            "spheres:2",
            "--width",
            "64",
            "--height",
            "64",
            "--samples",
            "4",
            "--k",
            "auto",
            "--capacity",
            "auto",
            "--scheme",
            "mdts,kbuffer-interlock-ordered-first,abuffer-masked",
        ],
    );
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(
        lines[0].contains("64x64 pixels at 4 samples (256x64 sample lists)"),
        "{stdout}"
    );
    let masked = lines
        .iter()
        .position(|l| l.starts_with("abuffer-masked"))
        .unwrap();
    assert!(
        masked > 2,
        "the masked A-buffer's line comes before the table:\n{stdout}"
    );
    // Every row's columns start where the header's do.
    let header = lines[1];
    let at = header.find("guarantee").unwrap();
    let starts = |line: &str| {
        (
            line[..at].to_owned(),
            line[at..].split_whitespace().next().map(str::to_owned),
        )
    };
    for row in &lines[2..4] {
        let (name, guarantee) = starts(row);
        assert!(name.ends_with(' '), "{row}");
        assert!(
            guarantee.is_some_and(|g| g.starts_with("exact")),
            "{header}\n{row}"
        );
    }
    // bench's terminal table stays within 120 characters.
    let bench = fragsim_in(
        &dir,
        &[
            "bench",
            "--scene",
            "spheres:2",
            "--width",
            "32",
            "--height",
            "24",
            "--frames",
            "1",
            "--scheme",
            "mdts,kbuffer-interlock-ordered-first",
            "--executor",
            "all",
        ],
    );
    let text = String::from_utf8(bench.stdout).unwrap();
    assert!(bench.status.success());
    for line in text
        .lines()
        .filter(|l| l.starts_with("mdts") || l.starts_with("kbuffer"))
    {
        assert!(
            line.chars().count() <= 120,
            "{} characters: {line}",
            line.chars().count()
        );
    }
    // The figures carry a caption strip under the picture and its panel.
    let plain = image::open(dir.join("out/bench/bench-mdts-serial.png")).unwrap();
    let figure = image::open(dir.join("out/bench/bench-mdts-serial-diff.png")).unwrap();
    assert_eq!(
        (plain.width(), plain.height()),
        (32, 24),
        "the effect image stays pixel data"
    );
    assert!(figure.height() > 300, "no caption under the figure");
}

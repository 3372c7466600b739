//! The README against the binary: its command table names every subcommand `fragsim --help`
//! lists, each example of the table runs (at a small size, writing into a scratch folder), and
//! the example output of the main job is what the binary prints, but for the times, the thread
//! count and the racy operation count.

use assert_cmd::Command;

fn readme() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap()
}

/// The subcommands `fragsim --help` lists (clap's `Commands:` section), `help` aside.
fn subcommands() -> Vec<String> {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&output.stdout).into_owned();
    help.lines()
        .skip_while(|line| !line.starts_with("Commands:"))
        .skip(1)
        .take_while(|line| line.starts_with("  "))
        .filter_map(|line| line.split_whitespace().next())
        .filter(|name| *name != "help")
        .map(str::to_string)
        .collect()
}

/// The README's command table: (command, example) of each row.
fn command_table(readme: &str) -> Vec<(String, String)> {
    readme
        .lines()
        .filter(|line| line.starts_with("| `fragsim "))
        .map(|line| {
            let cells: Vec<&str> = line.split(" | ").collect();
            let command = cells[0].trim_start_matches("| ").split('`').nth(1).unwrap();
            let example = cells
                .last()
                .unwrap()
                .trim_end_matches(" |")
                .trim_matches('`');
            (command.to_string(), example.to_string())
        })
        .collect()
}

#[test]
fn the_readme_table_names_every_subcommand_and_the_json_schema() {
    let readme = readme();
    let table: Vec<String> = command_table(&readme).into_iter().map(|(c, _)| c).collect();
    let subcommands = subcommands();
    assert!(subcommands.len() >= 8, "{subcommands:?}");
    for name in &subcommands {
        let command = format!("fragsim {name}");
        assert!(
            table.contains(&command),
            "the README's table lacks {command:?}: {table:?}"
        );
    }
    assert!(
        readme.contains("docs/json-schema.md"),
        "README lacks the JSON schema"
    );
}

/// Each example of the README's table, run as written but smaller (64 × 64 where the command
/// takes a scene) and writing under `dir`: it succeeds. `conform` needs a backend of the
/// reader's, so only its flags are checked.
#[test]
fn the_readme_table_examples_run() {
    let dir = crate::support::scratch("readme", "examples");
    let dir_text = dir.to_str().unwrap();
    // `compare oracle out/dumps/mdts` reads what a render with --dump wrote there.
    let dumped = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "--scheme",
            "mdts",
            "--width",
            "64",
            "--height",
            "64",
            "--no-images",
        ])
        .args(["--out", dir_text, "--dump"])
        .arg(dir.join("dumps"))
        .output()
        .unwrap();
    assert!(
        dumped.status.success(),
        "{}",
        String::from_utf8_lossy(&dumped.stderr)
    );
    for (command, example) in command_table(&readme()) {
        let words: Vec<String> = example
            .split_whitespace()
            .skip(1)
            .map(|word| match word.strip_prefix("out/") {
                Some(rest) => format!("{dir_text}/{rest}"),
                None => word.to_string(),
            })
            .collect();
        let subcommand = command.trim_start_matches("fragsim ");
        if subcommand == "conform" {
            let help = Command::cargo_bin("fragsim")
                .unwrap()
                .args(["conform", "--help"])
                .output()
                .unwrap();
            let help = String::from_utf8_lossy(&help.stdout);
            for flag in words.iter().filter(|w| w.starts_with("--")) {
                assert!(help.contains(flag.as_str()), "conform --help lacks {flag}");
            }
            continue;
        }
        let mut run = Command::cargo_bin("fragsim").unwrap();
        run.current_dir(&dir).args(&words);
        if !matches!(subcommand, "compare" | "explain") {
            run.args(["--width", "64", "--height", "64"]);
        }
        if !words.iter().any(|w| w == "--out") && !matches!(subcommand, "compare" | "explain") {
            run.args(["--out", dir_text]);
        }
        let output = run.output().unwrap();
        assert!(
            output.status.success(),
            "{example}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        assert!(!output.stdout.is_empty(), "{example} printed nothing");
    }
}

/// The README's example of `cargo run --release` line for line: the scene line but for the
/// oracle's time, the heading line exactly (its headings hold single spaces, so it is compared
/// whole), and every row's words but the times, the threads and the operation count.
#[test]
fn the_readme_example_output_is_what_the_main_job_prints() {
    let readme = readme();
    let block = readme
        .split_once("Example (`cargo run --release`")
        .and_then(|(_, rest)| rest.split_once("```\n"))
        .and_then(|(_, rest)| rest.split_once("```"))
        .map(|(block, _)| block)
        .expect("the README's example block");
    let dir = crate::support::scratch("readme", "main-job");
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["--no-images", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let printed = String::from_utf8_lossy(&output.stdout).into_owned();
    let expected: Vec<&str> = block.lines().collect();
    let got: Vec<&str> = printed.lines().collect();
    assert_eq!(
        expected.len(),
        got.len(),
        "README:\n{block}\nbinary:\n{printed}"
    );
    let before_time = |line: &str| {
        line.split(" (oracle")
            .next()
            .unwrap_or_default()
            .to_string()
    };
    assert_eq!(
        before_time(expected[0]),
        before_time(got[0]),
        "the scene line"
    );
    assert_eq!(expected[1], got[1], "the heading line");
    // Columns 3 (threads), 8 (time ms) and the last (mem ops: the parallel atomicMin walks
    // depend on the interleaving) vary from machine to machine and run to run.
    let steady = |line: &str| -> Vec<String> {
        let words: Vec<&str> = line.split_whitespace().collect();
        let last = words.len() - 1;
        words
            .iter()
            .enumerate()
            .filter(|(i, _)| ![3, 8, last].contains(i))
            .map(|(_, w)| (*w).to_string())
            .collect()
    };
    for (readme_row, binary_row) in expected[2..].iter().zip(&got[2..]) {
        assert_eq!(
            steady(readme_row),
            steady(binary_row),
            "{readme_row}\n{binary_row}"
        );
    }
}

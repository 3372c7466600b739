//! Issue 20, item 3: progress on long work, and the memory cap over the oracle's own storage.
//!
//! A progress bar is drawn on stderr when it is a terminal (the test runs `sweep` under a pty
//! made by `script`) and never when stderr is piped or `--quiet` is given. A scene whose oracle
//! would exceed the memory cap is refused before the work, fast, with the bytes it needs.

use std::time::{Duration, Instant};

use assert_cmd::cargo::CommandCargoExt;
use assert_cmd::Command;

/// A sweep long enough (several hundred ms: 24 views of the bunny's 69,451 triangles) for the
/// bar to be drawn more than once.
const SWEEP: [&str; 11] = [
    "sweep", "--width", "48", "--height", "48", "--angles", "24", "--scheme", "mdts", "--out", "",
];

fn sweep_args(out: &std::path::Path) -> Vec<String> {
    let mut args: Vec<String> = SWEEP.iter().map(|s| (*s).to_string()).collect();
    *args.last_mut().unwrap() = out.display().to_string();
    args
}

/// `fragsim ARGS` under a pseudo-terminal (`script -qc … /dev/null`): what the terminal saw.
fn on_a_terminal(args: &[String]) -> String {
    let binary = std::process::Command::cargo_bin("fragsim").unwrap();
    let line = std::iter::once(binary.get_program().to_string_lossy().into_owned())
        .chain(args.iter().cloned())
        .collect::<Vec<_>>()
        .join(" ");
    let output = std::process::Command::new("script")
        .args(["-qec", &line, "/dev/null"])
        .output()
        .expect("`script` (util-linux) runs the command under a pty");
    assert!(output.status.success(), "{line}: {output:?}");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn sweep_draws_a_bar_on_a_terminal_and_none_when_piped_or_quiet() {
    let out = std::env::temp_dir().join(format!("fragsim-progress-{}", std::process::id()));
    let args = sweep_args(&out);
    let terminal = on_a_terminal(&args);
    // The bar: its prefix and its position out of the 24 angles.
    assert!(
        terminal.contains("sweep") && terminal.contains("/24"),
        "{terminal}"
    );
    // The table still reaches the terminal.
    assert!(terminal.contains("mean EPR %"), "{terminal}");

    let mut quiet = args.clone();
    quiet.push("--quiet".into());
    let quiet_terminal = on_a_terminal(&quiet);
    assert!(!quiet_terminal.contains("/24"), "{quiet_terminal}");
    assert!(quiet_terminal.contains("mean EPR %"), "{quiet_terminal}");

    let piped = Command::cargo_bin("fragsim")
        .unwrap()
        .args(&args)
        .output()
        .unwrap();
    assert!(piped.status.success());
    let stderr = String::from_utf8_lossy(&piped.stderr);
    assert!(!stderr.contains("/24"), "{stderr}");
    assert!(String::from_utf8_lossy(&piped.stdout).contains("mean EPR %"));
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn an_oracle_beyond_the_memory_cap_is_refused_fast_with_the_bytes_it_needs() {
    // 20,000 coincident triangles, both windings (none culled), each covering about half of
    // the 512 × 512 view: billions of fragments, tens of gigabytes of oracle lists.
    let mut obj = String::from("v -1 -1 0\nv 1 -1 0\nv 1 1 0\n");
    for _ in 0..10_000 {
        obj.push_str("f 1 2 3\nf 1 3 2\n");
    }
    let dir = std::env::temp_dir().join(format!("fragsim-progress-cap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("coincident.obj");
    std::fs::write(&path, obj).unwrap();
    let start = Instant::now();
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["--no-images", "--mesh"])
        .arg(&path)
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    let took = start.elapsed();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the oracle of this view would need up to"),
        "{stderr}"
    );
    assert!(
        stderr.contains("over the memory cap of 4294967296 bytes"),
        "{stderr}"
    );
    // The bytes named exceed the cap: the number before " bytes (up to".
    let bytes: u64 = stderr
        .split("need up to ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no byte count in {stderr}"));
    assert!(bytes > 4 << 30, "{bytes}");
    // Refused before the work: well under the time rasterizing billions of fragments takes.
    assert!(took < Duration::from_secs(10), "{took:?}");
    let _ = std::fs::remove_dir_all(dir);
}

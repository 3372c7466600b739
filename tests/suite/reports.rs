//! What the reports tell a user, through the binary: each case a new user met that misled or
//! stopped them, redone as they did it.

use assert_cmd::Command;

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

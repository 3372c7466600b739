//! The battery's header family: each layout's dump of the battery scene written to disk, its
//! header then made to say two things, or a thing its layout cannot mean (an array it does not
//! use or another layout's, a scene with both a name and a mesh, fixed storage beside a counting
//! pass's offsets, a shape that fits only transposed, list numbering that names a node `null` or
//! passes 2^32), and judged through the binary exactly and within the precision of an f32 vertex
//! stage. None may be judged at all: each must be refused by name (exit 2, one line naming the
//! field), where the unedited dump is EQUAL under both judges (`docs/dump-format.md`, "the fields
//! that contradict one another are refused by name").

use std::path::Path;

use fragsim::catalog::SchemeName;
use fragsim::dump::Direction;
use fragsim::dump::{Dump, DumpScheme, LayoutSpec, Payload, SlotOrder};
use fragsim::oracle::Oracle;
use fragsim::raster::scene_spec::SceneSpec;
use fragsim::raster::Viewport;
use serde_json::{json, Value};

use super::super::binary::fragsim;
use super::super::bounded_input::edit_header;
use super::{scene_file, scratch, table, Tally, CAPACITY, K};

/// A way to make a header contradict itself.
#[derive(Clone, Copy, Debug)]
enum Conflict {
    /// An array no layout uses.
    UnusedArray,
    /// An array of another layout (`heads` beside slots, `slots` beside lists).
    ForeignArray,
    /// A scene with both a `name` and a `mesh`.
    NameAndMesh,
    /// Fixed storage (`capacity`) and a counting pass's `offsets`, whichever the dump lacked.
    CapacityAndOffsets,
    /// The slot or layer array's shape reversed.
    Transposed,
    /// A linked list's `null` equal to its first node's number.
    NullIsANode,
    /// A linked list's nodes numbered past 2^32.
    NumberingPast32Bits,
}

const CONFLICTS: [Conflict; 7] = [
    Conflict::UnusedArray,
    Conflict::ForeignArray,
    Conflict::NameAndMesh,
    Conflict::CapacityAndOffsets,
    Conflict::Transposed,
    Conflict::NullIsANode,
    Conflict::NumberingPast32Bits,
];

impl Conflict {
    fn name(self) -> &'static str {
        match self {
            Self::UnusedArray => "unused-array",
            Self::ForeignArray => "foreign-array",
            Self::NameAndMesh => "name-and-mesh",
            Self::CapacityAndOffsets => "capacity-offsets",
            Self::Transposed => "transposed",
            Self::NullIsANode => "null-is-a-node",
            Self::NumberingPast32Bits => "nodes-past-2^32",
        }
    }

    /// Edits the header in `dir` (writing any array file it names); returns what the refusal
    /// must name, or `None` where the conflict has no meaning for the layout.
    fn apply(self, dir: &Path, header: &Value) -> Option<&'static str> {
        let arrays = header["arrays"].as_object().unwrap();
        let words_file = |name: &str, count: usize| {
            std::fs::write(dir.join(name), vec![0_u8; 4 * count]).unwrap();
        };
        match self {
            Self::UnusedArray => {
                words_file("junk.u32", 1);
                edit_header(dir, |h| {
                    h["arrays"]["junk"] = json!({"file": "junk.u32", "dtype": "u32", "shape": [1]});
                });
                Some("array \"junk\"")
            }
            Self::ForeignArray => {
                let (name, text) = if arrays.contains_key("heads") {
                    ("slots", "array \"slots\"")
                } else {
                    ("heads", "array \"heads\"")
                };
                words_file("foreign.u32", 1);
                edit_header(dir, |h| {
                    h["arrays"][name] =
                        json!({"file": "foreign.u32", "dtype": "u32", "shape": [1]});
                });
                Some(text)
            }
            Self::NameAndMesh => {
                edit_header(dir, |h| h["scene"]["name"] = "spheres:3".into());
                Some("both \"name\"")
            }
            Self::CapacityAndOffsets => {
                if arrays.contains_key("offsets") {
                    edit_header(dir, |h| h["capacity"] = CAPACITY.into());
                } else if header.get("capacity").is_some() && arrays.contains_key("slots") {
                    let pixels =
                        header["width"].as_u64().unwrap() * header["height"].as_u64().unwrap();
                    let count = usize::try_from(pixels).expect("a test viewport's pixels") + 1;
                    words_file("offsets.u32", count);
                    edit_header(dir, |h| {
                        h["arrays"]["offsets"] =
                            json!({"file": "offsets.u32", "dtype": "u32", "shape": [count]});
                    });
                } else {
                    return None;
                }
                Some("not both")
            }
            Self::Transposed => {
                let name = ["slots", "layers"].into_iter().find(|name| {
                    arrays
                        .get(*name)
                        .is_some_and(|a| a["shape"].as_array().unwrap().len() == 2)
                })?;
                edit_header(dir, |h| {
                    let shape = h["arrays"][name]["shape"].as_array_mut().unwrap();
                    shape.reverse();
                });
                Some("looks transposed")
            }
            Self::NullIsANode => {
                let base = header["layout"].get("node_base")?.as_u64().unwrap();
                edit_header(dir, |h| h["layout"]["null"] = base.into());
                Some("is the number of a node")
            }
            Self::NumberingPast32Bits => {
                header["layout"].get("node_base")?;
                edit_header(dir, |h| {
                    h["layout"]["null"] = 0.into();
                    h["layout"]["node_base"] = u32::MAX.into();
                });
                Some("pass 2^32")
            }
        }
    }
}

/// `fragsim compare oracle DIR --no-images` with `options`: its exit code and its output.
fn compare(dir: &Path, options: &[&str]) -> (Option<i32>, String) {
    let output = fragsim()
        .args(["compare", "oracle"])
        .arg(dir)
        .arg("--no-images")
        .args(options)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout).into_owned()
        + &String::from_utf8_lossy(&output.stderr);
    (output.status.code(), text)
}

/// The judges: bit for bit, and within the precision of an f32 vertex stage.
const JUDGES: [(&str, &[&str]); 2] = [("exact", &[]), ("f32", &["--vertex-precision", "f32"])];

#[test]
fn header_conflicts_are_refused_by_name_exactly_and_under_f32() {
    let dir = scratch("mutation-battery-header");
    let mesh = scene_file(&dir);
    let spec = SceneSpec::mesh(&mesh, 30.0, 15.0);
    let scene = spec.load(None).unwrap();
    let view = spec.view(&scene, Viewport::new(48, 36).unwrap()).unwrap();
    let oracle = Oracle::build(&view);
    let lists = DumpScheme::LinkedLists {
        scheme: SchemeName::LinkedList,
        k: K,
        pool: u32::try_from(oracle.fragments()).expect("a 48 × 36 view's fragments"),
        spec: LayoutSpec::FRAGSIM_LISTS,
    };
    let mdts = DumpScheme::Mdts {
        k: K,
        direction: Direction::Ascending,
    };
    let layouts: [(&str, DumpScheme, Option<LayoutSpec>); 6] = [
        ("mdts", mdts.clone(), None),
        (
            "mdts-slotmaj",
            mdts,
            Some(LayoutSpec::Slots {
                order: SlotOrder::SlotMajor,
                payload: None,
            }),
        ),
        (
            "abuffer",
            DumpScheme::ABufferFixed {
                capacity: CAPACITY,
                sorted: false,
            },
            None,
        ),
        (
            "abuffer-offs",
            DumpScheme::ABufferExact {
                counts: oracle.depth_complexity(),
                sorted: false,
            },
            None,
        ),
        (
            "list-engine",
            lists,
            Some(LayoutSpec::LinkedList {
                payload: Payload::FRAGMENT,
                null: u32::MAX,
                node_base: 0,
            }),
        ),
        (
            "layer-major",
            DumpScheme::LayerMajor {
                k: K,
                payload: Payload::FRAGMENT,
            },
            None,
        ),
    ];
    let names: Vec<&str> = layouts.iter().map(|(name, ..)| *name).collect();
    let (mut tallies, mut wrong) = (Vec::new(), Vec::new());
    for (name, scheme, encoding) in layouts {
        let dump = Dump::record(&view, spec.clone(), &scheme, "battery")
            .unwrap()
            .in_layout(encoding)
            .unwrap();
        let unedited = dir.join(name);
        dump.write(&unedited).unwrap();
        for (judge, options) in JUDGES {
            let (code, text) = compare(&unedited, options);
            assert!(
                code == Some(0) && text.contains("EQUAL"),
                "{name} unedited, {judge}: {text}"
            );
        }
        let header: Value =
            serde_json::from_str(&std::fs::read_to_string(unedited.join("dump.json")).unwrap())
                .unwrap();
        for conflict in CONFLICTS {
            let edited = dir.join(format!("{name}-{}", conflict.name()));
            dump.write(&edited).unwrap();
            let Some(named) = conflict.apply(&edited, &header) else {
                continue;
            };
            for (judge, options) in JUDGES {
                let (code, text) = compare(&edited, options);
                let refused =
                    code == Some(2) && text.trim_end().lines().count() == 1 && text.contains(named);
                if !refused {
                    wrong.push(format!(
                        "{name} {}, {judge}: exit {code:?}, expected a refusal naming {named:?}: {text}",
                        conflict.name()
                    ));
                }
                tallies.push(Tally {
                    kind: conflict.name().to_string(),
                    layout: name,
                    judge,
                    right: usize::from(refused),
                    tried: 1,
                    conforming: false,
                });
            }
        }
    }
    println!(
        "header conflicts: refused by name / tried, exactly then under f32\n{}",
        table(&names, &tallies)
    );
    assert!(tallies.len() >= 40, "{} judgements", tallies.len());
    assert!(wrong.is_empty(), "accepted or misnamed: {wrong:#?}");
}

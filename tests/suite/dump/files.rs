//! Dumps through files: every layout round-trips and decodes to what its scheme promises, a dump
//! written by hand as a GPU backend writes it is read, malformed dumps are clear errors, and the
//! triangle export round-trips.

use std::path::Path;

use fragsim::capture::{Capacity, Keeps};
use fragsim::dump::triangles::TriangleExport;
use fragsim::dump::Direction;
use fragsim::dump::{Dtype, Dump, DumpScheme};
use fragsim::oracle::compare;
use fragsim::oracle::Oracle;
use fragsim::raster::scene_spec::SceneSpec;
use fragsim::raster::{OrbitCamera, Scene, Viewport};

use super::{every_layout, judged, scratch, spec, with_view, HEIGHT, SCENE, WIDTH};

#[test]
fn every_layout_round_trips_through_files_and_decodes_to_what_its_scheme_promises() {
    with_view(|view, oracle| {
        for (i, scheme) in every_layout(oracle).iter().enumerate() {
            let dump = Dump::record(view, spec(), scheme, "test").unwrap();
            let dir = scratch(&format!("round-trip-{i}"));
            dump.write(&dir).unwrap();
            let back = Dump::read(&dir).unwrap();
            assert_eq!(back, dump, "{scheme:?}");
            assert_eq!(Dump::read(&dir.join("dump.json")).unwrap(), dump);
            assert_eq!(back.scheme().unwrap(), *scheme);
            let capture = back.capture().unwrap();
            let diff = oracle.diff(&capture);
            assert!(diff.is_exact(), "{scheme:?}: {diff:?}");
            let comparison = compare::compare(oracle, &capture, 0, 4);
            assert!(comparison.is_equal());
            assert_eq!(comparison.diff.captured, diff.captured);
            assert_eq!(comparison.diff.overflowed, diff.overflowed);
            assert_eq!(comparison.counts.equal, u64::from(WIDTH * HEIGHT));
            // Every word read: fragsim's own memory breaks no rule of its layout.
            let words = back.check_words().unwrap();
            assert_eq!(
                (words.corrupt_words(), words.unchecked),
                (0, 0),
                "{scheme:?}"
            );
            let whole = judged(&back, oracle);
            assert!(whole.is_equal() && whole.words_checked, "{scheme:?}");
            // Storage that discards uncounted claims none; the oracle predicts it.
            let uncounted = matches!(
                capture.keeps,
                Keeps::All {
                    capacity: Capacity::PerPixelUncounted(_),
                    ..
                }
            );
            let claimed = if uncounted { 0 } else { diff.overflowed };
            assert_eq!(whole.claimed_overflow, claimed, "{scheme:?}");
        }
    });
}

#[test]
fn a_dump_written_by_hand_as_a_gpu_backend_writes_it_is_read_and_judged() {
    with_view(|_, oracle| {
        // What a CUDA or NumPy writer produces: the MDTS words of every pixel, K slots, empty = all
        // ones, raw little-endian, and a header typed by hand (NumPy dtype names, an extra field).
        let k = oracle.max_depth_complexity() as usize;
        let pixels = (WIDTH * HEIGHT) as usize;
        let mut bytes = Vec::new();
        for p in 0..pixels {
            let list = oracle.pixel(p);
            for slot in 0..k {
                bytes.extend_from_slice(&list.get(slot).copied().unwrap_or(u64::MAX).to_le_bytes());
            }
        }
        let dir = scratch("by-hand");
        std::fs::write(dir.join("words.bin"), &bytes).unwrap();
        let header = format!(
            r#"{{"format": "fragsim-dump", "version": 1, "producer": "numpy",
                "scene": {{"name": "{SCENE}", "view_degrees": 30, "elevation_degrees": 15}},
                "width": {WIDTH}, "height": {HEIGHT}, "scheme": "mdts", "k": {k},
                "arrays": {{"slots": {{"file": "words.bin", "dtype": "<u8", "shape": [{pixels}, {k}]}}}},
                "extra": {{"kernel_ms": 0.25, "something_new": true}}}}"#
        );
        std::fs::write(dir.join("dump.json"), header).unwrap();
        let dump = Dump::read(&dir).unwrap();
        assert_eq!(dump.header.arrays["slots"].dtype, Dtype::U64);
        assert_eq!(dump.header.scene, spec(), "defaults fill the camera");
        assert!(oracle.diff(&dump.capture().unwrap()).is_exact());
    });
}

#[test]
fn malformed_dumps_are_clear_errors() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let good = Dump::record(view, spec(), &scheme, "test").unwrap();
        let cases: Vec<(&str, Breaker<'_>)> = vec![
            (
                "version",
                Box::new(|d: &Path| edit_header(d, "\"version\": 1", "\"version\": 9")),
            ),
            (
                "elements",
                Box::new(|d: &Path| {
                    let f = d.join("slots.u64");
                    let mut b = std::fs::read(&f).unwrap();
                    b.truncate(b.len() - 8);
                    std::fs::write(f, b).unwrap();
                }),
            ),
            (
                "cannot read",
                Box::new(|d: &Path| std::fs::remove_file(d.join("slots.u64")).unwrap()),
            ),
            (
                "unknown scheme",
                Box::new(|d: &Path| edit_header(d, "\"scheme\": \"mdts\"", "\"scheme\": \"zbuf\"")),
            ),
            (
                "needs \"k\"",
                Box::new(|d: &Path| edit_header(d, &format!("\"k\": {k}"), "\"k\": 0")),
            ),
            (
                "\"width\" 24 × \"height\" 36",
                Box::new(|d: &Path| edit_header(d, "\"width\": 48", "\"width\": 24")),
            ),
        ];
        for (i, (message, break_it)) in cases.iter().enumerate() {
            let dir = scratch(&format!("malformed-{i}"));
            good.write(&dir).unwrap();
            break_it(&dir);
            let error = Dump::read(&dir)
                .and_then(|d| d.capture())
                .expect_err(message)
                .to_string();
            assert!(error.contains(message), "{message:?} not in {error:?}");
        }
    });
}

/// Damages a dump directory in one way.
type Breaker<'a> = Box<dyn Fn(&Path) + 'a>;

fn edit_header(dir: &Path, from: &str, to: &str) {
    let path = dir.join("dump.json");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from:?} not in {text}");
    std::fs::write(path, text.replace(from, to)).unwrap();
}

#[test]
fn the_triangle_export_round_trips_and_rescanning_it_reproduces_the_oracle() {
    for (scene, camera) in [
        (SCENE, OrbitCamera::default().at_angle(30.0)),
        // Close enough that triangles cross the near plane: clipped pieces keep their prim.
        (
            "quads:3",
            OrbitCamera {
                distance_scale: 0.3,
                ..OrbitCamera::default()
            },
        ),
    ] {
        let mesh = Scene::procedural(scene).unwrap();
        let view = mesh
            .view(Viewport::new(WIDTH, HEIGHT).unwrap(), &camera)
            .unwrap();
        let oracle = Oracle::build(&view);
        let export =
            TriangleExport::from_view(&view, SceneSpec::named(scene, camera.angle_degrees, 15.0));
        let bytes = export.to_bytes().unwrap();
        assert_eq!(&bytes[..8], b"FRAGTRI1");
        assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), WIDTH);
        assert_eq!(
            u32::from_le_bytes(bytes[16..20].try_into().unwrap()),
            HEIGHT
        );
        let count = u32::from_le_bytes(bytes[28..32].try_into().unwrap()) as usize;
        assert_eq!(count, export.triangles.len());
        assert_eq!((bytes.len() - 40) % 8, 0);
        assert_eq!(TriangleExport::from_bytes(&bytes).unwrap(), export);
        let mut lists = vec![Vec::new(); oracle.pixels()];
        for t in &export.triangles {
            view.scan(t, &mut |f| lists[f.pixel as usize].push(f.packed()));
        }
        for (p, list) in lists.iter_mut().enumerate() {
            list.sort_unstable();
            assert_eq!(list.as_slice(), oracle.pixel(p), "{scene}: pixel {p}");
        }
        assert!(TriangleExport::from_bytes(&bytes[..bytes.len() - 1]).is_err());
    }
}

//! The scene a dump names is the engine's: an explicit view-projection matrix and the
//! conventions round-trip through a header to their bits, `compare` rebuilds the view under them,
//! and the mesh is named by path and content hash, so that a different file is refused and a
//! dump that travelled finds its mesh again with `--mesh`.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use fragsim::dump::Direction;
use fragsim::dump::{Dump, DumpScheme};
use fragsim::oracle::compare::CompareOptions;
use fragsim::oracle::verdict::JudgeDump;
use fragsim::oracle::Oracle;
use fragsim::raster::scene_spec::{mesh_hash, SceneSpec, ViewProjection};
use fragsim::raster::{
    Conventions, DepthRange, OrbitCamera, Scene, VertexPrecision, Viewport, WindowOrigin,
};

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("conventions-tests", name)
}

/// OpenGL's conventions with an f32 vertex stage: every field away from the reference but the
/// sample count (one sample: these tests judge pixel centres).
const GL_F32: Conventions = Conventions {
    window_origin: WindowOrigin::LowerLeft,
    subpixel_bits: 4,
    depth_range: DepthRange::MinusOneToOne,
    vertex_precision: VertexPrecision::F32,
    samples: 1,
    edge_ties: None,
};

const VIEWPORT: (u32, u32) = (40, 28);

/// `spheres:3` as a GL engine would name it: the orbit's GL matrix, rounded to f32 as a uniform,
/// given explicitly.
fn engine_spec(scene: &Scene) -> SceneSpec {
    let viewport = Viewport::new(VIEWPORT.0, VIEWPORT.1).unwrap();
    let orbit = OrbitCamera::default().at_angle(30.0);
    let camera = scene.orbit_camera(viewport, &orbit, DepthRange::MinusOneToOne);
    #[expect(
        clippy::cast_possible_truncation,
        reason = "narrowing is the point: the engine's matrix is the camera's rounded to f32"
    )]
    let row_major = camera.row_major().map(|v| f64::from(v as f32));
    SceneSpec {
        view_projection: Some(ViewProjection {
            row_major,
            precision: VertexPrecision::F32,
        }),
        conventions: GL_F32,
        ..SceneSpec::named("spheres:3", 0.0, 0.0)
    }
}

/// The MDTS dump of the view `spec` names, recorded by fragsim (a correct engine capture).
fn engine_dump(spec: &SceneSpec) -> (Dump, Oracle) {
    let scene = spec.load(None).unwrap();
    let view = spec
        .view(&scene, Viewport::new(VIEWPORT.0, VIEWPORT.1).unwrap())
        .unwrap();
    let oracle = Oracle::build(&view);
    let scheme = DumpScheme::Mdts {
        k: oracle.max_depth_complexity(),
        direction: Direction::Ascending,
    };
    let dump = Dump::record(&view, spec.clone(), &scheme, "test").unwrap();
    (dump, oracle)
}

fn reparsed(dump: &Dump) -> Dump {
    let (text, files) = dump.encode().unwrap();
    Dump::parse("dump.json", text.as_bytes(), |file| {
        Ok(files.get(file).cloned().unwrap_or_default())
    })
    .unwrap()
}

#[test]
fn the_matrix_and_the_conventions_round_trip_to_their_bits() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let mut spec = engine_spec(&scene);
    // f64 entries JSON must keep exactly: a third, a subnormal, a negative zero, the largest.
    let mut matrix = spec.view_projection.unwrap();
    matrix.precision = VertexPrecision::F64;
    matrix.row_major[1] = 1.0 / 3.0;
    matrix.row_major[12] = -0.0;
    matrix.row_major[13] = 5e-324;
    matrix.row_major[14] = f64::MAX * 1e-300;
    spec.view_projection = Some(matrix);
    // An f32 vertex stage refuses the subnormal entry's products (they leave f32's normal
    // range): the round trip is the header's, so the stage is f64's here.
    spec.conventions.vertex_precision = VertexPrecision::F64;
    let (dump, _) = engine_dump(&spec);
    let (text, _) = dump.encode().unwrap();
    assert!(
        text.contains("\"lower-left\"") && text.contains("\"minus-one-to-one\""),
        "{text}"
    );
    let again = reparsed(&dump);
    let bits = |s: &SceneSpec| s.view_projection.unwrap().row_major.map(f64::to_bits);
    assert_eq!(bits(&again.header.scene), bits(&spec));
    assert_eq!(again.header.scene.conventions, spec.conventions);
    assert_eq!(again, dump);
}

#[test]
fn a_header_without_conventions_reads_as_the_reference() {
    let spec = SceneSpec::named("spheres:3", 30.0, 15.0);
    let (dump, _) = engine_dump(&spec);
    let (text, _) = dump.encode().unwrap();
    assert!(
        !text.contains("conventions") && !text.contains("view_projection"),
        "{text}"
    );
    assert_eq!(
        reparsed(&dump).header.scene.conventions,
        Conventions::REFERENCE
    );
}

#[test]
fn an_f32_matrix_holds_the_nearest_f32s_and_refuses_what_f32_cannot_hold() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let viewport = Viewport::new(VIEWPORT.0, VIEWPORT.1).unwrap();
    let mut spec = engine_spec(&scene);
    // "0.1", the shortest decimal of the f32 0.1, names that f32, not the f64 0.1.
    if let Some(matrix) = &mut spec.view_projection {
        matrix.row_major[5] = 0.1;
    }
    let camera = spec.camera(&scene, viewport).unwrap();
    assert_eq!(camera.row_major()[5], f64::from(0.1_f32));
    for (bad, reason) in [(1e39, "f32's normal range"), (f64::NAN, "finite")] {
        if let Some(matrix) = &mut spec.view_projection {
            matrix.row_major[5] = bad;
        }
        let error = spec.check_finite().unwrap_err().to_string();
        assert!(
            error.contains("row_major[5]") && error.contains(reason),
            "{error}"
        );
    }
}

#[test]
fn the_oracle_a_dump_names_is_built_under_its_matrix_and_conventions() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let (dump, _) = engine_dump(&engine_spec(&scene));
    let header = reparsed(&dump).header;
    let viewport = Viewport::new(header.width, header.height).unwrap();
    let options = CompareOptions::default();
    let rebuilt = Oracle::build(&header.scene.view(&scene, viewport).unwrap());
    assert!(dump.compare(&rebuilt, &options).unwrap().is_equal());
    // The same matrix under the reference conventions is another picture: the conventions are
    // what makes it equal.
    let reference = SceneSpec {
        conventions: Conventions::REFERENCE,
        ..header.scene.clone()
    };
    let other = Oracle::build(&reference.view(&scene, viewport).unwrap());
    assert!(!dump.compare(&other, &options).unwrap().is_equal());
}

fn fragsim() -> Command {
    Command::cargo_bin("fragsim").unwrap()
}

/// Runs `command`, asserts its exit code, returns stdout and stderr.
fn run(command: &mut Command, code: i32) -> String {
    let output = command.output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert_eq!(output.status.code(), Some(code), "{text}");
    text
}

#[test]
fn compare_oracle_rebuilds_the_engine_scene_through_the_binary() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let (dump, _) = engine_dump(&engine_spec(&scene));
    let dir = scratch("engine");
    dump.write(&dir.join("mdts")).unwrap();
    let text = run(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("mdts"))
            .arg("--no-images"),
        0,
    );
    assert!(text.contains("EQUAL"), "{text}");
}

#[test]
fn the_mesh_hash_is_fnv1a_64_of_the_bytes() {
    // The published FNV-1a 64 test vectors of "" and "a".
    assert_eq!(mesh_hash(b""), "fnv1a64:cbf29ce484222325");
    assert_eq!(mesh_hash(b"a"), "fnv1a64:af63dc4c8601ec8c");
}

const TETRAHEDRON: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";

#[test]
fn a_mesh_whose_bytes_hash_otherwise_is_refused() {
    let dir = scratch("hash");
    let path = dir.join("tetra.obj");
    std::fs::write(&path, TETRAHEDRON).unwrap();
    let spec = SceneSpec::hashed_mesh(&path, 30.0, 15.0).unwrap();
    let expected = mesh_hash(TETRAHEDRON.as_bytes());
    assert_eq!(spec.mesh_hash.as_deref(), Some(expected.as_str()));
    assert!(spec.load(None).is_ok());
    std::fs::write(&path, format!("# re-exported\n{TETRAHEDRON}")).unwrap();
    let error = spec.load(None).unwrap_err().to_string();
    assert!(
        error.contains(&expected) && error.contains("--mesh"),
        "{error}"
    );
}

#[test]
fn a_relative_mesh_found_nowhere_names_both_places() {
    let dir = scratch("nowhere");
    let spec = SceneSpec::mesh(Path::new("no-such-mesh.obj"), 30.0, 15.0);
    let error = spec.load(Some(&dir)).unwrap_err().to_string();
    let cwd = std::env::current_dir().unwrap();
    for place in [
        cwd.display().to_string(),
        dir.join("no-such-mesh.obj").display().to_string(),
    ] {
        assert!(error.contains(&place), "{place} not in {error}");
    }
}

#[test]
fn a_dump_that_travelled_finds_its_mesh_with_compare_mesh() {
    let dir = scratch("travel");
    let home = dir.join("home");
    std::fs::create_dir_all(&home).unwrap();
    std::fs::write(home.join("tetra.obj"), TETRAHEDRON).unwrap();
    let dumps = dir.join("dumps");
    run(
        fragsim()
            .args([
                "render", "--scheme", "mdts", "--width", "24", "--height", "16",
            ])
            .arg("--mesh")
            .arg(home.join("tetra.obj"))
            .args(["--no-images", "--dump"])
            .arg(&dumps),
        0,
    );
    let header = std::fs::read_to_string(dumps.join("mdts").join("dump.json")).unwrap();
    assert!(
        header.contains(&mesh_hash(TETRAHEDRON.as_bytes())),
        "{header}"
    );
    // The mesh moves away: the dump's path names nothing.
    let moved = dir.join("elsewhere.obj");
    std::fs::rename(home.join("tetra.obj"), &moved).unwrap();
    let compare = |mesh: Option<&Path>| {
        let mut command = fragsim();
        command
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .arg("--no-images");
        if let Some(mesh) = mesh {
            command.arg("--mesh").arg(mesh);
        }
        command
    };
    run(&mut compare(None), 2);
    let text = run(&mut compare(Some(&moved)), 0);
    assert!(text.contains("EQUAL"), "{text}");
    // Another file under --mesh is refused by its hash.
    let other = dir.join("other.obj");
    std::fs::write(&other, format!("{TETRAHEDRON}v 2 2 2\n")).unwrap();
    let other_text = run(&mut compare(Some(&other)), 2);
    assert!(other_text.contains("hash"), "{other_text}");
}

#[test]
fn render_dumps_under_the_conventions_it_is_given_and_compare_agrees() {
    let dir = scratch("render-gl");
    let gl = [
        "--window-origin",
        "lower-left",
        "--subpixel-bits",
        "4",
        "--depth-range",
        "minus-one-to-one",
        "--vertex-precision",
        "f32",
    ];
    run(
        fragsim()
            .args(["render", "--scene", "spheres:3", "--scheme", "mdts"])
            .args(["--width", "40", "--height", "28"])
            .args(gl)
            .args(["--no-images", "--dump"])
            .arg(&dir),
        0,
    );
    let dump = Dump::read(&dir.join("mdts")).unwrap();
    assert_eq!(dump.header.scene.conventions, GL_F32);
    let text = run(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("mdts"))
            .arg("--no-images"),
        0,
    );
    assert!(text.contains("EQUAL"), "{text}");
}

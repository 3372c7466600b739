//! Scene numbers in headers: every finite `f64` and `f32` round-trips to the same bits, any
//! decimal parses to the nearest `f64`, and numbers JSON cannot hold are refused by name.

use fragsim::dump::triangles::TriangleExport;
use fragsim::dump::Dump;
use fragsim::raster::scene_spec::SceneSpec;
use proptest::prelude::*;

use super::{mdts_header, parse_recording};

/// The scene's four numbers, as bits, so that `-0.0` and `0.0` differ.
fn scene_bits(scene: &SceneSpec) -> [u64; 4] {
    [
        scene.view_degrees,
        scene.elevation_degrees,
        scene.fov_y_degrees,
        scene.distance_scale,
    ]
    .map(f64::to_bits)
}

/// `dump` encoded and parsed back from memory.
fn reparsed(dump: &Dump) -> Result<Dump, String> {
    let (text, files) = dump.encode().map_err(|e| e.to_string())?;
    Dump::parse("dump.json", text.as_bytes(), |file| {
        Ok(files.get(file).cloned().unwrap_or_default())
    })
    .map_err(|e| e.to_string())
}

/// The 2 × 2 MDTS dump of [`mdts_header`] with these scene numbers.
fn dump_with_scene(numbers: [f64; 4]) -> Dump {
    let mut dump = parse_recording(&mdts_header("slots.u64", "[4, 2]"))
        .0
        .unwrap();
    let scene = &mut dump.header.scene;
    [
        scene.view_degrees,
        scene.elevation_degrees,
        scene.fov_y_degrees,
        scene.distance_scale,
    ] = numbers;
    dump
}

/// Any f64 bit pattern that is finite: subnormals, both zeros, the extremes included.
fn finite_f64() -> impl Strategy<Value = f64> {
    any::<u64>()
        .prop_map(f64::from_bits)
        .prop_filter("finite", |v| v.is_finite())
}

/// Any f32 bit pattern that is finite.
fn finite_f32() -> impl Strategy<Value = f32> {
    any::<u32>()
        .prop_map(f32::from_bits)
        .prop_filter("finite", |v| v.is_finite())
}

proptest! {
    // `PROPTEST_CASES` raises the count for a long run (`docs/extremes.md`).
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(4096)
    ))]

    /// Every finite f64 in a header comes back bit for bit through encode and parse, in a dump
    /// header and in a triangle export's scene.
    #[test]
    fn every_finite_f64_in_a_header_round_trips_to_the_same_bits(
        numbers in proptest::array::uniform4(finite_f64())
    ) {
        let dump = dump_with_scene(numbers);
        let again = reparsed(&dump).map_err(TestCaseError::fail)?;
        prop_assert_eq!(scene_bits(&again.header.scene), numbers.map(f64::to_bits));
        prop_assert_eq!(&again, &dump);
        let export = TriangleExport {
            scene: dump.header.scene.clone(),
            width: 2,
            height: 2,
            mesh_triangles: 0,
            triangles: Vec::new(),
        };
        let bytes = export.to_bytes().map_err(|e| TestCaseError::fail(e.to_string()))?;
        let read = TriangleExport::from_bytes(&bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(scene_bits(&read.scene), numbers.map(f64::to_bits));
    }

    /// Every finite f32 that fragsim writes into a JSON report (`explain`'s and `compare`'s
    /// depths) is written shortest as an f32 and reads back as an f32 to the same bits.
    #[test]
    fn every_finite_f32_written_to_json_reads_back_to_the_same_bits(x in finite_f32()) {
        let text = serde_json::to_string(&x).unwrap();
        let back: f32 = serde_json::from_str(&text).map_err(|e| TestCaseError::fail(format!("{text}: {e}")))?;
        prop_assert_eq!(back.to_bits(), x.to_bits(), "{} read back as {}", text, back);
        // Written as an f32, not widened to f64 (up to 17 digits): at most 9 significant digits.
        let mantissa: String = text
            .split(['e', 'E'])
            .next()
            .unwrap_or_default()
            .chars()
            .filter(char::is_ascii_digit)
            .collect();
        let significant = mantissa.trim_start_matches('0').trim_end_matches('0').len();
        prop_assert!(significant <= 9, "{} has {} significant digits", text, significant);
    }

    /// Any decimal, not only the shortest ones fragsim writes (a backend's printf may write 17 or
    /// 40 digits), parses in a header to the nearest f64, and as an f32 to the nearest f32: what
    /// Rust's own correctly rounded `str::parse` gives, an independent implementation; past the
    /// range it is an error.
    #[test]
    fn any_decimal_in_a_header_parses_to_the_nearest_f64(
        negative in any::<bool>(),
        digits in "[0-9]{1,40}",
        point in 0_usize..41,
        exponent in -360_i32..360,
    ) {
        let point = point.min(digits.len());
        let sign = if negative { "-" } else { "" };
        let fraction = if point == digits.len() { "0" } else { &digits[point..] };
        let whole = if point == 0 { "0" } else { digits[..point].trim_start_matches('0') };
        let whole = if whole.is_empty() { "0" } else { whole };
        let decimal = format!("{sign}{whole}.{fraction}e{exponent}");
        let nearest: f64 = decimal.parse().unwrap();
        let header = mdts_header("slots.u64", "[4, 2]").replace("15.0", &decimal);
        match parse_recording(&header).0 {
            Ok(dump) => prop_assert_eq!(
                dump.header.scene.elevation_degrees.to_bits(),
                nearest.to_bits(),
                "{} parsed as {}, nearest is {}", decimal, dump.header.scene.elevation_degrees, nearest
            ),
            Err(e) => {
                prop_assert!(nearest.is_infinite(), "{}: {}", decimal, e);
                prop_assert!(e.contains("out of range"), "{}: {}", decimal, e);
            }
        }
        // Read as an f32 (report fields), the same decimal rounds once, to the nearest f32.
        let nearest_f32: f32 = decimal.parse().unwrap();
        match serde_json::from_str::<f32>(&decimal) {
            Ok(got) => prop_assert_eq!(got.to_bits(), nearest_f32.to_bits(), "{} read as f32 {}, nearest is {}", decimal, got, nearest_f32),
            Err(e) => prop_assert!(nearest_f32.is_infinite(), "{}: {}", decimal, e),
        }
    }
}

#[test]
fn regression_the_fuzz_found_elevation_parses_to_the_nearest_f64_and_round_trips() {
    // `dump_parse` found it: without `float_roundtrip` it parsed to
    // 6.666666665999999e32, which re-encodes as 6.666666666e32 and parses to another number.
    // The same input is checked in as a corpus seed, `regression-elevation-not-read-exactly`.
    let decimal = "666666666600000133584280347126390.0";
    let header = mdts_header("slots.u64", "[4, 2]").replace("15.0", decimal);
    let dump = parse_recording(&header).0.unwrap();
    let nearest: f64 = decimal.parse().unwrap();
    assert_eq!(
        dump.header.scene.elevation_degrees.to_bits(),
        nearest.to_bits(),
        "parsed as {}, nearest is {nearest}",
        dump.header.scene.elevation_degrees
    );
    let again = reparsed(&dump).unwrap();
    assert_eq!(
        scene_bits(&again.header.scene),
        scene_bits(&dump.header.scene)
    );
    assert_eq!(again, dump);
}

#[test]
fn a_nan_or_infinite_scene_number_is_refused_by_name_when_writing() {
    for field in 0..4 {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut numbers = [30.0, 15.0, 45.0, 1.5];
            numbers[field] = bad;
            let dump = dump_with_scene(numbers);
            let name = [
                "view_degrees",
                "elevation_degrees",
                "fov_y_degrees",
                "distance_scale",
            ][field];
            let error = dump.encode().unwrap_err().to_string();
            assert!(
                error.contains(name) && error.contains("must be finite"),
                "{name} = {bad}: {error}"
            );
            let export = TriangleExport {
                scene: dump.header.scene.clone(),
                width: 2,
                height: 2,
                mesh_triangles: 0,
                triangles: Vec::new(),
            };
            let export_error = export.to_bytes().unwrap_err().to_string();
            assert!(
                export_error.contains(name),
                "{name} = {bad}: {export_error}"
            );
        }
    }
    assert!(dump_with_scene([30.0, 15.0, 45.0, 1.5]).encode().is_ok());
}

#[test]
fn a_header_number_json_cannot_hold_is_a_parse_error_naming_the_header() {
    for bad in [
        "1e400",
        "-1e400",
        "NaN",
        "Infinity",
        "-Infinity",
        "null",
        "\"15\"",
    ] {
        let header = mdts_header("slots.u64", "[4, 2]").replace("15.0", bad);
        let (parsed, asked) = parse_recording(&header);
        let error = parsed.expect_err(bad);
        assert!(error.starts_with("dump.json: "), "{bad}: {error}");
        assert!(
            asked.is_empty(),
            "{bad}: the reader was asked for {asked:?}"
        );
    }
}

//! The wgpu backend on whatever Vulkan adapter this machine has (Mesa's lavapipe in CI): every
//! scheme on the bunny and a procedural scene, in replay and engine mode, judged by the oracle's
//! verdict (within the precision of an f32 vertex stage, no tolerance of the test's own), and
//! replay coverage checked against fragsim's; every planted bug judged an error where the
//! correct shader is equal. Without an
//! adapter each test prints one line saying it was skipped and why; with `CI=true` or
//! `FRAGSIM_REQUIRE_GPU=1` it fails instead.

use std::process::Command;
use std::sync::atomic::{AtomicU32, Ordering};

use fragsim_catalog::DumpLayout;
use fragsim_dump::{Dump, Words};
use fragsim_schemes::linked_list::Resolve;

use fragsim_oracle::Oracle;
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::Viewport;
use fragsim_wgpu::judge::{judge, Judgement, Within, WithinJudgement};
use fragsim_wgpu::{
    adapter_or_skip, capture, capture_planted, Gpu, GpuError, GpuScheme, Mode, Plant,
};

/// The view of `scene` at 128² (view 30°, elevation 15°) captured by `scheme` (planted with
/// `plant`) in `mode`, its dump written and read back as `fragsim compare` would, and fragsim's
/// oracle of the view.
fn captured(
    gpu: &Gpu,
    scene: &str,
    scheme: GpuScheme,
    mode: Mode,
    plant: Option<Plant>,
) -> (Dump, Oracle) {
    let side = 128;
    let spec = SceneSpec::named(scene, 30.0, 15.0);
    let loaded = spec.load(None).unwrap();
    let view = loaded
        .view(Viewport::new(side, side).unwrap(), &spec.orbit())
        .unwrap();
    let oracle = Oracle::build(&view);
    let captured = capture_planted(gpu, &view, spec, &scheme, mode, plant).unwrap();
    // Tests run in parallel: each capture its own directory.
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let dir = std::env::temp_dir().join(format!(
        "fragsim-wgpu-test-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    captured.dump.write(&dir).unwrap();
    let dump = Dump::read(&dir).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(
        dump, captured.dump,
        "the dump read back is not the one written"
    );
    (dump, oracle)
}

/// [`captured`] with the correct shader, its coverage judged and its verdict every bit owed.
fn run(gpu: &Gpu, scene: &str, scheme: GpuScheme, mode: Mode) -> (Judgement, Oracle) {
    let (dump, oracle) = captured(gpu, scene, scheme, mode, None);
    let judgement = judge(&dump, &oracle, 0).unwrap();
    println!(
        "{scene} 128² {} {}, coverage: {}",
        scheme.name(),
        mode.name(),
        judgement.summary()
    );
    (judgement, oracle)
}

/// The precision verdicts' references, one per scene and mode (their dumps name the same
/// scene), built on first use.
#[derive(Default)]
struct References(Vec<Within>);

impl References {
    /// [`captured`] judged by the oracle's verdict within the precision of an f32 vertex stage
    /// (`fragsim compare oracle DIR --vertex-precision f32`): the depths are the GPU's f32
    /// interpolation in both modes, the positions its f32 vertex shader's in engine mode.
    fn judged(
        &mut self,
        gpu: &Gpu,
        scene: &str,
        scheme: GpuScheme,
        mode: Mode,
        plant: Option<Plant>,
    ) -> WithinJudgement {
        let (dump, _) = captured(gpu, scene, scheme, mode, plant);
        let at = match self.0.iter().position(|w| w.fits(&dump)) {
            Some(at) => at,
            None => {
                self.0.push(Within::of(&dump).unwrap());
                self.0.len() - 1
            }
        };
        let verdict = self.0[at].judge(&dump).unwrap();
        println!(
            "{scene} 128² {}{} {}: {}",
            scheme.name(),
            plant.map_or(String::new(), |p| format!(" planted {}", p.name())),
            mode.name(),
            verdict.summary()
        );
        verdict
    }
}

const SCENES: [&str; 2] = ["bunny", "bunny-spheres:8"];

/// The correct schemes (the non-atomic k-buffer races by design and is judged apart).
fn correct_schemes() -> [GpuScheme; 8] {
    let list = |resolve| GpuScheme::LinkedList {
        k: 8,
        pool_per_pixel: 16,
        resolve,
    };
    [
        GpuScheme::ABuffer { capacity: 32 },
        GpuScheme::ABuffer { capacity: 4 },
        GpuScheme::ABufferExact,
        GpuScheme::Mdts { k: 8 },
        GpuScheme::Mdts32 { k: 8 },
        list(Resolve::KeepFirst),
        list(Resolve::KeepNearest),
        GpuScheme::KbufferSpinlock { k: 8 },
    ]
}

#[test]
fn replay_coverage_is_fragsims_for_every_scheme() {
    let Some(gpu) = adapter_or_skip() else { return };
    for scene in SCENES {
        for scheme in correct_schemes() {
            let (j, oracle) = run(&gpu, scene, scheme, Mode::Replay);
            assert!(oracle.fragments() > 0, "{scene}: the view is empty");
            assert!(j.coverage_checked > 0);
            assert_eq!(j.coverage_differs, 0, "{scene} {}: coverage", scheme.name());
            assert_eq!(j.counters_differ.unwrap_or(0), 0, "{scene}: counters");
            assert_eq!(j.comparison.corrupt_words, 0, "{scene} {}", scheme.name());
        }
    }
}

#[test]
fn engine_mode_captures_of_every_correct_scheme_are_equal_under_the_precision_verdict() {
    let Some(gpu) = adapter_or_skip() else { return };
    let mut references = References::default();
    for scene in SCENES {
        for scheme in correct_schemes() {
            let verdict = references.judged(&gpu, scene, scheme, Mode::Engine, None);
            let what = format!("{scene} {}: {}", scheme.name(), verdict.summary());
            assert!(verdict.covered > 0, "{what}");
            assert!(verdict.comparison.is_equal(), "{what}");
            assert_eq!(verdict.comparison.corrupt_words, 0, "{what}");
        }
    }
}

#[test]
fn the_kbuffer_race_is_reported_as_it_is() {
    let Some(gpu) = adapter_or_skip() else { return };
    let (j, oracle) = run(&gpu, "bunny", GpuScheme::Kbuffer { k: 8 }, Mode::Replay);
    let d = &j.comparison.diff;
    // Whatever the adapter does: a lost fragment is a missing pixel, and the fragments the
    // dump holds plus those lost cover the K nearest of every pixel.
    assert_eq!(d.lost > 0, j.comparison.counts.missing > 0);
    let kept: u64 = oracle
        .depth_complexity()
        .iter()
        .map(|&n| u64::from(n.min(8)))
        .sum();
    assert_eq!(d.captured + d.lost - d.extra, kept, "{}", j.summary());
}

#[test]
fn replay_refuses_a_viewport_that_is_not_a_power_of_two() {
    let Some(gpu) = adapter_or_skip() else { return };
    let spec = SceneSpec::named("bunny", 30.0, 15.0);
    let loaded = spec.load(None).unwrap();
    let view = loaded
        .view(Viewport::new(96, 64).unwrap(), &spec.orbit())
        .unwrap();
    let e = capture(&gpu, &view, spec, &GpuScheme::Mdts32 { k: 4 }, Mode::Replay).unwrap_err();
    assert!(
        matches!(&e, GpuError::Refused(m) if m.contains("power-of-two")),
        "{e:?}"
    );
}

#[test]
fn with_no_vulkan_driver_the_command_says_so_and_exits_2() {
    let out = Command::new(env!("CARGO_BIN_EXE_fragsim-wgpu"))
        .arg("adapter")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no Vulkan adapter"), "{stderr}");
}

#[test]
fn every_planted_bug_is_an_error_where_the_correct_shader_is_equal() {
    let Some(gpu) = adapter_or_skip() else { return };
    let mut references = References::default();
    // At 32 slots no pixel of the bunny at 128² reaches the capacity, so an off-by-one in it
    // cannot show: the A-buffer is planted at 4 slots.
    let schemes = correct_schemes()
        .into_iter()
        .filter(|s| *s != GpuScheme::ABuffer { capacity: 32 });
    for scheme in schemes {
        let plants = std::iter::once(None).chain(
            Plant::ALL
                .into_iter()
                .filter(|p| p.applies_to(&scheme))
                .map(Some),
        );
        for plant in plants {
            let j = references.judged(&gpu, "bunny", scheme, Mode::Replay, plant);
            let what = format!(
                "{} {}: {}",
                scheme.name(),
                plant.map_or("correct", Plant::name),
                j.summary()
            );
            match plant {
                None => assert!(j.comparison.is_equal(), "{what}"),
                Some(_) => {
                    assert!(!j.comparison.is_equal(), "{what}");
                    assert!(j.comparison.diff.mismatched_pixels > 0, "{what}");
                }
            }
        }
    }
}

#[test]
fn the_correct_shaders_are_equal_on_a_procedural_scene() {
    let Some(gpu) = adapter_or_skip() else { return };
    let mut references = References::default();
    for scheme in correct_schemes() {
        let j = references.judged(&gpu, SCENES[1], scheme, Mode::Replay, None);
        assert!(
            j.comparison.is_equal(),
            "{}: {}",
            scheme.name(),
            j.summary()
        );
    }
}

#[test]
fn the_kbuffers_dump_the_catalogs_slots_and_are_judged_as_any_scheme() {
    let Some(gpu) = adapter_or_skip() else { return };
    for scheme in [
        GpuScheme::KbufferSpinlock { k: 8 },
        GpuScheme::Kbuffer { k: 8 },
    ] {
        let (dump, _) = captured(&gpu, "bunny", scheme, Mode::Replay, None);
        // What `fragsim render --dump` writes for the scheme: its catalog name, the k-buffer
        // slot layout, the K slots of each pixel and nothing else (the lock words stay on the
        // GPU).
        assert_eq!(dump.header.scheme, scheme.name());
        assert_eq!(
            DumpLayout::named(&dump.header.scheme),
            Some(DumpLayout::KBufferSlots)
        );
        assert_eq!(dump.header.layout, None);
        let arrays: Vec<&String> = dump.arrays.keys().collect();
        assert_eq!(arrays, ["slots"], "{}", scheme.name());
        assert!(
            matches!(dump.arrays.get("slots"), Some(Words::U64(_))),
            "{}",
            scheme.name()
        );
        let verdict = Within::of(&dump).unwrap().judge(&dump).unwrap();
        println!(
            "bunny 128² {} replay, precision verdict: {}",
            scheme.name(),
            verdict.summary()
        );
        let c = &verdict.comparison;
        match scheme {
            GpuScheme::KbufferSpinlock { .. } => assert!(c.is_equal(), "{}", verdict.summary()),
            // The race, whatever the adapter does: a lost fragment is a missing pixel.
            _ => assert_eq!(
                c.diff.lost > 0,
                c.counts.missing > 0,
                "{}",
                verdict.summary()
            ),
        }
    }
}

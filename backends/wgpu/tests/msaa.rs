//! Multisampling on whatever Vulkan adapter this machine has.
//!
//! - The per-sample counting pass (`src/sample_counts.rs`): the GPU's per-sample
//!   fragment counts of the bunny, replay mode, views 30° and 120° at 256², identical to
//!   fragsim's per-sample oracle at 4 and 8 samples a pixel and at 1 (the control); against the
//!   standard positions mirrored in y they differ, so identity does tell the sample positions
//!   apart.
//! - Per-sample captures (`capture_samples`): the A-buffer (fixed and exact, ids), MDTS
//!   (u64 words with ids, u32 keys) and the keep-nearest linked list of the bunny and
//!   `bunny-spheres:8` at 4 and 8 samples a pixel in engine mode (the f32 vertex shader, each
//!   sample's depth interpolated at the sample), judged by the oracle's verdict as `fragsim
//!   compare oracle DIR --vertex-precision f32` judges them: equal with 0 error samples, and
//!   every planted bug different.
//!
//! A sample count the adapter's target cannot render at is skipped with a line (lavapipe renders
//! at 1 and 4); without an adapter the tests are skipped with a line, or fail where a GPU is
//! required (`adapter_or_skip`).

use fragsim_dump::Dump;
use fragsim_oracle::verdict::{judge_sides, Side, SidesOptions, Verdict};
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::{SamplePattern, VertexPrecision, Viewport};
use fragsim_wgpu::judge::Within;
use fragsim_wgpu::sample_counts::{
    count_samples, count_samples_of, covering_prims, mirrored, reference_counts, CountDiff,
};
use fragsim_wgpu::{adapter_or_skip, capture_samples, say_skipped, GpuScheme, Mode, Plant};

#[test]
fn the_bunnys_sample_counts_are_fragsims_at_the_standard_positions() {
    let Some(gpu) = adapter_or_skip() else { return };
    let side = 256;
    for samples in [1, 4, 8] {
        if let Err(e) = gpu.check_samples(samples) {
            say_skipped(&format!("{samples} samples: {e}"));
            continue;
        }
        let pattern = SamplePattern::standard(samples).unwrap();
        for degrees in [30.0, 120.0] {
            let spec = SceneSpec::named("bunny", degrees, 15.0);
            let loaded = spec.load(None).unwrap();
            let view = spec
                .view(&loaded, Viewport::new(side, side).unwrap())
                .unwrap();
            let counted = count_samples(&gpu, &view, Mode::Replay, samples).unwrap();
            let reference = reference_counts(&view, pattern).unwrap();
            let diff = CountDiff::of(&counted.counts, &reference, side, samples, 5);
            let what = format!("bunny {side}² view {degrees} {samples}x replay");
            println!("{what}: {}", diff.summary());
            assert!(diff.reference_fragments > 0, "{what}: the view is empty");
            assert!(diff.is_identical(), "{what}: {diff:?}");
            if samples > 1 {
                let other = reference_counts(&view, mirrored(pattern).unwrap()).unwrap();
                let against = CountDiff::of(&counted.counts, &other, side, samples, 0);
                println!(
                    "{what} against the mirrored positions: {}",
                    against.summary()
                );
                assert!(against.samples_differ > 0, "{what}: {against:?}");
            }
        }
    }
}

/// The diagnosis of `msaa-count --alone`: at the deepest sample of the bunny, each triangle the
/// oracle finds there, drawn alone, is one fragment there; all of them together are the
/// oracle's count.
#[test]
fn triangles_drawn_alone_cover_the_samples_the_oracle_gives_them() {
    let Some(gpu) = adapter_or_skip() else { return };
    let samples = 4;
    if let Err(e) = gpu.check_samples(samples) {
        say_skipped(&format!("{samples} samples: {e}"));
        return;
    }
    let pattern = SamplePattern::standard(samples).unwrap();
    let spec = SceneSpec::named("bunny", 30.0, 15.0);
    let loaded = spec.load(None).unwrap();
    let view = spec.view(&loaded, Viewport::new(64, 64).unwrap()).unwrap();
    let reference = reference_counts(&view, pattern).unwrap();
    let deepest = (0..reference.len()).max_by_key(|&i| reference[i]).unwrap();
    let prims = &covering_prims(&view, pattern, &[deepest]).unwrap()[0];
    assert_eq!(prims.len(), reference[deepest] as usize);
    assert!(prims.len() > 1, "the deepest sample holds one fragment");
    for &prim in prims {
        let one = count_samples_of(&gpu, &view, &[prim], samples).unwrap();
        assert_eq!(one.counts[deepest], 1, "prim {prim} alone");
        assert_eq!(one.triangles, 1);
    }
    let together = count_samples_of(&gpu, &view, prims, samples).unwrap();
    assert_eq!(together.counts[deepest], reference[deepest]);
}

/// The per-sample engine captures of `scene` at `samples` a pixel and 128², view 30°, each scheme
/// correct and with every plant that applies, judged as `fragsim compare oracle DIR
/// --vertex-precision f32` judges them (`judge::Within`: built once, from the scene the first
/// dump names); the verdicts by (scheme, plant).
fn per_sample_verdicts(
    gpu: &fragsim_wgpu::Gpu,
    scene: &str,
    samples: u32,
) -> Vec<(GpuScheme, Option<Plant>, Verdict)> {
    let spec = SceneSpec::named(scene, 30.0, 15.0);
    let loaded = spec.load(None).unwrap();
    let viewport = Viewport::new(128, 128).unwrap();
    let view = spec.view(&loaded, viewport).unwrap();
    // A capacity the A-buffer reaches on these scenes at 4 slots, so that its off-by-one plant
    // has full lists to show in; MDTS on u64 words (ids) and on u32 keys; linked lists judged
    // on every node.
    let schemes = [
        GpuScheme::ABuffer { capacity: 4 },
        GpuScheme::ABufferExact,
        GpuScheme::Mdts { k: 8 },
        GpuScheme::Mdts32 { k: 8 },
        GpuScheme::parse("linked-list-nearest", 8, 4).unwrap(),
    ];
    let mut reference: Option<Within> = None;
    let mut verdicts = Vec::new();
    for scheme in schemes {
        let plants = std::iter::once(None).chain(
            Plant::ALL
                .into_iter()
                .filter(|p| p.applies_at(&scheme, samples))
                .map(Some),
        );
        for plant in plants {
            let captured = capture_samples(
                gpu,
                &view,
                spec.clone(),
                &scheme,
                Mode::Engine,
                plant,
                samples,
            )
            .unwrap();
            let dump = &captured.dump;
            assert_eq!(
                dump.header.scene.conventions.samples, samples,
                "the dump records the sample count it was captured at"
            );
            if !reference.as_ref().is_some_and(|r| r.fits(dump)) {
                reference = Some(Within::of(dump).unwrap());
            }
            let verdict = reference.as_ref().unwrap().verdict(dump).unwrap();
            if plant.is_none() {
                same_through_the_files(dump, &verdict, &format!("{scene} {}", scheme.name()));
            }
            verdicts.push((scheme, plant, verdict));
        }
    }
    verdicts
}

/// `dump` written, read back and judged by `fragsim compare oracle DIR --vertex-precision f32`'s
/// library call (`judge_sides`, the oracle rebuilt from the header): the verdict `judged` in
/// memory.
fn same_through_the_files(dump: &Dump, judged: &Verdict, what: &str) {
    let dir = std::env::temp_dir().join(format!(
        "fragsim-wgpu-msaa-{}-{}",
        std::process::id(),
        what.replace([' ', ':'], "-")
    ));
    dump.write(&dir).unwrap();
    let side = Side::open(dir.to_str().unwrap()).unwrap();
    let options = SidesOptions {
        vertex_precision: VertexPrecision::F32,
        ..SidesOptions::default()
    };
    let verdict = judge_sides(&Side::Oracle, &side, &options).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(verdict.equal, judged.equal, "{what}");
    assert_eq!(
        verdict.lists_per_pixel, dump.header.scene.conventions.samples,
        "one list per sample"
    );
    assert_eq!(
        verdict
            .per_sample
            .map(|c| (c.compared, c.differing_samples)),
        judged.per_sample.map(|c| (c.compared, c.differing_samples)),
        "{what}"
    );
}

#[test]
fn per_sample_engine_captures_are_equal_within_precision_and_planted_bugs_are_not() {
    let Some(gpu) = adapter_or_skip() else { return };
    for samples in [4, 8] {
        if let Err(e) = gpu.check_samples(samples) {
            say_skipped(&format!("{samples} samples: {e}"));
            continue;
        }
        for scene in ["bunny", "bunny-spheres:8"] {
            for (scheme, plant, verdict) in per_sample_verdicts(&gpu, scene, samples) {
                let counts = verdict.per_sample.expect("a per-sample verdict");
                let c = &verdict.comparison.counts;
                let what = format!(
                    "{scene} 128² {samples}x engine {} {}: {} of {} samples differ in {} pixels \
                     (missing {}, extra {}, misordered {}, miscounted {}, corrupt {}), {} ambiguous, \
                     {} within precision",
                    scheme.name(),
                    plant.map_or("correct", Plant::name),
                    counts.differing_samples,
                    counts.compared,
                    counts.differing_pixels,
                    c.missing,
                    c.extra,
                    c.misordered,
                    c.miscounted,
                    c.corrupt,
                    c.ambiguous,
                    c.within_precision,
                );
                println!("{what}");
                assert_eq!(counts.samples, samples, "{what}");
                assert!(verdict.reference_fragments.iter().any(|&n| n > 0), "{what}");
                match plant {
                    None => {
                        assert!(verdict.equal, "{what}: {:?}", verdict.examples);
                        assert_eq!(counts.differing_samples, 0, "{what}");
                        // The depths are the GPU's, not fragsim's: some are owed within precision,
                        // which the exact comparison would call wrong.
                        assert!(c.within_precision > 0, "{what}");
                    }
                    Some(_) => {
                        assert!(!verdict.equal, "{what}");
                        assert!(counts.differing_samples > 0, "{what}");
                    }
                }
            }
        }
    }
}

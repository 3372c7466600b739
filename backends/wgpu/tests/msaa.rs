//! Multisampling on whatever Vulkan adapter this machine has (issue 22, `src/sample_counts.rs`):
//! the GPU's per-sample fragment counts of the bunny, replay mode, views 30° and 120° at 256²,
//! identical to fragsim's per-sample oracle at 4 and 8 samples a pixel and at 1 (the control);
//! against the standard positions mirrored in y they differ, so identity does tell the sample
//! positions apart. A sample count the adapter's target cannot render at is skipped with a line
//! (lavapipe renders at 1 and 4); without an adapter the test is skipped with a line, or fails
//! where a GPU is required (`adapter_or_skip`).

use fragsim_oracle::scene::SceneAndCamera;
use fragsim_raster::{SamplePattern, Viewport};
use fragsim_wgpu::sample_counts::{
    count_samples, count_samples_of, covering_prims, mirrored, reference_counts, CountDiff,
};
use fragsim_wgpu::{adapter_or_skip, say_skipped, Mode};

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
            let spec = SceneAndCamera::named("bunny", degrees, 15.0);
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
    let spec = SceneAndCamera::named("bunny", 30.0, 15.0);
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

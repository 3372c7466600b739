//! Engine-mode captures (the mesh and the orbit camera's matrix in f32 in the vertex shader, the
//! GPU's own rasterizer and depth interpolation) judged by the oracle's verdict within precision
//! (`fragsim_wgpu::judge::Within`: the exact f64 oracle under the dump's conventions, the bounds
//! derived for an f32 vertex stage, `docs/semantics.md` §10): a correct A-buffer capture of the
//! bunny has no error pixel; the same capture with one fragment taken out of its dump's bytes is
//! an error at exactly that pixel, never excused as ambiguous; and the non-atomic k-buffer is
//! judged as what it stored: where it kept another list than MDTS on the same adapter the pixel
//! is an error (ambiguous only where MDTS's own pixel is), elsewhere its verdict is MDTS's. Without an adapter each test prints one line
//! saying it was skipped; with `CI=true` or `FRAGSIM_REQUIRE_GPU=1` it fails instead.

use fragsim_dump::Dump;
use fragsim_oracle::compare::{flags, Comparison};
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::Viewport;
use fragsim_wgpu::judge::Within;
use fragsim_wgpu::{adapter_or_skip, capture, Gpu, GpuScheme, Mode};

/// The bunny at 128², view 30°, drawn by `scheme` in engine mode.
fn engine_capture(gpu: &Gpu, scheme: &GpuScheme) -> Dump {
    let spec = SceneSpec::named("bunny", 30.0, 15.0);
    let loaded = spec.load(None).unwrap();
    let view = loaded
        .view(Viewport::new(128, 128).unwrap(), &spec.orbit())
        .unwrap();
    capture(gpu, &view, spec, scheme, Mode::Engine)
        .unwrap()
        .dump
}

/// The oracle's verdict on `dump` within the precision of an f32 vertex stage (`fragsim compare
/// oracle DIR --vertex-precision f32`), and the pixels the reference covers.
fn judged(dump: &Dump) -> (Comparison, u64) {
    let verdict = Within::of(dump).unwrap().judge(dump).unwrap();
    println!("{}: {}", dump.header.scheme, verdict.summary());
    (verdict.comparison, verdict.covered)
}

/// The dump with slot 0 of pixel `p` taken out of its bytes: the later slots move down, the
/// last becomes the empty marker and the counter loses one, as if the fragment never arrived.
fn without_first_fragment(dump: &Dump, p: usize) -> Dump {
    let (header, mut files) = dump.encode().unwrap();
    let capacity = dump.header.capacity.unwrap() as usize;
    let counters = files.get_mut("counters.u32").unwrap();
    let count = u32::from_le_bytes(counters[4 * p..4 * p + 4].try_into().unwrap());
    counters[4 * p..4 * p + 4].copy_from_slice(&(count - 1).to_le_bytes());
    let slots = files.get_mut("slots.u64").unwrap();
    let row = &mut slots[8 * p * capacity..8 * (p + 1) * capacity];
    row.copy_within(8.., 0);
    row[8 * (capacity - 1)..].fill(0xFF);
    Dump::parse("dump.json", header.as_bytes(), |name| {
        Ok(files[name].clone())
    })
    .unwrap()
}

#[test]
fn a_correct_engine_capture_has_no_error_and_one_dropped_fragment_is_one_error() {
    let Some(gpu) = adapter_or_skip() else { return };
    let dump = engine_capture(&gpu, &GpuScheme::ABuffer { capacity: 32 });
    let (comparison, covered) = judged(&dump);
    assert!(covered > 0, "the view is empty");
    assert_eq!(
        comparison.diff.mismatched_pixels, 0,
        "{:?}",
        comparison.diff
    );
    // A pixel of two fragments or more whose verdict is neither ambiguous nor within precision:
    // every fragment there is certain and bit-equal, so its loss can be excused by nothing.
    let capture = dump.capture().unwrap();
    let p = (0..capture.pixels())
        .find(|&p| capture.pixel(p).len() >= 2 && comparison.verdicts[p] == 0)
        .expect("a decided pixel of depth complexity 2 or more");
    let (bugged, _) = judged(&without_first_fragment(&dump, p));
    let wrong: Vec<usize> = (0..bugged.verdicts.len())
        .filter(|&q| bugged.verdicts[q] & flags::DIFFERS != 0)
        .collect();
    assert_eq!(wrong, [p], "the error is the planted pixel's alone");
    assert_eq!(
        bugged.verdicts[p] & (flags::DIFFERS | flags::AMBIGUOUS),
        flags::MISSING | flags::MISCOUNTED
    );
}

#[test]
fn the_kbuffer_is_judged_as_what_it_stored() {
    let Some(gpu) = adapter_or_skip() else { return };
    let mdts = engine_capture(&gpu, &GpuScheme::Mdts { k: 8 });
    let kbuffer = engine_capture(&gpu, &GpuScheme::Kbuffer { k: 8 });
    let ((reference, _), (raced, _)) = (judged(&mdts), judged(&kbuffer));
    let (a, b) = (mdts.capture().unwrap(), kbuffer.capture().unwrap());
    let mut differing = 0;
    let both = raced.verdicts.iter().zip(&reference.verdicts);
    for (p, (&flags, &mdts_flags)) in both.enumerate() {
        if a.pixel(p) == b.pixel(p) {
            assert_eq!(flags, mdts_flags, "pixel {p}");
        } else {
            differing += 1;
            // Where MDTS's list is not ambiguous, the pixel's conforming K-nearest lists are
            // known from it: another list is an error, never excused as ambiguous by fragments
            // the list does not hold. Where MDTS's own pixel is ambiguous (a fragment whose
            // coverage or depth a conforming implementation may decide either way), so may
            // the k-buffer's be.
            let expected = if mdts_flags & flags::AMBIGUOUS == 0 {
                flags::DIFFERS
            } else {
                flags::DIFFERS | flags::AMBIGUOUS
            };
            assert_ne!(
                flags & expected,
                0,
                "pixel {p}: another list than MDTS's, called correct"
            );
        }
    }
    println!("the k-buffer kept another list than MDTS at {differing} pixels");
    assert_eq!(raced.diff.lost > 0, raced.counts.missing > 0);
}

//! The k-buffer family and the stencil-routed A-buffer against the oracle: the k-buffer exact up
//! to K serially on both write-back machines and visibly wrong under interleavings, in the failure
//! classes of each machine (render targets: lost fragments only; separate stores: also duplicates
//! and slots out of order); the multi-pass k-buffer exact under any interleaving, paying for
//! hazards with extra passes; the stencil-routed A-buffer exact up to 8 fragments a pass, counting
//! the rest as overflow.

mod multipass;
use multipass::serial_passes;
mod single;
mod srab;

use fragsim::capture::executors::frame;
use fragsim::capture::executors::run_serial;
use fragsim::capture::executors::scheduled::{Granularity, Policy, Schedule};
use fragsim::capture::{CaptureError, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::SerialMemory;
use fragsim::oracle::Oracle;
use fragsim::raster::{Fragment, OrbitCamera, Scene, View, Viewport};
use fragsim::schemes::kbuffer::multipass::KBufferMultipass;
use fragsim::schemes::kbuffer::{KBuffer, WriteBack};
use fragsim::schemes::stencil_routed::StencilRouted;
use proptest::prelude::*;

use crate::support::fragments;

/// Looking straight down the z axis at `quads:N`: every pixel the quads cover has N fragments.
pub(super) fn head_on() -> OrbitCamera {
    OrbitCamera {
        elevation_degrees: 0.0,
        ..OrbitCamera::default()
    }
}

pub(super) fn viewport(width: u32, height: u32) -> Viewport {
    Viewport::new(width, height).unwrap()
}

/// The fragments of pixel 0 of a 1×1 view of `quads:n` seen head-on, nearest first.
pub(super) fn one_pixel_quads(scene: &Scene) -> (View<'_>, Vec<Fragment>) {
    let view = scene.view(viewport(1, 1), &head_on()).unwrap();
    let mut list = fragments(&view);
    list.sort_by_key(|f| f.packed());
    (view, list)
}

/// Runs a hand-written interleaving: `script[i]` names the fragment whose walk takes the i-th
/// step. Every walk must be over when the script ends.
pub(super) fn drive<S: Scheme<Input = Fragment>>(
    scheme: &S,
    memory: &SerialMemory,
    walks: &[Fragment],
    script: &[usize],
) {
    let mut script = script.iter();
    frame::interleaved(scheme, memory, 0, walks, |unfinished| {
        let w = script.next().expect("the script left a walk unfinished");
        unfinished
            .iter()
            .position(|u| u == w)
            .expect("the script steps a finished walk")
    });
    assert!(script.next().is_none(), "the script steps a finished walk");
}

/// Runs one pass of a multi-pass scheme over `all`, interleaving the walks as `pick` chooses among
/// the unfinished ones, then the between-pass kernel; returns whether another pass is needed.
pub(super) fn drive_pass<S: Scheme<Input = Fragment>>(
    scheme: &S,
    memory: &SerialMemory,
    pass: u32,
    all: &[Fragment],
    mut pick: impl FnMut(usize) -> usize,
) -> bool {
    // The unfinished walks stay in submission order, so `pick` returning 0 runs them one after
    // the other in primitive order (which render targets commit in).
    let (_, more) = frame::pass(scheme, memory, pass, |pass| {
        frame::interleaved(scheme, memory, pass, all, |unfinished| {
            pick(unfinished.len())
        })
    });
    more
}

/// How many fragments pixel `p`'s resolve reports now.
pub(super) fn captured_now<S: Scheme>(scheme: &S, memory: &SerialMemory, p: usize) -> usize {
    let mut out = Vec::new();
    scheme.resolve_pixel(memory, p, &mut out);
    out.len()
}

/// Both machines, render targets first.
pub(super) const MACHINES: [WriteBack; 2] = [WriteBack::RenderTarget, WriteBack::SeparateStores];

/// The bunny at 256 × 256 under the CLI's `--executor scheduled`: uniform random, 256 fragments
/// in flight, seed 0.
fn bunny_256_scheduled() -> (Scene, Schedule) {
    (
        Scene::procedural("bunny").unwrap(),
        Schedule {
            policy: Policy::Random,
            in_flight: 256,
            granularity: Granularity::Fragment,
            seed: 0,
        },
    )
}

// ---------------------------------------------------------------- constructors

#[test]
fn constructors_reject_k_zero_no_passes_and_too_much_memory() {
    let v = viewport(64, 64);
    let bad = |e: Result<(), CaptureError>| matches!(e, Err(CaptureError::BadParameter(_)));
    assert!(bad(KBuffer::with_k(v, 0).map(drop)));
    assert!(bad(
        KBufferMultipass::new(v, 0, 4, MEMORY_CAP_DEFAULT).map(drop)
    ));
    assert!(bad(StencilRouted::new(v, 0, MEMORY_CAP_DEFAULT).map(drop)));
    // The storage as documented, per pixel of 4,096: 8 slots of 8 bytes; render targets add a
    // lock and two tickets (12 bytes); the multi-pass k-buffer's slots and tentative list
    // (2 × 64), c, t and the window's nearest (24), three counts (12), the render-target words
    // (12), the output list too; stencil routing's 2 × 64 and a 4-byte count.
    let stores = |k, cap| KBuffer::with_write_back(v, k, WriteBack::SeparateStores, cap);
    let per_pixel = 128 + 24 + 12 + 12;
    let layouts = [
        (stores(8, MEMORY_CAP_DEFAULT).unwrap().layout(), 64),
        (KBuffer::new(v, 8, MEMORY_CAP_DEFAULT).unwrap().layout(), 76),
        (
            KBufferMultipass::new(v, 8, 0, MEMORY_CAP_DEFAULT)
                .unwrap()
                .layout(),
            per_pixel,
        ),
        (
            StencilRouted::new(v, 2, MEMORY_CAP_DEFAULT)
                .unwrap()
                .layout(),
            132,
        ),
    ];
    for (layout, bytes) in layouts {
        assert_eq!(layout.bytes(), 4096 * bytes);
    }
    assert!(
        KBufferMultipass::new(v, 8, 1, MEMORY_CAP_DEFAULT)
            .unwrap()
            .layout()
            .bytes()
            > 4096 * per_pixel
    );
    // The cap refuses at build what is allocated before any fragment (the page tables); the
    // pages are checked as a frame writes them.
    let too_much =
        |e: Result<(), CaptureError>| matches!(e, Err(CaptureError::TooMuchMemory { .. }));
    let least = layouts[1].0.least_bytes();
    assert!(KBuffer::new(v, 8, least).is_ok());
    assert!(too_much(KBuffer::new(v, 8, least - 1).map(drop)));
    let least3 = layouts[3].0.least_bytes();
    assert!(StencilRouted::new(v, 2, least3).is_ok());
    assert!(too_much(StencilRouted::new(v, 2, least3 - 1).map(drop)));
}

// ---------------------------------------------------------------- random scenes

fn scene_name() -> impl Strategy<Value = String> {
    prop_oneof![
        (1_u32..4).prop_map(|n| format!("spheres:{n}")),
        (1_u32..120, any::<u64>()).prop_map(|(count, seed)| format!("soup:{count}:{seed}")),
        (1_u32..20).prop_map(|n| format!("quads:{n}")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Serially, the k-buffer keeps exactly the K nearest, the multi-pass k-buffer every fragment
    /// in the passes its per-pixel counts predict, and the stencil-routed A-buffer all but the
    /// counted overflow.
    #[test]
    fn serial_kbuffers_and_srab_keep_what_they_promise_on_random_scenes(
        name in scene_name(),
        width in 3_u32..24,
        height in 3_u32..24,
        angle in 0.0_f64..360.0,
        k in 1_u32..6,
        srab_passes in 1_u32..4,
    ) {
        let scene = Scene::procedural(&name).unwrap();
        let view = scene.view(viewport(width, height), &OrbitCamera::default().at_angle(angle)).unwrap();
        let oracle = Oracle::build(&view);
        let d = oracle.max_depth_complexity();

        let kbuffer = KBuffer::with_k(view.viewport(), k).unwrap();
        let run = run_serial(&view, &kbuffer);
        let diff = oracle.diff(&run.capture);
        prop_assert!(diff.is_exact(), "kbuffer: {diff:?}");
        prop_assert_eq!(diff.overflowed, run.stats.counters.dropped);

        let multipass = KBufferMultipass::new(view.viewport(), k, d, MEMORY_CAP_DEFAULT).unwrap();
        let multipass_run = run_serial(&view, &multipass);
        let multipass_diff = oracle.diff(&multipass_run.capture);
        prop_assert!(multipass_diff.is_exact(), "multipass: {multipass_diff:?}");
        prop_assert_eq!(usize::try_from(multipass_diff.captured), Ok(oracle.fragments()));
        prop_assert_eq!(multipass_run.stats.passes, serial_passes(&oracle, k));

        let srab = StencilRouted::new(view.viewport(), srab_passes, MEMORY_CAP_DEFAULT).unwrap();
        let srab_run = run_serial(&view, &srab);
        let srab_diff = oracle.diff(&srab_run.capture);
        prop_assert!(srab_diff.is_exact(), "srab: {srab_diff:?}");
        let capacity = 8 * srab_passes;
        let overflow: u64 = oracle.depth_complexity().iter().map(|&n| u64::from(n.saturating_sub(capacity))).sum();
        prop_assert_eq!(srab_diff.overflowed, overflow);
        prop_assert_eq!(srab_run.stats.counters.dropped, overflow);
        prop_assert_eq!(srab_run.stats.passes, srab_passes.min(d.div_ceil(8).max(1)));
    }
}

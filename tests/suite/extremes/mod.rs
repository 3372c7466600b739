//! Numerical stability at the extremes: the ends of the depth range, the sentinels, the
//! counters, hostile geometry and extreme sizes. Each test names the extreme and asserts the expected result;
//! `docs/extremes.md` lists them with the numbers measured here.

#[path = "../../fuzz_support/camera.rs"]
mod camera;

use camera::{camera_from_columns, identity_camera};
use fragsim::capture::executors::{run_parallel, run_serial};
use fragsim::capture::{Scheme, Step, MEMORY_CAP_DEFAULT};
use fragsim::memory::Memory;
use fragsim::oracle::Oracle;
use fragsim::raster::{Camera, CullMode, Fragment, Mesh, View, Viewport};
use fragsim::schemes::mdts::{Direction, Mdts};

mod counters;
mod depth_encoding;
mod geometry;
mod sentinels;
mod sizes;

/// The key of depth 1.0: the largest a fragment can carry.
const MAX_KEY: u32 = 0x3F80_0000;

fn viewport(width: u32, height: u32) -> Viewport {
    Viewport::new(width, height).expect("a valid viewport")
}

/// D3D/Vulkan `perspective_rh` with a 90° field of view and aspect 1 (so `x` and `y` pass
/// unscaled), as `glam::DMat4::perspective_rh` builds it: `w = −z_eye`, depth 0 at `near`, 1 at
/// `far`. The model space is the eye space.
fn perspective(near: f64, far: f64) -> Camera {
    let r = far / (near - far);
    camera_from_columns([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, r, -1.0],
        [0.0, 0.0, r * near, 0.0],
    ])
}

/// A mesh of unshared triangles, primitive id = position in `triangles`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a hand-built soup has a few thousand triangles at most"
)]
fn soup(triangles: &[[[f32; 3]; 3]]) -> Mesh {
    Mesh {
        positions: triangles.iter().flatten().copied().collect(),
        triangles: (0..triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect(),
    }
}

/// The square `[-s, s]²` at depth (or eye-space z) `z`, as two triangles sharing a diagonal.
fn square(s: f32, z: f32) -> [[[f32; 3]; 3]; 2] {
    [
        [[-s, -s, z], [s, -s, z], [s, s, z]],
        [[-s, -s, z], [s, s, z], [-s, s, z]],
    ]
}

fn all_fragments(view: &View<'_>) -> Vec<Fragment> {
    let mut fragments = Vec::new();
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| fragments.push(f));
    }
    fragments
}

/// Fragments per pixel.
fn coverage(view: &View<'_>) -> Vec<u32> {
    let mut counts = vec![0; view.viewport().pixels()];
    for f in all_fragments(view) {
        counts[f.pixel as usize] += 1;
    }
    counts
}

fn identity_view(mesh: &Mesh, width: u32, height: u32) -> View<'_> {
    View::new(
        mesh,
        &identity_camera(),
        viewport(width, height),
        CullMode::None,
    )
}

/// Checks that `scheme` run serially and in parallel on `view` is exactly what it promises, with
/// the counted drops equal to the oracle's overflow; returns that overflow.
fn assert_exact<S: Scheme>(view: &View<'_>, oracle: &Oracle, scheme: &S) -> u64 {
    let overflow = [run_serial(view, scheme), run_parallel(view, scheme)].map(|run| {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{}: {diff:?}", scheme.name());
        assert_eq!(
            diff.overflowed,
            run.stats.counters.dropped,
            "{}",
            scheme.name()
        );
        diff.overflowed
    });
    assert_eq!(overflow[0], overflow[1], "{}", scheme.name());
    overflow[0]
}

/// The library's 32-bit MDTS (`K = 4`, one pixel) after inserting `keys` one after another on
/// memory `M`: the kept keys, nearest first, and how each walk ended.
fn mdts32_run<M: Memory>(keys: &[u32]) -> (Vec<u32>, Vec<Step>) {
    let mdts = Mdts::<u32>::new(viewport(1, 1), 4, Direction::Ascending, MEMORY_CAP_DEFAULT)
        .expect("a valid MDTS");
    let memory: M = mdts.layout().allocate();
    let mut steps = 0;
    let outcomes = keys
        .iter()
        .map(|&depth_key| {
            let fragment = Fragment {
                pixel: 0,
                depth_key,
                prim: 0,
            };
            mdts.insert(fragment, &memory, &mut steps)
        })
        .collect();
    let kept = mdts
        .resolve(&memory)
        .pixel(0)
        .iter()
        .map(|&e| (e >> 32) as u32)
        .collect();
    (kept, outcomes)
}

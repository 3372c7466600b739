//! Numerical stability at the extremes (issue 5): the ends of the depth range, the sentinels, the
//! counters, hostile geometry and extreme sizes. Each test names the extreme and asserts the expected result;
//! `docs/extremes.md` lists them with the numbers measured here.

#[path = "fuzz_support/camera.rs"]
mod camera;

use std::time::Instant;

use assert_cmd::Command;
use camera::{camera_from_columns, identity_camera};
use fragsim::capture::abuffer::{ABuffer, PostSort};
use fragsim::capture::abuffer_atomic_inc::ABufferAtomicInc;
use fragsim::capture::executor::{run_parallel, run_serial};
use fragsim::capture::mdts::{Direction, Mdts, MdtsWord};
use fragsim::capture::{
    CaptureError, Guarantee, Identity, Layout, Memory, Promise, Scheme, SerialMemory, Step,
    WordMemory, MEMORY_CAP_DEFAULT,
};
use fragsim::oracle::Oracle;
use fragsim::raster::{
    depth_from_key, depth_key, Camera, CullMode, Fragment, Mesh, MeshError, OrbitCamera, Scene,
    View, Viewport, EMPTY_KEY,
};
use proptest::prelude::*;

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

// ---------------------------------------------------------------------------------------------
// Depth encoding

#[test]
fn depth_zero_has_key_zero() {
    assert_eq!(depth_key(0.0), Some(0));
}

#[test]
fn negative_zero_has_the_key_of_positive_zero_not_0x80000000() {
    assert_eq!(depth_key(-0.0), Some(0));
    // Unmapped, its bit pattern would sort after every depth up to 1.0: the library's MDTS,
    // handed the raw bits, keeps the nearest depth there is behind depth 1.0.
    let raw = (-0.0f32).to_bits();
    assert_eq!(
        mdts32_run::<SerialMemory>(&[raw, MAX_KEY]).0,
        [MAX_KEY, raw]
    );
    assert_eq!(mdts32_run::<SerialMemory>(&[0, MAX_KEY]).0, [0, MAX_KEY]);
}

#[test]
fn the_smallest_subnormal_depth_has_key_one() {
    let smallest = f32::from_bits(1);
    assert!(smallest > 0.0 && !smallest.is_normal());
    assert_eq!(depth_key(smallest), Some(1));
}

#[test]
fn the_largest_depth_below_one_has_key_0x3f7fffff() {
    let below_one = 1.0 - f32::EPSILON / 2.0;
    assert_eq!(below_one.to_bits(), 0x3F7F_FFFF);
    assert_eq!(depth_key(below_one), Some(0x3F7F_FFFF));
    assert!(depth_key(below_one) < depth_key(1.0));
}

#[test]
fn depth_one_has_the_largest_key_0x3f800000() {
    assert_eq!(depth_key(1.0), Some(MAX_KEY));
    assert_eq!(depth_from_key(MAX_KEY), 1.0);
}

#[test]
fn depths_just_outside_the_unit_interval_have_no_key() {
    let above_one = f32::from_bits(0x3F80_0001);
    assert!(above_one > 1.0);
    for depth in [above_one, -f32::from_bits(1), -1e-30, 1.5, -1.0] {
        assert_eq!(depth_key(depth), None, "{depth:e}");
    }
}

#[test]
fn infinities_and_nan_have_no_key() {
    for depth in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -f32::NAN] {
        assert_eq!(depth_key(depth), None, "{depth}");
    }
}

#[test]
fn non_finite_vertices_are_stopped_by_mesh_validation_and_by_the_pipeline() {
    // At load: every OBJ mesh is validated finite.
    for text in ["v inf 0 0\n", "v nan 0 0\n", "v 0 -inf 0\n", "v 0 0 1e39\n"] {
        let obj = format!("{text}v 1 0 0\nv 1 1 0\nf 1 2 3\n");
        let err = Mesh::read_obj(&mut obj.as_bytes(), "hostile.obj").unwrap_err();
        assert!(
            matches!(err, MeshError::NonFinite { .. }),
            "{text:?}: {err}"
        );
    }
    // A hand-built mesh that skips validation: the pipeline emits nothing and does not panic
    // (a NaN or infinite w fails the `w > 0` test before any fixed-point arithmetic).
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mesh = soup(&[[[bad, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]]]);
        assert!(mesh.validate("hand-built").is_err());
        let view = identity_view(&mesh, 8, 8);
        assert!(all_fragments(&view).is_empty(), "{bad}");
        let view = View::new(
            &mesh,
            &perspective(0.1, 10.0),
            viewport(8, 8),
            CullMode::None,
        );
        assert!(all_fragments(&view).is_empty(), "{bad}");
    }
}

#[test]
fn fragments_interpolated_just_beyond_depth_one_are_dropped_one_by_one() {
    // Depth 1.0 at one corner, one ulp above 1.0 at the others: pixels near the first corner
    // round to exactly 1.0 and are kept; the rest are beyond the far plane and dropped.
    let above_one = f32::from_bits(0x3F80_0001);
    let mesh = soup(&[[
        [-1.0, 1.0, 1.0],
        [3.0, 1.0, above_one],
        [-1.0, -3.0, above_one],
    ]]);
    let view = identity_view(&mesh, 16, 16);
    let kept = all_fragments(&view);
    assert!(
        !kept.is_empty() && kept.len() < 256,
        "kept {} of 256",
        kept.len()
    );
    assert!(kept.iter().all(|f| f.depth_key == MAX_KEY));
    // The same triangle at depth 0.5 covers all 256 pixels.
    let flat = soup(&[[[-1.0, 1.0, 0.5], [3.0, 1.0, 0.5], [-1.0, -3.0, 0.5]]]);
    assert_eq!(all_fragments(&identity_view(&flat, 16, 16)).len(), 256);
}

#[test]
fn a_triangle_touching_depth_zero_from_below_is_clipped_away() {
    let below_zero = -f32::from_bits(1);
    let mesh = soup(&[[
        [-1.0, 1.0, 0.0],
        [3.0, 1.0, below_zero],
        [-1.0, -3.0, below_zero],
    ]]);
    assert!(all_fragments(&identity_view(&mesh, 16, 16)).is_empty());
}

proptest! {
    #[test]
    fn depth_key_order_equals_depth_order_on_the_unit_interval(
        a in prop_oneof![0u32..=MAX_KEY, Just(0x8000_0000u32)],
        b in prop_oneof![0u32..=MAX_KEY, Just(0x8000_0000u32)],
    ) {
        // Including -0.0, which equals +0.0 as a float and as a key.
        let (x, y) = (f32::from_bits(a), f32::from_bits(b));
        let (kx, ky) = (depth_key(x).unwrap(), depth_key(y).unwrap());
        prop_assert_eq!(x.partial_cmp(&y), Some(kx.cmp(&ky)));
        // And the library's 32-bit MDTS, which compares keys as integers, keeps them in depth
        // order: the nearer first (f32 order computed here, not by the library).
        let (near, far) = if x <= y { (kx, ky) } else { (ky, kx) };
        prop_assert_eq!(mdts32_run::<SerialMemory>(&[kx, ky]).0, vec![near, far]);
    }
}

// ---------------------------------------------------------------------------------------------
// Sentinels

/// What `depth_key` must return for a bit pattern: the pattern itself for `+0.0 ..= 1.0` (bits
/// `0 ..= 0x3F80_0000`), 0 for `−0.0`, nothing for the rest (negative, above 1, infinite, NaN).
fn expected_key(bits: u32) -> Option<u32> {
    match bits {
        0..=MAX_KEY => Some(bits),
        0x8000_0000 => Some(0),
        _ => None,
    }
}

#[test]
fn depth_keys_exist_only_up_to_0x3f800000_so_neither_sentinel_collides() {
    // Both signs, every exponent, the 4,096 smallest and largest mantissas of each: every
    // boundary of the float format (0, subnormals, 1.0, infinity, the NaNs) is covered exactly;
    // the proptest below samples the rest.
    for sign in [0, 0x8000_0000u32] {
        for exponent in 0..256u32 {
            let base = sign | exponent << 23;
            for mantissa in (0..4096).chain((1 << 23) - 4096..1 << 23) {
                let bits = base | mantissa;
                assert_eq!(
                    depth_key(f32::from_bits(bits)),
                    expected_key(bits),
                    "{bits:#x}"
                );
            }
        }
    }
    // The only bit patterns equal to the sentinels are NaNs, which have no key.
    for sentinel in [0x7FFF_FFFFu32, 0xFFFF_FFFF] {
        assert!(f32::from_bits(sentinel).is_nan());
        assert_eq!(depth_key(f32::from_bits(sentinel)), None);
    }
    assert_eq!(EMPTY_KEY, u32::MAX);
    // With 64-bit words the empty value u64::MAX would need key 0xFFFFFFFF.
    let largest_word = Fragment {
        pixel: 0,
        depth_key: MAX_KEY,
        prim: u32::MAX,
    }
    .packed();
    assert!(largest_word < u64::MAX);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    #[test]
    fn depth_key_of_any_bit_pattern_is_the_pattern_on_the_unit_interval_else_none(
        bits in any::<u32>(),
    ) {
        prop_assert_eq!(depth_key(f32::from_bits(bits)), expected_key(bits));
    }
}

/// Memory whose 32-bit `atomicMin` compares as signed `int` (CUDA's `atomicMin(int*, int)`);
/// everything else is the library's serial memory.
struct SignedMin(SerialMemory);

impl WordMemory<u32> for SignedMin {
    fn len(&self) -> usize {
        WordMemory::<u32>::len(&self.0)
    }
    fn load(&self, i: usize) -> u32 {
        WordMemory::<u32>::load(&self.0, i)
    }
    fn store(&self, i: usize, v: u32) {
        WordMemory::<u32>::store(&self.0, i, v);
    }
    fn fetch_min(&self, i: usize, v: u32) -> u32 {
        let old = WordMemory::<u32>::load(&self.0, i);
        if (v as i32) < (old as i32) {
            WordMemory::<u32>::store(&self.0, i, v);
        }
        old
    }
    fn fetch_max(&self, i: usize, v: u32) -> u32 {
        WordMemory::<u32>::fetch_max(&self.0, i, v)
    }
    fn fetch_add(&self, i: usize, v: u32) -> u32 {
        WordMemory::<u32>::fetch_add(&self.0, i, v)
    }
    fn fetch_or(&self, i: usize, v: u32) -> u32 {
        WordMemory::<u32>::fetch_or(&self.0, i, v)
    }
    fn swap(&self, i: usize, v: u32) -> u32 {
        WordMemory::<u32>::swap(&self.0, i, v)
    }
}

impl WordMemory<u64> for SignedMin {
    fn len(&self) -> usize {
        WordMemory::<u64>::len(&self.0)
    }
    fn load(&self, i: usize) -> u64 {
        WordMemory::<u64>::load(&self.0, i)
    }
    fn store(&self, i: usize, v: u64) {
        WordMemory::<u64>::store(&self.0, i, v);
    }
    fn fetch_min(&self, i: usize, v: u64) -> u64 {
        WordMemory::<u64>::fetch_min(&self.0, i, v)
    }
    fn fetch_max(&self, i: usize, v: u64) -> u64 {
        WordMemory::<u64>::fetch_max(&self.0, i, v)
    }
    fn fetch_add(&self, i: usize, v: u64) -> u64 {
        WordMemory::<u64>::fetch_add(&self.0, i, v)
    }
    fn fetch_or(&self, i: usize, v: u64) -> u64 {
        WordMemory::<u64>::fetch_or(&self.0, i, v)
    }
    fn swap(&self, i: usize, v: u64) -> u64 {
        WordMemory::<u64>::swap(&self.0, i, v)
    }
}

impl Memory for SignedMin {
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
        Self(SerialMemory::new(len32, init32, len64, init64))
    }
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

/// The library's sentinel against the integer semantics of `atomicMin`: with its own unsigned
/// `atomicMin`, every depth key from 0 to 1.0 is stored (the keys, sorted, as the depths sort);
/// a signed `int` `atomicMin` reads the same empty value `0xFFFFFFFF` as −1, below every key, so
/// it stores nothing, and every walk, handed back the empty value, takes itself for stored.
#[test]
fn a_signed_atomic_min_sees_the_librarys_empty_value_as_minus_one_and_keeps_nothing() {
    let depths = [0.5f32, 1.0, 0.0, f32::from_bits(1)];
    let keys: Vec<u32> = depths.iter().map(|&d| depth_key(d).unwrap()).collect();
    let (kept, outcomes) = mdts32_run::<SerialMemory>(&keys);
    let mut sorted = depths.to_vec();
    sorted.sort_by(f32::total_cmp);
    let sorted: Vec<u32> = sorted.iter().map(|d| d.to_bits()).collect();
    assert_eq!(kept, sorted);
    assert!(outcomes.iter().all(|&o| o == Step::Stored));
    let (kept, outcomes) = mdts32_run::<SignedMin>(&keys);
    assert_eq!(kept, [] as [u32; 0]);
    assert_eq!(outcomes, [Step::Stored; 4], "no walk notices");
}

/// `proof.md`'s cast to integer: with a unorm conversion, `round(d · (2^32 − 1))`, depth 1.0
/// becomes `0xFFFFFFFF`, the library's empty value. Its walk finds the empty slot, changes nothing,
/// reports itself stored, and the fragment is gone; the next fragment takes the slot. The bit
/// reinterpretation the library uses (`depth_key`) keeps depth 1.0 at `0x3F800000`.
#[test]
fn a_unorm_depth_one_equals_the_empty_value_and_vanishes_from_the_librarys_mdts() {
    let unorm = |d: f64| (d * f64::from(u32::MAX)).round() as u32;
    let empty = Mdts::<u32>::new(viewport(1, 1), 4, Direction::Ascending, MEMORY_CAP_DEFAULT)
        .unwrap()
        .layout()
        .init32;
    assert_eq!(unorm(1.0), empty);
    let (kept, outcomes) = mdts32_run::<SerialMemory>(&[unorm(1.0), unorm(0.25)]);
    assert_eq!(kept, [unorm(0.25)], "depth 1.0 vanished");
    assert_eq!(
        outcomes,
        [Step::Stored, Step::Stored],
        "and no drop was counted"
    );
    let bits = [depth_key(1.0).unwrap(), depth_key(0.25).unwrap()];
    assert_eq!(bits[0], MAX_KEY);
    assert_eq!(mdts32_run::<SerialMemory>(&bits).0, [bits[1], bits[0]]);
}

/// FreePipe's Table 1 as printed: slots initialised to `0xFFFFFFFF` (the text, §4.1.1) but the
/// loop stops when `atomicMin` returns `MAX_INTEGER` (`0x7FFFFFFF`, line 13). The returned value
/// is never `0x7FFFFFFF`, so every walk runs to the end of the array.
struct Table1Mdts {
    pixels: usize,
    k: u32,
}

/// The slot the walk tests next and the value it carries.
#[derive(Clone, Copy, Debug)]
struct Table1Walk {
    base: usize,
    slot: u32,
    carried: u32,
}

impl Scheme for Table1Mdts {
    type State = Table1Walk;

    fn name(&self) -> String {
        "mdts32-table1".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            words32: self.pixels * self.k as usize,
            init32: 0xFFFF_FFFF,
            words64: 0,
            init64: 0,
            table_bytes: 0,
        }
    }

    fn identity(&self) -> Identity {
        Identity::KeyOnly
    }

    fn promise(&self) -> Promise {
        Promise::Nearest(self.k)
    }

    fn guarantee(&self) -> Guarantee {
        // What the paper claims for it; the tests show where the literal reading breaks it.
        Guarantee::Exact
    }

    fn begin(&self, fragment: Fragment) -> Table1Walk {
        Table1Walk {
            base: fragment.pixel as usize * self.k as usize,
            slot: 0,
            carried: fragment.depth_key,
        }
    }

    fn step<M: Memory>(&self, walk: &mut Table1Walk, memory: &M) -> Step {
        let old =
            WordMemory::<u32>::fetch_min(memory, walk.base + walk.slot as usize, walk.carried);
        if old == 0x7FFF_FFFF {
            return Step::Stored;
        }
        walk.carried = walk.carried.max(old);
        walk.slot += 1;
        if walk.slot == self.k {
            // What falls off the end is usually the sentinel itself, yet it reads as a drop.
            Step::Dropped
        } else {
            Step::Continue
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let k = self.k as usize;
        out.extend(
            (0..k)
                .map(|slot| WordMemory::<u32>::load(memory, pixel * k + slot))
                .take_while(|&w| w != 0xFFFF_FFFF)
                .map(MdtsWord::decode),
        );
        0
    }

    fn pixels(&self) -> usize {
        self.pixels
    }
}

#[test]
fn freepipe_table1_mixed_sentinels_are_correct_but_never_exit_early() {
    let scene = Scene::procedural("spheres:4").unwrap();
    let view = scene
        .view(viewport(64, 64), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let k = oracle.max_depth_complexity();
    assert_eq!(k, 8);
    let table1 = Table1Mdts {
        pixels: view.viewport().pixels(),
        k,
    };
    let mdts =
        Mdts::<u32>::new(view.viewport(), k, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let (mixed, ours) = (run_serial(&view, &table1), run_serial(&view, &mdts));
    // Correct: the same sorted lists as MDTS with one sentinel, exactly the oracle's.
    assert_eq!(mixed.capture.entries, ours.capture.entries);
    assert_eq!(mixed.capture.offsets, ours.capture.offsets);
    assert!(oracle.diff(&mixed.capture).is_exact());
    // Never exits early: every fragment walks all K slots, and every walk ends as a "drop".
    let fragments = oracle.fragments() as u64;
    assert_eq!(mixed.stats.counters.steps, fragments * u64::from(k));
    assert_eq!(mixed.stats.counters.dropped, fragments);
    assert_eq!(ours.stats.counters.dropped, 0);
    let extra = mixed.stats.counters.steps - ours.stats.counters.steps;
    eprintln!(
        "spheres:4 64x64 K={k}: {fragments} fragments, Table 1 as printed {} steps, one sentinel {} steps, {extra} extra ({:.2}x)",
        mixed.stats.counters.steps,
        ours.stats.counters.steps,
        mixed.stats.counters.steps as f64 / ours.stats.counters.steps as f64
    );
    assert!(extra > 0);
}

// ---------------------------------------------------------------------------------------------
// Counters

#[test]
fn cuda_atomic_inc_past_capacity_overwrites_silently_where_fetch_add_counts_the_drop() {
    let scene = Scene::procedural("spheres:4").unwrap();
    let view = scene
        .view(viewport(64, 64), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 8);
    let capacity = 4;
    let vp = view.viewport();
    // fetch_add: what does not fit is dropped, counted, and the count is the oracle's overflow.
    let fixed = ABuffer::fixed(vp, capacity, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    let counted = assert_exact(&view, &oracle, &fixed);
    // atomicInc(&counter, capacity − 1): the counter wraps, later fragments overwrite slots 0, 1,
    // …, and the post pass reads `n mod capacity` slots. Nothing is dropped or reported.
    let inc = ABufferAtomicInc::wrapping(vp, capacity, MEMORY_CAP_DEFAULT).unwrap();
    let runs = [run_serial(&view, &inc), run_parallel(&view, &inc)];
    let complexity = oracle.depth_complexity();
    let kept: u64 = complexity.iter().map(|&n| u64::from(n % capacity)).sum();
    let overwritten: u64 = complexity
        .iter()
        .map(|&n| u64::from(n.saturating_sub(capacity)))
        .sum();
    for run in &runs {
        assert_eq!(run.stats.counters.dropped, 0);
        assert_eq!(run.capture.entries.len() as u64, kept);
        let diff = oracle.diff(&run.capture);
        assert_eq!(diff.reported_overflow, 0, "atomicInc reports no overflow");
        // The oracle predicts what should have overflowed, so the silence is a miscount at
        // every pixel past capacity, and what is missing beyond that prediction is lost.
        assert_eq!(diff.overflowed, overwritten);
        let past_capacity = complexity.iter().filter(|&&n| n > capacity).count() as u64;
        assert_eq!(diff.overflow_miscounted_pixels, past_capacity);
        assert_eq!(
            diff.lost + diff.overflowed,
            oracle.fragments() as u64 - kept,
            "{diff:?}"
        );
        assert!(!diff.is_exact());
    }
    // Even a pixel of exactly `capacity` fragments reads as empty: its counter wrapped to 0.
    let full = (0..oracle.pixels())
        .filter(|&p| complexity[p] == capacity)
        .collect::<Vec<_>>();
    assert!(!full.is_empty());
    assert!(full.iter().all(|&p| runs[0].capture.pixel(p).is_empty()));
    eprintln!(
        "spheres:4 64x64, capacity {capacity}: {} fragments; fetch_add keeps {}, drops and counts {counted}; \
         atomicInc keeps {kept}, overwrites {overwritten}, loses {} silently (reported overflow 0)",
        oracle.fragments(),
        oracle.fragments() as u64 - counted,
        oracle.fragments() as u64 - kept,
    );
}

#[test]
fn atomic_inc_on_ten_thousand_coincident_fragments_keeps_only_the_remainder() {
    let n = 10_000u32;
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]; n as usize],
    };
    let view = identity_view(&mesh, 1, 1);
    let oracle = Oracle::build(&view);
    let inc = ABufferAtomicInc::wrapping(view.viewport(), 8, MEMORY_CAP_DEFAULT).unwrap();
    let run = run_serial(&view, &inc);
    // 10,000 = 1250 · 8: the counter ends at 0 and the pixel reads as empty.
    assert!(run.capture.pixel(0).is_empty());
    let diff = oracle.diff(&run.capture);
    assert_eq!((diff.overflowed, diff.lost), (u64::from(n) - 8, 8));
    assert_eq!(diff.overflow_miscounted_pixels, 1);
    // With one fragment fewer the counter ends at 9999 mod 8 = 7: slots 0..=6 hold primitives
    // 9992..=9998, the last written there; slot 7 (primitive 9991) is not read.
    let fewer = Mesh {
        triangles: vec![[0, 1, 2]; n as usize - 1],
        ..mesh.clone()
    };
    let view = identity_view(&fewer, 1, 1);
    let run = run_serial(&view, &inc);
    let prims: Vec<u32> = run.capture.pixel(0).iter().map(|&w| w as u32).collect();
    assert_eq!(prims, (9992..9999).collect::<Vec<_>>());
    let fixed = ABuffer::fixed(view.viewport(), 8, PostSort::Insertion, MEMORY_CAP_DEFAULT);
    let run = run_serial(&view, &fixed.unwrap());
    assert_eq!(run.stats.counters.dropped, u64::from(n) - 1 - 8);
}

// ---------------------------------------------------------------------------------------------
// Geometry

#[test]
fn degenerate_triangles_produce_no_fragments() {
    let tiny = 1.0 / 4096.0; // 1/256 of a pixel on a 16-pixel side: below the snapping grid
    let mesh = soup(&[
        // collinear
        [[-1.0, -1.0, 0.5], [0.0, 0.0, 0.5], [1.0, 1.0, 0.5]],
        // a repeated vertex
        [[-1.0, -1.0, 0.5], [1.0, 0.0, 0.5], [1.0, 0.0, 0.5]],
        // one point
        [[0.3, 0.3, 0.5], [0.3, 0.3, 0.5], [0.3, 0.3, 0.5]],
        // smaller than the snapping grid, at a pixel centre
        [
            [1.0 / 16.0, 1.0 / 16.0, 0.5],
            [1.0 / 16.0 + tiny, 1.0 / 16.0, 0.5],
            [1.0 / 16.0, 1.0 / 16.0 + tiny, 0.5],
        ],
    ]);
    let view = identity_view(&mesh, 16, 16);
    for prim in 0..view.triangle_count() {
        let mut n = 0;
        view.rasterize(prim, &mut |_| n += 1);
        assert_eq!(n, 0, "triangle {prim}");
    }
}

#[test]
fn sliver_triangles_tile_the_screen_without_cracks_or_overlaps() {
    // A fan of 1,000 slivers from the top-left corner to the bottom edge, plus the triangle that
    // completes the square, and a sliver one grid step thick along the right edge.
    let n = 1000;
    let mut triangles: Vec<[[f32; 3]; 3]> = (0..n)
        .map(|i| {
            let x = |i: usize| -1.0 + 2.0 * i as f32 / n as f32;
            [[-1.0, 1.0, 0.5], [x(i), -1.0, 0.5], [x(i + 1), -1.0, 0.5]]
        })
        .collect();
    let thin = 1.0 - 1.0 / 8192.0;
    triangles.push([[-1.0, 1.0, 0.5], [1.0, -1.0, 0.5], [thin, 1.0, 0.5]]);
    triangles.push([[thin, 1.0, 0.5], [1.0, -1.0, 0.5], [1.0, 1.0, 0.5]]);
    let mesh = soup(&triangles);
    let counts = coverage(&identity_view(&mesh, 64, 64));
    assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
}

#[test]
fn vertices_at_1e7_are_clipped_to_the_guard_band_and_cover_the_screen_once() {
    // Identity camera: x = 1e7 is 3·10^8 pixels off screen, far beyond the guard band.
    let mesh = soup(&square(1e7, 0.5));
    for (width, height) in [(64, 48), (1, 1)] {
        let view = identity_view(&mesh, width, height);
        let fragments = all_fragments(&view);
        assert_eq!(fragments.len(), (width * height) as usize);
        assert!(coverage(&view).iter().all(|&c| c == 1));
        assert!(fragments
            .iter()
            .all(|f| f.depth_key == depth_key(0.5).unwrap()));
    }
    let mesh = soup(&[[[-1e7, -1e7, 0.25], [3e7, -1e7, 0.25], [-1e7, 3e7, 0.25]]]);
    assert!(coverage(&identity_view(&mesh, 33, 17))
        .iter()
        .all(|&c| c == 1));
}

#[test]
fn vertices_at_1e_minus_7_snap_to_one_point_and_produce_nothing() {
    // 1e-7 in clip space is 3·10^-6 pixels on a 64-pixel side: far below the 1/256 grid.
    let centre = 1.0 / 64.0; // the centre of pixel (32, 31)
    let mesh = soup(&[[
        [centre, centre, 0.5],
        [centre + 1e-7, centre, 0.5],
        [centre, centre + 1e-7, 0.5],
    ]]);
    assert!(all_fragments(&identity_view(&mesh, 64, 64)).is_empty());
}

/// Per-pixel depth complexity of `spheres:3` scaled by `scale`, seen by the orbit camera at
/// 64 × 64, after checking MDTS captures it exactly.
fn scaled_spheres(scale: f32) -> Vec<u32> {
    let mut scene = Scene::procedural("spheres:3").unwrap();
    for p in &mut scene.mesh.positions {
        *p = p.map(|c| c * scale);
    }
    let view = scene
        .view(viewport(64, 64), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let k = oracle.max_depth_complexity();
    assert_eq!(k, 6, "scale {scale:e}");
    let mdts = Mdts::<u64>::ascending(view.viewport(), k).unwrap();
    assert!(oracle.diff(&run_serial(&view, &mdts).capture).is_exact());
    oracle.depth_complexity()
}

#[test]
fn a_model_scaled_by_1e7_or_1e_minus_5_renders_like_the_original() {
    let reference = scaled_spheres(1.0);
    for scale in [1e7, 1e-5] {
        let scaled = scaled_spheres(scale);
        let differing = reference
            .iter()
            .zip(&scaled)
            .filter(|(a, b)| a != b)
            .count();
        // Scaling is not exact in binary: a few vertices may snap one grid step apart.
        assert!(
            differing <= reference.len() / 100,
            "scale {scale:e}: {differing} pixels differ"
        );
    }
}

#[test]
fn a_model_below_2e_minus_6_across_is_framed_as_if_it_were_2e_minus_6() {
    // `OrbitCamera` clamps the bounding radius to at least 1e-6 (to survive a one-point mesh):
    // spheres of radius 1e-7 are still captured exactly, but drawn about ten times smaller.
    let covered = |counts: Vec<u32>| counts.iter().filter(|&&c| c > 0).count();
    let reference = covered(scaled_spheres(1.0));
    let tiny = covered(scaled_spheres(1e-7));
    assert!(
        tiny > 0 && tiny * 20 < reference,
        "{tiny} vs {reference} pixels"
    );
}

/// The eye-space triangle A, B, C clipped by hand at `z = −near` (exactly representable here),
/// as a mesh: what the pipeline's homogeneous clipping must reproduce.
fn coverage_clipped_by_hand(pieces: &[[[f32; 3]; 3]], camera: &Camera) -> Vec<u32> {
    let mesh = soup(pieces);
    coverage(&View::new(&mesh, camera, viewport(32, 32), CullMode::None))
}

#[test]
fn a_triangle_crossing_the_near_plane_is_clipped_and_keeps_its_primitive_id() {
    let camera = perspective(1.0, 100.0);
    // C lies between the eye and the near plane (z = −0.5); A and B beyond it (z = −1.5).
    let (a, b, c) = ([-1.5, -1.5, -1.5], [1.5, -1.5, -1.5], [0.0, 0.5, -0.5]);
    let hidden = [[-1.0, -1.0, -50.0], [1.0, -1.0, -50.0], [0.0, 1.0, -50.0]];
    let mesh = soup(&[hidden, hidden, [a, b, c]]);
    let view = View::new(&mesh, &camera, viewport(32, 32), CullMode::None);
    let mut clipped = Vec::new();
    view.rasterize(2, &mut |f| clipped.push(f));
    assert!(!clipped.is_empty());
    assert!(clipped
        .iter()
        .all(|f| f.prim == 2 && f.depth_key <= MAX_KEY));
    let mut counts = vec![0; 32 * 32];
    for f in &clipped {
        counts[f.pixel as usize] += 1;
    }
    // The near plane cuts CA and CB at their midpoints (z = −1).
    let (ca, cb) = ([-0.75, -0.5, -1.0], [0.75, -0.5, -1.0]);
    let by_hand = coverage_clipped_by_hand(&[[a, b, cb], [a, cb, ca]], &camera);
    assert_eq!(counts, by_hand);
}

#[test]
fn a_triangle_crossing_the_eye_plane_w_0_is_clipped_not_inverted() {
    let camera = perspective(1.0, 100.0);
    // C is behind the eye (z = +1, so w = −1); the near plane cuts CA and CB at z = −1.
    let (a, b, c) = ([-1.0, -1.0, -3.0], [1.0, -1.0, -3.0], [0.0, 1.0, 1.0]);
    let mesh = soup(&[[a, b, c]]);
    let counts = coverage(&View::new(&mesh, &camera, viewport(32, 32), CullMode::None));
    let (ca, cb) = ([-0.5, 0.0, -1.0], [0.5, 0.0, -1.0]);
    let by_hand = coverage_clipped_by_hand(&[[a, b, cb], [a, cb, ca]], &camera);
    assert!(by_hand.iter().sum::<u32>() > 0);
    assert_eq!(counts, by_hand);
    // FreePipe's bounding-box-only approach divides by w < 0: C lands at the bottom of the
    // screen instead of beyond the top, and the triangle drawn is a different, inverted one.
    let project = |[x, y, z]: [f32; 3]| {
        let w = -z;
        [x / w, y / w, 0.5]
    };
    let naive = soup(&[[project(a), project(b), project(c)]]);
    let naive_counts = coverage(&identity_view(&naive, 32, 32));
    assert_ne!(naive_counts, counts);
}

#[test]
fn a_piece_with_a_vertex_at_w_0_is_dropped_as_documented() {
    // A projection with w = z does not keep w away from 0 at the near plane (z ≥ 0 ⇔ w ≥ 0): a
    // triangle reaching w < 0 is clipped to a piece with a vertex at w = 0, which is dropped.
    let camera = camera_from_columns([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, 0.0, 0.0],
    ]);
    let crossing = soup(&[[[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, -1.0]]]);
    let view = View::new(&crossing, &camera, viewport(16, 16), CullMode::None);
    assert!(all_fragments(&view).is_empty());
    // In front of w = 0 the same projection draws (depth z / w = 1 everywhere).
    let in_front = soup(&[[[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]]]);
    let view = View::new(&in_front, &camera, viewport(16, 16), CullMode::None);
    let fragments = all_fragments(&view);
    assert!(!fragments.is_empty());
    assert!(fragments.iter().all(|f| f.depth_key == MAX_KEY));
}

/// The depth keys of full-screen squares at these eye-space distances, under `camera`.
fn keys_of_layers(camera: &Camera, distances: &[f32]) -> (Vec<u32>, Mesh) {
    let triangles: Vec<[[f32; 3]; 3]> = distances
        .iter()
        .flat_map(|&d| square(2.0 * d, -d))
        .collect();
    let mesh = soup(&triangles);
    let view = View::new(&mesh, camera, viewport(1, 1), CullMode::None);
    let keys = (0..distances.len() as u32)
        .map(|layer| {
            let mut key = None;
            for prim in [2 * layer, 2 * layer + 1] {
                view.rasterize(prim, &mut |f| key = Some(f.depth_key));
            }
            key.expect("each layer covers the pixel")
        })
        .collect();
    (keys, mesh)
}

#[test]
fn a_near_far_ratio_of_1e_minus_7_merges_distinct_layers_ordered_by_primitive() {
    let distances: Vec<f32> = (1..=10).map(|i| i as f32 / 10.0).collect();
    let (keys, _) = keys_of_layers(&perspective(1e-7, 1.0), &distances);
    let mut distinct = keys.clone();
    distinct.dedup();
    // Depth ≈ 1 − 1e-7 / d: ten layers from 0.1 to 1.0 get only a handful of keys just below 1.0.
    assert!(keys.iter().all(|&k| k > depth_key(0.999_998).unwrap()));
    assert!(distinct.len() < distances.len(), "{keys:x?}");
    eprintln!(
        "near/far 1e-7: layers at 0.1..1.0 get {} distinct keys: {keys:x?}",
        distinct.len()
    );
    // With near/far = 1e-2 they are all distinct.
    let (keys, _) = keys_of_layers(&perspective(1e-2, 1.0), &distances);
    let mut distinct = keys.clone();
    distinct.dedup();
    assert_eq!(distinct.len(), distances.len());
    // Merged layers are still captured exactly: equal keys in primitive order, as the oracle.
    let camera = perspective(1e-7, 1.0);
    let (_, mesh) = keys_of_layers(&camera, &[0.9, 0.8, 0.7, 0.6, 0.5]);
    let view = View::new(&mesh, &camera, viewport(8, 8), CullMode::None);
    let oracle = Oracle::build(&view);
    let mdts = Mdts::<u64>::ascending(view.viewport(), oracle.max_depth_complexity()).unwrap();
    assert_exact(&view, &oracle, &mdts);
}

#[test]
fn two_layers_closer_than_one_ulp_keep_both_in_primitive_order() {
    let camera = perspective(1.0, 100.0);
    // Eye-space distances one f32 ulp apart; the farther layer has the lower primitive ids.
    let far = 50.0f32;
    let near = f32::from_bits(far.to_bits() - 1);
    let (keys, mesh) = keys_of_layers(&camera, &[far, near]);
    assert_eq!(keys[0], keys[1], "one depth key for both layers");
    let view = View::new(&mesh, &camera, viewport(4, 4), CullMode::None);
    let oracle = Oracle::build(&view);
    let mdts = Mdts::<u64>::ascending(view.viewport(), 2).unwrap();
    let run = run_serial(&view, &mdts);
    assert!(oracle.diff(&run.capture).is_exact());
    for p in 0..view.viewport().pixels() {
        let list = run.capture.pixel(p);
        assert_eq!(list.len(), 2, "pixel {p}");
        assert_eq!(list[0] >> 32, list[1] >> 32);
        assert!(
            (list[0] as u32) < 2 && (list[1] as u32) >= 2,
            "pixel {p}: {list:x?}"
        );
    }
    let keys_only =
        Mdts::<u32>::new(view.viewport(), 2, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let capture = run_serial(&view, &keys_only).capture;
    assert!(oracle.diff(&capture).is_exact());
    assert!((0..capture.pixels()).all(|p| capture.pixel(p).len() == 2));
}

#[test]
fn ten_thousand_coincident_triangles_on_one_pixel_are_ordered_by_primitive_id() {
    let n = 10_000u32;
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]; n as usize],
    };
    let view = identity_view(&mesh, 1, 1);
    let oracle = Oracle::build(&view);
    let key = u64::from(depth_key(0.5).unwrap()) << 32;
    let expected: Vec<u64> = (0..n).map(|prim| key | u64::from(prim)).collect();
    assert_eq!(oracle.pixel(0), expected.as_slice());
    let mdts = Mdts::<u64>::ascending(view.viewport(), n).unwrap();
    for run in [run_serial(&view, &mdts), run_parallel(&view, &mdts)] {
        assert_eq!(run.capture.pixel(0), expected.as_slice());
    }
    // Serially, fragment i walks past the i equal-key fragments before it: n (n + 1) / 2 steps.
    let steps = run_serial(&view, &mdts).stats.counters.steps;
    assert_eq!(steps, u64::from(n) * u64::from(n + 1) / 2);
    let abuffer = ABuffer::exact(
        &oracle.depth_complexity(),
        PostSort::Insertion,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    assert_exact(&view, &oracle, &abuffer);
    let bitonic = ABuffer::exact(
        &oracle.depth_complexity(),
        PostSort::Bitonic,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    assert_exact(&view, &oracle, &bitonic);
    let keys_only =
        Mdts::<u32>::new(view.viewport(), n, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let capture = run_serial(&view, &keys_only).capture;
    assert_eq!(capture.pixel(0), vec![key; n as usize].as_slice());
}

// ---------------------------------------------------------------------------------------------
// Sizes

#[test]
fn a_1x1_viewport_is_captured_exactly() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene.view(viewport(1, 1), &OrbitCamera::default()).unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 6);
    assert_exact(
        &view,
        &oracle,
        &Mdts::<u64>::ascending(view.viewport(), 6).unwrap(),
    );
    let abuffer = ABuffer::exact_default(&oracle.depth_complexity()).unwrap();
    assert_exact(&view, &oracle, &abuffer);
}

#[test]
fn a_16384_square_viewport_beyond_the_memory_cap_is_refused_naming_the_bytes() {
    let side = Viewport::MAX_SIDE;
    assert_eq!(side, 16384);
    let huge = viewport(side, side);
    let cap = 1_000_000;
    let pixels = u64::from(side) * u64::from(side);
    let refused = |result: Result<(), CaptureError>, needed: u64| {
        let err = result.unwrap_err();
        assert_eq!(
            err,
            CaptureError::TooMuchMemory {
                scheme: match &err {
                    CaptureError::TooMuchMemory { scheme, .. } => scheme.clone(),
                    other => panic!("{other}"),
                },
                needed,
                cap,
            }
        );
        let message = err.to_string();
        assert!(message.contains(&needed.to_string()), "{message}");
    };
    refused(
        Mdts::<u64>::new(huge, 1, Direction::Ascending, cap).map(drop),
        pixels * 8,
    );
    refused(
        Mdts::<u32>::new(huge, 1, Direction::Ascending, cap).map(drop),
        pixels * 4,
    );
    refused(
        ABuffer::fixed(huge, 1, PostSort::Insertion, cap).map(drop),
        pixels * 12,
    );
    // One more pixel per side is refused by the viewport itself.
    let err = Viewport::new(side + 1, 1).unwrap_err();
    assert!(err.contains("16384"), "{err}");
}

#[test]
fn the_binary_refuses_a_16384_square_viewport_beyond_the_memory_cap_before_the_oracle() {
    let start = Instant::now();
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "--width",
            "16384",
            "--height",
            "16384",
            "--memory-cap",
            "1000000",
            "--no-images",
        ])
        .output()
        .unwrap();
    let elapsed = start.elapsed();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(!stderr.contains("panicked"), "{stderr}");
    // MDTS with 64-bit words and the default K = 20: 16384² × 20 × 8 bytes.
    assert!(
        stderr.contains("42949672960") && stderr.contains("1000000"),
        "{stderr}"
    );
    // Refused before the oracle's counting pass (which took 20 s and 5.4 GB here before the fix).
    assert!(elapsed.as_secs() < 10, "took {elapsed:?}");
}

#[test]
fn k_1_keeps_exactly_the_nearest_layer_and_counts_the_rest() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene
        .view(viewport(48, 48), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let mdts = Mdts::<u64>::ascending(view.viewport(), 1).unwrap();
    // The overflow, counted here from the depth complexity alone: every fragment but one per
    // covered pixel; the scheme's own drops must equal it (`assert_exact`).
    let covered = oracle.depth_complexity().iter().filter(|&&c| c > 0).count() as u64;
    assert_eq!(
        assert_exact(&view, &oracle, &mdts),
        oracle.fragments() as u64 - covered
    );
    let run = run_serial(&view, &mdts);
    for p in 0..oracle.pixels() {
        assert_eq!(
            run.capture.pixel(p),
            &oracle.pixel(p)[..oracle.pixel(p).len().min(1)]
        );
    }
}

#[test]
fn k_1024_costs_memory_but_no_extra_steps() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene
        .view(viewport(32, 32), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let full = oracle.max_depth_complexity();
    let wide = Mdts::<u64>::ascending(view.viewport(), 1024).unwrap();
    let tight = Mdts::<u64>::ascending(view.viewport(), full).unwrap();
    assert_exact(&view, &oracle, &wide);
    let (w, t) = (run_serial(&view, &wide), run_serial(&view, &tight));
    assert_eq!(w.capture.entries, t.capture.entries);
    assert_eq!(w.capture.offsets, t.capture.offsets);
    // A walk stops at the first empty slot: slots beyond the depth complexity are never touched.
    assert_eq!(w.stats.counters.steps, t.stats.counters.steps);
    assert_eq!(w.stats.memory_bytes, 32 * 32 * 1024 * 8);
    assert_eq!(t.stats.memory_bytes, 32 * 32 * u64::from(full) * 8);
}

#[test]
fn a_scene_with_zero_triangles_is_a_clear_error() {
    let empty = Scene {
        name: "nothing".into(),
        mesh: Mesh {
            positions: vec![[0.0; 3]; 3],
            triangles: Vec::new(),
        },
    };
    let err = empty
        .view(viewport(8, 8), &OrbitCamera::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("nothing") && err.contains("no triangles"),
        "{err}"
    );
    let err =
        Mesh::read_obj(&mut "v 0 0 0\nv 1 0 0\nv 1 1 0\n".as_bytes(), "points.obj").unwrap_err();
    assert!(matches!(err, MeshError::Empty { .. }), "{err}");
    assert!(err.to_string().contains("points.obj has no triangles"));
}

#[test]
fn one_triangle_covering_the_whole_screen_covers_every_pixel_once() {
    let mesh = soup(&[[[-1.0, -1.0, 0.75], [3.0, -1.0, 0.75], [-1.0, 3.0, 0.75]]]);
    for (width, height) in [(64, 48), (1, 1), (1, 64)] {
        let view = identity_view(&mesh, width, height);
        assert!(coverage(&view).iter().all(|&c| c == 1), "{width}x{height}");
        let oracle = Oracle::build(&view);
        let mdts = Mdts::<u64>::ascending(view.viewport(), 1).unwrap();
        assert_exact(&view, &oracle, &mdts);
        assert_eq!(run_serial(&view, &mdts).stats.counters.dropped, 0);
    }
}

#[test]
fn depth_complexity_above_k_is_counted_as_overflow_equal_to_drops() {
    let scene = Scene::procedural("spheres:4").unwrap();
    let view = scene
        .view(viewport(48, 48), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 8);
    let k = 3;
    let beyond_k: u64 = oracle
        .depth_complexity()
        .iter()
        .map(|&c| u64::from(c.saturating_sub(k)))
        .sum();
    assert!(beyond_k > 0);
    let vp = view.viewport();
    let asc = Mdts::<u64>::ascending(vp, k).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &asc), beyond_k);
    let desc = Mdts::<u64>::new(vp, k, Direction::Descending, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &desc), beyond_k);
    let keys = Mdts::<u32>::new(vp, k, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &keys), beyond_k);
    let fixed = ABuffer::fixed(vp, k, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &fixed), beyond_k);
}

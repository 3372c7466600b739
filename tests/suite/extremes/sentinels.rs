//! Sentinels: no depth key collides with the empty values, against the integer semantics of
//! signed and unsigned `atomicMin`, and FreePipe's Table 1 with its mixed sentinels.

use fragsim::capture::executors::run_serial;
use fragsim::capture::{
    Descriptor, Guarantee, Identity, Promise, Scheme, Step, MEMORY_CAP_DEFAULT,
};
use fragsim::memory::{Layout, Memory, SerialMemory, WordMemory};
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, EMPTY_KEY};
use fragsim::schemes::mdts::{Direction, Mdts, MdtsWord};
use proptest::prelude::*;

use super::{mdts32_run, viewport, MAX_KEY};

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
    for sign in [0, 0x8000_0000_u32] {
        for exponent in 0..256_u32 {
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
    for sentinel in [0x7FFF_FFFF_u32, 0xFFFF_FFFF] {
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
/// The library's sentinel against the integer semantics of `atomicMin`: with its own unsigned
/// `atomicMin`, every depth key from 0 to 1.0 is stored (the keys, sorted, as the depths sort);
/// a signed `int` `atomicMin` reads the same empty value `0xFFFFFFFF` as −1, below every key, so
/// it stores nothing, and every walk, handed back the empty value, takes itself for stored.
#[test]
fn a_signed_atomic_min_sees_the_librarys_empty_value_as_minus_one_and_keeps_nothing() {
    let depths = [0.5_f32, 1.0, 0.0, f32::from_bits(1)];
    let keys: Vec<u32> = depths.iter().map(|&d| depth_key(d).unwrap()).collect();
    let (kept, outcomes) = mdts32_run::<SerialMemory>(&keys);
    let mut sorted = depths.to_vec();
    sorted.sort_by(f32::total_cmp);
    let sorted: Vec<u32> = sorted.iter().map(|d| d.to_bits()).collect();
    assert_eq!(kept, sorted);
    assert!(outcomes.iter().all(|&o| o == Step::Stored));
    let (signed_kept, signed_outcomes) = mdts32_run::<SignedMin>(&keys);
    assert_eq!(signed_kept, [] as [u32; 0]);
    assert_eq!(signed_outcomes, [Step::Stored; 4], "no walk notices");
}

/// `proof.md`'s cast to integer: with a unorm conversion, `round(d · (2^32 − 1))`, depth 1.0
/// becomes `0xFFFFFFFF`, the library's empty value. Its walk finds the empty slot, changes nothing,
/// reports itself stored, and the fragment is gone; the next fragment takes the slot. The bit
/// reinterpretation the library uses (`depth_key`) keeps depth 1.0 at `0x3F800000`.
#[test]
fn a_unorm_depth_one_equals_the_empty_value_and_vanishes_from_the_librarys_mdts() {
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a depth in [0, 1] scaled to u32::MAX fits u32"
    )]
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
    descriptor: Descriptor,
    k: u32,
}

impl Table1Mdts {
    /// The literal Table 1 with `k` slots for each of `pixels` pixels.
    fn new(pixels: usize, k: u32) -> Self {
        let descriptor = Descriptor {
            name: "mdts32-table1".into(),
            layout: Layout {
                words32: pixels * k as usize,
                init32: 0xFFFF_FFFF,
                words64: 0,
                init64: 0,
                table_bytes: 0,
            },
            identity: Identity::KeyOnly,
            // What the paper claims for it; the tests show where the literal reading breaks it.
            guarantee: Guarantee::Exact,
            promise: Promise::Nearest(k),
            pixels,
            counts_every_drop: false,
        };
        Self { descriptor, k }
    }
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
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
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
    let table1 = Table1Mdts::new(view.viewport().pixels(), k);
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

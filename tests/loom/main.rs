//! Exhaustive model checking of the atomic capture schemes with loom.
//!
//! Every scheme is generic over `Memory`, so this suite runs the library's own MDTS and A-buffer
//! code on [`LoomMemory`], loom's atomics behind the same seam, inside a plain
//! `cargo test --release --test loom`: no `--cfg loom`, no environment variables. Each model puts
//! one fragment per loom thread on ONE pixel (at most 4 spawned threads: loom's limit is 5
//! including the model's main thread), runs each walk with `Scheme::insert` (so one loom step per
//! `Scheme::step`, one memory operation each, every atomic `Relaxed`), joins them all, and checks
//! the post pass on the main thread. loom explores every interleaving of the steps and every value
//! a `Relaxed` load may read; with a preemption bound (named in the test's name) it explores every
//! interleaving with at most that many preemptions.
//!
//! The words are shared as `&'static` (a `Box` leaked once per model iteration), not through
//! `loom::sync::Arc`, whose reference counts loom would model too (that multiplies the state space
//! by about 225).
//!
//! The last tests are controls run through the same checker that passes MDTS: the library's
//! k-buffer, whose read–insert–write is not atomic, must lose a fragment in some interleaving
//! (so the harness is not vacuous); and two schemes written here: an MDTS variant that stops on an
//! equal slot must lose a duplicate depth, and FreePipe's Table 1 read literally (mismatched
//! sentinels) must stay correct while never exiting early. The proofs these tests check are in `docs/proof.md`, with the
//! interleaving counts and the suite's wall time.

use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;
use std::time::Instant;

use fragsim::capture::{Keeps, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};
use fragsim::memory::{Memory, WordMemory};
use fragsim::raster::{depth_key, Fragment, Viewport};
use fragsim::schemes::abuffer::ABuffer;
use fragsim::schemes::mdts::{Direction, Mdts, MdtsWord};
use loom::sync::atomic::{
    AtomicU32, AtomicU64,
    Ordering::{Acquire, Relaxed, Release},
};

mod abuffer;
mod kbuffer;
mod kbuffer_interlock;
mod kbuffer_interlock_ordered;
mod kbuffer_spinlock;
mod mdts;
mod mdts_emulated64;
mod shipping;
mod table1;

// ---------------------------------------------------------------------------------------------
// The memory seam on loom's atomics.

/// Per-pixel words on loom's atomics, every operation `Relaxed` (as `AtomicMemory`).
#[derive(Debug)]
struct LoomMemory {
    words32: Vec<AtomicU32>,
    words64: Vec<AtomicU64>,
}

macro_rules! loom_words {
    ($word:ty, $field:ident) => {
        impl WordMemory<$word> for LoomMemory {
            fn len(&self) -> usize {
                self.$field.len()
            }
            fn load(&self, i: usize) -> $word {
                self.$field[i].load(Relaxed)
            }
            fn store(&self, i: usize, v: $word) {
                self.$field[i].store(v, Relaxed);
            }
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_min(v, Relaxed)
            }
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_max(v, Relaxed)
            }
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_add(v, Relaxed)
            }
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_or(v, Relaxed)
            }
            fn swap(&self, i: usize, v: $word) -> $word {
                self.$field[i].swap(v, Relaxed)
            }
        }
    };
}

loom_words!(u32, words32);
loom_words!(u64, words64);

impl Memory for LoomMemory {
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
        Self {
            words32: (0..len32).map(|_| AtomicU32::new(init32)).collect(),
            words64: (0..len64).map(|_| AtomicU64::new(init64)).collect(),
        }
    }

    // The render-target k-buffer's pixel lock, in loom's terms: loom does not see std fences, so
    // the ordering is on the lock word itself (acquire compare-exchange, release store), and a
    // waiting thread yields so that loom schedules the holder. A failed compare-exchange writes
    // nothing, so waiting is not a state change loom would explore without end (a `swap` loop is).
    fn lock(&self, index: usize) {
        while self.words32[index]
            .compare_exchange(0, 1, Acquire, Relaxed)
            .is_err()
        {
            loom::thread::yield_now();
        }
    }

    // The spinlock's one attempt: the same acquire compare-exchange, once (the caller yields
    // before a retry).
    fn try_lock(&self, index: usize) -> bool {
        self.words32[index]
            .compare_exchange(0, 1, Acquire, Relaxed)
            .is_ok()
    }

    fn unlock(&self, index: usize) {
        self.words32[index].store(0, Release);
    }
}

// ---------------------------------------------------------------------------------------------
// The harness.

/// Runs `model` under loom, every interleaving (with at most `preemption_bound` preemptions when
/// one is given), and returns how many it explored. The limits are set here, not read from the
/// environment, so that no `LOOM_*` variable can make a run less exhaustive than its name says.
fn explore(
    name: &str,
    preemption_bound: Option<usize>,
    model: impl Fn() + Sync + Send + 'static,
) -> usize {
    let iterations = Arc::new(AtomicUsize::new(0));
    let counter = Arc::clone(&iterations);
    let mut builder = loom::model::Builder::new();
    builder.preemption_bound = preemption_bound;
    builder.max_permutations = None;
    builder.max_duration = None;
    builder.checkpoint_file = None;
    let start = Instant::now();
    builder.check(move || {
        counter.fetch_add(1, StdOrdering::Relaxed);
        model();
    });
    let explored = iterations.load(StdOrdering::Relaxed);
    let bound = preemption_bound.map_or("none".to_string(), |b| b.to_string());
    eprintln!(
        "loom {name}: {explored} interleavings, preemption bound {bound}, {:.2?}",
        start.elapsed()
    );
    explored
}

/// One fragment on pixel 0 (the only pixel of a 1×1 viewport).
fn fragment(depth: f32, prim: u32) -> Fragment {
    Fragment {
        pixel: 0,
        depth_key: depth_key(depth).expect("depth in [0, 1]"),
        prim,
    }
}

/// A 1×1 viewport: every model works on one pixel.
fn one_pixel() -> Viewport {
    Viewport::new(1, 1).expect("1×1 is a valid viewport")
}

/// What the joined walks of one model iteration report, in the fragments' order.
struct Walks {
    /// How each walk ended.
    outcomes: Vec<Step>,
    /// How many steps (memory operations) each walk took.
    steps: Vec<u64>,
}

/// Inside one model iteration: fresh words for `scheme`, one loom thread per fragment running its
/// walk to the end with `Scheme::insert`, all joined. Returns the words (leaked: loom threads need
/// `'static`) and the walks' outcomes and step counts.
fn run_threads<S>(scheme: &'static S, fragments: &[Fragment]) -> (&'static LoomMemory, Walks)
where
    S: Scheme<Input = Fragment> + 'static,
{
    let memory: &'static LoomMemory = Box::leak(Box::new(scheme.layout().allocate()));
    let handles: Vec<_> = fragments
        .iter()
        .map(|&f| {
            loom::thread::spawn(move || {
                let mut steps = 0;
                let outcome = scheme.insert(f, memory, &mut steps);
                (outcome, steps)
            })
        })
        .collect();
    let (outcomes, steps) = handles
        .into_iter()
        .map(|h| h.join().expect("a walk panicked"))
        .unzip();
    (memory, Walks { outcomes, steps })
}

/// Inside one model iteration: fresh words for `scheme`, one loom thread per fragment running its
/// walk step by step, all joined; returns the words and the walks' outcomes. A walk whose step
/// failed to take a lock or to enter ([`Scheme::simt`]'s `spinning`) yields before its retry, as
/// a spinning GPU thread gives way under independent thread scheduling (without it loom would
/// explore a spin without end). `before` sees each step's state before it runs, `after` the state
/// before and after it and how it ended (the spinlock's mutual-exclusion count).
fn run_spinning<S, B, A>(
    scheme: &'static S,
    fragments: &[Fragment],
    before: B,
    after: A,
) -> (&'static LoomMemory, Vec<Step>)
where
    S: Scheme<Input = Fragment> + 'static,
    B: Fn(&S::State) + Copy + Send + 'static,
    A: Fn(&S::State, &S::State) + Copy + Send + 'static,
{
    let memory: &'static LoomMemory = Box::leak(Box::new(scheme.layout().allocate()));
    let handles: Vec<_> = fragments
        .iter()
        .map(|&f| {
            loom::thread::spawn(move || {
                let mut walk = scheme.begin(f);
                loop {
                    before(&walk);
                    let was = walk.clone();
                    let outcome = scheme.step(&mut walk, memory);
                    after(&was, &walk);
                    match outcome {
                        Step::Continue if scheme.simt(&walk).spinning => {
                            loom::thread::yield_now();
                        }
                        Step::Continue => {}
                        done => return done,
                    }
                }
            })
        })
        .collect();
    let outcomes = handles
        .into_iter()
        .map(|h| h.join().expect("a walk panicked"))
        .collect();
    (memory, outcomes)
}

/// The checker shared by MDTS and the negative control: `kept`, the pixel's list from the post
/// pass (nearest first), must be exactly the `K` smallest of `values` (the `K` largest when
/// descending) in ascending order, every value as many times as it was inserted and no more; and
/// exactly one walk per value that did not fit must have ended `Dropped`, every other `Stored`.
/// Returns what is wrong, if anything.
fn k_best_error(
    direction: Direction,
    k: u32,
    values: &[u64],
    kept: &[u64],
    outcomes: &[Step],
) -> Option<String> {
    let mut sorted = values.to_vec();
    sorted.sort_unstable();
    let n = sorted.len();
    let m = n.min(k as usize);
    let expected = match direction {
        Direction::Ascending => &sorted[..m],
        Direction::Descending => &sorted[n - m..],
    };
    if kept != expected {
        return Some(format!(
            "a value was lost or duplicated: kept {kept:x?}, the {m} best of {values:x?} are {expected:x?}"
        ));
    }
    let dropped = outcomes.iter().filter(|&&o| o == Step::Dropped).count();
    let stored = outcomes.iter().filter(|&&o| o == Step::Stored).count();
    if (stored, dropped) != (m, n - m) {
        return Some(format!(
            "{stored} walks stored and {dropped} dropped, expected {m} and {}: {outcomes:?}",
            n - m
        ));
    }
    None
}

/// [`k_best_error`] as an assertion.
fn check_k_best(direction: Direction, k: u32, values: &[u64], kept: &[u64], outcomes: &[Step]) {
    if let Some(error) = k_best_error(direction, k, values, kept, outcomes) {
        panic!("{error}");
    }
}

/// Models MDTS over words `W` on one pixel with `K = k`, one loom thread per fragment, and checks
/// every interleaving: the post pass gives exactly the `K` best values, sorted (`check_k_best`);
/// `max(0, n − K)` walks dropped; the slots past the last kept value are still empty; and the walk
/// lengths are `1, 2, …, min(n, K)` and `K` for each dropped walk, that is exactly one walk stopped
/// at each slot (the one that found it empty), the induction step of `docs/proof.md`.
/// Returns the number of interleavings explored.
fn mdts_model<W: MdtsWord>(
    name: &str,
    direction: Direction,
    k: u32,
    fragments: &[Fragment],
    preemption_bound: Option<usize>,
) -> usize {
    let scheme =
        Mdts::<W>::new(one_pixel(), k, direction, MEMORY_CAP_DEFAULT).expect("a valid MDTS");
    mdts_scheme_model(name, scheme, direction, fragments, preemption_bound)
}

/// [`mdts_model`] for the probing walk (a load, then `atomicMin` only where it changes the
/// slot): every check but the walk lengths, which count the loads too.
fn mdts_probe_model<W: MdtsWord>(
    name: &str,
    direction: Direction,
    k: u32,
    fragments: &[Fragment],
    preemption_bound: Option<usize>,
) -> usize {
    let scheme =
        Mdts::<W>::new(one_pixel(), k, direction, MEMORY_CAP_DEFAULT).expect("a valid MDTS");
    mdts_scheme_model(
        name,
        scheme.probing(),
        direction,
        fragments,
        preemption_bound,
    )
}

/// The body of [`mdts_model`] and [`mdts_probe_model`].
fn mdts_scheme_model<W: MdtsWord>(
    name: &str,
    scheme: Mdts<W>,
    direction: Direction,
    fragments: &[Fragment],
    preemption_bound: Option<usize>,
) -> usize {
    assert!(
        fragments.len() <= 4,
        "loom allows 4 threads besides the main one"
    );
    let k = scheme.k();
    let probing = scheme.name().ends_with("-probe");
    let scheme: &'static Mdts<W> = Box::leak(Box::new(scheme));
    let fragments = fragments.to_vec();
    let values: Vec<u64> = fragments.iter().map(|&f| W::encode(f).decode()).collect();
    let empty = match direction {
        Direction::Ascending => W::MAX,
        Direction::Descending => W::ZERO,
    };
    explore(name, preemption_bound, move || {
        let (memory, Walks { outcomes, steps }) = run_threads(scheme, &fragments);
        let capture = scheme.resolve(memory);
        check_k_best(direction, k, &values, capture.pixel(0), &outcomes);
        let words = W::words(memory);
        let m = fragments.len().min(k as usize);
        for slot in m..k as usize {
            assert_eq!(words.load(slot), empty, "slot {slot} past the kept values");
        }
        if probing {
            return;
        }
        let mut lengths = steps.clone();
        lengths.sort_unstable();
        let expected: Vec<u64> = (1..=m as u64)
            .chain(std::iter::repeat_n(u64::from(k), fragments.len() - m))
            .collect();
        assert_eq!(
            lengths, expected,
            "one walk stops at each slot: {outcomes:?} {steps:?}"
        );
    })
}

/// Models the A-buffer `scheme` (one pixel, `capacity` slots) with one loom thread per fragment
/// and checks every interleaving: the counter ends at `n`; `min(n, capacity)` walks stored and the
/// rest dropped; the post pass gives distinct fragments, sorted, all of them when they fit and a
/// subset otherwise, with the overflow `n − capacity` reported; unused slots are untouched.
/// Returns the number of interleavings explored.
#[expect(
    clippy::cast_possible_truncation,
    clippy::shadow_unrelated,
    reason = "a loom model's list has a few fragments; the promise's capacity is the one the field holds"
)]
fn abuffer_model(
    name: &str,
    scheme: ABuffer,
    capacity: usize,
    fragments: &[Fragment],
    preemption_bound: Option<usize>,
) -> usize {
    assert!(
        fragments.len() <= 4,
        "loom allows 4 threads besides the main one"
    );
    let scheme: &'static ABuffer = Box::leak(Box::new(scheme));
    assert_eq!(
        scheme.layout().words64,
        capacity,
        "one pixel of {capacity} slots"
    );
    let fragments = fragments.to_vec();
    let mut values: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    values.sort_unstable();
    explore(name, preemption_bound, move || {
        let (memory, Walks { outcomes, steps }) = run_threads(scheme, &fragments);
        let n = fragments.len();
        let fit = n.min(capacity);
        assert_eq!(
            WordMemory::<u32>::load(memory, 0) as usize,
            n,
            "the counter"
        );
        let dropped = outcomes.iter().filter(|&&o| o == Step::Dropped).count();
        let stored = outcomes.iter().filter(|&&o| o == Step::Stored).count();
        assert_eq!((stored, dropped), (fit, n - fit), "walks: {outcomes:?}");
        #[expect(
            clippy::shadow_unrelated,
            reason = "each walk's own step count, of the walks' `steps`"
        )]
        for (outcome, steps) in outcomes.iter().zip(&steps) {
            let expected = if *outcome == Step::Stored { 2 } else { 1 };
            assert_eq!(*steps, expected, "{outcome:?} after {steps} steps");
        }
        let capture = scheme.resolve(memory);
        let kept = capture.pixel(0);
        assert_eq!(kept.len(), fit, "kept {kept:x?}");
        assert!(
            kept.windows(2).all(|w| w[0] < w[1]),
            "distinct and sorted: {kept:x?}"
        );
        assert!(
            kept.iter().all(|v| values.contains(v)),
            "a subset: {kept:x?}"
        );
        if fit == n {
            assert_eq!(kept, &values[..], "every fragment captured");
        }
        assert_eq!(
            capture.keeps,
            Keeps::All {
                // Fixed storage names its capacity; exact storage promises that nothing overflows
                // (a stale count that makes it overflow is then a miscount the oracle reports).
                capacity: match scheme.promise() {
                    Promise::All(capacity) => capacity,
                    other => panic!("the A-buffer keeps all, not {other:?}"),
                },
                overflow: vec![(n - fit) as u32]
            },
            "overflow reported"
        );
        for slot in fit..capacity {
            assert_eq!(
                WordMemory::<u64>::load(memory, slot),
                u64::MAX,
                "slot {slot}"
            );
        }
    })
}

/// Fragments `(depth, prim)` on pixel 0.
fn fragments(list: &[(f32, u32)]) -> Vec<Fragment> {
    list.iter().map(|&(d, p)| fragment(d, p)).collect()
}

/// Fragments with raw depth keys `(key, prim)` on pixel 0 (small keys are the bit patterns of
/// subnormal depths, still in `[0, 1]`).
fn keyed(list: &[(u32, u32)]) -> Vec<Fragment> {
    list.iter()
        .map(|&(depth_key, prim)| Fragment {
            pixel: 0,
            depth_key,
            prim,
        })
        .collect()
}

/// The tie case of `design.md`: depth keys [10, 10, 30, 50], submitted out of order.
const TIES: [(u32, u32); 4] = [(50, 0), (10, 1), (30, 2), (10, 3)];

/// Four distinct depths, submitted far to near and interleaved so that every walk meets larger
/// and smaller values.
const DISTINCT: [(f32, u32); 4] = [(0.5, 0), (0.25, 1), (0.75, 2), (0.125, 3)];

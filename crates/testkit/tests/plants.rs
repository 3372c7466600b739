//! The battery against A-buffer bugs a user could plant, in process: the four of
//! `docs/testing.md` ("Plants"), each caught within 100 cases on each of seeds 0 to 4 with
//! `fragsim conform`'s default sizes (K 2, capacity 3) and shrunk to a small case; the correct
//! A-buffer passes, with most cases overflowing its capacity. Controls: with cases too shallow to
//! overflow, the clamped counters pass and the battery says overflow was never exercised; a
//! backend that fails on every case stops at once, unshrunk, and one that fails only on deep
//! cases is shrunk as usual.
//!
//! The plants are those of `crates/testkit/python/backend.py` (which `tests/suite/conform.rs`
//! runs through the binary), here as a [`Backend`] so that CI runs all twenty in seconds.

use std::cell::Cell;

use fragsim_capture::Guarantee;
use fragsim_catalog::SchemeName;
use fragsim_dump::{Dump, DumpScheme, Words};
use fragsim_oracle::Oracle;
use fragsim_raster::scene_spec::mesh_hash;
use fragsim_testkit::{
    Backend, BackendError, Battery, Case, Exercised, Failure, GuaranteeError, Input, Limits,
    Output, Params, Property,
};

/// A bug planted in [`UserABuffer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Plant {
    /// The counters stop at the capacity: `counters = min(counters, C)`.
    ClampCounters,
    /// The 3rd fragment of the deepest pixel (the first of the most fragments) is never written.
    DeepestThird,
    /// Stores while `index <= C`: the overflowing fragment lands in the next pixel's first slot
    /// (past the last pixel, the backend fails).
    OffByOne,
    /// The counter is read and written back non-atomically: fragments run in waves of
    /// [`WAVE`], each reading its pixel's counter before any of the wave writes it back, so two
    /// fragments of a wave at one pixel are given one slot.
    RacyCounter,
}

const PLANTS: [Plant; 4] = [
    Plant::ClampCounters,
    Plant::DeepestThird,
    Plant::OffByOne,
    Plant::RacyCounter,
];

/// Fragments in flight at once under [`Plant::RacyCounter`].
const WAVE: usize = 32;

/// An empty slot of the fixed A-buffer (`docs/dump-format.md`).
const EMPTY: u64 = u64::MAX;

/// A user's fixed A-buffer (`counters` and `capacity` slots a pixel, fetch-and-add) with an
/// optional plant. Its fragments are the view's, taken from the oracle's lists: a triangle
/// covers a pixel at most once, so sorted by (primitive, pixel) they arrive as a serial scan
/// delivers them, triangle by triangle.
struct UserABuffer {
    plant: Option<Plant>,
}

impl Backend for UserABuffer {
    fn name(&self) -> String {
        format!("a user's A-buffer, planted {:?}", self.plant)
    }

    fn guarantee(&self, _: &Params) -> Result<Guarantee, GuaranteeError> {
        Ok(Guarantee::Exact)
    }

    #[expect(
        clippy::cast_possible_truncation,
        reason = "a word's low half is its primitive id; cap is a small test capacity"
    )]
    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError> {
        let (view, plant) = (input.view, self.plant);
        let cap = input.params.capacity as usize;
        let oracle = Oracle::build(view);
        let pixels = oracle.pixels();
        let mut stream: Vec<(usize, u64)> = (0..pixels)
            .flat_map(|p| oracle.pixel(p).iter().map(move |&word| (p, word)))
            .collect();
        stream.sort_by_key(|&(p, word)| (word as u32, p));
        let mut depth = vec![0_usize; pixels];
        for &(p, _) in &stream {
            depth[p] += 1;
        }
        let deepest = (0..pixels).max_by_key(|&p| (depth[p], std::cmp::Reverse(p)));
        let mut counters = vec![0_u32; pixels];
        let mut slots = vec![EMPTY; pixels * cap];
        let wave = if plant == Some(Plant::RacyCounter) {
            WAVE
        } else {
            1
        };
        for batch in stream.chunks(wave) {
            let read: Vec<u32> = batch.iter().map(|&(p, _)| counters[p]).collect();
            for (&(p, word), index) in batch.iter().zip(read) {
                counters[p] = index + 1;
                let index = index as usize;
                let lost = plant == Some(Plant::DeepestThird) && Some(p) == deepest && index == 2;
                let fits = if plant == Some(Plant::OffByOne) {
                    index <= cap
                } else {
                    index < cap
                };
                if fits && !lost {
                    let at = p * cap + index;
                    *slots.get_mut(at).ok_or_else(|| {
                        BackendError::Failed(format!("slot {at} is past the array"))
                    })? = word;
                }
            }
        }
        if plant == Some(Plant::ClampCounters) {
            for c in &mut counters {
                *c = (*c).min(cap as u32);
            }
        }
        let spec = Case::scene_and_camera("mesh.obj", mesh_hash(input.case.obj().as_bytes()));
        let scheme = DumpScheme::ABufferFixed {
            capacity: cap as u32,
            sorted: false,
        };
        let mut dump = Dump::record(view, spec, &scheme, "plant")
            .map_err(|e| BackendError::Setup(e.to_string()))?;
        dump.set_array("counters", Words::U32(counters), vec![pixels as u64]);
        dump.set_array("slots", Words::U64(slots), vec![pixels as u64, cap as u64]);
        Ok(Output::Dump(Box::new(dump)))
    }
}

/// `fragsim conform`'s default sizes on the A-buffer.
fn params() -> Params {
    Params {
        scheme: SchemeName::Abuffer,
        k: 2,
        capacity: 3,
    }
}

#[test]
fn the_correct_abuffer_passes_and_most_cases_overflow_its_capacity() {
    let mut all = Exercised::default();
    for seed in 0..5 {
        let backend = UserABuffer { plant: None };
        let passed = Battery::new(&backend, params())
            .cases(100)
            .seed(seed)
            .run()
            .unwrap_or_else(|f| panic!("seed {seed}: {f:?}"));
        let e = passed.exercised;
        println!("seed {seed}: {e:?}");
        assert_eq!(e.cases, 100);
        assert!(e.overflow_cases >= 40, "seed {seed}: {e:?}");
        assert!(e.tie_cases >= 5, "seed {seed}: {e:?}");
        assert!(e.empty_cases <= 15, "seed {seed}: {e:?}");
        assert!(e.deepest_pixel > 4, "seed {seed}: {e:?}");
        all = all.and(e);
    }
    // Most of the 500: past the capacity (3), and so past K (2).
    assert!(all.overflow_cases > 250, "{all:?}");
    assert!(all.k_cut_cases > 250, "{all:?}");
}

#[test]
fn each_plant_is_caught_within_100_cases_on_seeds_0_to_4_and_shrunk_small() {
    for plant in PLANTS {
        for seed in 0..5 {
            let backend = UserABuffer { plant: Some(plant) };
            let result = Battery::new(&backend, params()).cases(100).seed(seed).run();
            let Err(Failure::Counterexample(found)) = result else {
                panic!("{plant:?} seed {seed}: not caught: {result:?}");
            };
            let case = &found.submitted;
            println!(
                "{plant:?} seed {seed}: case {}, shrunk in {} steps to {}x{}, {} triangles, {} \
                 fragments: {}: {}",
                found.case_number,
                found.shrink_steps,
                case.viewport.width,
                case.viewport.height,
                case.triangles.len(),
                found.fragments,
                found.property,
                found.message
            );
            assert!(found.case_number <= 100);
            assert!(!found.case_independent);
            // Overflowing a capacity of 3 takes 4 fragments at a pixel.
            assert!(case.triangles.len() <= 4, "{plant:?} seed {seed}: {case:?}");
            assert!(
                case.viewport.pixels() <= 2,
                "{plant:?} seed {seed}: {case:?}"
            );
        }
    }
}

#[test]
fn cases_too_shallow_to_overflow_pass_the_clamped_counters_and_say_so() {
    let backend = UserABuffer {
        plant: Some(Plant::ClampCounters),
    };
    // At most 3 triangles: no pixel holds more than the capacity.
    let passed = Battery::new(&backend, params())
        .cases(100)
        .limits(Limits {
            max_triangles: 3,
            ..Limits::default()
        })
        .run()
        .expect("nothing overflows, so the clamp is never seen");
    assert_eq!(passed.exercised.overflow_cases, 0);
    assert_eq!(passed.exercised.over_capacity_cases, 0);
}

/// A backend that fails on every case it is given, or only on cases of `from` triangles or more;
/// it counts its runs.
struct Failing {
    from: usize,
    runs: Cell<u32>,
}

impl Backend for Failing {
    fn name(&self) -> String {
        "a failing backend".into()
    }

    fn guarantee(&self, _: &Params) -> Result<Guarantee, GuaranteeError> {
        Ok(Guarantee::Exact)
    }

    fn capture(&self, input: &Input<'_>) -> Result<Output, BackendError> {
        self.runs.set(self.runs.get() + 1);
        if input.case.triangles.len() >= self.from {
            return Err(BackendError::Failed("exit status 3".into()));
        }
        UserABuffer { plant: None }.capture(input)
    }
}

#[test]
fn a_backend_failing_on_every_case_stops_at_once_and_one_failing_on_deep_cases_is_shrunk() {
    let always = Failing {
        from: 0,
        runs: Cell::new(0),
    };
    let Err(Failure::Counterexample(found)) = Battery::new(&always, params()).cases(100).run()
    else {
        panic!("the failing backend passed");
    };
    assert!(found.case_independent, "{found:?}");
    assert_eq!(found.property, Property::Runs);
    assert_eq!((found.case_number, found.shrink_steps), (1, 0));
    assert_eq!(found.case, Case::smallest(found.case.schedule));
    // The first case, then the smallest.
    assert_eq!(always.runs.get(), 2);

    // Control: failing only from 2 triangles on depends on the case, and is shrunk to 2.
    let deep = Failing {
        from: 2,
        runs: Cell::new(0),
    };
    #[expect(
        clippy::shadow_unrelated,
        reason = "the deep battery's own counterexample"
    )]
    let Err(Failure::Counterexample(found)) = Battery::new(&deep, params()).cases(100).run() else {
        panic!("the backend failing on deep cases passed");
    };
    assert!(!found.case_independent, "{found:?}");
    assert!(found.shrink_steps > 0);
    assert_eq!(found.submitted.triangles.len(), 2, "{found:?}");
}

//! The control for the verdict: a scheme made to miscount its overflow by one is judged broken,
//! so a verdict of `kept` means something. The fault is injected here, by a test-only wrapper
//! ([`MiscountingOverflow`]) around catalog schemes, and judged by `judge_run` as `render` judges
//! every run; the product carries no fault. That `render` then exits 1 naming the run is
//! `fragsim_cli`'s unit test of its exit code (`render_verdict`, `crates/cli/src/lib.rs`).

use fragsim::capture::depth_count::{DepthCount, DepthCounts};
use fragsim::capture::executors::scheduled::{Granularity, Policy, Schedule};
use fragsim::capture::executors::{run_serial, Executor, Run};
use fragsim::capture::{Descriptor, PixelRun, Scheme, Simt, Step, WalkInput, MEMORY_CAP_DEFAULT};
use fragsim::catalog::{Build, SchemeName, SchemeVisitor};
use fragsim::memory::Memory;
use fragsim::oracle::verdict::{judge_run, RunVerdict};
use fragsim::oracle::{Oracle, Ties};
use fragsim::raster::{OrbitCamera, Scene, View, Viewport};

use crate::support::run_on;

/// The pixel whose overflow the wrapper miscounts.
const MISCOUNTED_PIXEL: usize = 0;

/// The scheduled executor's interleaving: walks picked at random, several in flight.
const SCHEDULE: Schedule = Schedule {
    policy: Policy::Random,
    in_flight: 8,
    granularity: Granularity::Fragment,
    seed: 0,
};

/// `scheme`, reporting one overflowing fragment more at pixel 0 than it counted: its fragments
/// stay right, only its count is wrong, the smallest fault the verdict must catch. Every other
/// method is the scheme's own, so that the run is the bare scheme's in all else.
struct MiscountingOverflow<'a, S> {
    scheme: &'a S,
}

impl<S: Scheme> Scheme for MiscountingOverflow<'_, S> {
    type State = S::State;
    type Input = S::Input;

    fn descriptor(&self) -> &Descriptor {
        self.scheme.descriptor()
    }
    fn tile_local(&self) -> bool {
        self.scheme.tile_local()
    }
    fn gathering(&self) -> <S::Input as WalkInput>::Gathering {
        self.scheme.gathering()
    }
    fn begin(&self, input: S::Input) -> S::State {
        self.scheme.begin(input)
    }
    fn begin_pass(&self, pass: u32, input: S::Input) -> Option<S::State> {
        self.scheme.begin_pass(pass, input)
    }
    fn step<M: Memory>(&self, state: &mut S::State, memory: &M) -> Step {
        self.scheme.step(state, memory)
    }
    fn prefetch<M: Memory>(&self, input: S::Input, memory: &M) {
        self.scheme.prefetch(input, memory);
    }
    fn insert_state<M: Memory>(&self, state: S::State, memory: &M, steps: &mut u64) -> Step {
        self.scheme.insert_state(state, memory, steps)
    }
    fn simt(&self, state: &S::State) -> Simt {
        self.scheme.simt(state)
    }
    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        self.scheme.end_pass(pass, memory)
    }
    fn pixel_run<M: Memory>(&self, memory: &M, pixel: usize, end: usize) -> PixelRun {
        // An empty pixel 0 would be skipped in bulk with nothing overflowed: it is resolved on
        // its own instead, so that its count is the one altered.
        match self.scheme.pixel_run(memory, pixel, end) {
            PixelRun::Empty(_) if pixel == MISCOUNTED_PIXEL => PixelRun::Resolve(1),
            run => run,
        }
    }
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let overflow = self.scheme.resolve_pixel(memory, pixel, out);
        overflow + u32::from(pixel == MISCOUNTED_PIXEL)
    }
}

/// A verdict of the test: the run's executor, whether the fault was injected, and the verdict.
type Judged = (Executor, bool, RunVerdict);

/// The visitor that runs a built scheme bare and miscounting on each of `executors` and judges
/// every run as `render` does (its own guarantee, the default tie policy).
struct BareAndMiscounting<'a, 'v> {
    view: &'a View<'v>,
    oracle: &'a Oracle,
    executors: &'a [Executor],
}

impl SchemeVisitor for BareAndMiscounting<'_, '_> {
    type Output = Vec<Judged>;
    fn visit<S: Scheme>(self, scheme: &S, _: Option<u32>) -> Vec<Judged> {
        let miscounting = MiscountingOverflow { scheme };
        let judge = |executor: Executor, run: Run| {
            judge_run(
                self.oracle,
                &run.capture,
                scheme.guarantee(),
                executor.serialises_pixels(),
                Ties::ByPrimitive,
            )
        };
        let mut judged = Vec::new();
        for &executor in self.executors {
            judged.push((
                executor,
                false,
                judge(executor, run_on(executor, self.view, scheme, &SCHEDULE)),
            ));
            let faulty = run_on(executor, self.view, &miscounting, &SCHEDULE);
            judged.push((executor, true, judge(executor, faulty)));
        }
        judged
    }
}

/// A scheme that counts its overflow one fragment wrong breaks its guarantee, though every
/// fragment it holds is right: the fixed A-buffer (capacity 2, so that the scene overflows it)
/// and the A-buffer sized by its counting pass, on `quads:4` at 8 × 8, each run bare (kept) and
/// miscounting (broken, one miscounted pixel, nothing lost).
#[test]
fn a_scheme_misreporting_its_overflow_by_one_breaks_its_guarantee() {
    let scene = Scene::procedural("quads:4").unwrap();
    let viewport = Viewport::new(8, 8).unwrap();
    let view = scene.view(viewport, &OrbitCamera::default()).unwrap();
    let oracle = Oracle::build(&view);
    assert!(
        oracle.max_depth_complexity() > 2,
        "the scene must overflow a capacity of 2 somewhere"
    );
    // abuffer-exact is sized by its own counting pass, as `SchemeRunner::run` sizes it.
    let counted = DepthCounts::from_run(run_serial(&view, &DepthCount::new(viewport)));
    let build = Build {
        counts: Some(&counted.counts),
        ..Build::fixed(viewport, 1, 2, counted.max(), MEMORY_CAP_DEFAULT)
    };
    let executors = [
        Executor::Serial,
        Executor::Parallel,
        Executor::Tiled,
        Executor::Scheduled,
    ];
    for name in ["abuffer", "abuffer-exact"] {
        let judged = SchemeName::from_name(name)
            .unwrap()
            .build(
                &build,
                BareAndMiscounting {
                    view: &view,
                    oracle: &oracle,
                    executors: &executors,
                },
            )
            .unwrap();
        assert_eq!(
            judged.len(),
            2 * executors.len(),
            "{name}: every run judged"
        );
        for (executor, faulty, verdict) in judged {
            let run = format!("{name} on the {executor} executor (miscounting: {faulty})");
            assert!(
                verdict.owed,
                "{run}: an A-buffer owes exact lists everywhere"
            );
            assert_eq!(verdict.kept, !faulty, "{run}: {:?}", verdict.diff);
            assert_eq!(
                verdict.diff.overflow_miscounted_pixels,
                u64::from(faulty),
                "{run}: {:?}",
                verdict.diff
            );
            assert_eq!(
                verdict.diff.lost, 0,
                "{run}: the fragments are right; only the count is wrong"
            );
        }
    }
}

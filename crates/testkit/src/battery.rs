//! The conformance battery: for a [`Backend`] and the guarantee it claims, the properties the
//! claim implies, checked on generated [`Case`]s, and on a failure the case shrunk by proptest
//! to its smallest scene, viewport and schedule.
//!
//! The properties, on every case:
//! - **equal**: the backend's output is equal to the oracle under the scheme's promise (the K
//!   nearest, every fragment but the predicted overflow), judged by [`crate::judge`] (what
//!   `fragsim compare oracle DUMP` says, within the precision of an f32 vertex stage where the
//!   backend declares one: [`Backend::vertex_precision`]); the case's ties (coplanar triangles at equal depths)
//!   are judged by the canonical order, the primitive id, and its extremes (depths 0 and 1,
//!   near- and far-plane crossers, guard-band clipping, 1×1 viewports) are in the generator;
//! - **order-independent**: the same triangles submitted in another order ([`Case::permuted`])
//!   are equal to that submission's oracle too;
//! - **overflow**: the overflow the backend's counters claim is exactly what the oracle predicts
//!   for its capacity (`Σ max(0, n − capacity)`);
//! - **runs**: the backend returns an output at all (no crash, no timeout, a readable dump).
//!
//! A pass claims only what its cases exercised: [`Exercised`] counts the cases that overflowed
//! (as the oracle predicts for the scheme), the deepest pixel, the fragments, the cases deeper
//! than K and than the capacity, the cases with ties and the empty ones. A backend that fails
//! to run on a case and on the smallest case too ([`Case::smallest`]) fails whatever the case:
//! the battery stops at once and reports that, shrinking nothing
//! ([`Counterexample::case_independent`]).
//!
//! Guarantee: a claim that owes exactness ([`Guarantee::owes_exactness`] on the backend's
//! executor) owes all four. A claim that owes nothing there is refused, as is one judged with
//! equal depths merged ([`Guarantee::ExactDistinctDepths`]): the battery judges canonical ties.
//! Source: the suite's properties (`tests/suite/properties/`) and `fragsim compare`.

use std::cell::{Cell, RefCell};
use std::fmt;
use std::time::{Duration, Instant};

use fragsim_capture::Guarantee;
use fragsim_oracle::compare::{flags, Comparison};
use fragsim_oracle::{Oracle, PixelMismatch};
use fragsim_raster::Conventions;
use proptest::strategy::Strategy;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};

use crate::backend::{Backend, BackendError, Input, Params};
use crate::case::{case, Case, Limits};
use crate::judge::judge;

/// A property of the battery.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// The backend returned an output.
    Runs,
    /// Equal to the oracle under the scheme's promise.
    Equal,
    /// Equal under another submission order.
    OrderIndependent,
    /// The claimed overflow is the predicted one.
    Overflow,
}

impl fmt::Display for Property {
    /// The spelling in reports and JSON: `runs`, `equal`, `order-independent`, `overflow`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Runs => "runs",
            Self::Equal => "equal",
            Self::OrderIndependent => "order-independent",
            Self::Overflow => "overflow",
        })
    }
}

/// A failing case, as the battery found it on the shrunk case.
#[derive(Clone, Debug)]
pub struct Counterexample {
    /// The shrunk case.
    pub case: Case,
    /// The case as it was submitted when it failed: `case` itself, or its other order.
    pub submitted: Case,
    /// The property broken.
    pub property: Property,
    /// What went wrong, in one line.
    pub message: String,
    /// The verdict, where the backend's output could be judged.
    pub comparison: Option<Comparison>,
    /// The oracle's fragments in the submitted case.
    pub fragments: usize,
    /// The cases checked before the failure (the failing one included; in a shard, its own).
    pub cases_run: u32,
    /// The failing case's number among the cases generated from the seed (from 1): the same
    /// in a shard as in the unsharded run.
    pub case_number: u32,
    /// The simplifications proptest tried while shrinking.
    pub shrink_steps: u32,
    /// Whether the backend failed to run on the smallest case too ([`Case::smallest`], which
    /// `case` then is): a failure that does not depend on the case, not shrunk.
    pub case_independent: bool,
    /// What the cases checked before the failure exercised (the failing one not included).
    pub exercised: Exercised,
}

impl Counterexample {
    /// The first differing pixels, both lists (the oracle's, the backend's).
    #[must_use]
    pub fn mismatches(&self) -> &[PixelMismatch] {
        self.comparison
            .as_ref()
            .map_or(&[], |c| c.diff.first_mismatches.as_slice())
    }
}

/// Why a battery did not pass.
#[derive(Clone, Debug)]
pub enum Failure {
    /// Nothing was checked: the claim owes nothing on the backend, the battery cannot judge it,
    /// or the backend cannot run at all ([`BackendError::Setup`]).
    Refused(String),
    /// A case broke a property.
    Counterexample(Box<Counterexample>),
}

/// A battery that passed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Passed {
    /// Cases checked (in a shard, its own).
    pub cases: u32,
    /// The claim checked.
    pub claim: Guarantee,
    /// What those cases exercised: a claim is made only of what they reached.
    pub exercised: Exercised,
}

/// What the checked cases exercised, from the oracle of each case as generated (in its
/// submission order; the other order has the same fragments): a pass says "overflow as
/// predicted" only of the cases that overflowed, and that overflow was never exercised where
/// none did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Exercised {
    /// Cases counted.
    pub cases: u32,
    /// The oracle's fragments over those cases.
    pub fragments: u64,
    /// The most fragments any pixel of any case held.
    pub deepest_pixel: u32,
    /// Cases with a pixel holding more fragments than K (where a K-sized scheme cuts).
    pub k_cut_cases: u32,
    /// Cases with a pixel holding more fragments than the capacity.
    pub over_capacity_cases: u32,
    /// Cases whose overflow, as the oracle predicts it for the scheme (beyond K, past the
    /// capacity, a pool exhausted), is not 0.
    pub overflow_cases: u32,
    /// The predicted overflow over those cases, in fragments.
    pub overflow_fragments: u64,
    /// Cases with a pixel holding two fragments at one depth (a tie, judged by primitive id).
    pub tie_cases: u32,
    /// Cases with no fragment at all.
    pub empty_cases: u32,
}

impl Exercised {
    /// What one case exercised: its `oracle` under `params`, and the overflow the verdict
    /// predicted for the scheme.
    fn of_case(oracle: &Oracle, params: &Params, predicted_overflow: u64) -> Self {
        let deepest_pixel = oracle.max_depth_complexity();
        let tie = (0..oracle.pixels()).any(|p| {
            oracle
                .pixel(p)
                .windows(2)
                .any(|pair| pair[0] >> 32 == pair[1] >> 32)
        });
        let fragments = oracle.fragments() as u64;
        Self {
            cases: 1,
            fragments,
            deepest_pixel,
            k_cut_cases: u32::from(deepest_pixel > params.k),
            over_capacity_cases: u32::from(deepest_pixel > params.capacity),
            overflow_cases: u32::from(predicted_overflow > 0),
            overflow_fragments: predicted_overflow,
            tie_cases: u32::from(tie),
            empty_cases: u32::from(fragments == 0),
        }
    }

    /// `self` and `other` together.
    #[must_use]
    pub fn and(self, other: Self) -> Self {
        Self {
            cases: self.cases + other.cases,
            fragments: self.fragments + other.fragments,
            deepest_pixel: self.deepest_pixel.max(other.deepest_pixel),
            k_cut_cases: self.k_cut_cases + other.k_cut_cases,
            over_capacity_cases: self.over_capacity_cases + other.over_capacity_cases,
            overflow_cases: self.overflow_cases + other.overflow_cases,
            overflow_fragments: self.overflow_fragments + other.overflow_fragments,
            tie_cases: self.tie_cases + other.tie_cases,
            empty_cases: self.empty_cases + other.empty_cases,
        }
    }
}

/// What the battery is doing, for a progress display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// Case `n` (from 1) of the run is being checked.
    Case(u32),
    /// A failure is being shrunk: simplification `n` (from 1).
    Shrink(u32),
}

/// The battery for one backend and scheme.
pub struct Battery<'b> {
    backend: &'b dyn Backend,
    params: Params,
    claim: Option<Guarantee>,
    limits: Limits,
    cases: u32,
    seed: u64,
    max_shrink_iters: u32,
    shard: (u32, u32),
}

// By hand: the backend is a trait object with no `Debug`; what the battery runs is the rest.
impl std::fmt::Debug for Battery<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Battery")
            .field("params", &self.params)
            .field("claim", &self.claim)
            .field("limits", &self.limits)
            .field("cases", &self.cases)
            .field("seed", &self.seed)
            .field("max_shrink_iters", &self.max_shrink_iters)
            .field("shard", &self.shard)
            .finish_non_exhaustive()
    }
}

/// How long proptest's shrinking may run the backend, as proptest's own default (2 minutes).
const SHRINK_TIME: Duration = Duration::from_secs(120);

/// Why a case stopped the battery.
enum Stop {
    /// The backend cannot run at all.
    Setup(String),
    /// A property broke (boxed: a verdict is large, and `Stop` is every check's error).
    Found(Box<Found>),
}

/// A property broken by one case, before shrinking ends.
struct Found {
    submitted: Case,
    property: Property,
    message: String,
    comparison: Option<Comparison>,
    fragments: usize,
}

impl<'b> Battery<'b> {
    /// The battery for `backend` running `params`: 64 cases of [`Limits::default`], seed 0, the
    /// claim the backend states ([`Backend::guarantee`]).
    #[must_use]
    pub fn new(backend: &'b dyn Backend, params: Params) -> Self {
        Self {
            backend,
            params,
            claim: None,
            limits: Limits::default(),
            cases: 64,
            seed: 0,
            max_shrink_iters: 2048,
            shard: (1, 1),
        }
    }

    /// Checks only shard `index` of `count` (from 1): of the cases generated from the seed,
    /// case `n` (from 1) when `(n − 1) mod count = index − 1`. Every shard generates the same
    /// cases, so the shards of one seed and case count are disjoint and together the unsharded
    /// run, case for case. A failing case is shrunk as in an unsharded run.
    #[must_use]
    pub fn shard(mut self, index: u32, count: u32) -> Self {
        self.shard = (index.clamp(1, count.max(1)), count.max(1));
        self
    }

    /// Checks `claim` instead of the backend's own (e.g. a k-buffer port that claims exactness).
    #[must_use]
    pub fn claiming(mut self, claim: Guarantee) -> Self {
        self.claim = Some(claim);
        self
    }

    /// Checks `cases` cases.
    #[must_use]
    pub fn cases(mut self, cases: u32) -> Self {
        self.cases = cases.max(1);
        self
    }

    /// Generates from `seed` (the same seed, the same cases and the same shrinking).
    #[must_use]
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Lets proptest try at most `steps` simplifications of a failing case (2048 by default)
    /// before the battery's own crop and triangle dropping: a cap for backends that are slow to
    /// start, since each step runs the backend once.
    #[must_use]
    pub fn shrink_steps(mut self, steps: u32) -> Self {
        self.max_shrink_iters = steps;
        self
    }

    /// Generates cases within `limits`.
    #[must_use]
    pub fn limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }

    /// Runs the battery.
    ///
    /// # Errors
    /// The claim is refused, or a shrunk counterexample.
    pub fn run(&self) -> Result<Passed, Failure> {
        self.run_with(&mut |_| {})
    }

    /// [`Battery::run`], calling `on_event` before each case and each shrinking step.
    ///
    /// # Errors
    /// As [`Battery::run`].
    pub fn run_with(&self, on_event: &mut dyn FnMut(Event)) -> Result<Passed, Failure> {
        let claim = match self.claim {
            Some(claim) => claim,
            None => self
                .backend
                .guarantee(&self.params)
                .map_err(|e| Failure::Refused(e.to_string()))?,
        };
        if claim.merges_equal_depths() {
            return Err(Failure::Refused(format!(
                "{claim} is judged with equal depths merged; the battery judges ties by primitive id"
            )));
        }
        if !claim.owes_exactness(self.backend.serialises_pixels()) {
            return Err(Failure::Refused(format!(
                "{claim} owes no exact capture on {}: nothing to check",
                self.backend.name()
            )));
        }
        let mut seed = [0_u8; 32];
        seed[..8].copy_from_slice(&self.seed.to_le_bytes());
        // proptest prints "Aborting shrinking after …" on stderr whenever it reaches its own
        // caps, whatever its verbosity: they are set out of reach, and the battery keeps its
        // own (`max_shrink_iters` backend runs, `SHRINK_TIME`), past which every simplification
        // is answered "passes" without running the backend, so proptest's shrinking winds down
        // quietly on the last failing case. 0 still disables shrinking.
        let config = Config {
            cases: self.cases,
            failure_persistence: None,
            max_shrink_iters: if self.max_shrink_iters == 0 {
                0
            } else {
                u32::MAX - 1
            },
            max_shrink_time: 0,
            ..Config::default()
        };
        let shrink_start = Cell::new(None::<Instant>);
        let mut runner =
            TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
        let events = RefCell::new(on_event);
        let (cases_run, shrink_steps) = (Cell::new(0_u32), Cell::new(0_u32));
        let last_found = RefCell::new(None);
        let setup = RefCell::new(None);
        let generated = Cell::new(0_u32);
        let exercised = Cell::new(Exercised::default());
        // The smallest case's failure, where the backend fails to run on it too.
        let everywhere = RefCell::new(None::<Found>);
        let (shard, shards) = self.shard;
        let result = runner.run(&case(self.case_limits()).boxed(), |case| {
            // A backend that cannot run, or fails to run whatever the case, fails every case
            // alike: stop at once, shrink nothing.
            if setup.borrow().is_some() || everywhere.borrow().is_some() {
                return Ok(());
            }
            let shrinking = last_found.borrow().is_some();
            if !shrinking {
                generated.set(generated.get() + 1);
                // Another shard's case: generated (so the cases after it are the same in every
                // shard), not checked.
                if (generated.get() - 1) % shards != shard - 1 {
                    return Ok(());
                }
                cases_run.set(cases_run.get() + 1);
                (events.borrow_mut())(Event::Case(cases_run.get()));
            } else {
                let started = shrink_start.get().unwrap_or_else(Instant::now);
                shrink_start.set(Some(started));
                if shrink_steps.get() >= self.max_shrink_iters || started.elapsed() > SHRINK_TIME {
                    return Ok(());
                }
                shrink_steps.set(shrink_steps.get() + 1);
                (events.borrow_mut())(Event::Shrink(shrink_steps.get()));
            }
            match self.check(&case) {
                Ok(seen) => {
                    if !shrinking {
                        exercised.set(exercised.get().and(seen));
                    }
                    Ok(())
                }
                Err(Stop::Setup(message)) => {
                    *setup.borrow_mut() = Some(message.clone());
                    Err(TestCaseError::fail(message))
                }
                Err(Stop::Found(found)) => {
                    let message = format!("{}: {}", found.property, found.message);
                    // A backend that does not run on a generated case: on the smallest case
                    // too, and the failure is not the case's.
                    if !shrinking && found.property == Property::Runs {
                        let smallest = Case::smallest(case.schedule);
                        match self.check_submitted(&smallest, Property::Runs) {
                            Err(Stop::Found(f)) if f.property == Property::Runs => {
                                *everywhere.borrow_mut() = Some(*f);
                            }
                            Err(Stop::Setup(m)) => *setup.borrow_mut() = Some(m),
                            _ => {}
                        }
                    }
                    *last_found.borrow_mut() = Some(*found);
                    Err(TestCaseError::fail(message))
                }
            }
        });
        if let Some(message) = setup.into_inner() {
            return Err(Failure::Refused(message));
        }
        if let Some(found) = everywhere.into_inner() {
            return Err(Failure::Counterexample(Box::new(Counterexample {
                case: found.submitted.clone(),
                submitted: found.submitted,
                property: found.property,
                message: format!(
                    "the backend fails whatever the case, the smallest (1x1, one triangle) too: {}",
                    found.message
                ),
                comparison: None,
                fragments: found.fragments,
                cases_run: cases_run.get(),
                case_number: generated.get(),
                shrink_steps: 0,
                case_independent: true,
                exercised: exercised.get(),
            })));
        }
        match result {
            Ok(()) => Ok(Passed {
                cases: cases_run.get(),
                claim,
                exercised: exercised.get(),
            }),
            Err(TestError::Fail(reason, case)) => {
                // The last case that failed is the shrunk one: proptest keeps each failing
                // simplification and reports the last.
                let found = last_found.into_inner().unwrap_or_else(|| Found {
                    submitted: case.clone(),
                    property: Property::Runs,
                    message: reason.to_string(),
                    comparison: None,
                    fragments: 0,
                });
                let mut steps = shrink_steps.get();
                let (case, found) = self.crop(case, found, &mut steps, &mut *events.into_inner());
                shrink_steps.set(steps);
                Err(Failure::Counterexample(Box::new(Counterexample {
                    case,
                    submitted: found.submitted,
                    property: found.property,
                    message: found.message,
                    comparison: found.comparison,
                    fragments: found.fragments,
                    cases_run: cases_run.get(),
                    case_number: generated.get(),
                    shrink_steps: shrink_steps.get(),
                    case_independent: false,
                    exercised: exercised.get(),
                })))
            }
            Err(TestError::Abort(reason)) => Err(Failure::Refused(reason.to_string())),
        }
    }

    /// Shrinks a failing case further where proptest's shrinking stops: proptest moves one
    /// value at a time towards zero, so a failure at pixel (2, 1) keeps a 3×2 viewport; here the
    /// case is cut to the window around its differing pixels (one pixel, their bounding box, a
    /// half of the viewport), each under its own schedule and the first few seeds, and its
    /// triangles are dropped one by one, as long as it still fails.
    fn crop(
        &self,
        mut case: Case,
        mut found: Found,
        steps: &mut u32,
        on_event: &mut dyn FnMut(Event),
    ) -> (Case, Found) {
        loop {
            let mut smaller = None;
            let power_of_two = self.case_limits().power_of_two;
            for candidate in candidates(&case, &found, power_of_two) {
                *steps += 1;
                on_event(Event::Shrink(*steps));
                if let Err(Stop::Found(f)) = self.check(&candidate) {
                    smaller = Some((candidate, *f));
                    break;
                }
            }
            match smaller {
                Some((c, f)) => (case, found) = (c, f),
                None => return (case, found),
            }
        }
    }

    /// The limits cases are generated and shrunk within: the battery's, with the backend's
    /// viewports ([`Backend::power_of_two_viewports`]).
    fn case_limits(&self) -> Limits {
        let depth = match self.limits.depth {
            0 => self.params.k.max(self.params.capacity) as usize + 2,
            depth => depth,
        };
        Limits {
            power_of_two: self.limits.power_of_two || self.backend.power_of_two_viewports(),
            depth,
            ..self.limits
        }
    }

    /// Every property on `case`: as generated, then in its other submission order; what the
    /// case exercised.
    fn check(&self, case: &Case) -> Result<Exercised, Stop> {
        let seen = self.check_submitted(case, Property::Equal)?;
        let permuted = case.permuted();
        if permuted.triangles != case.triangles {
            self.check_submitted(&permuted, Property::OrderIndependent)?;
        }
        Ok(seen)
    }

    /// The backend's output on `submitted` against its oracle; a difference breaks `property`.
    /// Returns what the case exercised.
    fn check_submitted(&self, submitted: &Case, property: Property) -> Result<Exercised, Stop> {
        let scene = submitted.scene();
        #[expect(
            clippy::shadow_unrelated,
            reason = "each call names the property its failure is found under"
        )]
        let found = |property, message: String, comparison, fragments| {
            Stop::Found(Box::new(Found {
                submitted: submitted.clone(),
                property,
                message,
                comparison,
                fragments,
            }))
        };
        let view = scene
            .view_under(submitted.viewport, &Case::camera(), Conventions::REFERENCE)
            .map_err(|e| found(Property::Runs, e.to_string(), None, 0))?;
        let oracle = Oracle::build(&view);
        let fragments = oracle.fragments();
        let input = Input {
            case: submitted,
            view: &view,
            params: &self.params,
        };
        let output = self.backend.capture(&input).map_err(|e| match e {
            BackendError::Setup(message) => Stop::Setup(message),
            BackendError::Failed(message) => found(Property::Runs, message, None, fragments),
        })?;
        let comparison = judge(&view, &oracle, &output, self.backend.vertex_precision())
            .map_err(|e| found(Property::Runs, e.to_string(), None, fragments))?;
        // The verdict judges the counters too (a pixel whose counter claims an overflow no
        // conforming run has is overflow-miscounted): where that is its only error, the broken
        // property is the overflow. Under precision a counter may count a fragment the
        // implementation may emit and the reference does not, so the claimed total alone is no
        // error.
        if !comparison.is_equal() {
            let c = &comparison.counts;
            let only_counters =
                c.miscounted > 0 && c.missing + c.extra + c.misordered + c.corrupt == 0;
            let (property, message) = if only_counters {
                let message = format!(
                    "the counters claim {} fragments overflowed, the oracle predicts {}",
                    comparison.claimed_overflow, comparison.diff.overflowed
                );
                (Property::Overflow, message)
            } else {
                (property, describe(&comparison, fragments))
            };
            return Err(found(property, message, Some(comparison), fragments));
        }
        Ok(Exercised::of_case(
            &oracle,
            &self.params,
            comparison.diff.overflowed,
        ))
    }
}

/// Smaller cases to try after `case` failed with `found`, most promising first: fewer pixels
/// (crops around the differing pixels, under the case's schedule and seeds 0 to 3; with
/// `power_of_two` each crop's sides rounded up to powers of two, and moved back inside the
/// viewport), then fewer triangles.
#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
)]
fn candidates(case: &Case, found: &Found, power_of_two: bool) -> Vec<Case> {
    let viewport = case.viewport;
    let (w, h) = (viewport.width, viewport.height);
    let differing: Vec<(u32, u32)> = found.comparison.as_ref().map_or(Vec::new(), |c| {
        c.verdicts
            .iter()
            .enumerate()
            .filter(|(_, &v)| v & flags::DIFFERS != 0)
            .map(|(p, _)| (p as u32 % w, p as u32 / w))
            .collect()
    });
    let mut windows: Vec<(u32, u32, u32, u32)> = differing
        .iter()
        .take(4)
        .map(|&(x, y)| (x, y, 1, 1))
        .collect();
    if let (Some(x0), Some(y0)) = (
        differing.iter().map(|p| p.0).min(),
        differing.iter().map(|p| p.1).min(),
    ) {
        let x1 = differing.iter().map(|p| p.0).max().unwrap_or(x0);
        let y1 = differing.iter().map(|p| p.1).max().unwrap_or(y0);
        windows.push((x0, y0, x1 - x0 + 1, y1 - y0 + 1));
    }
    let (hw, hh) = (w.div_ceil(2), h.div_ceil(2));
    windows.extend([
        (0, 0, hw, h),
        (w - hw, 0, hw, h),
        (0, 0, w, hh),
        (0, h - hh, w, hh),
    ]);
    let mut out = Vec::new();
    for (mut x, mut y, mut cw, mut ch) in windows {
        if power_of_two {
            (cw, ch) = (cw.next_power_of_two().min(w), ch.next_power_of_two().min(h));
            (x, y) = (x.min(w - cw), y.min(h - ch));
        }
        if u64::from(cw) * u64::from(ch) >= u64::from(w) * u64::from(h) {
            continue;
        }
        let Some(cropped) = case.cropped(x, y, cw, ch) else {
            continue;
        };
        let seeds = [case.schedule.seed, 0, 1, 2, 3];
        for (i, &seed) in seeds.iter().enumerate() {
            if i > 0 && seed == case.schedule.seed {
                continue;
            }
            let mut c = cropped.clone();
            c.schedule.seed = seed;
            out.push(c);
        }
    }
    if case.triangles.len() > 1 {
        out.extend((0..case.triangles.len()).map(|i| case.without(i)));
    }
    out
}

/// One line on a differing verdict: pixels per verdict.
fn describe(comparison: &Comparison, fragments: usize) -> String {
    let mut per_verdict = [0_u64; flags::NAMES.len()];
    for &flags in &comparison.verdicts {
        for (i, (flag, _)) in flags::NAMES.iter().enumerate() {
            per_verdict[i] += u64::from(flags & flag != 0);
        }
    }
    let named: Vec<String> = flags::NAMES
        .iter()
        .zip(per_verdict)
        .filter(|&((flag, _), n)| n > 0 && flag & flags::DIFFERS != 0)
        .map(|((_, name), n)| format!("{n} {name}"))
        .collect();
    format!(
        "{} of {} pixels differ from the oracle ({}; {} fragments in the case)",
        comparison.diff.mismatched_pixels,
        comparison.verdicts.len(),
        named.join(", "),
        fragments
    )
}

//! The `schemes_vs_oracle` target: an arbitrary fragment stream on a viewport of fewer than 16
//! pixels (depth keys from arbitrary f32 in `[0, 1]`, primitive ids distinct per pixel) through
//! every scheme of the catalog, each checked as its guarantee owes: run serially (every pass,
//! submission order) and, those exact under any interleaving, by the scheduled executor under a
//! schedule decoded from the input (schemes with a pass per layer on cases of depth complexity up
//! to 24). Each capture must be what the scheme promises of an oracle computed here by sorting,
//! and for one-pass schemes that count every drop the counted drops must equal what the capture
//! is missing.

use fragsim::capture::executors::frame::{self, Counters, Run};
use fragsim::capture::executors::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::{
    inputs_of, Capture, Guarantee, Identity, Keeps, Scheme, MEMORY_CAP_DEFAULT,
};
use fragsim::catalog::{Build, Passes, SchemeVisitor, CATALOG};
use fragsim::memory::SerialMemory;
use fragsim::raster::{depth_key, Fragment, Viewport};

use super::input::Input;

/// At most this many fragments are decoded (libFuzzer's inputs are short anyway).
const MAX_FRAGMENTS: usize = 512;

/// Multi-pass schemes are checked on cases of at most this depth complexity.
const MAX_MULTIPASS_LAYERS: u32 = 24;

/// The decoded case.
struct Case {
    pixels: u32,
    /// Slots of the short variants (MDTS below depth complexity, fixed A-buffer).
    k: u32,
    schedule: Schedule,
    fragments: Vec<Fragment>,
}

fn decode(data: &[u8]) -> Case {
    let mut input = Input::new(data);
    let pixels = 1 + u32::from(input.u8() % 15);
    let k = 1 + u32::from(input.u8() % 8);
    let policy = match input.u8() % 3 {
        0 => Policy::Random,
        1 => Policy::Warps,
        d => Policy::Pct {
            depth: u32::from(d),
        },
    };
    let in_flight = [1, 2, 3, 7, 32, 33, 256][usize::from(input.u8() % 7)];
    let seed = input.u64();
    let mut fragments: Vec<Fragment> = Vec::new();
    while !input.is_empty() && fragments.len() < MAX_FRAGMENTS {
        let header = input.u8();
        let pixel = u32::from(header & 0x0F) % pixels;
        // Few distinct depths make ties (equal keys) common; raw bits reach every key.
        let depth_key = if header & 0x10 == 0 {
            depth_key(f32::from(input.u8() % 8) / 7.0).expect("in [0, 1]")
        } else {
            let bits = input.u32();
            depth_key(f32::from_bits(bits)).unwrap_or(bits % (0x3F80_0000 + 1))
        };
        let prim = if header & 0x20 == 0 {
            u32::try_from(fragments.len()).expect("at most MAX_FRAGMENTS fragments")
        } else {
            input.u32()
        };
        // As from a rasterizer: a triangle covers a pixel at most once.
        if fragments.iter().any(|f| f.pixel == pixel && f.prim == prim) {
            continue;
        }
        fragments.push(Fragment {
            pixel,
            depth_key,
            prim,
        });
    }
    Case {
        pixels,
        k,
        schedule: Schedule {
            policy,
            in_flight,
            granularity: Granularity::Fragment,
            seed,
        },
        fragments,
    }
}

/// Every pixel's fragments, packed, in canonical order: the oracle, by sorting.
pub(crate) fn sorted_lists(pixels: u32, fragments: &[Fragment]) -> Vec<Vec<u64>> {
    let mut lists = vec![Vec::new(); pixels as usize];
    for f in fragments {
        lists[f.pixel as usize].push(f.packed());
    }
    for list in &mut lists {
        list.sort_unstable();
    }
    lists
}

/// Checks `capture` against `lists` under the capture's promise; `dropped`, where given, is the
/// count of walks that ended in [`Step::Dropped`], which must equal the fragments missing from the
/// capture (multi-pass schemes count overflow per pass and the z-buffer overwrites uncounted,
/// so they give none).
pub(crate) fn check_capture(
    name: &str,
    lists: &[Vec<u64>],
    capture: &Capture,
    dropped: Option<u64>,
) {
    assert_eq!(capture.pixels(), lists.len(), "{name}: pixel count");
    let mask = match capture.identity {
        Identity::KeyAndPrim | Identity::MaskedNodes(_) => u64::MAX,
        Identity::KeyOnly => u64::MAX << 32,
        Identity::PrimOnly => panic!("{name}: no exact scheme keeps primitive ids only"),
    };
    let mut missing = 0;
    for (p, list) in lists.iter().enumerate() {
        let all: Vec<u64> = list.iter().map(|e| e & mask).collect();
        let got = capture.pixel(p);
        let n = all.len();
        match &capture.keeps {
            Keeps::Nearest(k) => {
                let kept = n.min(*k as usize);
                assert_eq!(got, &all[..kept], "{name}: pixel {p}, the nearest {k}");
            }
            Keeps::Farthest(k) => {
                let kept = n.min(*k as usize);
                assert_eq!(got, &all[n - kept..], "{name}: pixel {p}, the farthest {k}");
            }
            Keeps::All { capacity, overflow } => {
                // The overflow is predicted from the capacity, never taken from the scheme.
                assert_eq!(
                    overflow[p] as usize,
                    capacity.reported_overflow(n),
                    "{name}: pixel {p}, counted overflow"
                );
                assert_eq!(
                    got.len() + capacity.overflow(n),
                    n,
                    "{name}: pixel {p}, kept + overflow"
                );
                assert!(
                    got.windows(2).all(|w| w[0] <= w[1]),
                    "{name}: pixel {p} out of order: {got:?}"
                );
                // Which ones overflow depends on arrival order; the kept ones are real.
                let mut rest = all.clone();
                for e in got {
                    let i = rest.iter().position(|r| r == e).unwrap_or_else(|| {
                        panic!("{name}: pixel {p} holds {e:#x}, not a fragment of it")
                    });
                    rest.remove(i);
                }
            }
        }
        missing += (n - got.len()) as u64;
    }
    if let Some(dropped) = dropped {
        assert_eq!(
            dropped, missing,
            "{name}: counted drops vs fragments missing"
        );
    }
}

/// How a scheme is checked, from its guarantee: every exact one serially (in submission order,
/// every pass), and those exact under any interleaving also under the case's schedule. The
/// read–modify–write schemes (the k-buffers) are owed exactness only without concurrent hazards,
/// and stencil routing only in one arrival order, so they are checked serially alone; the
/// schemes that merge equal depths only on cases whose pixels hold distinct depths; approximate
/// schemes not at all (their losses are what they report).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Runs {
    SerialAndScheduled,
    SerialOnly,
    Skip,
}

impl Runs {
    fn owed(guarantee: Guarantee, distinct_depths: bool) -> Self {
        match guarantee {
            Guarantee::Exact | Guarantee::ExactWithinCapacity(_) => Self::SerialAndScheduled,
            Guarantee::ExactDistinctDepths if distinct_depths => Self::SerialAndScheduled,
            Guarantee::ExactWithoutHazards | Guarantee::ExactInArrivalOrder => Self::SerialOnly,
            Guarantee::ExactDistinctDepths | Guarantee::Approximate => Self::Skip,
        }
    }
}

/// Runs `scheme` over the case and checks each capture: serially (every pass, fragments in
/// submission order, each walk to its end), and for `Runs::SerialAndScheduled` under the case's
/// schedule too. For one-pass schemes that count every drop
/// ([`Scheme::counts_every_drop`]) the counted drops must equal the fragments missing.
fn check_scheme<S: Scheme>(scheme: &S, case: &Case, lists: &[Vec<u64>], runs: Runs) {
    if runs == Runs::Skip {
        return;
    }
    let name = scheme.name();
    // The fragments as the scheme's walks take them (themselves, for a scheme of fragments).
    let inputs = inputs_of(scheme, case.fragments.iter().copied());
    let memory: SerialMemory = scheme.layout().allocate();
    let (counters, _) = frame::passes(scheme, &memory, |pass| {
        frame::walks(scheme, &memory, pass, &inputs)
    });
    // A scheme whose second pass would take no fragment is a one-pass scheme; multi-pass schemes
    // count overflow per pass.
    let one_pass = scheme.counts_every_drop()
        && inputs
            .first()
            .is_none_or(|&f| scheme.begin_pass(1, f).is_none());
    let capture = scheme.resolve(&memory);
    let dropped = counted_drops(one_pass, &counters);
    check_capture(&format!("{name} serial"), lists, &capture, dropped);
    if runs == Runs::SerialOnly {
        return;
    }
    let Run {
        capture: scheduled,
        stats,
    } = run_fragments(scheme, &inputs, &case.schedule, false).run;
    if one_pass {
        assert_eq!(
            stats.counters.fragments,
            case.fragments.len() as u64,
            "{name}: every fragment begins one walk"
        );
    }
    let scheduled_drops = counted_drops(one_pass, &stats.counters);
    let name = format!("{name} under {:?}", case.schedule);
    check_capture(&name, lists, &scheduled, scheduled_drops);
}

/// The drops that must equal the fragments missing: those of a one-pass scheme that counts every
/// drop.
fn counted_drops(one_pass: bool, counters: &Counters) -> Option<u64> {
    one_pass.then_some(counters.dropped)
}

/// The catalog's schemes, each checked as its guarantee owes.
struct CheckOwed<'a> {
    case: &'a Case,
    lists: &'a [Vec<u64>],
    distinct_depths: bool,
}

impl SchemeVisitor for CheckOwed<'_> {
    type Output = ();

    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) {
        let runs = Runs::owed(scheme.guarantee(), self.distinct_depths);
        check_scheme(scheme, self.case, self.lists, runs);
    }
}

/// Whether no two fragments of a pixel share a depth key.
fn distinct_depths(lists: &[Vec<u64>]) -> bool {
    lists
        .iter()
        .all(|list| list.windows(2).all(|w| w[0] >> 32 != w[1] >> 32))
}

/// Decodes a fragment stream and checks every scheme of the catalog as its guarantee owes (see
/// [`Runs`]), with storage for the deepest pixel and with the case's smaller `k` (K, capacity,
/// and for multi-pass schemes the layers they peel); linked lists get a pool of the case's
/// fragments; schemes whose passes grow with the layers only on cases of depth complexity up to
/// [`MAX_MULTIPASS_LAYERS`].
pub(crate) fn check(data: &[u8]) {
    let case = decode(data);
    let lists = sorted_lists(case.pixels, &case.fragments);
    let counts: Vec<u32> = lists
        .iter()
        .map(|l| u32::try_from(l.len()).expect("at most MAX_FRAGMENTS fragments a pixel"))
        .collect();
    let full = counts.iter().copied().max().unwrap_or(0).max(1);
    let viewport = Viewport::new(case.pixels, 1).expect("1..=15 pixels");
    let distinct_depths = distinct_depths(&lists);
    for k in [case.k, full] {
        let build = Build {
            counts: Some(&counts),
            pool: case.fragments.len().max(1),
            ..Build::fixed(viewport, k, k, full, MEMORY_CAP_DEFAULT)
        };
        for entry in CATALOG {
            // A pass per layer over every fragment: deep cases skip these schemes, so that the
            // fuzzer keeps its pace.
            let per_layer = matches!(
                entry.passes,
                Passes::PerLayers { .. } | Passes::UntilConfirmed
            );
            if per_layer && full > MAX_MULTIPASS_LAYERS {
                continue;
            }
            let visitor = CheckOwed {
                case: &case,
                lists: &lists,
                distinct_depths,
            };
            entry
                .scheme
                .build(&build, visitor)
                .unwrap_or_else(|e| panic!("{}: cannot build for the case: {e}", entry.name));
        }
    }
}

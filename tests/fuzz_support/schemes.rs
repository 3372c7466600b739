//! The `schemes_vs_oracle` target: an arbitrary fragment stream on a viewport of fewer than 16
//! pixels (depth keys from arbitrary f32 in `[0, 1]`, primitive ids distinct per pixel) through
//! every exact scheme — MDTS with u64 words ascending and descending, with u32 words, and the
//! A-buffer with exact and fixed storage — run by `Scheme::insert` on `SerialMemory` and by the
//! scheduled executor under a schedule decoded from the input. Each capture must be what the
//! scheme promises of an oracle computed here by sorting, and the counted drops must equal what
//! the capture is missing.

use fragsim::capture::abuffer::{ABuffer, PostSort};
use fragsim::capture::executor::Run;
use fragsim::capture::mdts::{Direction, Mdts, MdtsWord};
use fragsim::capture::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::{Capture, Identity, Keeps, Scheme, SerialMemory, Step, MEMORY_CAP_DEFAULT};
use fragsim::raster::{depth_key, Fragment, Viewport};

use super::input::Input;

/// At most this many fragments are decoded (libFuzzer's inputs are short anyway).
const MAX_FRAGMENTS: usize = 512;

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
            fragments.len() as u32
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
pub fn sorted_lists(pixels: u32, fragments: &[Fragment]) -> Vec<Vec<u64>> {
    let mut lists = vec![Vec::new(); pixels as usize];
    for f in fragments {
        lists[f.pixel as usize].push(f.packed());
    }
    for list in &mut lists {
        list.sort_unstable();
    }
    lists
}

/// Checks `capture` against `lists` under the capture's promise; `dropped` is the count of walks
/// that ended in [`Step::Dropped`], which must equal the fragments missing from the capture.
pub fn check_capture(name: &str, lists: &[Vec<u64>], capture: &Capture, dropped: u64) {
    assert_eq!(capture.pixels(), lists.len(), "{name}: pixel count");
    let mask = match capture.identity {
        Identity::KeyAndPrim => u64::MAX,
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
            Keeps::All { overflow } => {
                let o = overflow[p] as usize;
                assert_eq!(got.len() + o, n, "{name}: pixel {p}, kept + overflow");
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
    assert_eq!(
        dropped, missing,
        "{name}: counted drops vs fragments missing"
    );
}

/// Runs `scheme` both ways over the case and checks both captures.
fn check_scheme<S: Scheme>(scheme: &S, case: &Case, lists: &[Vec<u64>]) {
    let name = scheme.name();
    let memory: SerialMemory = scheme.layout().allocate();
    let (mut steps, mut dropped) = (0, 0);
    for &f in &case.fragments {
        match scheme.insert(f, &memory, &mut steps) {
            Step::Dropped => dropped += 1,
            Step::Stored => {}
            other => panic!("{name}: a one-pass walk ended with {other:?}"),
        }
    }
    check_capture(
        &format!("{name} serial"),
        lists,
        &scheme.resolve(&memory),
        dropped,
    );
    let Run { capture, stats } = run_fragments(scheme, &case.fragments, &case.schedule, false).run;
    assert_eq!(stats.counters.fragments, case.fragments.len() as u64);
    check_capture(
        &format!("{name} under {:?}", case.schedule),
        lists,
        &capture,
        stats.counters.dropped,
    );
}

fn check_mdts<W: MdtsWord>(case: &Case, lists: &[Vec<u64>], k: u32) {
    let viewport = Viewport::new(case.pixels, 1).expect("1..=15 pixels");
    for direction in [Direction::Ascending, Direction::Descending] {
        let scheme = Mdts::<W>::new(viewport, k, direction, MEMORY_CAP_DEFAULT)
            .expect("K ≥ 1 on a few pixels");
        check_scheme(&scheme, case, lists);
    }
}

/// Decodes a fragment stream and checks every exact scheme on it.
pub fn check(data: &[u8]) {
    let case = decode(data);
    let lists = sorted_lists(case.pixels, &case.fragments);
    let counts: Vec<u32> = lists.iter().map(|l| l.len() as u32).collect();
    let full = counts.iter().copied().max().unwrap_or(0).max(1);
    for k in [case.k, full] {
        check_mdts::<u64>(&case, &lists, k);
        check_mdts::<u32>(&case, &lists, k);
    }
    let viewport = Viewport::new(case.pixels, 1).expect("1..=15 pixels");
    for sort in [PostSort::Insertion, PostSort::Bitonic] {
        let exact = ABuffer::exact(&counts, sort, MEMORY_CAP_DEFAULT).expect("tiny storage");
        check_scheme(&exact, &case, &lists);
        let fixed =
            ABuffer::fixed(viewport, case.k, sort, MEMORY_CAP_DEFAULT).expect("tiny storage");
        check_scheme(&fixed, &case, &lists);
    }
}

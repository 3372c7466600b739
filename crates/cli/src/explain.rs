//! `fragsim explain`: finds an interleaving of a few fragments on one pixel that shows a scheme's
//! property, shrinks it, and prints it step by step, one column per thread.
//!
//! - `--scheme kbuffer`: the read–insert–write k-buffer, on the machine `--write-back` names
//!   (`render-target`, the default: the read and the write-back are one step each and write-backs
//!   commit in primitive order; `separate-stores`: `K` loads and `K` stores, one step each). Seeds
//!   of the scheduled executor (uniform random and PCT, one thread per fragment) are searched for a
//!   run whose slots differ from the sorted input (a fragment lost or duplicated); that run is
//!   shrunk (fragments dropped, then context switches removed, each change kept only if the hazard
//!   still shows) and printed with the lost value named. The shortest losing interleaving is 4
//!   steps on render targets and `4 K` with separate stores (`fragsim_capture::kbuffer` says why).
//! - `--scheme mdts`: the densest interleaving (most context switches) among the seeds, with
//!   `docs/proof.md`'s invariant checked after every step: each slot only ever decreases, and the
//!   multiset of slot values plus the values carried in flight (plus those carried past the last
//!   slot) equals the inputs.
//!
//! Every run is a replay of an explicit order through
//! [`fragsim_capture::scheduled::run_fragments_in_order`], so what is printed is what ran. A row
//! is one step, however many memory operations it did (a render-target read is `K` loads under the
//! pixel's lock, printed as one `read`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use clap::{Args, ValueEnum};
use fragsim_capture::kbuffer::{KBuffer, WriteBack, EMPTY};
use fragsim_capture::mdts::Mdts;
use fragsim_capture::scheduled::{
    run_fragments, run_fragments_in_order, Op, Policy, Schedule, Trace, TraceEvent,
};
use fragsim_capture::Scheme;
use fragsim_raster::{depth_key, Fragment, Viewport};

/// Schemes `explain` knows how to explain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExplainScheme {
    /// The read–insert–write k-buffer: shows a lost or duplicated fragment.
    Kbuffer,
    /// MDTS (`atomicMin` chain, u64 words): shows the invariant holding at every step.
    Mdts,
}

/// Options of `fragsim explain`.
#[derive(Debug, Clone, Args)]
pub struct ExplainArgs {
    /// The scheme to explain.
    #[arg(long, default_value = "kbuffer")]
    pub scheme: ExplainScheme,
    /// Depths (in [0, 1]) of the fragments on the one pixel, comma-separated; fragment `i` is
    /// primitive `i` and runs on thread `i`.
    // `-0.1,0.5` is a value to check (and refuse, out of [0, 1]), not an unknown flag.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0.3,0.5,0.1",
        allow_hyphen_values = true
    )]
    pub depths: Vec<f32>,
    /// Slots per pixel (default: the number of fragments, so nothing falls off by design).
    #[arg(long)]
    pub k: Option<u32>,
    /// Seeds of the scheduled executor to search.
    #[arg(long, default_value_t = 200)]
    pub seeds: u64,
    /// Print the interleaving as found, without shrinking it.
    #[arg(long)]
    pub no_shrink: bool,
    /// The k-buffer's machine: render targets (the papers' GPUs) or separate stores (CUDA).
    #[arg(long, value_enum, default_value = "render-target")]
    pub write_back: WriteBackArg,
}

/// The k-buffer's machine, on the command line (`fragsim_capture::kbuffer::WriteBack`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WriteBackArg {
    /// The read of the K slots is one step, the write-back one step, write-backs commit in
    /// primitive order: only reads can be stale.
    RenderTarget,
    /// K loads and K stores, one step each, as CUDA code does: write-backs can tear.
    SeparateStores,
}

impl WriteBackArg {
    /// The library's value.
    #[must_use]
    pub fn machine(self) -> WriteBack {
        match self {
            WriteBackArg::RenderTarget => WriteBack::RenderTarget,
            WriteBackArg::SeparateStores => WriteBack::SeparateStores,
        }
    }

    /// How reports name the machine.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            WriteBackArg::RenderTarget => "render-target write-backs",
            WriteBackArg::SeparateStores => "separate stores",
        }
    }
}

/// Runs `explain`: `Ok(true)` when the property was shown (a hazard for the k-buffer, the
/// invariant at every step for MDTS).
///
/// # Errors
/// Bad depths or parameters.
pub fn explain(args: &ExplainArgs) -> Result<bool, String> {
    let (text, shown) = explain_text(args)?;
    out!("{text}");
    Ok(shown)
}

/// The report `explain` prints, and whether the property was shown.
///
/// # Errors
/// Bad depths or parameters.
pub fn explain_text(args: &ExplainArgs) -> Result<(String, bool), String> {
    if args.depths.is_empty() || args.depths.len() > 64 {
        return Err("explain needs 1 to 64 depths".into());
    }
    let fragments = args
        .depths
        .iter()
        .enumerate()
        .map(|(i, &d)| {
            depth_key(d)
                .map(|depth_key| Fragment {
                    pixel: 0,
                    depth_key,
                    prim: i as u32,
                })
                .ok_or_else(|| format!("depth {d} is outside [0, 1]"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let k = args.k.unwrap_or(fragments.len() as u32);
    let viewport = Viewport::new(1, 1)?;
    match args.scheme {
        ExplainScheme::Kbuffer => {
            let scheme = KBuffer::with_write_back(
                viewport,
                k,
                args.write_back.machine(),
                fragsim_capture::MEMORY_CAP_DEFAULT,
            )
            .map_err(|e| e.to_string())?;
            Ok(explain_kbuffer(&scheme, k, &fragments, args))
        }
        ExplainScheme::Mdts => {
            let scheme = Mdts::<u64>::ascending(viewport, k).map_err(|e| e.to_string())?;
            Ok(explain_mdts(&scheme, k, &fragments, args.seeds))
        }
    }
}

/// The schedule searched at `seed`: uniform random on even seeds, PCT on odd ones.
fn schedule(seed: u64, threads: usize) -> Schedule {
    Schedule {
        policy: if seed.is_multiple_of(2) {
            Policy::Random
        } else {
            Policy::Pct { depth: 3 }
        },
        in_flight: threads,
        granularity: fragsim_capture::scheduled::Granularity::Fragment,
        seed,
    }
}

fn record<S: Scheme>(scheme: &S, fragments: &[Fragment], order: &[u32]) -> Trace {
    run_fragments_in_order(scheme, fragments, order, true)
        .trace
        .expect("recorded")
}

fn order_of(trace: &Trace) -> Vec<u32> {
    trace.order()
}

/// Steps in the trace (a step may record several memory operations).
fn step_count(trace: &Trace) -> usize {
    trace.steps().count()
}

/// Times the running thread changes from one step to the next.
fn switches(trace: &Trace) -> usize {
    trace.order().windows(2).filter(|w| w[0] != w[1]).count()
}

/// The pixel's `k` slot words (the `u64` words; a render target's lock and last writer are `u32`)
/// after each step, replayed from the trace's (operand, returned) pairs.
fn memory_after(trace: &Trace, k: u32, init: u64) -> Vec<Vec<u64>> {
    let mut words = vec![init; k as usize];
    trace
        .steps()
        .map(|events| {
            for e in events.iter().filter(|e| e.width == 64) {
                words[e.word] = match e.op {
                    Op::Load => e.returned,
                    Op::Store | Op::Swap => e.operand,
                    Op::FetchMin => e.returned.min(e.operand),
                    Op::FetchMax => e.returned.max(e.operand),
                    Op::FetchAdd => e.returned.wrapping_add(e.operand),
                    Op::FetchOr => e.returned | e.operand,
                };
            }
            words.clone()
        })
        .collect()
}

/// What the k-buffer's slots got wrong against the `k` nearest inputs: (lost, duplicated).
fn kbuffer_damage(fragments: &[Fragment], k: u32, slots: &[u64]) -> (Vec<u64>, Vec<u64>) {
    let mut expected: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    expected.sort_unstable();
    expected.truncate(k as usize);
    let mut counts: BTreeMap<u64, i64> = BTreeMap::new();
    for &v in slots.iter().filter(|&&v| v != EMPTY) {
        *counts.entry(v).or_default() += 1;
    }
    let lost = expected
        .iter()
        .filter(|v| !counts.contains_key(v))
        .copied()
        .collect();
    let duplicated = counts
        .iter()
        .filter(|&(_, &c)| c > 1)
        .map(|(&v, _)| v)
        .collect();
    (lost, duplicated)
}

/// A k-buffer run's damage, if it shows any.
fn kbuffer_hazard(
    scheme: &KBuffer,
    k: u32,
    fragments: &[Fragment],
    order: &[u32],
) -> Option<(Trace, Vec<u64>, Vec<u64>)> {
    let trace = record(scheme, fragments, order);
    let last = memory_after(&trace, k, EMPTY).pop().unwrap_or_default();
    let (lost, duplicated) = kbuffer_damage(fragments, k, &last);
    (!lost.is_empty() || !duplicated.is_empty()).then_some((trace, lost, duplicated))
}

/// Interleavings of the shrunk walks tried one by one when there are at most this many.
const EXHAUSTIVE_LIMIT: u64 = 200_000;

/// What shrinking minimises, in order: steps; render-target write-backs dropped because a later
/// reader's had committed (the same loss reads more plainly as the later one's stale read
/// erasing the earlier write-back, in commit order); context switches.
fn rank(trace: &Trace) -> (usize, usize, usize) {
    let dropped = trace
        .steps()
        .filter(|events| events.len() > 1 && events.iter().all(|e| e.width == 32))
        .count();
    (step_count(trace), dropped, switches(trace))
}

/// Every distinct reordering of `order` (the same steps per thread), or `None` when there are
/// more than `limit`.
fn interleavings(order: &[u32], limit: u64) -> Option<Vec<Vec<u32>>> {
    let threads = order.iter().max().map_or(0, |&t| t as usize + 1);
    let mut left = vec![0usize; threads];
    for &t in order {
        left[t as usize] += 1;
    }
    // The multinomial coefficient, stopping once past the limit.
    let mut count: u64 = 1;
    let mut placed: u64 = 0;
    for &n in &left {
        for i in 1..=n as u64 {
            placed += 1;
            count = count.checked_mul(placed)? / i;
            if count > limit {
                return None;
            }
        }
    }
    fn extend(left: &mut [usize], prefix: &mut Vec<u32>, len: usize, out: &mut Vec<Vec<u32>>) {
        if prefix.len() == len {
            out.push(prefix.clone());
            return;
        }
        for t in 0..left.len() {
            if left[t] > 0 {
                left[t] -= 1;
                prefix.push(t as u32);
                extend(left, prefix, len, out);
                prefix.pop();
                left[t] += 1;
            }
        }
    }
    let mut out = Vec::new();
    extend(&mut left, &mut Vec::new(), order.len(), &mut out);
    Some(out)
}

/// Drops fragments, then context switches, while the hazard still shows: fewer steps first.
fn shrink(
    scheme: &KBuffer,
    k: u32,
    mut fragments: Vec<Fragment>,
    mut order: Vec<u32>,
) -> (Vec<Fragment>, Vec<u32>) {
    let mut changed = true;
    while changed {
        changed = false;
        for drop in (0..fragments.len()).rev() {
            if fragments.len() <= 1 {
                break;
            }
            let mut fewer = fragments.clone();
            fewer.remove(drop);
            // Renumber so that thread t still carries fewer[t] (and its primitive id is t).
            for (t, f) in fewer.iter_mut().enumerate() {
                f.prim = t as u32;
            }
            let drop = drop as u32;
            let remapped: Vec<u32> = order
                .iter()
                .filter(|&&t| t != drop)
                .map(|&t| if t > drop { t - 1 } else { t })
                .collect();
            if let Some((trace, ..)) = kbuffer_hazard(scheme, k, &fewer, &remapped) {
                fragments = fewer;
                order = order_of(&trace);
                changed = true;
                break;
            }
        }
    }
    // Few enough interleavings of these walks: try them all. Else move one step earlier
    // wherever the hazard survives it and the rank improves.
    if let Some(all) = interleavings(&order, EXHAUSTIVE_LIMIT) {
        if let Some(best) = all
            .iter()
            .filter_map(|candidate| kbuffer_hazard(scheme, k, &fragments, candidate))
            .map(|(trace, ..)| trace)
            .min_by_key(|trace| (rank(trace), order_of(trace)))
        {
            order = order_of(&best);
        }
        return (fragments, order);
    }
    let mut best = record(scheme, &fragments, &order);
    let mut changed = true;
    while changed {
        changed = false;
        'search: for j in 1..order.len() {
            for i in 0..j {
                if order[i] == order[j] {
                    continue;
                }
                let mut candidate = order.clone();
                let moved = candidate.remove(j);
                candidate.insert(i, moved);
                if let Some((trace, ..)) = kbuffer_hazard(scheme, k, &fragments, &candidate) {
                    if rank(&trace) < rank(&best) {
                        order = order_of(&trace);
                        best = trace;
                        changed = true;
                        break 'search;
                    }
                }
            }
        }
    }
    (fragments, order)
}

fn explain_kbuffer(
    scheme: &KBuffer,
    k: u32,
    fragments: &[Fragment],
    args: &ExplainArgs,
) -> (String, bool) {
    let mut out = String::new();
    let threads = fragments.len();
    let found = (0..args.seeds).find_map(|seed| {
        let run = run_fragments(scheme, fragments, &schedule(seed, threads), true);
        let order = order_of(&run.trace.expect("recorded"));
        kbuffer_hazard(scheme, k, fragments, &order).map(|(trace, ..)| (seed, trace))
    });
    let machine = args.write_back.label();
    let Some((seed, trace)) = found else {
        let _ = writeln!(
            out,
            "k-buffer ({machine}), K = {k}, {threads} fragments: no losing interleaving in {} seeds",
            args.seeds
        );
        return (out, false);
    };
    let _ = writeln!(
        out,
        "k-buffer ({machine}), K = {k}: found at seed {seed} ({:?}): {} steps, {} threads, {} switches",
        schedule(seed, threads).policy,
        step_count(&trace),
        threads,
        switches(&trace)
    );
    let (fragments, order) = if args.no_shrink {
        (fragments.to_vec(), order_of(&trace))
    } else {
        shrink(scheme, k, fragments.to_vec(), order_of(&trace))
    };
    let (trace, lost, duplicated) =
        kbuffer_hazard(scheme, k, &fragments, &order).expect("the shrunk order shows the hazard");
    let _ = writeln!(
        out,
        "{}: {} steps, {} threads, {} switches",
        if args.no_shrink { "unshrunk" } else { "shrunk" },
        step_count(&trace),
        fragments.len(),
        switches(&trace)
    );
    let memory = memory_after(&trace, k, EMPTY);
    out.push_str(&table(&fragments, &trace, &memory, &[]));
    let expected: Vec<u64> = {
        let mut v: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
        v.sort_unstable();
        v.truncate(k as usize);
        v
    };
    let _ = writeln!(
        out,
        "expected slots: {}",
        expected
            .iter()
            .map(|&v| value(v))
            .collect::<Vec<_>>()
            .join(" ")
    );
    for v in &lost {
        let _ = writeln!(
            out,
            "LOST: {} (fragment {}, depth {}): overwritten by a write-back computed from a read that missed it",
            value(*v),
            *v as u32,
            f32::from_bits((v >> 32) as u32)
        );
    }
    for v in &duplicated {
        let _ = writeln!(out, "DUPLICATED: {} is in two slots", value(*v));
    }
    let _ = writeln!(
        out,
        "{}",
        match args.write_back {
            WriteBackArg::RenderTarget =>
                "machine: render targets: a read of the K slots is one step and a write-back one \
                 step, write-backs commit in order; only a read can be stale, so the \
                 only failure is a lost fragment",
            WriteBackArg::SeparateStores =>
                "machine: separate stores: K loads, then K stores, one step each; write-backs can \
                 interleave store by store (duplicates, slots out of order) as well as lose",
        }
    );
    (out, true)
}

/// Checks `docs/proof.md`'s invariant after each MDTS step (slots only decrease; slots, carried
/// and dropped values together are the inputs); also names the values in flight after each step.
fn mdts_invariant(
    fragments: &[Fragment],
    k: u32,
    trace: &Trace,
    memory: &[Vec<u64>],
) -> (Vec<bool>, Vec<String>) {
    let mut inputs: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    inputs.sort_unstable();
    let mut carried: Vec<Option<u64>> = inputs.iter().map(|_| None).collect();
    for f in fragments {
        carried[f.prim as usize] = Some(f.packed());
    }
    let mut dropped: Vec<u64> = Vec::new();
    let mut before = vec![EMPTY; k as usize];
    let mut in_flight = Vec::new();
    let checks = trace
        .events
        .iter()
        .zip(memory)
        .map(|(e, after)| {
            let t = e.thread as usize;
            let decreased = after.iter().zip(&before).all(|(a, b)| a <= b);
            carried[t] = (e.returned != EMPTY).then(|| e.returned.max(e.operand));
            if e.word + 1 == k as usize {
                dropped.extend(carried[t].take());
            }
            let mut seen: Vec<u64> = after.iter().copied().filter(|&v| v != EMPTY).collect();
            seen.extend(carried.iter().flatten());
            seen.extend(&dropped);
            seen.sort_unstable();
            before.clone_from(after);
            let mut flying: Vec<String> = carried.iter().flatten().map(|&v| value(v)).collect();
            flying.extend(dropped.iter().map(|&v| format!("{} dropped", value(v))));
            in_flight.push(flying.join(", "));
            decreased && seen == inputs
        })
        .collect();
    (checks, in_flight)
}

fn explain_mdts(scheme: &Mdts<u64>, k: u32, fragments: &[Fragment], seeds: u64) -> (String, bool) {
    let threads = fragments.len();
    let densest = (0..seeds.max(1))
        .map(|seed| {
            let run = run_fragments(scheme, fragments, &schedule(seed, threads), true);
            (seed, run.trace.expect("recorded"))
        })
        .max_by_key(|(seed, trace)| (switches(trace), std::cmp::Reverse(*seed)))
        .expect("at least one seed");
    let (seed, trace) = densest;
    // Replay it from its order, so that what is printed is a replayable interleaving.
    let trace = record(scheme, fragments, &order_of(&trace));
    let memory = memory_after(&trace, k, EMPTY);
    let (checks, in_flight) = mdts_invariant(fragments, k, &trace, &memory);
    let marks: Vec<String> = checks
        .iter()
        .map(|&c| if c { "✓" } else { "✗" }.to_string())
        .collect();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "MDTS, K = {k}: densest of {seeds} seeds is seed {seed} ({:?}): {} steps, {threads} threads, {} switches",
        schedule(seed, threads).policy,
        step_count(&trace),
        switches(&trace)
    );
    out.push_str(&table(
        fragments,
        &trace,
        &memory,
        &[("carried (in flight)", in_flight), ("inv", marks)],
    ));
    let mut expected: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    expected.sort_unstable();
    expected.truncate(k as usize);
    let last: Vec<u64> = memory
        .last()
        .map(|m| m.iter().copied().filter(|&v| v != EMPTY).collect())
        .unwrap_or_default();
    let all = checks.iter().all(|&c| c);
    let _ = writeln!(
        out,
        "invariant (slots only decrease; slots + carried + dropped = inputs): {} at {} of {} steps",
        if all { "✓ holds" } else { "✗ FAILS" },
        checks.iter().filter(|&&c| c).count(),
        checks.len()
    );
    let sorted = last == expected;
    let _ = writeln!(
        out,
        "final slots {} the {} nearest inputs in order: {}",
        if sorted { "are" } else { "are NOT" },
        k,
        last.iter().map(|&v| value(v)).collect::<Vec<_>>().join(" ")
    );
    (out, all && sorted)
}

/// A slot value: `∅` for empty, else `depth#prim`.
fn value(v: u64) -> String {
    if v == EMPTY {
        "∅".into()
    } else {
        format!("{}#{}", f32::from_bits((v >> 32) as u32), v as u32)
    }
}

fn cell(e: &TraceEvent) -> String {
    let w = e.word;
    match e.op {
        Op::Load => format!("load w{w} → {}", value(e.returned)),
        Op::Store => format!(
            "store w{w} ← {} (was {})",
            value(e.operand),
            value(e.returned)
        ),
        op => {
            let name = match op {
                Op::FetchMin => "fetch_min",
                Op::FetchMax => "fetch_max",
                Op::FetchAdd => "fetch_add",
                Op::Swap => "swap",
                _ => "fetch_or",
            };
            format!("{name} w{w} ← {} → {}", value(e.operand), value(e.returned))
        }
    }
}

/// One step's cell: its memory operation, or, for a step of several (a render target's read or
/// write-back of the pixel's slots, under its lock), what it did to the slots as a whole.
fn step_cell(events: &[TraceEvent]) -> String {
    if let [e] = events {
        return cell(e);
    }
    let slots: Vec<&TraceEvent> = events.iter().filter(|e| e.width == 64).collect();
    let list = |f: fn(&TraceEvent) -> u64| {
        format!(
            "[{}]",
            slots
                .iter()
                .map(|&e| value(f(e)))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    if slots.is_empty() {
        // The write-back found a later reader's committed: in commit order it came first.
        let last = events
            .iter()
            .find(|e| e.width == 32 && e.op == Op::Load)
            .map_or(0, |e| e.returned);
        format!(
            "write-back dropped: ticket {} (a later read) committed after it in commit order",
            last.saturating_sub(1)
        )
    } else if slots.iter().all(|e| e.op == Op::Load) {
        format!("read {}", list(|e| e.returned))
    } else {
        format!(
            "write {} (was {})",
            list(|e| e.operand),
            list(|e| e.returned)
        )
    }
}

/// The step-by-step table: a column per thread, then the memory after the step, then `extra`
/// columns (title, one cell per step).
fn table(
    fragments: &[Fragment],
    trace: &Trace,
    memory: &[Vec<u64>],
    extra: &[(&str, Vec<String>)],
) -> String {
    let threads = fragments.len();
    let mut header: Vec<String> = vec!["step".into()];
    header.extend(
        fragments
            .iter()
            .enumerate()
            .map(|(t, f)| format!("T{t} ({})", value(f.packed()))),
    );
    header.push("memory after".into());
    header.extend(extra.iter().map(|(title, _)| (*title).to_string()));
    let mut rows = vec![header];
    for (i, (events, m)) in trace.steps().zip(memory).enumerate() {
        let mut row = vec![i.to_string()];
        row.extend((0..threads).map(|t| {
            if events[0].thread as usize == t {
                step_cell(events)
            } else {
                String::new()
            }
        }));
        row.push(format!(
            "[{}]",
            m.iter().map(|&v| value(v)).collect::<Vec<_>>().join(", ")
        ));
        row.extend(extra.iter().map(|(_, cells)| cells[i].clone()));
        rows.push(row);
    }
    let columns = rows[0].len();
    let widths: Vec<usize> = (0..columns)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    let mut out = String::new();
    for (r, row) in rows.iter().enumerate() {
        let line: Vec<String> = row
            .iter()
            .zip(&widths)
            .map(|(s, &w)| format!("{s}{}", " ".repeat(w - s.chars().count())))
            .collect();
        let _ = writeln!(out, "| {} |", line.join(" | "));
        if r == 0 {
            let rule: Vec<String> = widths.iter().map(|&w| "-".repeat(w)).collect();
            let _ = writeln!(out, "|-{}-|", rule.join("-|-"));
        }
    }
    out
}

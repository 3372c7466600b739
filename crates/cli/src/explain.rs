//! `fragsim explain`: finds an interleaving of a few fragments on one pixel that shows a scheme's
//! property, shrinks it, and prints it step by step, one column per thread.
//!
//! - `--scheme kbuffer` (or `kbuffer-stores`): the read–insert–write k-buffer, on the machine
//!   `--write-back` names (`render-target`, `kbuffer`'s: the read and the write-back are one step
//!   each and write-backs commit in primitive order; `separate-stores`, `kbuffer-stores`'s: `K`
//!   loads and `K` stores, one step each). Seeds of the scheduled executor (uniform random and
//!   PCT, one thread per fragment) are searched for a run whose slots differ from the sorted
//!   input (a fragment lost or duplicated); that run is shrunk (fragments dropped, then context
//!   switches removed, each change kept only if the hazard still shows) and printed with the
//!   lost value named. The shortest losing interleaving is 4 steps on render targets and `4 K`
//!   with separate stores (`fragsim_capture::schemes::kbuffer` says why).
//! - `--scheme mdts`: the densest interleaving (most context switches) among the seeds, with
//!   `docs/proof.md`'s invariant checked after every step: each slot only ever decreases, and the
//!   multiset of slot values plus the values carried in flight (plus those carried past the last
//!   slot) equals the inputs.
//!
//! The search, the shrinker and the invariant are `fragsim_explain`'s; the schemes offered are
//! the catalog's entries it can explain ([`fragsim_explain::Shown::schemes`]). This module holds
//! the options and the printing. A row is one step, however many memory operations it did (a
//! render-target read is `K` loads under the pixel's lock, printed as one `read`).

use std::fmt::Write as _;

use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use fragsim_capture::catalog::SchemeName;
use fragsim_capture::executors::scheduled::Trace;
use fragsim_capture::schemes::kbuffer::{KBuffer, WriteBack, EMPTY};
use fragsim_capture::schemes::mdts::Mdts;
use fragsim_explain::interleaving::{
    memory_after, nearest, one_pixel, schedule, step_count, switches,
};
use fragsim_explain::{kbuffer, mdts, Shown};
use fragsim_memory::{Op, TraceEvent};
use fragsim_raster::{Fragment, Viewport};

use crate::table::Table;

/// A catalog scheme `explain` can explain ([`Shown::of`]), on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExplainedScheme(pub SchemeName);

impl ValueEnum for ExplainedScheme {
    fn value_variants<'a>() -> &'a [Self] {
        // The catalog's explainable entries, listed once for clap's lifetime.
        static VARIANTS: std::sync::OnceLock<Vec<ExplainedScheme>> = std::sync::OnceLock::new();
        VARIANTS.get_or_init(|| Shown::schemes().map(|e| Self(e.scheme)).collect())
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let entry = self.0.entry();
        Some(PossibleValue::new(entry.name).help(entry.description))
    }
}

/// Options of `fragsim explain`.
#[derive(Debug, Clone, Args)]
pub struct ExplainArgs {
    /// The scheme to explain: the k-buffer shows a lost or duplicated fragment, MDTS its
    /// invariant holding at every step.
    #[arg(long, default_value = "kbuffer")]
    pub scheme: ExplainedScheme,
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
    /// Slots per pixel [default: one per depth of --depths, so nothing falls off by design].
    #[arg(long)]
    pub k: Option<u32>,
    /// Seeds of the scheduled executor to search.
    #[arg(long, default_value_t = 200)]
    pub seeds: u64,
    /// Print the interleaving as found, without shrinking it.
    #[arg(long)]
    pub no_shrink: bool,
    /// The k-buffer's machine: render targets (the papers' GPUs) or separate stores (CUDA);
    /// default: the scheme's own (`kbuffer`: render targets, `kbuffer-stores`: separate stores).
    #[arg(long, value_enum)]
    pub write_back: Option<WriteBackArg>,
    /// Print one JSON Lines record (`docs/json-schema.md`): the scheme, the depths, whether the
    /// property was shown, and the report's lines.
    #[arg(long)]
    pub json: bool,
}

/// What the symbols of the step table mean, printed under it; `example`, a fragment of the
/// table, illustrates the fragment notation, so that the key agrees with the run it explains.
fn key(example: &Fragment) -> String {
    format!(
        "key: {} = a fragment: depth {}, primitive {p} (index {p} in --depths), run by thread \
         T{p}; ∅ = an empty slot; w2 = memory word 2 (the pixel's slot 2); \
         ← = the value written; → = the value the operation returned; \
         (was …) = what a store overwrote",
        value(example.packed()),
        example.depth(),
        p = example.prim
    )
}

/// `explain`'s one JSON Lines record.
#[derive(serde::Serialize)]
struct ExplainRecord<'a> {
    scheme: &'static str,
    depths: &'a [f32],
    seeds: u64,
    /// Whether the property was shown (a hazard for the k-buffer, the invariant for MDTS).
    shown: bool,
    /// The printed report, line by line.
    lines: Vec<&'a str>,
}

/// The k-buffer's machine, on the command line (`fragsim_capture::schemes::kbuffer::WriteBack`).
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
            Self::RenderTarget => WriteBack::RenderTarget,
            Self::SeparateStores => WriteBack::SeparateStores,
        }
    }
}

/// How reports name a machine.
fn machine_label(machine: WriteBack) -> &'static str {
    match machine {
        WriteBack::RenderTarget => "render-target write-backs",
        WriteBack::SeparateStores => "separate stores",
    }
}

/// Runs `explain`: `Ok(true)` when the property was shown (a hazard for the k-buffer, the
/// invariant at every step for MDTS).
///
/// # Errors
/// Bad depths or parameters.
#[expect(
    clippy::cast_possible_truncation,
    reason = "at most fragsim_explain::interleaving::MAX_FRAGMENTS (64) depths"
)]
pub(crate) fn explain(args: &ExplainArgs) -> Result<bool, String> {
    let (text, shown) = explain_text(args)?;
    if args.json {
        let mut context = crate::record::Context::new(
            "explain",
            &fragsim_raster::scene_spec::SceneSpec::named("one-pixel", 0.0, 0.0),
            1,
            1,
        );
        (context.view_degrees, context.elevation_degrees) = (None, None);
        context.k = Some(crate::record::Slots::Fixed(
            args.k.unwrap_or(args.depths.len() as u32),
        ));
        context.executor = Some("scheduled".into());
        context.threads = Some(args.depths.len());
        let record = ExplainRecord {
            scheme: args.scheme.0.name(),
            depths: &args.depths,
            seeds: args.seeds,
            shown,
            lines: text.lines().collect(),
        };
        crate::record::emit("explain", &context, &record)?;
    } else {
        out!("{text}");
    }
    Ok(shown)
}

/// The report `explain` prints, and whether the property was shown.
///
/// # Errors
/// Bad depths or parameters, or a `--write-back` other than the `-stores` scheme's machine.
pub(crate) fn explain_text(args: &ExplainArgs) -> Result<(String, bool), String> {
    let fragments = one_pixel(&args.depths)?;
    #[expect(
        clippy::cast_possible_truncation,
        reason = "at most fragsim_explain::interleaving::MAX_FRAGMENTS (64) depths"
    )]
    let k = args.k.unwrap_or(fragments.len() as u32);
    let viewport = Viewport::new(1, 1).map_err(|e| e.to_string())?;
    let name = args.scheme.0;
    match Shown::of(name).ok_or_else(|| format!("explain cannot explain {name}"))? {
        Shown::Hazard(own) => {
            let machine = match args.write_back.map(WriteBackArg::machine) {
                // `kbuffer` is the k-buffer on either machine; a `-stores` name fixes its own.
                Some(asked) if asked != own && own == WriteBack::SeparateStores => {
                    return Err(format!(
                        "--scheme {name} runs on separate stores; --write-back names the other \
                         machine (use --scheme kbuffer for render targets)"
                    ))
                }
                Some(asked) => asked,
                None => own,
            };
            let scheme =
                KBuffer::with_write_back(viewport, k, machine, fragsim_capture::MEMORY_CAP_DEFAULT)
                    .map_err(|e| e.to_string())?;
            Ok(explain_kbuffer(&scheme, machine, k, &fragments, args))
        }
        Shown::Invariant => {
            let scheme = Mdts::<u64>::ascending(viewport, k).map_err(|e| e.to_string())?;
            Ok(explain_mdts(&scheme, k, &fragments, args.seeds))
        }
        Shown::Deadlock => match fragsim_explain::spinlock::shortest_deadlock(k, &fragments) {
            Ok(Some(report)) => Ok((format!("{report}\n"), true)),
            Ok(None) => Ok((
                "kbuffer-spinlock: one fragment cannot deadlock\n".into(),
                false,
            )),
            Err(e) => Err(e.to_string()),
        },
    }
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "a word's low half is its primitive id"
)]
fn explain_kbuffer(
    scheme: &KBuffer,
    machine: WriteBack,
    k: u32,
    fragments: &[Fragment],
    args: &ExplainArgs,
) -> (String, bool) {
    let mut out = String::new();
    let threads = fragments.len();
    let label = machine_label(machine);
    let Some((seed, trace)) = kbuffer::search(scheme, k, fragments, args.seeds) else {
        let _ = writeln!(
            out,
            "k-buffer ({label}), K = {k}, {threads} fragments: no losing interleaving in {} seeds",
            args.seeds
        );
        return (out, false);
    };
    let _ = writeln!(
        out,
        "k-buffer ({label}), K = {k}: found at seed {seed} ({:?}): {} steps, {} threads, {} switches",
        schedule(seed, threads).policy,
        step_count(&trace),
        threads,
        switches(&trace)
    );
    let (fragments, order) = if args.no_shrink {
        (fragments.to_vec(), trace.order())
    } else {
        kbuffer::shrink(scheme, k, fragments.to_vec(), trace.order())
    };
    #[expect(
        clippy::shadow_unrelated,
        reason = "the shrunk trace replaces the one it was shrunk from"
    )]
    let (trace, damage) =
        kbuffer::hazard(scheme, k, &fragments, &order).expect("the shrunk order shows the hazard");
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
    let _ = writeln!(out, "{}", key(&fragments[0]));
    let _ = writeln!(out, "expected slots: {}", values(&nearest(&fragments, k)));
    for v in &damage.lost {
        let _ = writeln!(
            out,
            "LOST: {} (fragment {}, depth {}): overwritten by a write-back computed from a read that missed it",
            value(*v),
            *v as u32,
            f32::from_bits((v >> 32) as u32)
        );
    }
    for v in &damage.duplicated {
        let _ = writeln!(out, "DUPLICATED: {} is in two slots", value(*v));
    }
    let _ = writeln!(
        out,
        "{}",
        match machine {
            WriteBack::RenderTarget =>
                "machine: render targets: a read of the K slots is one step and a write-back one \
                 step, write-backs commit in order; only a read can be stale, so the \
                 only failure is a lost fragment",
            WriteBack::SeparateStores =>
                "machine: separate stores: K loads, then K stores, one step each; write-backs can \
                 interleave store by store (duplicates, slots out of order) as well as lose",
        }
    );
    (out, true)
}

fn explain_mdts(scheme: &Mdts<u64>, k: u32, fragments: &[Fragment], seeds: u64) -> (String, bool) {
    let threads = fragments.len();
    let (seed, trace) = mdts::densest(scheme, fragments, seeds);
    let memory = memory_after(&trace, k, EMPTY);
    let checks = mdts::invariant(fragments, k, &trace, &memory);
    let marks: Vec<String> = checks
        .iter()
        .map(|c| if c.holds { "✓" } else { "✗" }.to_string())
        .collect();
    let in_flight: Vec<String> = checks
        .iter()
        .map(|c| {
            let mut flying: Vec<String> = c.carried.iter().map(|&v| value(v)).collect();
            flying.extend(c.dropped.iter().map(|&v| format!("{} dropped", value(v))));
            flying.join(", ")
        })
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
    let _ = writeln!(
        out,
        "{}; inv: ✓ the invariant holds after the step (a cross where it fails)",
        key(&fragments[0])
    );
    let last: Vec<u64> = memory
        .last()
        .map(|m| m.iter().copied().filter(|&v| v != EMPTY).collect())
        .unwrap_or_default();
    let held = checks.iter().filter(|c| c.holds).count();
    let all = held == checks.len();
    let _ = writeln!(
        out,
        "invariant (slots only decrease; slots + carried + dropped = inputs): {} at {} of {} steps",
        if all { "✓ holds" } else { "✗ FAILS" },
        held,
        checks.len()
    );
    let sorted = last == nearest(fragments, k);
    let _ = writeln!(
        out,
        "final slots {} the {} nearest inputs in order: {}",
        if sorted { "are" } else { "are NOT" },
        k,
        values(&last)
    );
    (out, all && sorted)
}

/// Slot values separated by spaces.
fn values(words: &[u64]) -> String {
    words
        .iter()
        .map(|&v| value(v))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A slot value: `∅` for empty, else `depth#prim`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
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
            .map(|f| format!("T{} ({})", f.prim, value(f.packed()))),
    );
    header.push("memory after".into());
    header.extend(extra.iter().map(|(title, _)| (*title).to_string()));
    let mut table = Table::new(header, usize::MAX);
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
        table.push(row);
    }
    table.markdown()
}

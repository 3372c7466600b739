//! What `fragsim explain` reports, as data: the interleaving found for a scheme ([`Shown::of`]),
//! shrunk, as lines of text around a step-by-step table ([`Explanation`]); the command line lays
//! the table out and prints it.
//!
//! A row of the table is one step, however many memory operations it did (a render-target read
//! is `K` loads under the pixel's lock, shown as one `read`).

use fragsim_capture::executors::scheduled::Trace;
use fragsim_catalog::SchemeName;
use fragsim_memory::{Op, TraceEvent};
use fragsim_raster::{Fragment, Viewport};
use fragsim_schemes::kbuffer::{KBuffer, WriteBack, EMPTY};
use fragsim_schemes::mdts::Mdts;

use crate::interleaving::{memory_after, nearest, one_pixel, schedule, step_count, switches};
use crate::{kbuffer, mdts, Shown};

/// What to explain: the scheme, the fragments on the one pixel, and the search.
#[derive(Debug, Clone)]
pub struct ExplainParams<'a> {
    /// The catalog scheme ([`Shown::of`] says what is shown of it).
    pub scheme: SchemeName,
    /// Depths (in [0, 1]) of the fragments on the one pixel; fragment `i` is primitive `i` and
    /// runs on thread `i`.
    pub depths: &'a [f32],
    /// Slots per pixel (`None`: one per depth, so nothing falls off by design).
    pub k: Option<u32>,
    /// Seeds of the scheduled executor to search.
    pub seeds: u64,
    /// Whether the interleaving found is shrunk before it is shown.
    pub shrink: bool,
    /// The k-buffer's machine (`None`: the scheme's own).
    pub write_back: Option<WriteBack>,
}

/// The step-by-step table: a column per thread, then the memory after the step, then any
/// columns of the scheme's own (MDTS: the values in flight, the invariant).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StepTable {
    /// One heading a column.
    pub headings: Vec<String>,
    /// A row a step, one cell a column.
    pub rows: Vec<Vec<String>>,
}

/// The report of one explanation: lines, the step table, more lines.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Explanation {
    /// The lines before the table (what was searched, what was found).
    pub head: Vec<String>,
    /// The interleaving step by step (`None` where nothing was found to show).
    pub steps: Option<StepTable>,
    /// The lines after the table (the key, what the interleaving shows).
    pub tail: Vec<String>,
    /// Whether the property was shown (a hazard for the k-buffer, the invariant at every step
    /// for MDTS, a deadlock for the spinlock).
    pub shown: bool,
}

impl Explanation {
    /// The report of `head` lines alone.
    fn lines(head: Vec<String>, shown: bool) -> Self {
        Self {
            head,
            steps: None,
            tail: Vec::new(),
            shown,
        }
    }
}

/// Explains `params.scheme` on the fragments of `params.depths`.
///
/// # Errors
/// Bad depths or parameters, a scheme `explain` cannot explain, or a write-back machine other
/// than a `-stores` scheme's own.
pub fn explain(params: &ExplainParams<'_>) -> Result<Explanation, String> {
    let fragments = one_pixel(params.depths)?;
    #[expect(
        clippy::cast_possible_truncation,
        reason = "at most crate::interleaving::MAX_FRAGMENTS (64) depths"
    )]
    let k = params.k.unwrap_or(fragments.len() as u32);
    let viewport = Viewport::new(1, 1).map_err(|e| e.to_string())?;
    let name = params.scheme;
    match Shown::of(name).ok_or_else(|| format!("explain cannot explain {name}"))? {
        Shown::Hazard(own) => {
            let machine = match params.write_back {
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
            Ok(explain_kbuffer(&scheme, machine, k, &fragments, params))
        }
        Shown::Invariant => {
            let scheme = Mdts::<u64>::ascending(viewport, k).map_err(|e| e.to_string())?;
            Ok(explain_mdts(&scheme, k, &fragments, params.seeds))
        }
        Shown::Deadlock => match crate::spinlock::shortest_deadlock(k, &fragments) {
            Ok(Some(report)) => Ok(Explanation::lines(vec![report.to_string()], true)),
            Ok(None) => Ok(Explanation::lines(
                vec!["kbuffer-spinlock: one fragment cannot deadlock".into()],
                false,
            )),
            Err(e) => Err(e.to_string()),
        },
    }
}

/// How reports name a machine.
fn machine_label(machine: WriteBack) -> &'static str {
    match machine {
        WriteBack::RenderTarget => "render-target write-backs",
        WriteBack::SeparateStores => "separate stores",
    }
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

#[expect(
    clippy::cast_possible_truncation,
    reason = "a word's low half is its primitive id"
)]
fn explain_kbuffer(
    scheme: &KBuffer,
    machine: WriteBack,
    k: u32,
    fragments: &[Fragment],
    params: &ExplainParams<'_>,
) -> Explanation {
    let threads = fragments.len();
    let label = machine_label(machine);
    let Some((seed, trace)) = kbuffer::search(scheme, k, fragments, params.seeds) else {
        return Explanation::lines(
            vec![format!(
                "k-buffer ({label}), K = {k}, {threads} fragments: no losing interleaving in {} \
                 seeds",
                params.seeds
            )],
            false,
        );
    };
    let mut head = vec![format!(
        "k-buffer ({label}), K = {k}: found at seed {seed} ({:?}): {} steps, {} threads, {} switches",
        schedule(seed, threads).policy,
        step_count(&trace),
        threads,
        switches(&trace)
    )];
    let (fragments, order) = if params.shrink {
        kbuffer::shrink(scheme, k, fragments.to_vec(), trace.order())
    } else {
        (fragments.to_vec(), trace.order())
    };
    #[expect(
        clippy::shadow_unrelated,
        reason = "the shrunk trace replaces the one it was shrunk from"
    )]
    let (trace, damage) =
        kbuffer::hazard(scheme, k, &fragments, &order).expect("the shrunk order shows the hazard");
    head.push(format!(
        "{}: {} steps, {} threads, {} switches",
        if params.shrink { "shrunk" } else { "unshrunk" },
        step_count(&trace),
        fragments.len(),
        switches(&trace)
    ));
    let memory = memory_after(&trace, k, EMPTY);
    let steps = table(&fragments, &trace, &memory, &[]);
    let mut tail = vec![
        key(&fragments[0]),
        format!("expected slots: {}", values(&nearest(&fragments, k))),
    ];
    for v in &damage.lost {
        tail.push(format!(
            "LOST: {} (fragment {}, depth {}): overwritten by a write-back computed from a read that missed it",
            value(*v),
            *v as u32,
            f32::from_bits((v >> 32) as u32)
        ));
    }
    for v in &damage.duplicated {
        tail.push(format!("DUPLICATED: {} is in two slots", value(*v)));
    }
    tail.push(
        match machine {
            WriteBack::RenderTarget => {
                "machine: render targets: a read of the K slots is one step and a write-back one \
                 step, write-backs commit in order; only a read can be stale, so the \
                 only failure is a lost fragment"
            }
            WriteBack::SeparateStores => {
                "machine: separate stores: K loads, then K stores, one step each; write-backs can \
                 interleave store by store (duplicates, slots out of order) as well as lose"
            }
        }
        .into(),
    );
    Explanation {
        head,
        steps: Some(steps),
        tail,
        shown: true,
    }
}

fn explain_mdts(scheme: &Mdts<u64>, k: u32, fragments: &[Fragment], seeds: u64) -> Explanation {
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
    let head = vec![format!(
        "MDTS, K = {k}: densest of {seeds} seeds is seed {seed} ({:?}): {} steps, {threads} threads, {} switches",
        schedule(seed, threads).policy,
        step_count(&trace),
        switches(&trace)
    )];
    let steps = table(
        fragments,
        &trace,
        &memory,
        &[("carried (in flight)", in_flight), ("inv", marks)],
    );
    let last: Vec<u64> = memory
        .last()
        .map(|m| m.iter().copied().filter(|&v| v != EMPTY).collect())
        .unwrap_or_default();
    let held = checks.iter().filter(|c| c.holds).count();
    let all = held == checks.len();
    let sorted = last == nearest(fragments, k);
    let tail = vec![
        format!(
            "{}; inv: ✓ the invariant holds after the step (a cross where it fails)",
            key(&fragments[0])
        ),
        format!(
            "invariant (slots only decrease; slots + carried + dropped = inputs): {} at {} of {} steps",
            if all { "✓ holds" } else { "✗ FAILS" },
            held,
            checks.len()
        ),
        format!(
            "final slots {} the {} nearest inputs in order: {}",
            if sorted { "are" } else { "are NOT" },
            k,
            values(&last)
        ),
    ];
    Explanation {
        head,
        steps: Some(steps),
        tail,
        shown: all && sorted,
    }
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

/// One memory operation's cell.
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
) -> StepTable {
    let threads = fragments.len();
    let mut headings: Vec<String> = vec!["step".into()];
    headings.extend(
        fragments
            .iter()
            .map(|f| format!("T{} ({})", f.prim, value(f.packed()))),
    );
    headings.push("memory after".into());
    headings.extend(extra.iter().map(|(title, _)| (*title).to_string()));
    let mut rows = Vec::new();
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
    StepTable { headings, rows }
}

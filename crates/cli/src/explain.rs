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
//!   with separate stores (`fragsim_schemes::kbuffer` says why).
//! - `--scheme mdts`: the densest interleaving (most context switches) among the seeds, with
//!   `docs/proof.md`'s invariant checked after every step: each slot only ever decreases, and the
//!   multiset of slot values plus the values carried in flight (plus those carried past the last
//!   slot) equals the inputs.
//!
//! The search, the shrinker, the invariant and the report's lines and step table are
//! `fragsim_explain`'s ([`fragsim_explain::report`]); the schemes offered are the catalog's
//! entries it can explain ([`fragsim_explain::Shown::schemes`]). This module holds the options
//! and lays out and prints the report.

use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use fragsim_catalog::SchemeName;
use fragsim_explain::report::ExplainParams;
use fragsim_explain::Shown;
use fragsim_schemes::kbuffer::WriteBack;

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

/// The k-buffer's machine, on the command line (`fragsim_schemes::kbuffer::WriteBack`).
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
    let explanation = fragsim_explain::report::explain(&ExplainParams {
        scheme: args.scheme.0,
        depths: &args.depths,
        k: args.k,
        seeds: args.seeds,
        shrink: !args.no_shrink,
        write_back: args.write_back.map(WriteBackArg::machine),
    })?;
    let mut text = String::new();
    for line in &explanation.head {
        text.push_str(line);
        text.push('\n');
    }
    if let Some(steps) = explanation.steps {
        let mut table = Table::new(steps.headings, usize::MAX);
        for row in steps.rows {
            table.push(row);
        }
        text.push_str(&table.markdown());
    }
    for line in &explanation.tail {
        text.push_str(line);
        text.push('\n');
    }
    Ok((text, explanation.shown))
}

//! Progress bars (indicatif) on stderr for the work that can take more than a second: render's
//! schemes, bench's frames, sweep's angles, hazard's rows (the measurements' [`Progress`] drawn
//! as bars: [`Bars`]).
//!
//! Guarantee: a bar is drawn only when stderr is a terminal and `--quiet` was not given, so
//! that piped or captured output (and `--json` on stdout) carries no bar; stdout is never
//! touched.

use std::cell::RefCell;
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use fragsim_measure::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Set by `--quiet`.
static QUIET: AtomicBool = AtomicBool::new(false);

/// `--quiet`: no progress bars for the rest of the process.
pub(crate) fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// A bar of `len` steps doing `what`, hidden unless stderr is a terminal and `--quiet` is off.
pub(crate) fn bar(len: u64, what: &str) -> ProgressBar {
    let shown = !QUIET.load(Ordering::Relaxed) && std::io::stderr().is_terminal();
    let target = if shown {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(len), target);
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix} {spinner} [{elapsed_precise}] {bar:30} {pos}/{len} (eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(what.to_string());
    if shown {
        bar.enable_steady_tick(Duration::from_millis(100));
    }
    bar
}

/// The command line's [`Progress`]: each stage a measurement begins is a bar ([`bar`]), its
/// warnings lines on stderr.
#[derive(Debug, Default)]
pub(crate) struct Bars {
    /// The bar of the current stage.
    current: RefCell<Option<ProgressBar>>,
}

impl Progress for Bars {
    fn begin(&self, steps: u64, what: &str) {
        self.end();
        *self.current.borrow_mut() = Some(bar(steps, what));
    }

    fn message(&self, text: &str) {
        if let Some(bar) = &*self.current.borrow() {
            bar.set_message(text.to_string());
        }
    }

    fn step(&self) {
        if let Some(bar) = &*self.current.borrow() {
            bar.inc(1);
        }
    }

    fn end(&self) {
        if let Some(bar) = self.current.borrow_mut().take() {
            bar.finish_and_clear();
        }
    }

    fn warn(&self, warning: &str) {
        eprintln!("warning: {warning}");
    }
}

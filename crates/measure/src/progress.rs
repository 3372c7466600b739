//! What a long measurement tells its caller while it runs: the stages it begins (with their
//! steps), what it is doing, each step done, and warnings. The library never prints; the command
//! line draws bars on stderr from these calls, a script may ignore them ([`Silent`]).

/// The receiver of a measurement's progress. Stages come one after another, never nested: each
/// [`begin`](Self::begin) is followed by its steps and one [`end`](Self::end).
pub trait Progress {
    /// A stage of `steps` steps doing `what` (`bench`, `sweep`, `hazard --baselines`) begins.
    fn begin(&self, steps: u64, what: &str);
    /// What the current stage is doing now (a scheme and executor, an angle).
    fn message(&self, text: &str);
    /// One step of the current stage is done.
    fn step(&self);
    /// The current stage is over.
    fn end(&self);
    /// Something the caller should know that does not stop the measurement (a view that
    /// covers no pixel).
    fn warn(&self, warning: &str);
}

/// Progress that nobody watches.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {
    fn begin(&self, _steps: u64, _what: &str) {}
    fn message(&self, _text: &str) {}
    fn step(&self) {}
    fn end(&self) {}
    fn warn(&self, _warning: &str) {}
}

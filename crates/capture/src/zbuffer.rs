//! Placeholder: filled in by the baselines work (issue 3).

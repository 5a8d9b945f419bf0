//! The communication grid of a run, checked once before anything is instantiated.
//!
//! Time is kept as an integer step count: the communication points are `start + k * step`,
//! each computed from `k`, so they never drift however long the run (Reference-FMUs #507).

use super::{RunError, RunOptions};

/// More steps than this and `k` is no longer exact in an f64.
const MAX_STEPS: f64 = (1u64 << 53) as f64;

pub(super) struct Grid {
    pub start: f64,
    pub step: f64,
    pub steps: u64,
    /// The recording interval in steps.
    pub every: u64,
}

impl Grid {
    /// The grid of the options, or why they do not make one: a step that is not a positive
    /// number, times that are not finite, a stop before the start, a span or recording
    /// interval that is not a whole number of steps, or more than 2^53 steps (an endless run).
    pub fn new(opts: &RunOptions) -> Result<Grid, RunError> {
        if !(opts.step > 0.0 && opts.step.is_finite()) {
            return Err(RunError::Config(format!(
                "step {} must be a positive number",
                opts.step
            )));
        }
        if !(opts.start.is_finite() && opts.stop.is_finite()) {
            return Err(RunError::Config(format!(
                "the start time {} s and the stop time {} s must be finite numbers",
                opts.start, opts.stop
            )));
        }
        let span = opts.stop - opts.start;
        if !(span >= 0.0) {
            return Err(RunError::Config(format!(
                "the stop time {} s is before the start time {} s",
                opts.stop, opts.start
            )));
        }
        let steps = (span / opts.step).round();
        if (steps * opts.step - span).abs() > 1e-9 * span.abs().max(1.0) {
            return Err(RunError::Config(format!(
                "the run from {} s to {} s is not a whole number of {} s steps",
                opts.start, opts.stop, opts.step
            )));
        }
        if steps > MAX_STEPS {
            use model_description::format_f64 as f;
            return Err(RunError::Config(format!(
                "the run from {} s to {} s has {steps:e} steps of {} s, more than 2^53",
                f(opts.start),
                f(opts.stop),
                f(opts.step)
            )));
        }
        let every = match opts.interval {
            None => 1,
            Some(i) => {
                let m = (i / opts.step).round();
                if m < 1.0 || (m * opts.step - i).abs() > 1e-9 * i.max(1.0) {
                    return Err(RunError::Config(format!(
                        "recording interval {i} s is not a whole number of {} s steps",
                        opts.step
                    )));
                }
                m as u64
            }
        };
        Ok(Grid {
            start: opts.start,
            step: opts.step,
            steps: steps as u64,
            every,
        })
    }

    /// The communication point after `k` steps.
    #[inline]
    pub fn time(&self, k: u64) -> f64 {
        self.start + k as f64 * self.step
    }
}

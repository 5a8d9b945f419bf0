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

#[cfg(test)]
mod tests {
    use super::*;

    fn options(start: f64, stop: f64, step: f64, interval: Option<f64>) -> RunOptions {
        RunOptions {
            interval,
            ..RunOptions::new(start, stop, step)
        }
    }

    fn refusal(o: RunOptions) -> String {
        match Grid::new(&o) {
            Err(e) => e.to_string(),
            Ok(g) => panic!("accepted: {} steps", g.steps),
        }
    }

    #[test]
    fn points_come_from_the_step_count_and_do_not_drift() {
        let g = Grid::new(&options(1.0, 1001.0, 1e-3, Some(0.01))).unwrap();
        assert_eq!((g.steps, g.every), (1_000_000, 10));
        assert_eq!(g.time(0), 1.0);
        assert_eq!(g.time(g.steps), 1001.0);
        // Summing the step a million times drifts; k * h does not.
        let mut summed = 1.0;
        for _ in 0..g.steps {
            summed += 1e-3;
        }
        assert_ne!(summed, 1001.0);
        let empty = Grid::new(&options(2.0, 2.0, 0.1, None)).unwrap();
        assert_eq!((empty.steps, empty.every), (0, 1));
    }

    #[test]
    fn bad_grids_are_refused_with_their_numbers() {
        assert_eq!(
            refusal(options(0.0, 1.0, 0.0, None)),
            "step 0 must be a positive number"
        );
        assert_eq!(
            refusal(options(0.0, 1.0, f64::NAN, None)),
            "step NaN must be a positive number"
        );
        assert_eq!(
            refusal(options(0.0, f64::INFINITY, 0.1, None)),
            "the start time 0 s and the stop time inf s must be finite numbers"
        );
        assert_eq!(
            refusal(options(1.0, 0.5, 0.1, None)),
            "the stop time 0.5 s is before the start time 1 s"
        );
        assert_eq!(
            refusal(options(0.0, 1.0, 0.3, None)),
            "the run from 0 s to 1 s is not a whole number of 0.3 s steps"
        );
        assert_eq!(
            refusal(options(0.0, 1e300, 1e-3, None)),
            "the run from 0 s to 1e300 s has 1e303 steps of 0.001 s, more than 2^53"
        );
        assert_eq!(
            refusal(options(0.0, 1.0, 0.1, Some(0.15))),
            "recording interval 0.15 s is not a whole number of 0.1 s steps"
        );
        assert_eq!(
            refusal(options(0.0, 1.0, 0.1, Some(0.0))),
            "recording interval 0 s is not a whole number of 0.1 s steps"
        );
    }
}

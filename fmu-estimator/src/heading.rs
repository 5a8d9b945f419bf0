//! The heading the yaw gyroscope integrates in motion, against what straight track gives: the
//! check that tells a curve the estimator was not told of, or a gyroscope bias it has not
//! removed, from the irregularities it was fitted on.
//!
//! # Why the heading
//! The wheelset's yaw angle in a fixed frame is the track's heading plus the wheelset's yaw
//! relative to the track. On straight track both are the slopes of bounded irregularities, so
//! the heading's change over any distance stays bounded; a curve of radius `R` turns it by
//! `d / R` over `d` metres, and a yaw-rate bias `b` by `b d / V`. Both break the estimate
//! (docs/accuracy.md: a curved line told nothing, whole Jrel 42.6; a 3e-4 rad/s bias told
//! nothing, 0.49 against 0.11), and neither reaches the novelty, whose contact features are
//! band-passed at 3-40 m.
//!
//! # The statistic
//! `heading_change`: the integral of the yaw rate (the estimated bias and the design line's
//! response removed, [`crate::step`]) over the last [`WINDOW`] metres run (since the run's start
//! before that), read at [`CELL`] boundaries. The train's distance, not time, sets the window:
//! the irregularities are laid in space, so straight track's spread is the same at every
//! speed. Samples standing (speed below [`crate::bias::STANDSTILL_SPEED`]) do not count: the
//! train does not turn there.
//!
//! Straight track's spread, 10 km runs of validation seeds 102-109 (`heading_probe`, 2026-11-29,
//! rms / largest over a run, mrad; the window's length hardly matters from 200 m, the heading
//! being stationary):
//!
//! | track spectrum | speeds (m/s) | rms | largest |
//! |---|---|---|---|
//! | German low (the training's) | 10, 20, 30 | 0.8-1.1 | 3.9 |
//! | German high | 20 | 1.5 | 5.9 |
//! | FRA class 6 | 20 | 1.7 | 7.1 |
//! | FRA class 5 | 12.5, 20 | 2.5-2.8 | 9.7 |
//! | FRA class 5 | 30 | 3.2-3.5 | 12.4 |
//!
//! Other wheels and vehicles (conicity 0.05 at Kalker 50 %, 0.4, the Manchester vehicle) and the
//! tactical and MEMS presets' noise and drifting bias (their turn-on bias removed) stay within
//! German low's largest, bar the MEMS drift at 4.6.
//!
//! # The level
//! [`LEVEL`] is set above the largest change of the roughest spectrum (1.2 times FRA class 5's
//! at 30 m/s, 4 times German low's), so that no straight track of the four is flagged. A curve
//! passes it within metres of its transition. A bias passes it once `b W / V > LEVEL`: at 20
//! m/s from 6e-4 rad/s (after 500 m), 1e-3 rad/s within 300 m.
//! Smaller biases cost less (1e-4 rad/s: whole 0.18 against 0.11) and only the log's warning
//! over [`SUSPECT_DISTANCE`] says so ([`Heading::suspected_bias`]). Told the bias priors, the
//! estimator removes them at a standstill ([`crate::bias`]).
//!
//! # A bias suspected in motion
//! The yaw rate's mean over the distance run since the last standstill is kept too: on
//! straight track (German low) it has an rms of 1.9e-5 rad/s over 1000 m (the heading's 0.9
//! mrad over 50 s), so a mean beyond [`SUSPECT_LEVEL`] after [`SUSPECT_DISTANCE`] is a
//! gyroscope bias the estimator was not told of or could not see, and the FMU says so once in
//! its log. Rougher track gives such a mean too (FRA class 5: 2.6 mrad rms over 50 s), which
//! is why it is a warning and not the flag.

use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// The distance \[m\] over which the heading's change is judged.
pub const WINDOW: f64 = 500.0;
/// The spacing \[m\] of the headings kept over the window.
pub const CELL: f64 = 10.0;
/// The heading change \[rad\] beyond which the yaw rate carries what straight track does not.
pub const LEVEL: f64 = 0.015;
/// The distance \[m\] over which the yaw rate's mean is judged for a bias.
pub const SUSPECT_DISTANCE: f64 = 1000.0;
/// The yaw rate's mean \[rad/s\] beyond which a bias is suspected: five times its rms over
/// 1000 m of straight track.
pub const SUSPECT_LEVEL: f64 = 1e-4;

/// The yaw rate's integrals in motion. Part of the FMU state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Heading {
    /// The integral of the yaw rate in motion since the run's start \[rad\].
    heading: f64,
    /// Distance run into the current cell \[m\].
    into_cell: f64,
    /// The heading at the cell ends of the last `WINDOW` metres, oldest first (`WINDOW / CELL
    /// + 1` of them); the run's start (0) until the window is full.
    marks: VecDeque<f64>,
    /// Distance run since the last standstill \[m\], and the integral of the yaw rate over it
    /// \[rad/s m\].
    since_stop: (f64, f64),
}

impl Default for Heading {
    fn default() -> Self {
        Heading {
            heading: 0.0,
            into_cell: 0.0,
            marks: VecDeque::from([0.0]),
            since_stop: (0.0, 0.0),
        }
    }
}

impl Heading {
    /// One sample's yaw rate `yaw_rate` (biases and design response removed) after a step of
    /// `h` at `speed`; `standing` restarts the mean since the last standstill. A non-finite
    /// speed or yaw rate adds nothing.
    pub fn observe(&mut self, standing: bool, speed: f64, h: f64, yaw_rate: f64) {
        if standing {
            self.since_stop = (0.0, 0.0);
            return;
        }
        if !(speed.is_finite() && yaw_rate.is_finite()) {
            return;
        }
        let ds = speed * h;
        self.since_stop.0 += ds;
        self.since_stop.1 += yaw_rate * ds;
        self.heading += yaw_rate * h;
        self.into_cell += ds;
        while self.into_cell >= CELL {
            self.into_cell -= CELL;
            self.marks.push_back(self.heading);
            if self.marks.len() > (WINDOW / CELL) as usize + 1 {
                self.marks.pop_front();
            }
        }
    }

    /// The heading's change \[rad\] over the last [`WINDOW`] metres (to the last cell end: the
    /// window is `WINDOW` to `WINDOW + CELL` long), or since the run's start before that.
    pub fn change(&self) -> f64 {
        self.heading - self.marks.front().copied().unwrap_or(0.0)
    }

    /// Whether the heading changed by more than straight track's irregularities give.
    pub fn outside(&self) -> bool {
        self.change().abs() > LEVEL
    }

    /// The factor the estimate's standard deviation is grown by ([`growth`]).
    pub fn growth(&self) -> f64 {
        growth(self.change())
    }

    /// The yaw rate's mean since the last standstill \[rad/s\] when it suggests a bias (module
    /// docs), with the distance it is over.
    pub fn suspected_bias(&self) -> Option<(f64, f64)> {
        let (distance, integral) = self.since_stop;
        let mean = integral / distance;
        (distance >= SUSPECT_DISTANCE && mean.abs() > SUSPECT_LEVEL).then_some((mean, distance))
    }
}

/// The factor the estimate's standard deviation is grown by at a heading change `change`: the
/// change over its level when beyond it (the estimate's error from an untold curvature or bias
/// grows with the heading it did not explain), else 1.
pub fn growth(change: f64) -> f64 {
    (change.abs() / LEVEL).max(1.0)
}

#[cfg(test)]
mod tests {
    use super::{CELL, Heading, LEVEL, WINDOW};

    /// `secs` of motion at 20 m/s and 1 kHz with the yaw rate `rate(t)`.
    fn run(heading: &mut Heading, secs: f64, rate: impl Fn(f64) -> f64) {
        let h = 1e-3;
        for k in 0..(secs / h).round() as usize {
            heading.observe(false, 20.0, h, rate((k + 1) as f64 * h));
        }
    }

    /// A constant rate: the change grows as the rate times the time until the window is full,
    /// then holds at the rate times the window's time (500 m at 20 m/s: 25 s, to within a
    /// cell's 0.5 s, and a sample's rounding of the distance at a cell's end).
    #[test]
    fn a_constant_rate_turns_the_heading_by_its_window() {
        let mut a = Heading::default();
        run(&mut a, 10.0, |_| 1e-3);
        assert!((a.change() - 1e-2).abs() < 1e-9, "{}", a.change());
        assert!(!a.outside());
        assert_eq!(a.growth(), 1.0);
        run(&mut a, 50.0, |_| 1e-3);
        let (lo, hi) = (1e-3 * WINDOW / 20.0, 1e-3 * (WINDOW + CELL) / 20.0);
        let sample = 1e-3 * 1e-3;
        assert!(
            a.change() >= lo - sample && a.change() <= hi + sample,
            "{}",
            a.change()
        );
        assert!(a.outside());
        assert!((a.growth() - a.change() / LEVEL).abs() < 1e-12);
    }

    /// A curve of radius 1000 m entered after 200 m (its rate `V / R`) passes the level once
    /// it has turned 15 mrad (15 m in), and the flag clears a window after the curve's end.
    #[test]
    fn a_curve_sets_it_and_a_window_after_its_end_clears_it() {
        let v = 20.0;
        let curve = |t: f64| {
            if (10.0..20.0).contains(&t) {
                v / 1000.0
            } else {
                0.0
            }
        };
        let mut a = Heading::default();
        run(&mut a, 10.0 + 14.0 / v, curve);
        assert!(!a.outside(), "{}", a.change());
        run(&mut a, 2.0 / v, |t| curve(t + 10.0 + 14.0 / v));
        assert!(a.outside(), "{}", a.change());
        let mut b = Heading::default();
        run(&mut b, 20.0 + (WINDOW + 2.0 * CELL) / v, curve);
        assert!(b.change().abs() < 1e-9 && !b.outside(), "{}", b.change());
    }

    /// A wave of zero mean (a straight track's heading, 3 mrad) stays inside the level and grows
    /// nothing; non-finite samples and standing ones add nothing.
    #[test]
    fn straight_tracks_wave_is_inside_and_gaps_add_nothing() {
        let mut a = Heading::default();
        run(&mut a, 100.0, |t| 3e-3 * 2.0 * (2.0 * t).cos());
        assert!(
            a.change().abs() <= 6e-3 + 1e-9 && !a.outside(),
            "{}",
            a.change()
        );
        assert_eq!(a.growth(), 1.0);
        let before = a.clone();
        a.observe(false, 20.0, 1e-3, f64::NAN);
        a.observe(false, f64::NAN, 1e-3, 1.0);
        assert_eq!(a, before);
        a.observe(true, 0.0, 1e-3, 1.0);
        assert_eq!(a.change(), before.change());
    }

    /// 1020 m at 20 m/s: a yaw-rate wave of zero mean is not suspected, the same with 2e-4
    /// rad/s added is (its mean found), before 1000 m it is not judged, and a standstill
    /// starts the mean again.
    #[test]
    fn a_yaw_rate_mean_beyond_a_straight_tracks_is_suspected() {
        let run_for = |bias: f64, secs: f64| {
            let mut a = Heading::default();
            run(&mut a, secs, |t| bias + 3e-3 * (2.0 * t).sin());
            a
        };
        assert_eq!(run_for(0.0, 51.0).suspected_bias(), None);
        let (mean, distance) = run_for(2e-4, 51.0).suspected_bias().unwrap();
        // The wave's own mean over 51 s: 3e-3 (1 - cos 102) / 102.
        let want = 2e-4 + 3e-3 * (1.0 - 102f64.cos()) / 102.0;
        assert!((mean - want).abs() < 1e-6, "{mean} vs {want}");
        assert!((distance - 1020.0).abs() < 1e-6);
        assert_eq!(run_for(2e-4, 49.0).suspected_bias(), None);
        let mut b = run_for(2e-4, 51.0);
        b.observe(true, 0.0, 1e-3, 0.0);
        assert_eq!(b.suspected_bias(), None);
    }
}

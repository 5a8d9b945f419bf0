//! What the sensors integrate to in motion, against what straight track gives: the checks
//! that tell a curve the estimator was not told of, or a sensor bias it has not removed, from
//! the irregularities it was fitted on.
//!
//! # Why integrals
//! - **Heading.** The wheelset's yaw angle in a fixed frame is the track's heading plus the
//!   wheelset's yaw relative to the track. On straight track both are the slopes of bounded
//!   irregularities, so the heading's change over any distance stays bounded; a curve of
//!   radius `R` turns it by `d / R` over `d` metres, and a yaw-rate bias `b` by `b d / V`.
//! - **Relative velocity.** The wheelset accelerometer less the frame accelerometer above it
//!   integrates to the wheelset's lateral velocity relative to the frame, which the primary
//!   suspension bounds on any line; a bias of one accelerometer that the other does not share
//!   adds `b d / V`. A bias both share (a tilt, a cant the design does not give) cancels, as it
//!   does in the estimate (docs/accuracy.md, "Real sensors": both tilted, 0.110 against 0.108;
//!   the wheelset's alone biased 0.05 m/s2, 0.247).
//!
//! Both break the estimate (a curved line told nothing, whole Jrel 42.6; a 3e-4 rad/s gyro bias
//! told nothing, 0.49 against 0.11) and neither reaches the novelty, whose contact features are
//! band-passed at 3-40 m.
//!
//! # The statistics
//! `heading_change` and `relative_velocity_change`: the integrals of the yaw rate and of
//! `ws_acc_y - frame_acc_y` (the estimated biases and the design line's response removed,
//! [`crate::step`]) over the last [`WINDOW`] metres run (since the run's start before that),
//! read at [`CELL`] boundaries. The train's distance, not time, sets the window: the
//! irregularities are laid in space, so straight track's spread is nearly the same at every
//! speed. Samples standing (speed below [`crate::bias::STANDSTILL_SPEED`]) do not count.
//!
//! Straight track's spread, 10 km runs of validation seeds 102-104 (`tests/integrals_probe.py`,
//! 2026-11-29; largest rms of a run / largest value over the runs; both are stationary, so the
//! window's length hardly matters from 200 m):
//!
//! | condition | heading (mrad) | relative velocity (mm/s) |
//! |---|---|---|
//! | German low (the training's spectrum), 10 / 20 / 30 m/s | 0.8-1.1 / 3.8 | 5.4-9.4 / 31.7 |
//! | German high, 20 m/s | 1.6 / 5.7 | 9.6 / 38.7 |
//! | FRA class 6, 20 m/s | 1.8 / 6.9 | 8.8 / 37.2 |
//! | FRA class 5, 20 m/s | 2.7 / 10.5 | 18.0 / 63.5 |
//! | FRA class 5, 30 m/s | 3.4 / 11.7 | 30.3 / 104.0 |
//! | conicity 0.05 at Kalker 50 %; conicity 0.4 | 1.9 / 5.9; 0.8 / 2.6 | 5.5 / 22.4; 7.9 / 31.7 |
//! | the Manchester vehicle | 0.7 / 2.5 | 8.9 / 35.7 |
//! | tactical; MEMS preset (noise, drifting biases; turn-on biases removed) | 0.9 / 3.2; 1.5 / 4.7 | 6.0 / 24.6; 13.0 / 39.4 |
//!
//! On FRA class 5 at 30 m/s other seeds (104-109) reached 12.4 mrad.
//!
//! # The levels
//! The heading's level starts at [`HEADING_LEVEL`], above the largest change of the roughest
//! spectrum (1.2 times FRA class 5's at 30 m/s, 4 times German low's), so that no straight
//! track of the four is flagged; a curve passes it within metres of its transition. Once
//! [`WANDER_SPAN`] metres are run it follows the track: [`WANDER_FACTOR`] times the heading's
//! wander, the rms of its residual from a least-squares straight line over the span (a bias's
//! steady turn is a straight line, so it does not raise the level it is judged against), within
//! [`HEADING_FLOOR`] (German low's largest change) and [`HEADING_LEVEL`]. The factor: the
//! largest change over 500 m of those runs was 5.9 times the wander measured over the 2000 m
//! before it (German low, FRA class 5 at 30 m/s, conicity 0.05 at Kalker 50 %, the MEMS preset;
//! 10 km, seeds 102-103), so 8 keeps a margin of 1.36; on the table's conditions (seeds
//! 102-104, the paper's filter, whose flag is these checks' alone) it set the level at 4.0-6.0
//! mrad on German low at 10-30 m/s and the other vehicles, 8-10 on German high, FRA class 6 and
//! conicity 0.05, 14-15 on FRA class 5, and flagged nothing (the largest change 0.97 of its
//! level). [`VELOCITY_LEVEL`] is where
//! an accelerometer bias starts to cost: 0.05 m/s2 on the wheelset's costs the 400 m standard
//! case 0.247 against 0.108, so about 0.04 doubles its error, and passes 0.5 m/s within 250 m
//! at 20 m/s; 0.01 m/s2 costs nothing measurable (2 km, validation seed 102: 0.099 against
//! 0.103) and stays below it. The level is 5 times FRA class 5's largest at 30 m/s.
//!
//! A bias passes a level once `b W / V` does: at 20 m/s a yaw-rate bias from 6e-4 rad/s within
//! the first 2000 m (1e-3 rad/s within 300 m), and from 2000 m on, on German low, from about
//! 2e-4 (10 km runs, validation seeds 102-104: 3e-4 rad/s flagged from 2000 m on 80 % of the
//! distance, whole 0.143-0.146 against 0.09-0.10 without it; 2e-4 on 36-43 %, 0.115-0.118;
//! 1e-4 on 0.2-0.5 %, 0.094-0.098); an accelerometer bias from 0.02 m/s2 (0.033 within 300 m;
//! 0.05 within 200 m). The log's warning over [`SUSPECT_DISTANCE`] names smaller gyroscope
//! biases ([`Integrals::suspected_bias`]). Told the bias priors, the estimator removes them at a
//! standstill ([`crate::bias`]).
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

/// The distance \[m\] over which the integrals' changes are judged.
pub const WINDOW: f64 = 500.0;
/// The spacing \[m\] of the integrals kept over the window.
pub const CELL: f64 = 10.0;
/// The heading change \[rad\] beyond which the yaw rate carries what straight track does not,
/// before the track's own wander is known (and the most it is ever set to).
pub const HEADING_LEVEL: f64 = 0.015;
/// The span \[m\] over which the heading's wander is measured.
pub const WANDER_SPAN: f64 = 2000.0;
/// The heading level over the wander's rms, once measured.
pub const WANDER_FACTOR: f64 = 8.0;
/// The least heading level \[rad\]: the training's own track's largest change.
pub const HEADING_FLOOR: f64 = 0.004;
/// The relative velocity change \[m/s\] beyond which the accelerometers carry what straight
/// track does not.
pub const VELOCITY_LEVEL: f64 = 0.5;
/// The distance \[m\] over which the yaw rate's mean is judged for a bias.
pub const SUSPECT_DISTANCE: f64 = 1000.0;
/// The yaw rate's mean \[rad/s\] beyond which a bias is suspected: five times its rms over
/// 1000 m of straight track.
pub const SUSPECT_LEVEL: f64 = 1e-4;

/// The sensors' integrals in motion. Part of the FMU state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Integrals {
    /// The heading \[rad\] and the relative lateral velocity \[m/s\] integrated in motion
    /// since the run's start.
    now: [f64; 2],
    /// Distance run into the current cell \[m\].
    into_cell: f64,
    /// The two at the cell ends of the last `WANDER_SPAN` metres, oldest first
    /// (`WANDER_SPAN / CELL + 1` of them), the run's start (0) first until then.
    marks: VecDeque<[f64; 2]>,
    /// The level the heading's change is judged against \[rad\] (module docs).
    heading_level: f64,
    /// Distance run since the last standstill \[m\], and the integral of the yaw rate over it
    /// \[rad/s m\].
    since_stop: (f64, f64),
}

impl Default for Integrals {
    fn default() -> Self {
        Integrals {
            now: [0.0; 2],
            into_cell: 0.0,
            marks: VecDeque::from([[0.0; 2]]),
            heading_level: HEADING_LEVEL,
            since_stop: (0.0, 0.0),
        }
    }
}

impl Integrals {
    /// One sample after a step of `h` at `speed`: `x` = `ws_acc_y`, the yaw rate, `frame_acc_y`
    /// (biases and design response removed); `standing` restarts the mean since the last
    /// standstill. A non-finite speed adds nothing; a non-finite sensor adds nothing to what
    /// it feeds.
    pub fn observe(&mut self, standing: bool, speed: f64, h: f64, x: [f64; 3]) {
        if standing {
            self.since_stop = (0.0, 0.0);
            return;
        }
        let ds = speed * h;
        if !ds.is_finite() {
            return;
        }
        let [acc, yaw_rate, frame] = x;
        if yaw_rate.is_finite() {
            self.since_stop.0 += ds;
            self.since_stop.1 += yaw_rate * ds;
            self.now[0] += yaw_rate * h;
        }
        if (acc - frame).is_finite() {
            self.now[1] += (acc - frame) * h;
        }
        self.into_cell += ds;
        if self.into_cell < CELL {
            return;
        }
        // Every cell end passed in this step holds the same integrals; a step longer than the
        // span (a hostile speed) fills it at once instead of looping cell by cell.
        let span = (WANDER_SPAN / CELL) as usize + 1;
        let cells = (self.into_cell / CELL).floor().min(span as f64) as usize;
        self.into_cell = self.into_cell.rem_euclid(CELL);
        for _ in 0..cells {
            self.marks.push_back(self.now);
            if self.marks.len() > span {
                self.marks.pop_front();
            }
        }
        if self.marks.len() == span {
            let level = WANDER_FACTOR * wander(self.marks.iter().map(|m| m[0]));
            self.heading_level = level.clamp(HEADING_FLOOR, HEADING_LEVEL);
        }
    }

    /// The change of each integral over the last [`WINDOW`] metres (from the cell end at or
    /// before `WINDOW` metres back: a window of `WINDOW` to `WINDOW + CELL`), or since the
    /// run's start before that.
    fn change(&self, i: usize) -> f64 {
        let back = (WINDOW / CELL) as usize;
        let at = self.marks.len().saturating_sub(back + 1);
        self.now[i] - self.marks.get(at).map_or(0.0, |m| m[i])
    }

    /// The level the heading's change is judged against \[rad\] (the FMU's `heading_level`).
    pub fn heading_level(&self) -> f64 {
        self.heading_level
    }

    /// The heading's change \[rad\] (the FMU's `heading_change`).
    pub fn heading_change(&self) -> f64 {
        self.change(0)
    }

    /// The relative lateral velocity's change \[m/s\] (the FMU's `relative_velocity_change`).
    pub fn velocity_change(&self) -> f64 {
        self.change(1)
    }

    /// Whether either changed by more than straight track's irregularities give.
    pub fn outside(&self) -> bool {
        self.heading_change().abs() > self.heading_level
            || self.velocity_change().abs() > VELOCITY_LEVEL
    }

    /// `heading_change`, `relative_velocity_change`, `heading_level`.
    pub fn outputs(&self) -> [f64; 3] {
        [
            self.heading_change(),
            self.velocity_change(),
            self.heading_level,
        ]
    }

    /// The yaw rate's mean since the last standstill \[rad/s\] when it suggests a bias (module
    /// docs), with the distance it is over.
    pub fn suspected_bias(&self) -> Option<(f64, f64)> {
        let (distance, integral) = self.since_stop;
        let mean = integral / distance;
        (distance >= SUSPECT_DISTANCE && mean.abs() > SUSPECT_LEVEL).then_some((mean, distance))
    }
}

/// The factor the estimate's standard deviation is grown by at these outputs
/// ([`Integrals::outputs`]): the larger change over its level when beyond it (the estimate's
/// error from an untold curvature or bias grows with what it did not explain), else 1.
pub fn growth([heading, velocity, heading_level]: [f64; 3]) -> f64 {
    (heading.abs() / heading_level)
        .max(velocity.abs() / VELOCITY_LEVEL)
        .max(1.0)
}

/// The rms of the headings' residual from their least-squares straight line (equally spaced):
/// the track's wander, without a bias's steady turn.
fn wander(headings: impl ExactSizeIterator<Item = f64> + Clone) -> f64 {
    let n = headings.len() as f64;
    let mid = (n - 1.0) / 2.0;
    let mean = headings.clone().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (k, y) in headings.enumerate() {
        let (x, y) = (k as f64 - mid, y - mean);
        sxy += x * y;
        sxx += x * x;
        syy += y * y;
    }
    ((syy - sxy * sxy / sxx).max(0.0) / n).sqrt()
}

#[cfg(test)]
mod tests {
    use super::{
        CELL, HEADING_FLOOR, HEADING_LEVEL, Integrals, VELOCITY_LEVEL, WANDER_FACTOR, WINDOW,
        growth, wander,
    };

    /// `secs` of motion at 20 m/s and 1 kHz with the yaw rate `rate(t)`, the accelerometers
    /// 0.
    fn run(a: &mut Integrals, secs: f64, rate: impl Fn(f64) -> f64) {
        let h = 1e-3;
        for k in 0..(secs / h).round() as usize {
            a.observe(false, 20.0, h, [0.0, rate((k + 1) as f64 * h), 0.0]);
        }
    }

    /// A constant rate: the change grows as the rate times the time until the window is full,
    /// then holds at the rate times the window's time (500 m at 20 m/s: 25 s, to within a
    /// cell's 0.5 s, and a sample's rounding of the distance at a cell's end).
    #[test]
    fn a_constant_rate_turns_the_heading_by_its_window() {
        let mut a = Integrals::default();
        run(&mut a, 10.0, |_| 1e-3);
        assert!(
            (a.heading_change() - 1e-2).abs() < 1e-9,
            "{}",
            a.heading_change()
        );
        assert!(!a.outside());
        assert_eq!(growth(a.outputs()), 1.0);
        run(&mut a, 50.0, |_| 1e-3);
        let (lo, hi) = (1e-3 * WINDOW / 20.0, 1e-3 * (WINDOW + CELL) / 20.0);
        let sample = 1e-3 * 1e-3;
        assert!(
            a.heading_change() >= lo - sample && a.heading_change() <= hi + sample,
            "{}",
            a.heading_change()
        );
        assert!(a.outside());
        assert!((growth(a.outputs()) - a.heading_change() / HEADING_LEVEL).abs() < 1e-12);
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
        let mut a = Integrals::default();
        run(&mut a, 10.0 + 14.0 / v, curve);
        assert!(!a.outside(), "{}", a.heading_change());
        run(&mut a, 2.0 / v, |t| curve(t + 10.0 + 14.0 / v));
        assert!(a.outside(), "{}", a.heading_change());
        let mut b = Integrals::default();
        run(&mut b, 20.0 + (WINDOW + 2.0 * CELL) / v, curve);
        assert!(
            b.heading_change().abs() < 1e-9 && !b.outside(),
            "{}",
            b.heading_change()
        );
    }

    /// A wave of zero mean (a straight track's heading, 3 mrad) stays inside the level and grows
    /// nothing; a non-finite speed adds nothing, non-finite sensors add nothing to their
    /// integrals, and standing samples add nothing.
    #[test]
    fn straight_tracks_wave_is_inside_and_gaps_add_nothing() {
        let mut a = Integrals::default();
        run(&mut a, 100.0, |t| 3e-3 * 2.0 * (2.0 * t).cos());
        assert!(
            a.heading_change().abs() <= 6e-3 + 1e-9 && !a.outside(),
            "{}",
            a.heading_change()
        );
        assert_eq!(growth(a.outputs()), 1.0);
        let before = a.clone();
        a.observe(false, f64::NAN, 1e-3, [1.0, 1.0, 0.0]);
        assert_eq!(a, before);
        a.observe(false, 20.0, 1e-3, [f64::NAN, f64::NAN, 0.0]);
        assert_eq!(a.now, before.now);
        let moved = a.clone();
        a.observe(true, 0.0, 1e-3, [1.0, 1.0, 0.0]);
        assert_eq!(a.heading_change(), moved.heading_change());
    }

    /// 1020 m at 20 m/s: a yaw-rate wave of zero mean is not suspected, the same with 2e-4
    /// rad/s added is (its mean found), before 1000 m it is not judged, and a standstill
    /// starts the mean again.
    #[test]
    fn a_yaw_rate_mean_beyond_a_straight_tracks_is_suspected() {
        let run_for = |bias: f64, secs: f64| {
            let mut a = Integrals::default();
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
        b.observe(true, 0.0, 1e-3, [0.0; 3]);
        assert_eq!(b.suspected_bias(), None);
    }

    /// An accelerometer bias the other does not share: 0.05 m/s2 on the wheelset's passes the
    /// 0.5 m/s level after 10 s (200 m at 20 m/s); the same on both (a tilt) changes nothing.
    #[test]
    fn one_accelerometers_bias_passes_the_velocity_level_and_a_shared_one_does_not() {
        let run_acc = |x: [f64; 3], secs: f64| {
            let mut a = Integrals::default();
            for _ in 0..(secs / 1e-3).round() as usize {
                a.observe(false, 20.0, 1e-3, x);
            }
            a
        };
        let a = run_acc([0.05, 0.0, 0.0], 9.9);
        assert!(!a.outside() && (a.velocity_change() - 0.495).abs() < 1e-9);
        let a = run_acc([0.05, 0.0, 0.0], 10.1);
        assert!(
            a.outside()
                && (growth(a.outputs()) - a.velocity_change() / VELOCITY_LEVEL).abs() < 1e-12
        );
        let b = run_acc([0.05, 0.0, 0.05], 60.0);
        assert_eq!(b.velocity_change(), 0.0);
        assert!(!b.outside());
    }

    /// The wander is a straight line's residual rms: nil for a line (a bias's turn), `A / sqrt 2`
    /// for a sine of amplitude `A` over whole periods, whatever line it rides on.
    #[test]
    fn the_wander_leaves_a_straight_line_out() {
        let n = 201;
        let line = (0..n).map(|k| 0.3 + 2e-3 * k as f64);
        assert!(wander(line.clone()) < 1e-15);
        let sine = |k: usize| 1e-3 * (2.0 * std::f64::consts::PI * k as f64 / 25.0).sin();
        let wave: Vec<f64> = (0..n).map(sine).collect();
        let on_line: Vec<f64> = (0..n).map(|k| sine(k) + 0.3 + 2e-3 * k as f64).collect();
        let want = 1e-3 / 2f64.sqrt();
        assert!((wander(wave.iter().copied()) - want).abs() < 0.03 * want);
        assert!((wander(on_line.iter().copied()) - wander(wave.iter().copied())).abs() < 1e-12);
    }

    /// A track whose heading wanders by 1 mrad (a 100 m wave) lowers the level, once 2000 m
    /// are run, to 8 times its wander (5.7 mrad), the same with a 3e-4 rad/s bias as without:
    /// the bias (7.5 mrad over the window at 20 m/s) then sets the flag, the wave alone not.
    #[test]
    fn a_known_wander_lowers_the_heading_level_and_a_bias_does_not_raise_it() {
        let wave = |t: f64| {
            1e-3 * (2.0 * std::f64::consts::PI / 5.0) * (2.0 * std::f64::consts::PI * t / 5.0).cos()
        };
        let mut plain = Integrals::default();
        let mut biased = Integrals::default();
        run(&mut plain, 90.0, wave);
        run(&mut biased, 90.0, |t| wave(t) + 3e-4);
        assert_eq!(plain.heading_level(), HEADING_LEVEL);
        assert!(!biased.outside());
        run(&mut plain, 20.0, |t| wave(t + 90.0));
        run(&mut biased, 20.0, |t| wave(t + 90.0) + 3e-4);
        let want = WANDER_FACTOR * 1e-3 / 2f64.sqrt();
        assert!(
            (plain.heading_level() - want).abs() < 0.03 * want,
            "{}",
            plain.heading_level()
        );
        assert!((biased.heading_level() - plain.heading_level()).abs() < 1e-9);
        assert!(HEADING_FLOOR < want && want < HEADING_LEVEL);
        assert!(
            !plain.outside() && biased.outside(),
            "{}",
            biased.heading_change()
        );
    }

    /// A step of a hostile length (1e300 m) fills the span at once, without a loop per cell:
    /// the window's change is then nil and the level the wander of equal marks (the floor).
    #[test]
    fn a_step_past_the_span_fills_it_at_once() {
        let mut a = Integrals::default();
        a.observe(false, 20.0, 1e-3, [0.0, 1.0, 0.0]);
        a.observe(false, 1e300, 1e-3, [0.0, 1.0, 0.0]);
        assert!(a.into_cell >= 0.0 && a.into_cell < CELL);
        assert_eq!(a.marks.len(), 201);
        assert_eq!(a.heading_change(), 0.0);
        assert_eq!(a.heading_level(), HEADING_FLOOR);
        let before = a.clone();
        a.observe(false, f64::MAX, 10.0, [0.0, 1.0, 0.0]);
        assert_eq!(a, before);
    }
}

//! The learned filter at run time: the grid, the channels' history, the taps of the speeds
//! around the current one, and the estimates between grid points.
//!
//! Per sample: the sample joins its cell ([`Grid`]). When cells close, their values enter the
//! history and, if the speed lies inside the bank's range, the estimate of the newest cell
//! (causal) and of the cell `lag` points behind (fixed lag) are computed with the taps of the
//! two bank speeds around the current speed, blended linearly in speed. Between closings the
//! outputs extrapolate the last two grid estimates linearly in distance (causal).
//!
//! At the start of a run the history is short: each entry has windows with shorter pasts, and
//! the longest one the history covers is used. Until the fixed-lag window has its `lag` metres
//! of look-ahead (the first `lag` + 1 m), the fixed-lag output is the causal output made when
//! the vehicle was at `distance - lag` (a delay line of the causal grid estimates): the best
//! estimate there is of that position, never one of another position relabelled.
//!
//! Outside the bank's speed range no learned estimate is made (the caller falls back to the
//! Kalman filter); the history goes on, so the learned estimate resumes as soon as the speed is
//! back inside. Where no learned causal estimate is made (the first metre, outside the speed
//! range) the delay line keeps the Kalman filter's estimate, which is then the causal output:
//! the fixed-lag output there is also the one made at its position, from the first grid point
//! on (before it, the first point's). Why it matters: the evaluation's D3 band-pass spreads an
//! error in a record's first metres over 100-200 m of it (docs/learned-filter.md).
//!
//! Taps fitted at constant speed meet, while the speed changes, windows whose cells were
//! recorded at other speeds: the history keeps each cell divided by its speed's
//! [`TAP_SPEED_POWER`] (a speed below the bank's lowest counts as that one: the slowest cells carry
//! little of the track anyway, and a quotient by a near-zero speed would amplify their noise),
//! and the estimate multiplies it back by the current speed's.
//!
//! A bank with per-condition taps (a contact model, [`super::contact`]) is blended in the
//! contact condition too: every closed cell updates the contact features, the model turns them
//! into a Kalker-coefficient scale, and the taps of the two trained conditions around it are
//! blended linearly, as the speeds are (up to four windows per estimate). Where a condition was
//! left out at a speed (the vehicle is unstable there), the nearest trained condition stands in.

use super::bank::{Bank, Entry};
use super::contact::{ContactModel, Moments};
use super::grid::{CHANNELS, Grid, KALMAN, ROLL_RATE};
use super::weights;
use super::window::{self, Window};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The windows of one entry, shortest history first.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Windows(Vec<Window>);

impl Windows {
    fn of(e: &Entry) -> Windows {
        let slot = |name: &String| CHANNELS.iter().position(|c| c == name).expect("checked");
        let slots: Vec<usize> = e.channels.iter().map(slot).collect();
        let mut w: Vec<Window> = e
            .windows
            .iter()
            .map(|w| Window::from_file_order(w.past, w.future, slots.clone(), &w.taps, w.rms_error))
            .collect();
        w.sort_by_key(Window::len);
        Windows(w)
    }

    /// The estimate from the longest window the history covers, and its rms error; `gain` per
    /// channel slot brings the history's speed quotients back to the current speed.
    fn apply(&self, hist: &History, gain: &[f64; 5]) -> Option<(f64, f64)> {
        let w = window::longest_covered(&self.0, hist.filled)?;
        Some((w.apply(hist, gain), w.rms_error()))
    }

    fn longest(&self) -> usize {
        self.0.iter().map(Window::len).max().unwrap_or(0)
    }
}

/// The power of the speed each channel ([`CHANNELS`]) is divided by in the history. The taps
/// were fitted at constant speed; while the speed changes, the cells of a window were recorded
/// at other speeds than the current one, and the quotients rescale each to the current speed
/// (at constant speed they cancel: the standard case is unchanged to rounding).
///
/// | channel | power | why |
/// |---|---|---|
/// | `ws_acc_y`, `frame_acc_y` | 1.5 | a wheelset following a track wave `y(s)` has `y'' V^2` of lateral acceleration, but the gravity of its roll (cross-level) `g phi` does not grow with speed and dominates the long waves (70 m at 20 m/s: `V^2 (2 pi / 70)^2 = 3.2` against `g / 1.5 m = 6.5` per metre of amplitude) |
/// | `ws_yaw_rate`, `ws_roll_rate` | 1 | `psi' V` and `phi' V` |
/// | `kalman` | 0 | already a distance |
///
/// The powers were chosen on the validation seeds 102-106 (variable-speed profile, mean whole
/// Jrel over the seven learned variants of `alignment-studies variants`; accelerations / rates):
/// 0 / 0 (no quotients) 0.138, 0.5 / 0.5 0.135, 1 / 1 0.133, 1.5 / 1 0.132, 2 / 1 0.138 (its
/// gyro fixed-lag output 0.168 against 0.153 without quotients), 2 / 1 with the roll rate at 0
/// worse still (0.203), 1 / 0 0.135.
pub const TAP_SPEED_POWER: [f64; 5] = [1.5, 1.0, 1.5, 1.0, 0.0];

/// `V^TAP_SPEED_POWER` per channel (with one square root: it runs at every closed cell).
fn speed_factors(v: f64) -> [f64; 5] {
    let v15 = v * v.sqrt();
    [v15, v, v15, v, 1.0]
}

/// The bank's entries for one sensor set and lag, by speed, then by contact condition.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Selection {
    speeds: Vec<f64>,
    /// Contact conditions (Kalker-coefficient scales, ascending); empty without a contact
    /// model (one set of windows per speed).
    conditions: Vec<f64>,
    causal: Vec<Vec<Windows>>,
    lagged: Vec<Vec<Windows>>,
    contact: Option<ContactModel>,
    lag: usize,
    uses_roll_rate: bool,
    sample_step: f64,
}

/// Per channel, the newest `capacity` values, each written twice (at `i` and `i + capacity`)
/// so the newest `n` are always one contiguous slice.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct History {
    capacity: usize,
    data: Vec<Vec<f64>>,
    /// Position of the next write.
    pos: usize,
    filled: usize,
}

impl History {
    fn new(capacity: usize) -> History {
        History {
            capacity,
            data: vec![vec![0.0; 2 * capacity]; CHANNELS.len()],
            pos: 0,
            filled: 0,
        }
    }

    fn push(&mut self, x: &[f64; 5]) {
        for (d, v) in self.data.iter_mut().zip(x) {
            d[self.pos] = *v;
            d[self.pos + self.capacity] = *v;
        }
        self.pos = (self.pos + 1) % self.capacity;
        self.filled = (self.filled + 1).min(self.capacity);
    }
}

impl window::History for History {
    fn filled(&self) -> usize {
        self.filled
    }

    fn latest(&self, c: usize, n: usize) -> &[f64] {
        let end = self.pos + self.capacity;
        &self.data[c][end - n..end]
    }
}

/// An estimate on the grid: its value, rms error, and the distance it was made at.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq)]
struct Point {
    value: f64,
    std: f64,
    distance: f64,
}

/// The last two grid estimates, for the linear extrapolation between closings.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Track {
    points: Vec<Point>,
}

impl Track {
    fn push(&mut self, p: Point) {
        if self.points.len() == 2 {
            self.points.remove(0);
        }
        self.points.push(p);
    }

    fn clear(&mut self) {
        self.points.clear();
    }

    /// The estimate at `distance` (linear extrapolation from the last two points; the last
    /// point alone when only one exists or they coincide).
    fn at(&self, distance: f64) -> Option<(f64, f64)> {
        match self.points.as_slice() {
            [] => None,
            [p] => Some((p.value, p.std)),
            [a, b] => {
                let span = b.distance - a.distance;
                let slope = if span > 0.0 {
                    (b.value - a.value) / span
                } else {
                    0.0
                };
                // Never further than one cell ahead: a held speed of zero must not extrapolate.
                let ahead = (distance - b.distance).clamp(0.0, span.max(0.0));
                Some((b.value + slope * ahead, b.std))
            }
            _ => unreachable!("two points at most"),
        }
    }
}

/// The causal output on the grid over the last `lag` metres (and two more points), oldest
/// first: learned estimates, or the Kalman filter's where none was made. The fixed-lag output
/// while its own window is not available.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Delay {
    points: std::collections::VecDeque<Point>,
    capacity: usize,
}

impl Delay {
    /// Keeps `p` (nothing without a lagged output).
    fn push(&mut self, p: Point) {
        if self.capacity == 0 {
            return;
        }
        if self.points.len() == self.capacity {
            self.points.pop_front();
        }
        self.points.push_back(p);
    }

    /// The causal estimate made at `distance` (linear between grid points; the oldest point
    /// before it, the newest after it).
    fn at(&self, distance: f64) -> Option<(f64, f64)> {
        let first = self.points.front()?;
        if distance <= first.distance {
            return Some((first.value, first.std));
        }
        let i = self.points.partition_point(|p| p.distance < distance);
        let Some(b) = self.points.get(i) else {
            let last = self.points.back().expect("non-empty");
            return Some((last.value, last.std));
        };
        let a = &self.points[i - 1];
        let w = (distance - a.distance) / (b.distance - a.distance);
        Some((a.value + w * (b.value - a.value), b.std))
    }
}

/// The learned filter's run-time state. Cloning it (FMU state) shares the taps.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Learned {
    selection: Arc<Selection>,
    grid: Grid,
    history: History,
    causal: Track,
    lagged: Track,
    delay: Delay,
    /// Whether the last closed cell's speed was inside the bank's range.
    in_range: bool,
    /// The contact features' moments (a bank with a contact model).
    moments: Option<Moments>,
    /// The estimated Kalker-coefficient scale (0 without a contact model).
    contact_scale: f64,
}

/// The windows of `entries` by ascending speed, and per speed one per condition of
/// `conditions` (the entry of the nearest condition at that speed), or the single entry of each
/// speed when `conditions` is empty; `what` names the entries in errors.
#[allow(clippy::type_complexity)]
fn by_speed(
    entries: &[&Entry],
    conditions: &[f64],
    what: &str,
) -> Result<(Vec<f64>, Vec<Vec<Windows>>), String> {
    let mut speeds: Vec<f64> = entries.iter().map(|e| e.speed).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let mut table = vec![];
    for v in &speeds {
        let at: Vec<&Entry> = entries.iter().copied().filter(|e| e.speed == *v).collect();
        if conditions.is_empty() {
            if at.len() > 1 {
                return Err(format!(
                    "the tap bank has two {what} entries for one speed ({v} m/s)"
                ));
            }
            table.push(vec![Windows::of(at[0])]);
            continue;
        }
        let row = conditions
            .iter()
            .map(|c| {
                let nearest = at
                    .iter()
                    .min_by(|a, b| {
                        let d = |e: &Entry| (e.condition.unwrap_or(f64::NAN) - c).abs();
                        d(a).total_cmp(&d(b))
                    })
                    .expect("an entry at this speed");
                Windows::of(nearest)
            })
            .collect();
        table.push(row);
    }
    Ok((speeds, table))
}

/// What [`Learned::new`] needs to know of the FMU's configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// Use the taps fitted with the wheelset roll-rate gyroscope.
    pub roll_rate: bool,
    /// The fixed-lag output's lag \[m\] (0: none).
    pub lag: f64,
}

impl Learned {
    /// The learned filter with the bank's entries for `choice`: the sensor set with or without
    /// the roll-rate channel and, for the fixed-lag output, the lag the bank holds nearest
    /// `choice.lag` (refused unless within half a grid step of it).
    pub fn new(bank: &Bank, choice: Choice) -> Result<Learned, String> {
        let roll = |e: &Entry| e.channels.iter().any(|c| c == CHANNELS[ROLL_RATE]);
        let of_set = |lag: usize| -> Vec<&Entry> {
            bank.entries
                .iter()
                .filter(|e| roll(e) == choice.roll_rate && e.lag == lag)
                .collect()
        };
        let sensors = if choice.roll_rate {
            "four sensors (with the roll-rate gyroscope)"
        } else {
            "three sensors"
        };
        let causal = of_set(0);
        if causal.is_empty() {
            return Err(format!("the tap bank has no causal taps for {sensors}"));
        }
        let mut conditions: Vec<f64> = match &bank.contact {
            Some(_) => causal.iter().filter_map(|e| e.condition).collect(),
            None => vec![],
        };
        conditions.sort_by(f64::total_cmp);
        conditions.dedup();
        let (speeds, causal) = by_speed(&causal, &conditions, "causal")?;
        let (lag, lagged) = if choice.lag > 0.0 {
            let want = choice.lag / bank.grid;
            let lags: Vec<usize> = {
                let mut l: Vec<usize> = bank
                    .entries
                    .iter()
                    .filter(|e| roll(e) == choice.roll_rate && e.lag > 0)
                    .map(|e| e.lag)
                    .collect();
                l.sort();
                l.dedup();
                l
            };
            let best = lags.iter().copied().min_by(|a, b| {
                (*a as f64 - want)
                    .abs()
                    .total_cmp(&(*b as f64 - want).abs())
            });
            let shown: Vec<String> = lags
                .iter()
                .map(|l| format!("{}", *l as f64 * bank.grid))
                .collect();
            match best {
                Some(l) if (l as f64 - want).abs() <= 0.5 => {
                    let what = format!("{} m lag", l as f64 * bank.grid);
                    let (at, windows) = by_speed(&of_set(l), &conditions, &what)?;
                    if at != speeds {
                        return Err(format!(
                            "the tap bank's {what} taps are not at the speeds of its causal taps"
                        ));
                    }
                    (l, windows)
                }
                _ => {
                    return Err(format!(
                        "lag = {} m: the tap bank holds fixed-lag taps for {} m ({sensors}); 0 switches the lagged output off",
                        choice.lag,
                        if shown.is_empty() {
                            "no lag".into()
                        } else {
                            shown.join(", ")
                        }
                    ));
                }
            }
        } else {
            (0, vec![])
        };
        let capacity = causal
            .iter()
            .chain(&lagged)
            .flatten()
            .map(Windows::longest)
            .max()
            .unwrap_or(1)
            .max(1);
        let contact = bank.contact.clone().filter(|_| !conditions.is_empty());
        Ok(Learned {
            moments: contact.as_ref().map(|c| c.moments(bank.grid)),
            contact_scale: 0.0,
            selection: Arc::new(Selection {
                speeds,
                conditions,
                causal,
                lagged,
                contact,
                lag,
                uses_roll_rate: choice.roll_rate,
                sample_step: bank.provenance.sample_step,
            }),
            grid: Grid::new(bank.grid, bank.kalman_highpass),
            history: History::new(capacity),
            causal: Track::default(),
            lagged: Track::default(),
            delay: Delay {
                points: Default::default(),
                capacity: if lag > 0 { lag + 2 } else { 0 },
            },
            in_range: false,
        })
    }

    /// The estimated Kalker-coefficient scale of the contact (1: the nominal coefficients), from
    /// the last closed cell; 0 when the taps do not estimate it.
    pub fn contact_scale(&self) -> f64 {
        self.contact_scale
    }

    /// The speed range the taps cover \[m/s\].
    pub fn speed_range(&self) -> (f64, f64) {
        let s = &self.selection.speeds;
        (s[0], s[s.len() - 1])
    }

    /// The lag of the fixed-lag output \[m\] (0: none).
    pub fn lag(&self) -> f64 {
        self.selection.lag as f64 * self.grid.step_length()
    }

    /// The sample step the taps were fitted for \[s\].
    pub fn sample_step(&self) -> f64 {
        self.selection.sample_step
    }

    pub fn uses_roll_rate(&self) -> bool {
        self.selection.uses_roll_rate
    }

    /// Whether the last closed cell's speed was inside the taps' range.
    pub fn in_range(&self) -> bool {
        self.in_range
    }

    /// One sample: `distance` after the step, the speed over it, the channels in
    /// [`CHANNELS`] order (the Kalman filter's alignment estimate last), and the Kalman
    /// estimate's standard deviation `kalman_std` (what the outputs carry where no learned
    /// estimate is made).
    pub fn step(&mut self, distance: f64, speed: f64, x: &[f64; 5], kalman_std: f64) {
        let Some(closed) = self.grid.add(distance, x) else {
            return;
        };
        // Inside the bank's range these are also the gain the estimate multiplies back by.
        let factors = speed_factors(speed.max(self.selection.speeds[0]));
        for cell in &closed.cells {
            self.history
                .push(&std::array::from_fn(|c| cell[c] / factors[c]));
            if let Some(m) = self.moments.as_mut() {
                m.push(cell, speed);
            }
        }
        if let (Some(model), Some(m)) = (&self.selection.contact, &self.moments) {
            // Nominal until the features exist (the first cells of a run).
            self.contact_scale = model.estimate_from(m).unwrap_or(model.range[1]);
        }
        let s = &self.selection.speeds;
        self.in_range = speed >= s[0] && speed <= s[s.len() - 1];
        // Where no learned causal estimate is made, the causal output is the Kalman filter's:
        // the delay line keeps it, so the fixed-lag output for that position is the estimate
        // made there, not a learned one of another position.
        let kalman = Point {
            value: x[KALMAN],
            std: kalman_std,
            distance: closed.distance,
        };
        if !self.in_range {
            self.causal.clear();
            self.lagged.clear();
            self.delay.push(kalman);
            return;
        }
        let sel = Arc::clone(&self.selection);
        let by_speed = weights(&sel.speeds, speed);
        let by_condition = if sel.conditions.is_empty() {
            vec![(0, 1.0)]
        } else {
            weights(&sel.conditions, self.contact_scale)
        };
        let blend = |set: &[Vec<Windows>], hist: &History| -> Option<(f64, f64)> {
            let (mut e, mut r) = (0.0, 0.0);
            for (s, a) in &by_speed {
                for (c, b) in &by_condition {
                    let (ei, ri) = set[*s][*c].apply(hist, &factors)?;
                    e += a * b * ei;
                    r += a * b * ri;
                }
            }
            Some((e, r))
        };
        let d = closed.distance;
        match blend(&sel.causal, &self.history) {
            Some((value, std)) => {
                let p = Point {
                    value,
                    std,
                    distance: d,
                };
                self.causal.push(p);
                self.delay.push(p);
            }
            None => self.delay.push(kalman),
        }
        if !sel.lagged.is_empty()
            && let Some((value, std)) = blend(&sel.lagged, &self.history)
        {
            self.lagged.push(Point {
                value,
                std,
                distance: d,
            });
        }
    }

    /// The causal estimate at `distance` and its standard deviation; `None` while there is
    /// none (start of the run, speed outside the taps' range).
    pub fn causal(&self, distance: f64) -> Option<(f64, f64)> {
        self.causal.at(distance)
    }

    /// The fixed-lag estimate for the position `lag` metres behind `distance` (the causal
    /// estimate made there while the fixed-lag window is not yet available).
    pub fn lagged(&self, distance: f64) -> Option<(f64, f64)> {
        if self.selection.lagged.is_empty() {
            return None;
        }
        self.lagged
            .at(distance)
            .or_else(|| self.delay.at(distance - self.lag()))
    }
}

#[cfg(test)]
#[path = "stream_tests.rs"]
mod tests;

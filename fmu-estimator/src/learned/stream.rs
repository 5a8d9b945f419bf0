//! The learned filter at run time: what happens when a sample arrives and when an estimate is
//! asked for. Its parts each have a file: the history (`history.rs`), the entries chosen
//! (`selection.rs`), their blend (`blend.rs`), the extrapolation between grid
//! points (`track.rs`) and the delay line of the fixed-lag output (`delay.rs`).
//!
//! Per sample: the sample joins its cell ([`Grid`]). When cells close, their values enter the
//! history and, if the speed lies inside the bank's range, the estimate of the newest cell
//! (causal) and of the cell `lag` points behind (fixed lag) are computed with the taps of the
//! two bank speeds around the current speed, blended linearly in speed. With a bank's
//! long-wave stage ([`super::stage`]) every closed cell also steps the stage, whose correction
//! is added to the causal estimate (not to the fixed-lag one). Between closings the outputs
//! extrapolate the last two grid estimates linearly in distance (causal).
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

use super::bank::Bank;
use super::blend::Blend;
use super::contact::Moments;
use super::delay::Delay;
use super::grid::{Grid, KALMAN};
use super::history::History;
pub use super::selection::Choice;
use super::selection::Selection;
use super::spectral::Spectral;
use super::stage::{Stage, StageRow};
use super::track::{Point, Track};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The power of the speed each channel ([`super::grid::CHANNELS`]) is divided by in the history. The taps
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

/// How far (as a ratio) the judged conicity ([`CONICITY_MEMORY`]) may lie beyond the selected
/// taps' conicities before `outside_training` sets. Why 1.15: the default's taps, fitted at
/// conicity 0.1, lose twice their error from about 15-20 % off it (validation seeds 102-106,
/// 400 m at 20 m/s, whole Jrel over the nominal's: 0.09 1.3-1.8, 0.08 2.1-3.2, 0.12 1.9-2.5), and
/// on the same seeds 1.15 and 1.12 both flagged every run past twice the nominal error within
/// 300 m, with no false alarm over 9 runs of 10 km at conicity 0.1 (1.10: 0.65 % of their
/// distance; 1.18 missed 4 runs of 107).
pub const CONICITY_MARGIN: f64 = 1.15;

/// The memory of the judged conicity \[m\]: a running mean of `ln(conicity_estimate)`, over
/// the distance since it began until it reaches this, then exponential. The estimate itself
/// (200 m of features) scatters by 5-8 % in `ln` about 0.1 over 10 km on the nominal ML95 (one
/// track seed's spectrum moves it): read raw, 1.25 set `outside_training` on 1.5 % of a
/// seed's distance; over 500 m of it, none on the same runs.
pub const CONICITY_MEMORY: f64 = 500.0;

/// How the error of taps fitted at one conicity grows with the wheels' distance from it, in
/// `ln(conicity)`: `sqrt(1 + (d / CONICITY_ERROR_SCALE)^2)` times the validation error. Fitted by
/// eye on the default's whole Jrel over its nominal one (validation seeds 102-106, conicity
/// 0.075-0.3, Kalker 100 and 75 %: within 20 % from 0.075 to 0.2, the rule 20 % low at
/// Kalker 50 % and at 0.3), what `alignment_std` is grown by.
pub const CONICITY_ERROR_SCALE: f64 = 0.1;

/// The long-wave stage's inputs: the sensor channels the taps read, then their estimate.
fn stage_inputs(roll_rate: bool) -> usize {
    if roll_rate { 5 } else { 4 }
}

/// `V^TAP_SPEED_POWER` per channel (with one square root: it runs at every closed cell).
fn speed_factors(v: f64) -> [f64; 5] {
    let v15 = v * v.sqrt();
    [v15, v, v15, v, 1.0]
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
    /// The conicity given by the user (`conicity` parameter), if any.
    told_conicity: Option<f64>,
    /// The Kalker scale given by the user (`kalker_scale` parameter), if any.
    told_kalker: Option<f64>,
    /// The conicity told or estimated (0 in a bank without a conicity model); the taps are
    /// blended at it within their own conicities.
    conicity: f64,
    /// The features' novelty ([`super::contact::Condition::novelty`]; 0 in a bank without
    /// conicity conditions, and before the novelty is first judged: [`super::contact::NOVELTY_FROM`]).
    novelty: f64,
    /// Whether the features fill enough of their memory to be judged
    /// ([`super::contact::NOVELTY_FROM`]): `outside_training` waits for it.
    judged: bool,
    /// The judged conicity: `ln` of the one told, or the running mean of the estimate's over
    /// [`CONICITY_MEMORY`] from where the features' memory first filled; `None` before (or in a
    /// bank without conicity conditions).
    judged_conicity: Option<f64>,
    /// Where the features' memory began (the first closed cell) and where the judged
    /// conicity's mean began \[m\].
    started: Option<f64>,
    judged_from: f64,
    /// Closed cells until the novelty is judged again ([`super::contact::NOVELTY_EVERY`]).
    to_novelty: usize,
    /// The conicity by Whittle's likelihood, in a bank whose contact model has spectra and
    /// when no conicity is told ([`super::spectral`]).
    spectral: Option<Spectral>,
    /// The Kalman filter's estimates over the last `lag` metres: its share of the fixed-lag
    /// output ([`super::fallback_share`]) is its estimate made at that output's position.
    kalman_delay: Delay,
    /// The long-wave stage's band-passes and memory ([`super::stage`]): with a bank's stage,
    /// or while its inputs are logged for the fit.
    stage: Option<Stage>,
    /// The stage's inputs per closed cell, for the fit ([`Self::log_stage`]); not part of an
    /// FMU state.
    #[serde(skip)]
    stage_log: Option<Vec<StageRow>>,
}

impl Learned {
    /// The learned filter with the bank's entries for `choice` (`selection.rs`), at the
    /// start of a run.
    pub fn new(bank: &Bank, choice: Choice) -> Result<Learned, super::error::LearnedError> {
        let selection = Selection::new(bank, choice)?;
        let told_conicity = choice.conicity.filter(|c| *c > 0.0);
        let spectral = selection
            .contact
            .as_ref()
            .filter(|c| told_conicity.is_none() && c.speeds.iter().all(|s| s.spectra.is_some()))
            .map(|_| Spectral::new(bank.grid));
        Ok(Learned {
            spectral,
            moments: selection.contact.as_ref().map(|c| c.moments(bank.grid)),
            contact_scale: 0.0,
            told_conicity,
            told_kalker: choice.kalker.filter(|k| *k > 0.0),
            conicity: 0.0,
            novelty: 0.0,
            judged: false,
            judged_conicity: None,
            started: None,
            judged_from: 0.0,
            to_novelty: 0,
            grid: Grid::new(bank.grid, bank.kalman_highpass, bank.kalman_shelf),
            history: History::new(selection.longest()),
            causal: Track::default(),
            lagged: Track::default(),
            delay: Delay::new(selection.lag),
            kalman_delay: Delay::new(selection.lag),
            in_range: false,
            stage: selection
                .stage
                .as_ref()
                .map(|_| Stage::new(stage_inputs(choice.roll_rate), bank.grid)),
            stage_log: None,
            selection: Arc::new(selection),
        })
    }

    /// Logs the long-wave stage's inputs at every closed cell from here on, for its fit
    /// (`alignment-studies stage`): the band-passed inputs and the taps' estimate before the
    /// stage, whether the bank has a stage or not.
    pub fn log_stage(&mut self) {
        let inputs = stage_inputs(self.selection.uses_roll_rate);
        let grid = self.grid.step_length();
        self.stage.get_or_insert_with(|| Stage::new(inputs, grid));
        self.stage_log.get_or_insert_with(Vec::new);
    }

    /// The rows logged since [`Self::log_stage`] (empty without it).
    pub fn take_stage_log(&mut self) -> Vec<StageRow> {
        self.stage_log
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Whether the bank's long-wave stage corrects the causal output.
    pub fn has_stage(&self) -> bool {
        self.selection.stage.is_some()
    }

    /// Steps the long-wave stage with the cells just closed (`cells`, raw, at `speed`;
    /// `factors` their speed's gains) and the taps' causal estimate `made` (the Kalman
    /// filter's `kalman` where they made none); the correction of `made`, blended in speed
    /// as the taps were (`by_speed`, [`Blend::by_speed`]; 0 without a stage or an estimate).
    #[allow(clippy::too_many_arguments)]
    fn stage_step(
        &mut self,
        cells: &[[f64; 5]],
        factors: &[f64; 5],
        made: Option<f64>,
        kalman: f64,
        distance: f64,
        speed: f64,
        by_speed: &[(usize, f64)],
    ) -> f64 {
        let Some(stage) = self.stage.as_mut() else {
            return 0.0;
        };
        let n = stage_inputs(self.selection.uses_roll_rate) - 1;
        let mut x = [0.0; 5];
        x[n] = made.unwrap_or(kalman);
        let mut passed = [0.0; 5];
        for cell in cells {
            for c in 0..n {
                x[c] = cell[c] / factors[c];
            }
            passed = stage.push(&x[..=n], speed);
        }
        // The sensors' share of the correction is multiplied back by the current speed's
        // gain, as the taps' is: at constant speed the stage reads the band-passed raw cells.
        let mut gain = [1.0; 5];
        gain[..n].copy_from_slice(&factors[..n]);
        if let Some(log) = self.stage_log.as_mut() {
            log.push(StageRow {
                distance,
                estimate: made.unwrap_or(f64::NAN),
                inputs: std::array::from_fn(|c| passed[c] * gain[c]),
            });
        }
        let (Some(taps), Some(_)) = (&self.selection.stage, made) else {
            return 0.0;
        };
        let share = stage.share();
        if share == 0.0 {
            return 0.0;
        }
        share
            * by_speed
                .iter()
                .map(|(i, w)| w * stage.correction(&taps.taps[*i], &gain[..=n]))
                .sum::<f64>()
    }

    /// The estimated Kalker-coefficient scale of the contact (1: the nominal coefficients), from
    /// the last closed cell; 0 when the taps do not estimate it.
    pub fn contact_scale(&self) -> f64 {
        self.contact_scale
    }

    /// The wheels' equivalent conicity, told or estimated from the sensors (the taps are blended
    /// at it within their own conicities); 0 when the bank has no conicity model.
    pub fn conicity(&self) -> f64 {
        self.conicity
    }

    /// The judged conicity ([`CONICITY_MEMORY`]) that `outside_training` reads; `None` before
    /// it is judged and without a conicity model.
    pub fn judged_conicity(&self) -> Option<f64> {
        self.judged_conicity.map(f64::exp)
    }

    /// How far the sensors' features lie from what the taps were fitted on, in units of the
    /// level exceeded on 0.2 % of the validation distance ([`super::contact::LEVEL_SHARE`]);
    /// 0 when the taps have no conicity conditions, or before it is first judged ([`super::contact::NOVELTY_FROM`]; then every [`super::contact::NOVELTY_EVERY`] cells).
    pub fn novelty(&self) -> f64 {
        self.novelty
    }

    /// Whether the sensors are unlike what the selected taps were fitted on: the novelty
    /// exceeds its level (1), or the judged conicity lies beyond the selected taps' conicities
    /// by more than [`CONICITY_MARGIN`] (the default bank's taps, and the four-sensor taps of
    /// `learned-conicity.taps`, hold conicity 0.1 only, while their contact model estimates
    /// 0.05-0.4).
    pub fn outside_training(&self) -> bool {
        self.beyond_conicities() || (self.judged && self.novelty > super::contact::NOVELTY_LEVEL)
    }

    /// Whether the judged conicity lies beyond the selected taps' conicities by more than
    /// [`CONICITY_MARGIN`].
    pub fn beyond_conicities(&self) -> bool {
        self.conicity_distance() > CONICITY_MARGIN.ln()
    }

    /// How far the judged conicity lies beyond the selected taps' conicities, in
    /// `ln(conicity)` (0 inside them, before it is judged, and without conicity conditions).
    pub fn conicity_distance(&self) -> f64 {
        match (self.selection.conicity_range(), self.judged_conicity) {
            (Some([lo, hi]), Some(x)) => (lo.ln() - x).max(x - hi.ln()).max(0.0),
            _ => 0.0,
        }
    }

    /// The factor the taps' validation error is grown by for the judged conicity's distance
    /// from theirs ([`CONICITY_ERROR_SCALE`]).
    pub fn conicity_growth(&self) -> f64 {
        (1.0 + (self.conicity_distance() / CONICITY_ERROR_SCALE).powi(2)).sqrt()
    }

    /// The conicities of the selected taps (empty without conicity conditions).
    pub fn selected_conicities(&self) -> &[f64] {
        &self.selection.conicities
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

    /// Whether the taps read the wheelset roll-rate channel; when they do not, the per-sample
    /// step ([`crate::step::step`]) zeroes that input, so that an unused (even non-finite)
    /// column cannot spoil the grid's cells.
    pub fn uses_roll_rate(&self) -> bool {
        self.selection.uses_roll_rate
    }

    /// Whether the last closed cell's speed was inside the taps' range.
    pub fn in_range(&self) -> bool {
        self.in_range
    }

    /// One sample: `distance` after the step, the speed over it, the channels in
    /// [`super::grid::CHANNELS`] order (the Kalman filter's alignment estimate last), and the Kalman
    /// estimate's standard deviation `kalman_std` (what the outputs carry where no learned
    /// estimate is made).
    pub fn step(&mut self, distance: f64, speed: f64, x: &[f64; 5], kalman_std: f64) {
        let Some(closed) = self.grid.add(distance, x) else {
            return;
        };
        // Inside the bank's range these are also the gain the estimate multiplies back by.
        let factors = speed_factors(speed.max(self.selection.speeds[0]));
        let mut due = false;
        for cell in &closed.cells {
            self.history
                .push(&std::array::from_fn(|c| cell[c] / factors[c]));
            if let Some(m) = self.moments.as_mut() {
                m.push(cell, speed);
            }
            if let Some(s) = self.spectral.as_mut() {
                due |= s.push(cell, speed);
            }
        }
        if due {
            self.update_spectral(speed);
        }
        let first = *self.started.get_or_insert(closed.distance);
        if let (Some(model), Some(m)) = (&self.selection.contact, &self.moments) {
            let taps = self.selection.conicity_range();
            self.to_novelty = self.to_novelty.saturating_sub(closed.cells.len());
            let judge = self.to_novelty == 0;
            if judge {
                self.to_novelty = super::contact::NOVELTY_EVERY;
            }
            // The likelihood's conicity, once it has one, stands for the features' estimate.
            let told = self.told_conicity.or_else(|| {
                self.spectral
                    .as_ref()
                    .and_then(Spectral::ln_conicity)
                    .map(f64::exp)
            });
            match model.estimate_told(m, told, self.told_kalker, taps, judge) {
                Some(c) => {
                    self.contact_scale = c.kalker;
                    self.conicity = c.conicity.unwrap_or(0.0);
                    if judge {
                        self.novelty = c.novelty.unwrap_or(0.0);
                        self.judged = c.novelty.is_some();
                    }
                    let memory_full = closed.distance - first >= model.memory;
                    self.judge_conicity(closed.distance, closed.cells.len(), memory_full);
                }
                // Until the features exist (the first cells of a run): nominal contact, and
                // in a bank over conicities the conicity told or the range's geometric middle.
                None => {
                    self.contact_scale = self
                        .told_kalker
                        .map_or(model.range[1], |k| k.clamp(model.range[0], model.range[1]));
                    self.conicity = model.conicity_range.map_or(0.0, |[lo, hi]| {
                        self.told_conicity.unwrap_or((lo * hi).sqrt())
                    });
                }
            }
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
        self.kalman_delay.push(kalman);
        let d = closed.distance;
        if !self.in_range {
            self.causal.clear();
            self.lagged.clear();
            self.delay.push(kalman);
            self.stage_step(&closed.cells, &factors, None, x[KALMAN], d, speed, &[]);
            return;
        }
        let sel = &self.selection;
        let blend = Blend::at(
            &sel.speeds,
            speed,
            &sel.conditions,
            self.contact_scale,
            &sel.conicities,
            self.conicity,
        );
        let made = blend.apply(&sel.causal, &self.history, &factors);
        let lagged = if sel.lagged.is_empty() {
            None
        } else {
            blend.apply(&sel.lagged, &self.history, &factors)
        };
        let correction = self.stage_step(
            &closed.cells,
            &factors,
            made.map(|m| m.0),
            x[KALMAN],
            d,
            speed,
            blend.by_speed(),
        );
        match made {
            Some((value, std)) => {
                let p = Point {
                    value: value + correction,
                    std,
                    distance: d,
                };
                self.causal.push(p);
                self.delay.push(p);
            }
            None => self.delay.push(kalman),
        }
        if let Some((value, std)) = lagged {
            self.lagged.push(Point {
                value,
                std,
                distance: d,
            });
        }
    }

    /// A new estimate of the conicity at `speed`: the likelihood's, averaged with the features'
    /// by its fit and their agreement ([`super::spectral::share`]); the output moves to it from
    /// the conicity the filter has now (the features' estimate before the first).
    fn update_spectral(&mut self, speed: f64) {
        let (Some(model), Some(s), Some(m)) = (
            &self.selection.contact,
            self.spectral.as_mut(),
            self.moments.as_ref(),
        ) else {
            return;
        };
        let models: Vec<(f64, &super::spectral::Spectra)> = model
            .speeds
            .iter()
            .filter_map(|m| Some((m.speed, m.spectra.as_ref()?)))
            .collect();
        let before = if self.conicity > 0.0 {
            self.conicity.ln()
        } else {
            model
                .conicity_range
                .map_or(0.0, |[lo, hi]| 0.5 * (lo.ln() + hi.ln()))
        };
        let Some(reading) = s.update(speed, &models) else {
            return;
        };
        let x = reading.ln_c;
        let features = model
            .estimate_told(
                m,
                None,
                self.told_kalker,
                self.selection.conicity_range(),
                false,
            )
            .and_then(|c| c.conicity)
            .map(f64::ln);
        let target = match features {
            Some(f) => {
                let w = super::spectral::share(reading.cells, x - f, reading.dispersion);
                w * x + (1.0 - w) * f
            }
            None => x,
        };
        s.aim(target, before);
    }

    /// Adds the conicity of `cells` closed cells ending at `distance` to the judged one: the
    /// one told at once; an estimate from where the features' memory is full (`memory_full`),
    /// before which its scatter set `outside_training` at the start of runs on the conicity
    /// the taps were fitted at (10 of 15 validation runs from 100 m on).
    fn judge_conicity(&mut self, distance: f64, cells: usize, memory_full: bool) {
        if self.conicity <= 0.0 {
            return;
        }
        let x = self.conicity.ln();
        if self.told_conicity.is_some() {
            self.judged_conicity = Some(x);
            return;
        }
        if !memory_full {
            return;
        }
        let step = cells as f64 * self.grid.step_length();
        match self.judged_conicity {
            None => {
                self.judged_conicity = Some(x);
                self.judged_from = distance;
            }
            Some(y) => {
                let span = (distance - self.judged_from + step).min(CONICITY_MEMORY);
                self.judged_conicity = Some(y + step / span * (x - y));
            }
        }
    }

    /// The causal estimate at `distance` and its standard deviation; `None` while there is
    /// none (start of the run, speed outside the taps' range).
    pub fn causal(&self, distance: f64) -> Option<(f64, f64)> {
        self.causal.at(distance)
    }

    /// The Kalman filter's alignment estimate made at the fixed-lag output's position, `lag`
    /// metres behind `distance`; `None` before the first closed cell and without a fixed-lag
    /// output.
    pub fn kalman_lagged(&self, distance: f64) -> Option<f64> {
        self.kalman_delay.at(distance - self.lag()).map(|(a, _)| a)
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

//! Which of a bank's entries the learned filter runs: the sensor set and lag the FMU's
//! parameters choose, by speed and by contact condition.

use super::bank::{Bank, Entry};
use super::contact::ContactModel;
use super::error::{LearnedError, Taps};
use super::grid::{CHANNELS, ROLL_RATE};
use super::stage::StageTaps;
use super::window::Windows;
use serde::{Deserialize, Serialize};

/// What [`super::Learned::new`] needs to know of the FMU's configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// Use the taps fitted with the wheelset roll-rate gyroscope.
    pub roll_rate: bool,
    /// The fixed-lag output's lag \[m\] (0: none).
    pub lag: f64,
    /// The wheels' equivalent conicity, when known (`conicity` parameter): the taps are
    /// blended at it instead of at the one estimated from the sensors. `None` or 0: estimate.
    pub conicity: Option<f64>,
    /// The wheel-rail contact's Kalker-coefficient scale, when known (`kalker_scale`
    /// parameter): the taps are blended at it instead of at the estimated `contact_scale`.
    /// `None` or 0: estimate.
    pub kalker: Option<f64>,
}

/// The bank's entries for one sensor set and lag, by speed, then by contact condition.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct Selection {
    pub(super) speeds: Vec<f64>,
    /// Contact conditions (Kalker-coefficient scales, ascending); empty without a contact
    /// model (one set of windows per speed).
    pub(super) conditions: Vec<f64>,
    /// The conicities of the entries (ascending); empty in a bank without conicity
    /// conditions. With them, a speed's windows are conicity-major: `conicity index *
    /// conditions.len() + condition index`.
    pub(super) conicities: Vec<f64>,
    pub(super) causal: Vec<Vec<Windows>>,
    pub(super) lagged: Vec<Vec<Windows>>,
    pub(super) contact: Option<ContactModel>,
    /// The fixed-lag output's lag in grid points (0: none).
    pub(super) lag: usize,
    pub(super) uses_roll_rate: bool,
    pub(super) sample_step: f64,
    /// The long-wave stage's taps for this sensor set, one per speed of `speeds`, when the
    /// bank has them ([`super::stage`]).
    pub(super) stage: Option<StageTaps>,
}

impl Selection {
    /// The bank's entries for `choice`: the sensor set with or without the roll-rate channel
    /// and, for the fixed-lag output, the lag the bank holds nearest `choice.lag` (refused
    /// unless within half a grid step of it).
    pub(super) fn new(bank: &Bank, choice: Choice) -> Result<Selection, LearnedError> {
        let causal = of_set(bank, choice.roll_rate, 0);
        if causal.is_empty() {
            return Err(LearnedError::NoCausal {
                roll_rate: choice.roll_rate,
            });
        }
        let conditions = conditions(bank, &causal);
        let conicities = conicities(&causal);
        let grid = Conditions {
            kalker: &conditions,
            conicities: &conicities,
        };
        let (speeds, causal) = by_speed(&causal, &grid, Taps::Causal)?;
        let (lag, lagged) = if choice.lag > 0.0 {
            let l = nearest_lag(bank, choice)?;
            let taps = Taps::Lagged(l as f64 * bank.grid);
            let (at, windows) = by_speed(&of_set(bank, choice.roll_rate, l), &grid, taps)?;
            if at != speeds {
                return Err(LearnedError::LagSpeeds { taps });
            }
            (l, windows)
        } else {
            (0, vec![])
        };
        let contact = bank.contact.clone().filter(|_| !conditions.is_empty());
        let sensors = &CHANNELS[..if choice.roll_rate { 4 } else { 3 }];
        let stage = bank
            .stage
            .as_ref()
            .and_then(|st| StageTaps::select(st, sensors, &speeds));
        Ok(Selection {
            speeds,
            conditions,
            conicities,
            causal,
            lagged,
            contact,
            lag,
            uses_roll_rate: choice.roll_rate,
            sample_step: bank.provenance.sample_step,
            stage,
        })
    }

    /// The lowest and highest conicity of the selected taps; `None` without conicity
    /// conditions.
    pub(super) fn conicity_range(&self) -> Option<[f64; 2]> {
        Some([*self.conicities.first()?, *self.conicities.last()?])
    }

    /// The most cells of history any selected window reads (at least 1).
    pub(super) fn longest(&self) -> usize {
        self.causal
            .iter()
            .chain(&self.lagged)
            .flatten()
            .map(Windows::longest)
            .max()
            .unwrap_or(1)
            .max(1)
    }
}

/// Whether an entry reads the roll-rate channel.
fn uses_roll(e: &Entry) -> bool {
    e.channels.iter().any(|c| c == CHANNELS[ROLL_RATE])
}

/// The entries of one sensor set and lag (grid points).
fn of_set(bank: &Bank, roll_rate: bool, lag: usize) -> Vec<&Entry> {
    bank.entries
        .iter()
        .filter(|e| uses_roll(e) == roll_rate && e.lag == lag)
        .collect()
}

/// The contact conditions of the causal entries, ascending; none without a contact model.
fn conditions(bank: &Bank, causal: &[&Entry]) -> Vec<f64> {
    if bank.contact.is_none() {
        return vec![];
    }
    let mut c: Vec<f64> = causal.iter().filter_map(|e| e.condition).collect();
    c.sort_by(f64::total_cmp);
    c.dedup();
    c
}

/// The conicities of the causal entries, ascending; none in a bank without them.
fn conicities(causal: &[&Entry]) -> Vec<f64> {
    let mut c: Vec<f64> = causal.iter().filter_map(|e| e.conicity).collect();
    c.sort_by(f64::total_cmp);
    c.dedup();
    c
}

/// The conditions a speed's windows are laid out by: conicity-major, then Kalker scale.
struct Conditions<'a> {
    kalker: &'a [f64],
    conicities: &'a [f64],
}

/// How far apart two conditions are, for the stand-in of a condition left out at a speed: a
/// conicity ratio of 1.5 counts as a Kalker-scale difference of 0.25 (one bank step of each).
fn apart(e: &Entry, conicity: Option<f64>, kalker: Option<f64>) -> f64 {
    let dk = match (e.condition, kalker) {
        (Some(a), Some(b)) => (a - b).abs() / 0.25,
        _ => 0.0,
    };
    let dc = match (e.conicity, conicity) {
        (Some(a), Some(b)) => (a / b).ln().abs() / 1.5f64.ln(),
        _ => 0.0,
    };
    dk + dc
}

/// The bank's fixed lag (grid points) nearest `choice.lag`, if within half a grid step.
fn nearest_lag(bank: &Bank, choice: Choice) -> Result<usize, LearnedError> {
    let want = choice.lag / bank.grid;
    let mut lags: Vec<usize> = bank
        .entries
        .iter()
        .filter(|e| uses_roll(e) == choice.roll_rate && e.lag > 0)
        .map(|e| e.lag)
        .collect();
    lags.sort();
    lags.dedup();
    let best = lags.iter().copied().min_by(|a, b| {
        (*a as f64 - want)
            .abs()
            .total_cmp(&(*b as f64 - want).abs())
    });
    match best {
        Some(l) if (l as f64 - want).abs() <= 0.5 => Ok(l),
        _ => Err(LearnedError::Lag {
            lag: choice.lag,
            held: lags.iter().map(|l| *l as f64 * bank.grid).collect(),
            roll_rate: choice.roll_rate,
        }),
    }
}

/// The windows of `entries` by ascending speed, and per speed one per condition of `grid`
/// (the entry of the nearest condition at that speed: a condition left out there, where the
/// vehicle is unstable, has a stand-in), or the single entry of each speed without
/// conditions; `taps` names the entries in errors.
#[allow(clippy::type_complexity)]
fn by_speed(
    entries: &[&Entry],
    grid: &Conditions,
    taps: Taps,
) -> Result<(Vec<f64>, Vec<Vec<Windows>>), LearnedError> {
    let mut speeds: Vec<f64> = entries.iter().map(|e| e.speed).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let kalker: Vec<Option<f64>> = if grid.kalker.is_empty() {
        vec![None]
    } else {
        grid.kalker.iter().copied().map(Some).collect()
    };
    let conicities: Vec<Option<f64>> = if grid.conicities.is_empty() {
        vec![None]
    } else {
        grid.conicities.iter().copied().map(Some).collect()
    };
    let mut table = vec![];
    for v in &speeds {
        let at: Vec<&Entry> = entries.iter().copied().filter(|e| e.speed == *v).collect();
        if grid.kalker.is_empty() && grid.conicities.is_empty() {
            if at.len() > 1 {
                return Err(LearnedError::TwoEntries { taps, speed: *v });
            }
            table.push(vec![Windows::of(at[0])]);
            continue;
        }
        let mut row = vec![];
        for c in &conicities {
            for k in &kalker {
                let nearest = at
                    .iter()
                    .min_by(|a, b| apart(a, *c, *k).total_cmp(&apart(b, *c, *k)))
                    .expect("an entry at this speed");
                row.push(Windows::of(nearest));
            }
        }
        table.push(row);
    }
    Ok((speeds, table))
}

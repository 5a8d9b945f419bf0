//! The studies' vehicle records and the estimator run over them: what every study (the
//! variants, the learned FIR smoother, the tap fit) takes as its data, in a module of its own
//! so that none of them depends on another for it.

use super::runs::{Fmus, STEP, Settings, SpeedProfile, vehicle_run_stepped};
use crate::Error;
use fmu_estimator::offline::{self, Sample};
use orchestrator::master::Table;
use serde::Serialize;
use std::path::Path;

/// The vehicle variables a record holds.
const RECORDED: [&str; 6] = [
    "forward_speed",
    "ws_acc_y",
    "ws_yaw_rate",
    "frame_acc_y",
    "distance",
    "alignment",
];

/// One vehicle run: the estimator's inputs and the truth.
#[derive(Debug, Clone)]
pub struct Record {
    /// The estimator's inputs, one per communication step (the run's first row, the initial
    /// values, left out).
    pub samples: Vec<Sample>,
    /// The vehicle's distance travelled at each sample \[m\].
    pub distance: Vec<f64>,
    /// The true alignment the leading wheelset meets at each sample \[m\].
    pub alignment: Vec<f64>,
}

impl Record {
    /// The first `n` samples.
    pub fn head(&self, n: usize) -> Record {
        self.part(0, n)
    }

    /// The record from sample `from` on.
    pub fn tail(&self, from: usize) -> Record {
        self.part(from, self.samples.len())
    }

    /// Samples `from..to`, both clamped to the record.
    fn part(&self, from: usize, to: usize) -> Record {
        let to = to.min(self.samples.len());
        let from = from.min(to);
        Record {
            samples: self.samples[from..to].to_vec(),
            distance: self.distance[from..to].to_vec(),
            alignment: self.alignment[from..to].to_vec(),
        }
    }
}

/// Runs the vehicle alone with `settings` for `stop` seconds, its speed input from `speed` (or
/// its default, 20 m/s), and returns the record.
pub fn record(
    fmus: &Fmus,
    settings: Settings,
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
) -> Result<Record, Error> {
    record_with(fmus, settings, stop, speed, None)
}

/// [`record`], also recording the vehicle's `extra` column as the samples' roll rate
/// (`ws_roll_rate`, for the learned filter's four-sensor taps).
pub fn record_with(
    fmus: &Fmus,
    settings: Settings,
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
    roll_rate: Option<&str>,
) -> Result<Record, Error> {
    Ok(record_table(fmus, settings, stop, speed, roll_rate, &[])?.0)
}

/// [`record_with`] with the communication step `step` (the sensors' sample step).
pub fn record_stepped(
    fmus: &Fmus,
    settings: Settings,
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
    roll_rate: Option<&str>,
    step: f64,
) -> Result<Record, Error> {
    Ok(record_table_at(fmus, settings, stop, speed, roll_rate, &[], step)?.0)
}

/// [`record_with`], also recording the vehicle's variables `more`: the record and the table
/// of every recorded column.
pub fn record_table(
    fmus: &Fmus,
    settings: Settings,
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
    roll_rate: Option<&str>,
    more: &[&str],
) -> Result<(Record, Table), Error> {
    record_table_at(fmus, settings, stop, speed, roll_rate, more, STEP)
}

/// [`record_table`] with the communication step `step`.
fn record_table_at(
    fmus: &Fmus,
    settings: Settings,
    stop: f64,
    speed: Option<SpeedProfile<'_>>,
    roll_rate: Option<&str>,
    more: &[&str],
    step: f64,
) -> Result<(Record, Table), Error> {
    let mut variables = RECORDED.to_vec();
    variables.extend(roll_rate);
    variables.extend(more);
    let table = vehicle_run_stepped(fmus, settings, &variables, stop, speed, step)?;
    let mut rec = from_table(&table)?;
    if let Some(name) = roll_rate {
        let col = table
            .column(&format!("vehicle.{name}"))
            .ok_or_else(|| Error::Input(format!("no column vehicle.{name}")))?;
        rec.samples = Sample::with_roll_rate(rec.samples, &col[1..]);
    }
    Ok((rec, table))
}

/// The record from a table of the vehicle's variables (row 0, the initial values, dropped: row
/// `k` holds the samples at the end of step `k`).
fn from_table(table: &Table) -> Result<Record, Error> {
    let c = |n: &str| {
        table
            .column(&format!("vehicle.{n}"))
            .map(|x| x[1..].to_vec())
            .ok_or_else(|| Error::Input(format!("no column vehicle.{n}")))
    };
    let (speed, acc, yaw, frame) = (
        c("forward_speed")?,
        c("ws_acc_y")?,
        c("ws_yaw_rate")?,
        c("frame_acc_y")?,
    );
    Ok(Record {
        samples: Sample::from_columns(&speed, &acc, &yaw, &frame),
        distance: c("distance")?,
        alignment: c("alignment")?,
    })
}

/// The estimator FMU's output a variant is judged on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Output {
    /// `alignment` at `distance`.
    Alignment,
    /// `alignment_lagged` at `distance_lagged` (the learned filter's fixed lag).
    Lagged,
}

impl Output {
    pub(crate) fn is_alignment(&self) -> bool {
        *self == Output::Alignment
    }
}

/// The estimator with `settings` (and the calibration file `calibration`, else its built-in one)
/// over `samples` at step `h`: the distance it integrates and its alignment estimate per sample,
/// the RTS smoother's if `smooth`, else the causal filter's.
pub fn estimate(
    samples: &[Sample],
    h: f64,
    settings: &[(String, String)],
    calibration: Option<&Path>,
    smooth: bool,
) -> Result<(Vec<f64>, Vec<f64>), Error> {
    let values = offline::settings(settings)?;
    let (config, _) = offline::config(&values, calibration)?;
    let out = offline::process(&config, h, samples, smooth)?;
    let est = if smooth {
        out.smoothed
            .ok_or_else(|| Error::input("the estimator returned no smoothed estimate"))?
    } else {
        out.filtered
    };
    Ok((out.distance, est.into_iter().map(|e| e.0).collect()))
}

/// The estimator FMU's learned filter (`estimator` 2) with `settings` over `samples`, as the
/// FMU runs it (the built-in tap bank): all it computes (the estimates, `outside_training`),
/// and its lag \[m\].
pub fn run_learned(
    samples: &[Sample],
    h: f64,
    settings: &[(String, String)],
) -> Result<(offline::Processed, f64), Error> {
    let values = offline::settings(settings)?;
    let (config, _) = offline::config(&values, None)?;
    let learned = offline::learned(&values, &config)?
        .ok_or_else(|| Error::input("the settings do not select the learned filter"))?;
    let lag = learned.lag();
    let out = offline::process_learned(&config, Some(learned), h, samples, false)?;
    Ok((out, lag))
}

/// The learned filter's positions, `alignment` and `outside_training` per sample.
pub type Flagged = (Vec<f64>, Vec<f64>, Vec<bool>);

/// [`run_learned`]'s `alignment` at its positions, with its `outside_training`.
pub fn flagged_learned(
    samples: &[Sample],
    h: f64,
    settings: &[(String, String)],
) -> Result<Flagged, Error> {
    let (out, _) = run_learned(samples, h, settings)?;
    let est = out
        .learned
        .ok_or_else(|| Error::input("no learned estimate"))?
        .iter()
        .map(|e| e.alignment)
        .collect();
    Ok((out.distance, est, out.outside_training))
}

/// The share of `flags` set.
pub fn share_of(flags: &[bool]) -> f64 {
    flags.iter().filter(|f| **f).count() as f64 / flags.len().max(1) as f64
}

/// The estimator FMU's learned filter (`estimator` 2) with `settings` over `samples`: the
/// positions and values of `output`, as the FMU computes them (the built-in tap bank).
pub fn estimate_learned(
    samples: &[Sample],
    h: f64,
    settings: &[(String, String)],
    output: Output,
) -> Result<(Vec<f64>, Vec<f64>), Error> {
    let (out, lag) = run_learned(samples, h, settings)?;
    let est = out
        .learned
        .ok_or_else(|| Error::input("no learned estimate"))?;
    Ok(match output {
        Output::Alignment => (out.distance, est.iter().map(|e| e.alignment).collect()),
        Output::Lagged => {
            if lag <= 0.0 {
                return Err(Error::input("the lagged output needs lag > 0"));
            }
            (
                out.distance.iter().map(|d| d - lag).collect(),
                est.iter().map(|e| e.lagged).collect(),
            )
        }
    })
}

//! `alignment-studies learn`: fits the learned FIR estimator on runs of the vehicle FMU and
//! saves it (JSON) for `smooth --learned`.

use super::{CALIBRATION_SEED, Report, StandardFmus};
use crate::Error;
use crate::report::learned::LearnOptions;
use clap::Args;
use std::path::PathBuf;

/// `learn`'s options.
#[derive(Args, Clone, Debug)]
pub struct LearnArgs {
    /// The vehicle and estimator FMUs the training runs use.
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// Track seed of the training run.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub seed: u32,
    /// Length of the training run in s, more than 40.
    #[arg(long, default_value_t = 1000.0, allow_negative_numbers = true, value_parser = orchestrator::cli::positive)]
    pub stop: f64,
    /// Look-ahead in m (rounded to grid points) for an on-board filter combined with the
    /// paper's causal filter, 0 for a causal one; absent: the offline smoother (60 m each
    /// way) with the shaping filter's RTS smoother.
    #[arg(long, allow_negative_numbers = true, value_parser = super::lag)]
    pub lag: Option<f64>,
    /// Grid step along the track in m the sensors are decimated to (finer costs more: the
    /// window is 60 m whatever the step).
    #[arg(long, default_value_t = crate::study::learned::SMOOTHER_GRID, allow_negative_numbers = true, value_parser = positive_m)]
    pub grid: f64,
    /// Kalker-coefficient scales of the vehicle to train on, one run each (e.g. 1,0.5 for a
    /// filter robust to the wheel-rail contact; 1: the vehicle as it is).
    #[arg(long, value_delimiter = ',', default_value = "1", allow_negative_numbers = true, value_parser = super::kalker_scale)]
    pub kalker_scales: Vec<f64>,
    /// Constant speed of the training runs in m/s (default: the vehicle's, 20); the filter
    /// applies to records at this speed only.
    #[arg(long, allow_negative_numbers = true, value_parser = super::speed)]
    pub speed: Option<f64>,
    /// The file to write.
    #[arg(long, default_value = "out/learned.json")]
    pub out: PathBuf,
    /// Replace an existing file at --out that this command did not write (never an input, a
    /// symlink, a FIFO or a directory).
    #[arg(long)]
    pub force: bool,
}

/// How every saved smoother begins ([`crate::study::learned::LearnedSmoother::to_json`]).
const MARK: &[u8] = b"{\n  \"format\": ";

/// Fits the learned FIR smoother ([`crate::report::learned::learn`]).
pub fn execute(a: &LearnArgs) -> Result<Report, Error> {
    let inputs = [a.fmus.vehicle.as_path(), a.fmus.estimator.as_path()];
    let guard = super::guard(&a.out, &inputs, a.force, Some(MARK))?;
    let options = LearnOptions {
        seed: a.seed,
        stop: a.stop,
        lag: a.lag,
        grid: a.grid,
        kalker_scales: a.kalker_scales.clone(),
        speed: a.speed,
    };
    let mut report = crate::report::learned::learn(&a.fmus.fmus(), &options, &a.out)?;
    report.guarded.push(guard);
    Ok(report)
}

/// A length in m: a finite number above zero.
fn positive_m(s: &str) -> Result<f64, Error> {
    orchestrator::cli::positive(s)
        .map_err(|_| Error::input("expected a finite number of metres above zero"))
}

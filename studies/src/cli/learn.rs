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
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// Track seed of the training run.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub seed: u32,
    /// Length of the training run \[s\], more than 40.
    #[arg(long, default_value_t = 1000.0)]
    pub stop: f64,
    /// Look-ahead \[m\] (rounded to grid points) for an on-board filter combined with the
    /// paper's causal filter, 0 for a causal one; absent: the offline smoother (60 m each
    /// way) with the shaping filter's RTS smoother.
    #[arg(long)]
    pub lag: Option<f64>,
    /// Grid step along the track \[m\] the sensors are decimated to (finer costs more: the
    /// window is 60 m whatever the step).
    #[arg(long, default_value_t = crate::study::learned::SMOOTHER_GRID)]
    pub grid: f64,
    /// Kalker-coefficient scales of the vehicle to train on, one run each (e.g. 1,0.5 for a
    /// filter robust to the wheel-rail contact; 1: the vehicle as it is).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub kalker_scales: Vec<f64>,
    /// Constant speed of the training runs [m/s] (default: the vehicle's, 20); the filter
    /// applies to records at this speed only.
    #[arg(long)]
    pub speed: Option<f64>,
    /// The file to write.
    #[arg(long, default_value = "out/learned.json")]
    pub out: PathBuf,
}

/// Fits the learned FIR smoother ([`crate::report::learned::learn`]).
pub fn execute(a: &LearnArgs) -> Result<Report, Error> {
    let options = LearnOptions {
        seed: a.seed,
        stop: a.stop,
        lag: a.lag,
        grid: a.grid,
        kalker_scales: a.kalker_scales.clone(),
        speed: a.speed,
    };
    crate::report::learned::learn(&a.fmus.fmus(), &options, &a.out)
}

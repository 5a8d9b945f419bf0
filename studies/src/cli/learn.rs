//! `alignment-studies learn`: fits the learned FIR estimator on runs of the vehicle FMU and
//! saves it (JSON) for `smooth --learned`.

use super::{CALIBRATION_SEED, Report, StandardFmus};
use crate::Error;
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
    /// Length of the training run [s], more than 40.
    #[arg(long, default_value_t = 1000.0)]
    pub stop: f64,
    /// Look-ahead [m] (rounded to grid points) for an on-board filter combined with the
    /// paper's causal filter, 0 for a causal one; absent: the offline smoother (60 m each
    /// way) with the shaping filter's RTS smoother.
    #[arg(long)]
    pub lag: Option<f64>,
    /// Grid step along the track [m] the sensors are decimated to (finer costs more: the
    /// window is 60 m whatever the step).
    #[arg(long, default_value_t = crate::study::learned::GRID)]
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

pub fn learn(a: &LearnArgs) -> Result<Report, Error> {
    use crate::study::learned::{
        Lookahead, WINDOW, decimation, default_partner, learn, training_runs, validation,
    };
    use crate::study::runs::{STEP, STOP};
    use crate::study::variants;
    let (grid, out) = (a.grid, &a.out);
    // The grid the filter will have (a whole number of samples), checked before the runs.
    let speed = a.speed.unwrap_or(20.0);
    let grid =
        STEP * speed * decimation(speed, grid).map_err(|e| format!("--grid: {e}"))? as f64;
    let lookahead = match a.lag {
        None => Lookahead::Smoother,
        Some(m) if (0.0..=WINDOW).contains(&m) => Lookahead::FixedLag((m / grid).round() as usize),
        Some(m) => {
            return Err(Error::Input(format!(
                "--lag must be between 0 and {WINDOW} m (the window), not {m}"
            )));
        }
    };
    let (runs, provenance) = training_runs(
        &a.fmus.fmus(),
        a.seed,
        a.stop,
        &a.kalker_scales,
        a.speed,
    )
    ?;
    // The shaping filter's virtual-measurement sigma, chosen as the study does, on the first
    // 20 s of the (first) training run.
    let (sigma, _) =
        variants::tune_prior_sigma(&validation(&runs[0]), 3, &[], None)?;
    let (l, j) = learn(
        &runs,
        &provenance,
        lookahead,
        grid,
        default_partner(lookahead, sigma),
    )
    ?;
    let ahead = match l.lookahead {
        Lookahead::Smoother => format!("smoother, {WINDOW} m each way"),
        Lookahead::FixedLag(n) => format!("look-ahead {} m", n as f64 * l.grid()),
    };
    let markdown = format!(
        "learned FIR ({ahead}, grid {} m) at {} m/s: {}; split {} m with {} (whole Jrel on the first {} s: {j:.3}); wrote {}",
        l.grid(),
        l.speed,
        l.provenance,
        l.split,
        l.partner.name,
        STOP,
        out.display()
    );
    let mut report = Report {
        markdown,
        ..Report::default()
    };
    report.file(out.clone(), l.to_json());
    Ok(report)
}

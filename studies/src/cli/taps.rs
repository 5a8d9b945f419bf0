//! `alignment-studies taps`: fits the estimator FMU's learned filter (the tap bank,
//! resources/learned.taps) in the metric's bands.

use super::{CALIBRATION_SEED, Report, StandardFmus};
use crate::Error;
use clap::Args;
use std::path::PathBuf;

/// `taps`' options.
#[derive(Args, Clone, Debug)]
pub struct TapsArgs {
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// Speeds of the bank [m/s].
    #[arg(long, value_delimiter = ',', default_value = "5,10,15,20,25,30")]
    pub speeds: Vec<f64>,
    /// Kalker-coefficient scales of the training runs (one run each): each condition gets its
    /// own taps, blended at run time by the contact model fitted with them.
    #[arg(long, value_delimiter = ',', default_value = "1,0.75,0.5")]
    pub kalker_scales: Vec<f64>,
    /// One set of taps fitted on every condition's runs at once, no contact model.
    #[arg(long)]
    pub pooled: bool,
    /// Lags of the fixed-lag entries [m].
    #[arg(long, value_delimiter = ',', default_value = "10")]
    pub lags: Vec<f64>,
    /// Fit only the three-sensor taps (the vehicle has no ws_roll_rate).
    #[arg(long)]
    pub no_roll_rate: bool,
    /// Track seed of the training runs.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub seed: u32,
    /// Track seeds the ridge is chosen on (neither the training seed nor an evaluation seed).
    #[arg(long, value_delimiter = ',', default_value = "102,103,104,105,106")]
    pub validation_seeds: Vec<u32>,
    /// The file to write.
    #[arg(long, default_value = "fmu-estimator/resources/learned.taps")]
    pub out: PathBuf,
}

pub fn taps(a: &TapsArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    use crate::study::learned::taps::{Options, fit};
    let mut o = Options::shipped();
    o.speeds = a.speeds.clone();
    o.kalker_scales = a.kalker_scales.clone();
    o.per_condition = !a.pooled;
    o.lags = a.lags.clone();
    o.roll_rate = !a.no_roll_rate;
    o.training_seed = a.seed;
    o.validation_seeds = a.validation_seeds.clone();
    let defaults = Options::shipped();
    if (
        o.speeds.clone(),
        o.kalker_scales.clone(),
        o.per_condition,
        o.lags.clone(),
        o.roll_rate,
        o.training_seed,
        o.validation_seeds.clone(),
    ) != (
        defaults.speeds,
        defaults.kalker_scales,
        defaults.per_condition,
        defaults.lags,
        defaults.roll_rate,
        defaults.training_seed,
        defaults.validation_seeds,
    ) {
        o.command = std::env::args().collect::<Vec<_>>().join(" ");
    }
    let started = std::time::Instant::now();
    let bank = fit(&a.fmus.fmus(), &o, log)?;
    let mut lines = vec![];
    for m in bank.contact.iter().flat_map(|c| &c.speeds) {
        lines.push(format!(
            "{:>5} m/s contact model: rms error of the Kalker scale on the validation runs {:.3}",
            m.speed, m.rms_error
        ));
    }
    for e in &bank.entries {
        let w = e.windows.last().expect("full window");
        let condition = e
            .condition
            .map(|c| format!("Kalker {:>3} %", c * 100.0))
            .unwrap_or_default();
        lines.push(format!(
            "{:>5} m/s {condition} {:<48} lag {:>4} m: ridge {:.0e}, validation objective {:.4}, rms error {:.3} mm",
            e.speed,
            e.channels.join(","),
            e.lag as f64 * bank.grid,
            e.ridge,
            e.validation_objective,
            w.rms_error * 1e3
        ));
    }
    let mut report = Report {
        markdown: lines.join("\n"),
        note: format!(
            "tap bank in {:.1} s; wrote {}",
            started.elapsed().as_secs_f64(),
            a.out.display()
        ),
        ..Report::default()
    };
    report.file(a.out.clone(), bank.to_bytes());
    Ok(report)
}

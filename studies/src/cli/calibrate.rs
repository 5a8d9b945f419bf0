//! `alignment-studies calibrate`: identifies the simplified model and calibrates the filter on
//! one track seed, and writes the estimator's calibration file.

use super::{CALIBRATION_SEED, Report, StudyFmus};
use crate::Error;
use crate::report::written::StudyDir;
use clap::Args;
use std::path::PathBuf;

/// The calibration the estimator's build reads.
const SHIPPED: &str = "fmu-estimator/resources/calibration.toml";

/// `calibrate`'s options.
#[derive(Args, Clone, Debug)]
pub struct CalibrateArgs {
    /// The FMUs and the user's settings (another vehicle's, for its own calibration).
    #[command(flatten)]
    pub fmus: StudyFmus,
    /// The calibration file to write (default: the shipped one,
    /// fmu-estimator/resources/calibration.toml; required with --set, which makes a
    /// calibration for another vehicle).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Track seed of the identification and calibration runs (not the vehicle's default
    /// track, seed 1, so that a plain `run` of the standard case is a held-out track).
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub seed: u32,
    /// Directory for the figure of the identification (model_adjustment.svg).
    #[arg(long, default_value = "out/study")]
    pub plots: PathBuf,
    /// Replace an existing file at --out, or a figure's name in --plots, that this command did
    /// not write (never an input, a symlink, a FIFO or a directory).
    #[arg(long)]
    pub force: bool,
}

/// How every calibration file begins ([`crate::study::calibrate::to_toml`]).
const MARK: &[u8] =
    b"# Calibration of the AlignmentEstimator FMU, written by `alignment-studies calibrate`.";

/// Checks the settings and the file to write (the shipped calibration only without `--set`),
/// then identifies, calibrates and tunes ([`crate::report::calibration`]); `log` gets each
/// stage's figures as it ends.
pub fn execute(a: &CalibrateArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    if let Some(s) = a.fmus.set.iter().find(|s| s.starts_with("estimator.")) {
        return Err(Error::Input(format!(
            "--set {s}: calibrate builds the estimator's parameters and noise itself; --set takes vehicle settings here"
        )));
    }
    let out = match (&a.out, a.fmus.set.is_empty()) {
        (Some(out), _) => out.clone(),
        (None, true) => PathBuf::from(SHIPPED),
        (None, false) => {
            return Err(Error::Input(
                "--out is required with --set: a calibration for another vehicle must not replace the shipped one".into(),
            ));
        }
    };
    let inputs = [
        a.fmus.fmus.vehicle.as_path(),
        a.fmus.fmus.estimator.as_path(),
    ];
    let guard = super::guard(&out, &inputs, a.force, Some(MARK))?;
    let plots = StudyDir::check(
        &a.plots,
        &[crate::report::calibration::FIGURE.to_string()],
        a.force,
    )?;
    let mut report =
        crate::report::calibration::calibration(&a.fmus.fmus()?, a.seed, out, &a.plots, log)?;
    report.guarded.push(guard);
    report.study_dir = Some(plots);
    Ok(report)
}

//! `alignment-studies calibrate`: identifies the simplified model and calibrates the filter on
//! one track seed, and writes the estimator's calibration file.

use super::{CALIBRATION_SEED, Report, StudyFmus};
use crate::Error;
use crate::study::{calibrate, identify, plot, runs};
use clap::Args;
use std::path::PathBuf;

/// The calibration the estimator's build reads.
const SHIPPED: &str = "fmu-estimator/resources/calibration.toml";

#[derive(Args, Clone, Debug)]
pub struct CalibrateArgs {
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
}

/// Identifies, calibrates and tunes; `log` gets each stage's figures as it ends. The report's
/// file is the calibration.
pub fn calibrate(a: &CalibrateArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
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
    let seed = a.seed;
    let fmus = a.fmus.fmus()?;
    let vehicle = fmus.vehicle_params()?;
    let id = identify::identify(&fmus, &vehicle, seed, runs::STOP, runs::STEP)?;
    let p = &id.params;
    log(&format!(
        "identified on seed {seed} ({} evaluations): kx {:.4e} N/m, cx {:.4e} N s/m, ky {:.4e} N/m, cy {:.4e} N s/m (Table 2: 7.95e5, 1.47e4, 4.12e6, 1.41e5)",
        id.evaluations, p.kx, p.cx, p.ky, p.cy
    ));
    log(&format!(
        "misfit J_ls {:.4} (with Table 2's values {:.4})",
        id.cost, id.cost_table_2
    ));
    std::fs::create_dir_all(&a.plots)
        .map_err(|e| Error::Io(format!("cannot create {}: {e}", a.plots.display())))?;
    let figure = a.plots.join("model_adjustment.svg");
    plot::model_adjustment(&figure, &id).map_err(Error::Io)?;
    log(&format!("wrote {}", figure.display()));
    let cal = calibrate::calibrate(&fmus, &id.params, seed, runs::STOP, runs::STEP)?;
    let r = cal.r.diagonal().map(f64::sqrt);
    log(&format!(
        "calibrated on seed {seed}: sqrt(diag R) = [{:.3e}, {:.3e}, {:.3e}, {:.3e}]",
        r[0], r[1], r[2], r[3]
    ));
    let cal = calibrate::tune(&fmus, &cal, runs::STOP)?;
    log(&format!(
        "tuned on seed {seed}: virtual measurement variance x {:e}, alignment process noise x {:e}: whole-band Jrel there {:.4}",
        cal.virtual_scale,
        cal.xi_scale,
        cal.tuned_jrel.unwrap_or(f64::NAN)
    ));
    let cal = calibrate::tune_prior(&fmus, &cal)?;
    log(&format!(
        "8-state prior (integrated random walk) on seed {seed}: prior_sigma_xi {} m (whole-band Jrel there {:.4})",
        cal.prior_sigma_xi.unwrap_or(f64::NAN),
        cal.prior_jrel.unwrap_or(f64::NAN)
    ));
    let mut report = Report {
        figures: vec![figure],
        markdown: format!(
            "wrote {} (rebuild the estimator FMU: cargo xtask fmu)",
            out.display()
        ),
        ..Report::default()
    };
    report.file(out, calibrate::to_toml(&cal, seed, calibrate::PROVENANCE));
    Ok(report)
}

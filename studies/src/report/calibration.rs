//! Identification of the simplified model and calibration of the filter on one track seed
//! (`alignment-studies calibrate`): the report's file is the estimator's calibration file, its
//! figure the identification's fit.

use super::{Report, create_dir};
use crate::Error;
use crate::study::runs::{self, Fmus};
use crate::study::{calibrate, identify, plot};
use std::path::{Path, PathBuf};

/// The identification's figure, in the `--plots` directory.
pub const FIGURE: &str = "model_adjustment.svg";

/// Identifies `kx, cx, ky, cy`, calibrates Q and R, tunes the virtual measurement and the
/// 8-state prior, all on track `seed`, and returns the calibration file for `out` with the
/// figure `plots/model_adjustment.svg`. `log` gets each stage's figures as it ends.
pub fn calibration(
    fmus: &Fmus,
    seed: u32,
    out: PathBuf,
    plots: &Path,
    log: &dyn Fn(&str),
) -> Result<Report, Error> {
    let vehicle = fmus.vehicle_params()?;
    let id = identify::identify(fmus, &vehicle, seed, runs::STOP, runs::STEP)?;
    let p = &id.params;
    log(&format!(
        "identified on seed {seed} ({} evaluations): kx {:.4e} N/m, cx {:.4e} N s/m, ky {:.4e} N/m, cy {:.4e} N s/m (Table 2: 7.95e5, 1.47e4, 4.12e6, 1.41e5)",
        id.evaluations, p.kx, p.cx, p.ky, p.cy
    ));
    log(&format!(
        "misfit J_ls {:.4} (with Table 2's values {:.4})",
        id.cost, id.cost_table_2
    ));
    create_dir(plots)?;
    let figure = plots.join(FIGURE);
    plot::model_adjustment(&figure, &id)?;
    log(&format!("wrote {}", figure.display()));
    let cal = calibrate::calibrate(fmus, &id.params, seed, runs::STOP, runs::STEP)?;
    let r = cal.r.diagonal().map(f64::sqrt);
    log(&format!(
        "calibrated on seed {seed}: sqrt(diag R) = [{:.3e}, {:.3e}, {:.3e}, {:.3e}]",
        r[0], r[1], r[2], r[3]
    ));
    let cal = calibrate::tune(fmus, &cal, runs::STOP)?;
    log(&format!(
        "tuned on seed {seed}: virtual measurement variance x {:e}, alignment process noise x {:e}: whole-band Jrel there {:.4}",
        cal.virtual_scale,
        cal.xi_scale,
        cal.tuned_jrel.unwrap_or(f64::NAN)
    ));
    let cal = calibrate::tune_prior(fmus, &cal)?;
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

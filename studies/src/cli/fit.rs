//! `alignment-studies fit`: the estimator fitted to one vehicle FMU, written as a directory
//! ([`crate::report::fit`]).
//!
//! The directory is built beside its final place under a temporary name and renamed into
//! place when complete: a fit that fails or is interrupted leaves nothing half-written at
//! `--out`.

use super::{CALIBRATION_SEED, StudyFmus};
use crate::Error;
use crate::report::fit::FitOptions;
use crate::study::learned::taps::Options;
use clap::Args;
use std::path::{Path, PathBuf};

/// `fit`'s options.
#[derive(Args, Clone, Debug)]
pub struct FitArgs {
    /// The vehicle FMU to fit for (with --set vehicle.NAME=VALUE for its parameters, e.g.
    /// vehicle.vehicle=manchester.toml) and the estimator FMU.
    #[command(flatten)]
    pub fmus: StudyFmus,
    /// The directory to write: fitted-calibration.toml, fitted.taps, model_adjustment.svg,
    /// report.md. It must not exist, or be empty.
    #[arg(long)]
    pub out: PathBuf,
    /// Speeds of the bank in m/s.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "5,7.5,10,12.5,15,17.5,20,22.5,25,27.5,30",
        value_parser = super::speed
    )]
    pub speeds: Vec<f64>,
    /// Kalker-coefficient scales (contact conditions), each with its own taps, blended at run
    /// time by the contact the estimator reads from the sensors.
    #[arg(long, value_delimiter = ',', default_value = "1,0.75,0.5", value_parser = super::kalker_scale)]
    pub kalker_scales: Vec<f64>,
    /// Wheels' equivalent conicities, each with every Kalker scale (0: the vehicle's own, no
    /// conicity conditions).
    #[arg(long, value_delimiter = ',', default_value = "0", value_parser = super::conicity)]
    pub conicities: Vec<f64>,
    /// Lags of the fixed-lag entries in m.
    #[arg(long, value_delimiter = ',', default_value = "10", value_parser = super::lag)]
    pub lags: Vec<f64>,
    /// Fit only the three-sensor taps (also when the vehicle has no ws_roll_rate).
    #[arg(long)]
    pub no_roll_rate: bool,
    /// Track seed of the calibration and the training runs.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub seed: u32,
    /// Track seeds the ridge is chosen on.
    #[arg(long, value_delimiter = ',', default_value = "102,103,104,105,106")]
    pub validation_seeds: Vec<u32>,
    /// Held-out track seeds of the standard case in report.md.
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5")]
    pub evaluation_seeds: Vec<u32>,
    /// Fit from these recorded passes of an instrumented train instead of from the vehicle
    /// FMU (the recording format of docs/python.md, CSV or Parquet, at 1 ms), against
    /// --reference.
    #[arg(long, num_args = 1.., requires = "reference", conflicts_with_all = ["set", "speeds", "kalker_scales", "conicities", "evaluation_seeds", "validation_seeds", "seed"])]
    pub recordings: Vec<PathBuf>,
    /// The reference alignment of the recordings' line (CSV or Parquet: distance, alignment),
    /// a track recording car's.
    #[arg(long, requires = "recordings")]
    pub reference: Option<PathBuf>,
    /// With --recordings: the share of the line, at its end, that validates (the rest trains).
    #[arg(long, default_value_t = 0.3, requires = "recordings", value_parser = share)]
    pub validation_share: f64,
    /// With --recordings: the calibration of the Kalman channel the taps are fitted with
    /// (another vehicle's, from `fit` or `calibrate`); default the estimator's built-in one.
    #[arg(long, requires = "recordings")]
    pub calibration: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// `--validation-share`: strictly between 0 and 1.
fn share(s: &str) -> Result<f64, String> {
    orchestrator::cli::number(
        s,
        |v| v > 0.0 && v < 1.0,
        "expected a share strictly between 0 and 1",
        "expected a number",
    )
}

/// Checks everything, fits into a staging directory beside `--out`, and renames it into place;
/// `log` gets the stages' lines. Returns the report's text.
pub fn execute(a: &FitArgs, log: &dyn Fn(&str)) -> Result<String, Error> {
    if let Some(s) = a.fmus.set.iter().find(|s| s.starts_with("estimator.")) {
        return Err(Error::Input(format!(
            "--set {s}: fit makes the estimator's calibration and taps itself; --set takes vehicle settings here"
        )));
    }
    check_out(&a.out)?;
    if !a.recordings.is_empty() {
        return from_recordings(a, log);
    }
    let fmus = a.fmus.fmus()?;
    let interface = crate::study::interface::check(&fmus.vehicle)?;
    let mut taps = Options::shipped();
    taps.speeds = a.speeds.clone();
    taps.kalker_scales = a.kalker_scales.clone();
    taps.conicities = super::own_conicities(&a.conicities)?;
    taps.roll_rate_conicities = taps.conicities.iter().take(1).copied().collect();
    taps.lags = a.lags.clone();
    taps.roll_rate = !a.no_roll_rate && interface.roll_rate;
    taps.training_seed = a.seed;
    taps.validation_seeds = a.validation_seeds.clone();
    // The contact model judged on every validation seed the user gives.
    taps.contact_validation_seeds = vec![];
    taps.command = command_line();
    if !interface.kalker_scale && taps.kalker_scales != [1.0] {
        return Err(Error::input(format!(
            "{}: the vehicle FMU has no parameter kalker_scale, so only its own contact can be fitted: give --kalker-scales 1",
            fmus.vehicle.display()
        )));
    }
    if !interface.conicity && !taps.conicities.is_empty() {
        return Err(Error::input(format!(
            "{}: the vehicle FMU has no parameter conicity, so only its own wheels can be fitted: give --conicities 0",
            fmus.vehicle.display()
        )));
    }
    crate::study::learned::taps::check(&taps)?;
    let o = FitOptions {
        taps,
        evaluation_seeds: a.evaluation_seeds.clone(),
        final_dir: a.out.clone(),
    };
    let bar = bar(a.quiet);
    let md = staged(&a.out, log, |dir| {
        crate::report::fit::fit(&fmus, &o, dir, &|l| bar.suspend(|| log(l)), &|f| {
            bar.set_position((f * 1000.0).round() as u64)
        })
    });
    bar.finish_and_clear();
    md
}

/// `fit --recordings`: reads and checks every input, then fits in a staged directory.
fn from_recordings(a: &FitArgs, log: &dyn Fn(&str)) -> Result<String, Error> {
    let mut taps = Options::shipped();
    taps.conicities = vec![];
    taps.roll_rate_conicities = vec![];
    taps.kalker_scales = vec![1.0];
    taps.roll_rate = false;
    taps.lags = a.lags.clone();
    taps.calibration = a.calibration.clone();
    taps.command = command_line();
    crate::study::learned::taps::check(&taps)?;
    if let Some(c) = &a.calibration {
        fmu_estimator::calibration::load(c)
            .map_err(|e| Error::Input(format!("--calibration {}: {e}", c.display())))?;
    }
    let reference = reference(a)?;
    let passes: Vec<_> = a
        .recordings
        .iter()
        .map(|p| crate::study::learned::recorded::read_pass(p))
        .collect::<Result<_, _>>()?;
    let fmus = a.fmus.fmus()?;
    let share = a.validation_share;
    staged(&a.out, log, |dir| {
        crate::report::fit::from_recordings(
            &fmus,
            &taps,
            &passes,
            &reference,
            share,
            (dir, &a.out),
            log,
        )
    })
}

/// The reference named by --reference.
fn reference(a: &FitArgs) -> Result<crate::study::learned::recorded::Reference, Error> {
    let path = a
        .reference
        .as_deref()
        .ok_or_else(|| Error::input("--recordings needs --reference"))?;
    crate::study::learned::recorded::read_reference(path)
}

/// Runs `work` in a hidden directory beside `out` and renames it to `out` when it succeeds;
/// on failure the hidden directory is removed.
fn staged(
    out: &Path,
    log: &dyn Fn(&str),
    work: impl FnOnce(&Path) -> Result<String, Error>,
) -> Result<String, Error> {
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent)
        .map_err(|e| Error::Io(format!("cannot create {}: {e}", parent.display())))?;
    let staging = tempfile::Builder::new()
        .prefix(".fit-")
        .tempdir_in(&parent)
        .map_err(|e| {
            Error::Io(format!(
                "cannot create a directory in {}: {e}",
                parent.display()
            ))
        })?;
    let md = work(staging.path())?;
    // From here on the fit is complete: a failure keeps it where it is and says so.
    let keep = |staging: tempfile::TempDir, why: String| {
        let kept = staging.keep();
        Error::Io(format!(
            "the fit is complete in {} but {why}",
            kept.display()
        ))
    };
    // Checked again: the directory may have appeared during the fit.
    if let Err(e) = check_out(out) {
        return Err(keep(staging, e.to_string()));
    }
    if out.exists()
        && let Err(e) = std::fs::remove_dir(out)
    {
        return Err(keep(
            staging,
            format!("the empty {} cannot be replaced: {e}", out.display()),
        ));
    }
    let written: Vec<String> = std::fs::read_dir(staging.path())
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    let staged = staging.keep();
    std::fs::rename(&staged, out).map_err(|e| {
        Error::Io(format!(
            "the fit is complete in {} but cannot be moved to {}: {e}",
            staged.display(),
            out.display()
        ))
    })?;
    log(&format!("wrote {} ({})", out.display(), written.join(", ")));
    Ok(md)
}

/// `--out` must not exist, or be an empty directory (never a file).
fn check_out(out: &Path) -> Result<(), Error> {
    match std::fs::symlink_metadata(out) {
        Err(_) => Ok(()),
        Ok(m) if m.is_dir() => {
            let empty = std::fs::read_dir(out)
                .map_err(|e| Error::Io(format!("{}: {e}", out.display())))?
                .next()
                .is_none();
            if empty {
                Ok(())
            } else {
                Err(Error::Input(format!(
                    "--out {}: the directory is not empty (a fit writes a new directory; remove the old one or name another)",
                    out.display()
                )))
            }
        }
        Ok(_) => Err(Error::Input(format!(
            "--out {}: exists and is not a directory",
            out.display()
        ))),
    }
}

/// The fit's progress bar in thousandths, with the time left.
fn bar(quiet: bool) -> indicatif::ProgressBar {
    if quiet {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {percent:>3} %, about {eta} left",
        )
        .expect("template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_secs(1));
    bar
}

/// The command line, for the report and the bank's provenance (not UTF-8 parts replaced).
fn command_line() -> String {
    std::env::args_os()
        .map(|a| a.to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join(" ")
}

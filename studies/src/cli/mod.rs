//! The `alignment-studies` commands: each module holds a command's options and one function
//! that turns them into the library's terms and calls the one library function
//! ([`crate::report`]) that returns what the command produces (a [`Report`], a run). `main.rs`
//! only parses, calls, writes and maps the error to an exit code ([`Error::exit_code`]).

pub mod calibrate;
pub mod cases;
pub mod design;
pub mod fit;
pub mod learn;
pub mod run;
pub mod smooth;
pub mod stage;
pub mod taps;
pub mod variants;

use crate::Error;
use crate::report::Evaluation;
pub use crate::report::{Guard, Report};
use crate::study::runs::Fmus;
use clap::Args;
use orchestrator::outfile::Replace;
use orchestrator::system::Endpoint;
use std::path::Path;
use std::path::PathBuf;

/// The track seed the shipped estimator is identified and calibrated on.
pub const CALIBRATION_SEED: u32 = 101;

/// `--vehicle` and `--estimator`: the two FMUs of the standard case, as built by
/// `cargo xtask fmu` by default.
#[derive(Args, Clone, Debug)]
pub struct StandardFmus {
    /// The vehicle FMU of the standard case.
    #[arg(long, default_value = "target/fmu/RailVehicle.fmu")]
    pub vehicle: PathBuf,
    /// The estimator FMU of the standard case.
    #[arg(long, default_value = "target/fmu/AlignmentEstimator.fmu")]
    pub estimator: PathBuf,
}

impl StandardFmus {
    /// The two FMUs, with no settings.
    pub fn fmus(&self) -> Fmus {
        Fmus::new(self.vehicle.clone(), self.estimator.clone())
    }
}

/// The studies' FMUs and the user's settings for them.
#[derive(Args, Clone, Debug)]
pub struct StudyFmus {
    /// The vehicle and estimator FMUs.
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// Set a parameter of the vehicle or the estimator in every run of the study:
    /// vehicle.NAME=VALUE or estimator.NAME=VALUE (repeatable), e.g. vehicle.vehicle=manchester.toml
    /// with estimator.calibration_file=/abs/path/cal.toml from `calibrate`. The seeds and
    /// the cases' conditions stay the study's.
    #[arg(long = "set", value_name = "COMPONENT.VARIABLE=VALUE")]
    pub set: Vec<String>,
}

impl StudyFmus {
    /// The study's FMUs with the user's `--set` settings.
    pub fn fmus(&self) -> Result<Fmus, Error> {
        let mut fmus = self.fmus.fmus();
        for s in &self.set {
            let (name, value) = orchestrator::cli::split_assignment(s)?;
            let e = Endpoint::parse(name).map_err(|e| Error::Input(format!("--set {s}: {e}")))?;
            fmus.set(&e.component, &e.variable, value)
                .map_err(|e| e.context(format!("--set {s}")))?;
        }
        Ok(fmus)
    }
}

/// The options of the paper's studies (`standard`, `robustness`, `resonance`, `all`).
#[derive(Args, Clone, Debug)]
pub struct StudyArgs {
    /// The FMUs and the user's settings for every run.
    #[command(flatten)]
    pub fmus: StudyFmus,
    /// Held-out track seeds (never the calibration seed).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5")]
    pub seeds: Vec<u32>,
    /// The seed the estimator was calibrated on, refused among the evaluation seeds.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub calibration_seed: u32,
    /// Output directory for the JSON results and report.md.
    #[arg(long, default_value = "out/study")]
    pub out: PathBuf,
    /// Also write the report's tables, headed by how and when they were made, to FILE: the
    /// project's docs/results.md is `alignment-studies all --doc docs/results.md`.
    #[arg(long, value_name = "FILE")]
    pub doc: Option<PathBuf>,
    /// Replace an existing --doc FILE, or a file of the report's names in --out, that no study
    /// wrote (never an input, a symlink, a FIFO or a directory).
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

impl StudyArgs {
    /// The seeds as the library takes them.
    pub fn evaluation(&self) -> Evaluation {
        Evaluation {
            seeds: self.seeds.clone(),
            calibration_seed: self.calibration_seed,
        }
    }
}

/// The file `path` checked by the single-file rule ([`orchestrator::outfile`]) before any
/// work: not one of `inputs`, not a special file, and absent, or starting with `mark` (written
/// by this command before), or `force`d.
pub fn guard(
    path: &Path,
    inputs: &[&Path],
    force: bool,
    mark: Option<&'static [u8]>,
) -> Result<Guard, Error> {
    let g = Guard {
        path: path.to_path_buf(),
        inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
        replace: Replace { force, mark },
    };
    g.check()?;
    Ok(g)
}

/// A progress bar drawn on stderr from a study's [`Progress`](crate::report::cases::Progress)
/// calls, hidden with `quiet`.
pub fn progress_bar(quiet: bool) -> impl Fn(crate::report::cases::Progress) + Sync {
    use crate::report::cases::Progress;
    let bar = indicatif::ProgressBar::hidden();
    move |p| match p {
        Progress::Runs(n) if !quiet => {
            bar.set_length(n as u64);
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        Progress::Runs(_) => {}
        Progress::Done => bar.inc(1),
        Progress::Finished => bar.finish_and_clear(),
    }
}

pub use orchestrator::cli::summary_text as orchestrator_summary;

/// A speed in m/s (`taps --speeds`, `learn --speed`): a finite number above zero. Checked as
/// the command line is parsed, so a bad value stops the command before any run.
pub fn speed(s: &str) -> Result<f64, String> {
    orchestrator::cli::number(
        s,
        |v| v > 0.0,
        "expected a finite speed in m/s above zero",
        "expected a number of m/s",
    )
}

/// A look-ahead in m (`taps --lags`, `learn --lag`): a finite number, not negative (0: causal).
pub fn lag(s: &str) -> Result<f64, String> {
    orchestrator::cli::number(
        s,
        |v| v >= 0.0,
        "expected a finite look-ahead in m, not negative",
        "expected a number of metres",
    )
}

/// A wheels' equivalent conicity (`taps --conicities`): a finite number, not negative (0: the
/// vehicle's own, no conicity conditions).
pub fn conicity(s: &str) -> Result<f64, String> {
    orchestrator::cli::number(
        s,
        |v| (0.0..=1.0).contains(&v),
        "expected a finite conicity from 0 (the vehicle's own) to 1",
        "expected a number",
    )
}

/// `--conicities` as the fit takes them: `0` alone is the vehicle's own conicity (no conicity
/// conditions, empty), which cannot be combined with other conicities.
pub fn own_conicities(c: &[f64]) -> Result<Vec<f64>, Error> {
    match c {
        [z] if *z == 0.0 => Ok(vec![]),
        _ if c.contains(&0.0) => Err(Error::input(
            "--conicities 0 (the vehicle's own) cannot be combined with other conicities",
        )),
        _ => Ok(c.to_vec()),
    }
}

/// A Kalker-coefficient scale (`--kalker-scales`): a finite number above zero (1: the vehicle's
/// own coefficients).
pub fn kalker_scale(s: &str) -> Result<f64, String> {
    orchestrator::cli::number(
        s,
        |v| v > 0.0,
        "expected a finite scale above zero",
        "expected a number",
    )
}

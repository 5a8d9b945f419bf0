//! The `alignment-studies` commands as a library: each module holds a command's options and
//! one function returning what the command produces (a [`Report`], a run), so `main.rs` only
//! parses, calls, writes and maps the error to an exit code ([`Error::exit_code`]).

pub mod calibrate;
pub mod cases;
pub mod learn;
pub mod run;
pub mod smooth;
pub mod taps;
pub mod variants;

use crate::Error;
use crate::study::runs::Fmus;
use clap::Args;
use orchestrator::system::Endpoint;
use std::path::{Path, PathBuf};

/// The track seed the shipped estimator is identified and calibrated on.
pub const CALIBRATION_SEED: u32 = 101;

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
    pub fn fmus(&self) -> Fmus {
        Fmus::new(self.vehicle.clone(), self.estimator.clone())
    }
}

/// The studies' FMUs and the user's settings for them.
#[derive(Args, Clone, Debug)]
pub struct StudyFmus {
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
            let e = Endpoint::parse(name).map_err(|e| format!("--set {s}: {e}"))?;
            fmus.set(&e.component, &e.variable, value)
                .map_err(|e| format!("--set {s}: {e}"))?;
        }
        Ok(fmus)
    }
}

#[derive(Args, Clone, Debug)]
pub struct StudyArgs {
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
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

impl StudyArgs {
    /// Accuracy is measured on tracks the estimator was not calibrated on.
    pub fn held_out(&self) -> Result<(), Error> {
        if self.seeds.contains(&self.calibration_seed) {
            return Err(Error::Input(format!(
                "seed {} is the calibration seed: accuracy must be measured on other tracks",
                self.calibration_seed
            )));
        }
        Ok(())
    }
}

/// What a study produces: Markdown for the screen, the files of its report (Markdown, JSON,
/// CSV, each with its contents) and the figures it drew (SVG files, written while drawing).
#[derive(Debug, Default)]
pub struct Report {
    pub markdown: String,
    pub files: Vec<(PathBuf, Vec<u8>)>,
    pub figures: Vec<PathBuf>,
    /// The closing line for stderr: time taken, where the report is.
    pub note: String,
}

impl Report {
    pub fn file(&mut self, path: PathBuf, contents: impl Into<Vec<u8>>) {
        self.files.push((path, contents.into()));
    }

    /// Writes the files, prints the Markdown, then the note.
    pub fn write(&self) -> Result<(), Error> {
        for (path, contents) in &self.files {
            create_parent(path)?;
            std::fs::write(path, contents).map_err(|e| Error::write(path, e))?;
        }
        if !self.markdown.is_empty() {
            println!("{}", self.markdown);
        }
        if !self.note.is_empty() {
            eprintln!("{}", self.note);
        }
        Ok(())
    }
}

/// Creates the directory a file is to be written in, if it names one.
pub fn create_parent(file: &Path) -> Result<(), Error> {
    match file.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => std::fs::create_dir_all(dir)
            .map_err(|e| Error::Io(format!("cannot create {}: {e}", dir.display()))),
        None => Ok(()),
    }
}

pub use orchestrator::cli::summary_text as orchestrator_summary;

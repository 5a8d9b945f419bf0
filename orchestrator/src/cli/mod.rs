//! The command line's pieces as a library, so that each command of `orchestrator` (and of a
//! program built on the master, such as the studies' `alignment-studies run`) is a small
//! module: its options, one function that returns a value, and nothing else. `main.rs` only
//! parses, dispatches and maps the error to an exit code ([`RunError::exit_code`]).

pub mod export;
pub mod info;
pub mod run;
pub mod simulate;

use crate::master::{Algorithm, Cosimulation, Progress, RunError, RunOptions, RunSummary};
use crate::outdir::OutputDir;
use crate::system::{Endpoint, System};
use clap::{Args, ValueEnum};
use fmi_abi::types::fmi2Status;
use fmi_import::LogConfig;
use std::path::{Path, PathBuf};

/// The options every run shares (`run`, `simulate`).
#[derive(Args, Clone, Debug)]
pub struct Common {
    /// Stop time [s] (default: the system's, else the first FMU's default experiment).
    #[arg(long)]
    pub stop: Option<f64>,
    /// Communication step [s] (default: the system's, else the first FMU's default step).
    #[arg(long)]
    pub step: Option<f64>,
    /// Start time [s].
    #[arg(long, default_value_t = 0.0)]
    pub start: f64,
    /// Output directory for results.csv and results.units.csv.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Record only these variables (component.variable, repeatable or comma-separated); default: every output.
    #[arg(long, value_delimiter = ',')]
    pub record: Vec<String>,
    /// Recording interval [s], a whole number of steps (default: every step).
    #[arg(long)]
    pub interval: Option<f64>,
    /// Do not write results.
    #[arg(long)]
    pub no_record: bool,
    /// Lowest FMU log status shown.
    #[arg(long, value_enum, default_value_t = LogLevel::Warning)]
    pub log_level: LogLevel,
    /// FMU log categories to switch on (with --log-level info), comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub log_categories: Vec<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum LogLevel {
    Info,
    Warning,
    Error,
}

impl Common {
    pub fn log_config(&self) -> LogConfig {
        let min_status = match self.log_level {
            LogLevel::Info => fmi2Status::OK,
            LogLevel::Warning => fmi2Status::Warning,
            LogLevel::Error => fmi2Status::Error,
        };
        LogConfig {
            min_status,
            debug_logging: matches!(self.log_level, LogLevel::Info),
            categories: (!self.log_categories.is_empty()).then(|| self.log_categories.clone()),
            ..LogConfig::default()
        }
    }

    /// The run's options: stop and step from the command line, else the system's, else the
    /// first FMU's default experiment.
    pub fn options(&self, system: &System, cosim: &Cosimulation) -> Result<RunOptions, RunError> {
        let default = cosim
            .model_descriptions()
            .first()
            .and_then(|m| m.default_experiment.as_ref());
        let stop = self
            .stop
            .or(system.experiment.stop)
            .or_else(|| default.and_then(|d| d.stop_time))
            .ok_or_else(|| RunError::Config("no stop time: give --stop".into()))?;
        let step = self
            .step
            .or(system.experiment.step)
            .or_else(|| default.and_then(|d| d.step_size))
            .ok_or_else(|| RunError::Config("no communication step: give --step".into()))?;
        let record = if self.record.is_empty() {
            None
        } else {
            Some(
                self.record
                    .iter()
                    .map(|r| Endpoint::parse(r).map_err(RunError::Config))
                    .collect::<Result<Vec<_>, _>>()?,
            )
        };
        Ok(RunOptions {
            start: self.start,
            stop,
            step,
            algorithm: Algorithm::GaussSeidel,
            out_dir: (!self.no_record).then(|| self.out.clone()),
            record,
            interval: self.interval,
            collect: false,
            progress: !self.quiet,
            log: self.log_config(),
        })
    }

    /// The output directory, held for this run ([`OutputDir::hold`]: locked, cleared of the
    /// previous run's outputs, its `files` checked, the manifest written); none with
    /// --no-record.
    pub fn hold_output(
        &self,
        program: &str,
        files: &[&str],
        fmus: &[(&str, &Path)],
        settings: &[String],
    ) -> Result<Option<OutputDir>, RunError> {
        if self.no_record {
            return Ok(None);
        }
        OutputDir::hold(&self.out, program, files, fmus, settings)
            .map(Some)
            .map_err(|e| {
                RunError::Io(format!(
                    "cannot write results in {} (nothing was run): {e}",
                    self.out.display()
                ))
            })
    }
}

/// `NAME=VALUE`.
pub fn split_assignment(s: &str) -> Result<(&str, &str), RunError> {
    s.split_once('=')
        .ok_or_else(|| RunError::Config(format!("--set {s}: expected NAME=VALUE")))
}

/// `--fmu COMPONENT=PATH` options as the SSP reader takes them.
pub fn fmu_sources(given: &[String]) -> Result<crate::ssp::Sources, RunError> {
    given
        .iter()
        .map(|s| match s.split_once('=') {
            Some((c, p)) if !c.is_empty() && !p.is_empty() => Ok((c.into(), PathBuf::from(p))),
            _ => Err(RunError::Config(format!(
                "--fmu {s}: expected COMPONENT=PATH"
            ))),
        })
        .collect()
}

/// The command line's progress bar, drawn on stderr from the master's [`Progress`] reports for a
/// run of 10 000 steps or more (the master itself draws nothing).
pub fn progress_bar() -> impl FnMut(Progress) {
    let mut bar: Option<indicatif::ProgressBar> = None;
    move |p| match p {
        Progress::Start { total } if total >= 10_000 => {
            let b = indicatif::ProgressBar::new(total);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {percent:>3}% {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar = Some(b);
        }
        Progress::Start { .. } => {}
        Progress::Step { done } => {
            if let Some(b) = &bar {
                b.set_position(done);
            }
        }
        Progress::End { .. } => {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
        }
    }
}

/// What a finished run prints on stderr: steps, time, cost per step and where the rows are.
pub fn summary_text(summary: &RunSummary) -> String {
    let mut text = String::new();
    if let Some(who) = &summary.ended_by {
        text.push_str(&format!(
            "'{who}' ended the simulation at t = {} s (fmi2DoStep returned fmi2Discard with fmi2Terminated): the run stops there\n",
            summary.final_time
        ));
    }
    let per_step = summary.wall.as_secs_f64() / summary.steps.max(1) as f64 * 1e6;
    text.push_str(&format!(
        "{} steps to t = {} s in {:.3} s ({:.3} us per step){}",
        summary.steps,
        summary.final_time,
        summary.wall.as_secs_f64(),
        per_step,
        summary
            .results
            .as_ref()
            .map(|p| format!("; {} rows in {}", summary.rows, p.display()))
            .unwrap_or_default()
    ));
    text
}

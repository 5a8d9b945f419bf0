//! The command line's pieces as a library, so that each command of `orchestrator` (and of a
//! program built on the master, such as the studies' `alignment-studies run`) is a small
//! module: its options, one function that returns a value, and nothing else. `main.rs` only
//! parses, dispatches and maps the error to an exit code ([`RunError::exit_code`]).

pub mod export;
pub mod info;
mod report;
pub mod run;
pub mod simulate;

pub use report::{progress_bar, summary_text};

use crate::master::{Cosimulation, ResultsFile, RunError, RunOptions, StopToken};
use crate::outdir::OutputDir;
use crate::system::{Endpoint, System};
use clap::{Args, ValueEnum};
use fmi_abi::types::fmi2Status;
use fmi_import::LogConfig;
use std::path::{Path, PathBuf};

/// The options every run shares (`run`, `simulate`). Times and sizes are checked as they are
/// parsed (a negative number is taken as a value, then refused by name), so a bad one stops
/// the command before anything is read or created.
#[derive(Args, Clone, Debug)]
pub struct Common {
    /// Stop time in s (default for `run`: the system's, else the first FMU's default
    /// experiment; for `simulate`: the input's last time, else the FMU's default experiment).
    #[arg(long, allow_negative_numbers = true, value_parser = time)]
    pub stop: Option<f64>,
    /// Communication step in s (default: the system's for `run`, else the (first) FMU's default
    /// experiment).
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub step: Option<f64>,
    /// Start time in s (default for `run`: the system's startTime, 0 when it gives none; for
    /// `simulate`: 0).
    #[arg(long, allow_negative_numbers = true, value_parser = time)]
    pub start: Option<f64>,
    /// Output directory for the results (and manifest.json).
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// The results file's name in --out: NAME.csv (with NAME.units.csv) or NAME.parquet
    /// (units and manifest in its metadata).
    #[arg(long, default_value = "results.csv", value_name = "NAME")]
    pub results: String,
    /// Record only these variables (component.variable, repeatable or comma-separated); default: every output.
    #[arg(long, value_delimiter = ',')]
    pub record: Vec<String>,
    /// Recording interval in s, a whole number of steps (default: every step).
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub interval: Option<f64>,
    /// Do not write results.
    #[arg(long)]
    pub no_record: bool,
    /// The largest results file a run may write, estimated before it starts (rows x columns x
    /// 20 bytes for CSV, 8 for Parquet), e.g. 50G; a larger run is refused, as is one the free
    /// disk space cannot hold.
    #[arg(long, value_name = "SIZE", default_value = "10G", value_parser = crate::record::size::parse)]
    pub max_output_size: u64,
    /// Lowest FMU log status shown.
    #[arg(long, value_enum, default_value_t = LogLevel::Warning)]
    pub log_level: LogLevel,
    /// FMU log categories to switch on (with --log-level info), comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub log_categories: Vec<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// The run's stop token, not an option: set by the Ctrl-C handler when the command
    /// installs one ([`run::stop_on_interrupt`]), never otherwise.
    #[arg(skip)]
    pub interrupt: StopToken,
}

/// A time in s: a finite number, not negative.
pub fn time(s: &str) -> Result<f64, String> {
    number(
        s,
        |v| v >= 0.0,
        "expected a finite time in s, not negative",
        "expected a number of seconds",
    )
}

/// A duration in s: a finite number above zero.
pub fn positive(s: &str) -> Result<f64, String> {
    number(
        s,
        |v| v > 0.0,
        "expected a finite number of seconds above zero",
        "expected a number of seconds",
    )
}

/// A command-line number: finite and `accepted`, else `refused`; `not_a_number` when `s` does
/// not parse. The value parsers of both binaries' options are this with their own words.
pub fn number(
    s: &str,
    accepted: impl Fn(f64) -> bool,
    refused: &str,
    not_a_number: &str,
) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && accepted(v) => Ok(v),
        Ok(_) => Err(refused.into()),
        Err(_) => Err(not_a_number.into()),
    }
}

/// `--log-level`: the lowest status of the FMU log messages shown. `Info`: every message, with
/// the FMUs' debug logging switched on; `Warning` (the default): warnings and worse; `Error`:
/// errors and worse.
// The variants are documented here, not one by one: clap makes a variant's doc comment its
// possible value's help, which would reflow the `--help` of every run command.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum LogLevel {
    Info,
    Warning,
    Error,
}

impl Common {
    /// The FMU logging `--log-level` and `--log-categories` ask for.
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

    /// The run's options: start from the command line, else the system's; stop and step from
    /// the command line, else the system's, else the first FMU's default experiment.
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
        self.run_options(
            self.start.unwrap_or(system.experiment.start),
            stop,
            step,
            record,
        )
    }

    /// The run's options from the command line, with the start and stop times, step and
    /// recorded variables the command resolved.
    pub fn run_options(
        &self,
        start: f64,
        stop: f64,
        step: f64,
        record: Option<Vec<Endpoint>>,
    ) -> Result<RunOptions, RunError> {
        Ok(RunOptions {
            out_dir: (!self.no_record).then(|| self.out.clone()),
            results: self.results_file()?,
            record,
            interval: self.interval,
            progress: !self.quiet,
            log: self.log_config(),
            max_output: self.max_output_size,
            ..RunOptions::new(start, stop, step)
        })
    }

    /// `--results` checked.
    pub fn results_file(&self) -> Result<ResultsFile, RunError> {
        ResultsFile::new(&self.results).map_err(RunError::Config)
    }

    /// The output directory, held for this run ([`OutputDir::hold`]: locked, cleared of the
    /// previous run's outputs, its files checked, the manifest written); none with
    /// --no-record. The files are the results' and `extra` (what the caller adds); a Parquet
    /// results file gets the manifest as its provenance.
    pub fn hold_output(
        &self,
        opts: &mut RunOptions,
        program: &str,
        extra: &[&str],
        fmus: &[(&str, &Path)],
        settings: &[String],
    ) -> Result<Option<OutputDir>, RunError> {
        // Before the directory is made: a run refused for its times leaves nothing behind.
        crate::master::check_grid(opts)?;
        if self.no_record {
            return Ok(None);
        }
        let mut files = opts.results.files();
        files.extend(extra.iter().map(|f| f.to_string()));
        let files: Vec<&str> = files.iter().map(String::as_str).collect();
        let out = OutputDir::hold(&self.out, program, &files, fmus, settings).map_err(|e| {
            RunError::Io(format!(
                "cannot write results in {} (nothing was run): {e}",
                self.out.display()
            ))
        })?;
        if let Some(m) = out.manifest() {
            opts.results.provenance = serde_json::to_string(m).expect("a manifest serializes");
        }
        Ok(Some(out))
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

//! Why a run did not complete, typed so that a caller (the command line, the studies) can
//! tell a bad input from a failing FMU and map each to its exit code, without parsing text.

use fmi_import::{FmiError, ImportError};
use std::path::PathBuf;

/// Why loading or running a system failed. The message names the file, component, variable
/// or time concerned; [`RunError::exit_code`] gives the command line's exit code.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// An FMU could not be opened: a missing or corrupt archive, binary or symbol (exit 2).
    #[error(transparent)]
    Import(#[from] ImportError),
    /// The system does not fit its FMUs: unknown variables, bad connections, algebraic loops
    /// (exit 2).
    #[error(transparent)]
    Resolve(#[from] crate::resolve::ResolveError),
    /// Other bad input: options, the grid, the recorded variables, a `--set`, a file read
    /// (exit 2).
    #[error("{0}")]
    Config(String),
    /// An FMU failed during the run (exit 3); `results` is where the rows recorded until then
    /// are, if any were written.
    #[error("{error}{}", .results.as_ref().map(|p| format!("\nthe results recorded until then are in {}", p.display())).unwrap_or_default())]
    Fmi {
        /// The failing call: instance, FMU, function, status, time and the FMU's log messages.
        error: FmiError,
        /// The results file holding the rows recorded before the failure (whole lines), if one
        /// was written.
        results: Option<PathBuf>,
    },
    /// The results could not be written (exit 1).
    #[error("{0}")]
    Io(String),
    /// The run's [`super::StopToken`] was set (e.g. by Ctrl-C) and the run stopped at a step
    /// boundary (exit 130).
    #[error(
        "interrupted at t = {time} s, after {steps} of {total} steps{}",
        match .results {
            Some(p) => format!("; the {rows} rows recorded until then are in {}", p.display()),
            None => String::new(),
        }
    )]
    Interrupted {
        /// The communication point the run stopped at \[s\] (the last step done ended there).
        time: f64,
        /// Communication steps done.
        steps: u64,
        /// Communication steps the run would have done to its stop time.
        total: u64,
        /// Rows in the results file (the start row included).
        rows: u64,
        /// The results file holding those rows, if the run recorded any.
        results: Option<PathBuf>,
    },
}

impl RunError {
    /// The process exit code: 2 for a problem with the input (files, system, parameters),
    /// 3 for an FMU that failed during the run, 1 for an I/O failure, 130 (128 + SIGINT, as
    /// shells report a process ended by Ctrl-C) for an interrupted run.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Import(_) | RunError::Resolve(_) | RunError::Config(_) => 2,
            RunError::Fmi { .. } => 3,
            RunError::Io(_) => 1,
            RunError::Interrupted { .. } => 130,
        }
    }
}

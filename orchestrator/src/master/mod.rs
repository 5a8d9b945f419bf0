//! The master: instantiate, initialize with values propagated through the connections, then
//! step every component with a fixed communication step.
//!
//! It is cut along libcosim's seams, so that each concern can be read, changed and tested
//! without the others, and so that nothing here knows what a caller does with a run:
//! - `grid`: the communication points, `start + k * step` from an integer `k`, so they never
//!   drift however long the run (Reference-FMUs #507);
//! - `transfer`: value transfer along the connections and from external inputs, the only work
//!   the master adds to every step, through flat buffers with nothing allocated;
//! - [`Algorithm`]: what one communication step is, Gauss-Seidel (the default) or Jacobi;
//! - `observe`: recording as an observer that owns the results file and the table;
//! - [`Progress`]: reported to a callback, so that a library run draws nothing (the command
//!   line draws its bar, a study its own, a thread nothing);
//! - `run`: the phases of a run, in the order that keeps results safe.
//!
//! Reliability: the results file is created (and its header flushed) before any FMU is
//! instantiated, so an unwritable destination or a full disk stops the run before it starts;
//! an FMU failing mid-run, or [`request_stop`] (Ctrl-C on the command line, checked once per
//! step), ends the run at a step boundary with every recorded row kept as whole lines in
//! `results.csv`; a write failing mid-run names the file and the time the run stopped at.

mod algorithm;
mod error;
mod grid;
mod observe;
mod run;
mod table;
mod transfer;

pub use crate::record::ResultsFile;
pub use algorithm::Algorithm;
pub use error::RunError;
pub use table::Table;

/// Checks the options' times and step (finite, a positive step, stop not before start, a
/// whole number of steps), as a run does first: a command calls it before it creates anything.
pub fn check_grid(opts: &RunOptions) -> Result<(), RunError> {
    grid::Grid::new(opts).map(|_| ())
}

use crate::resolve::{Plan, resolve};
use crate::system::{Endpoint, System, Value};
use fmi_import::{Fmu, LogConfig};
use model_description::{BaseType, ModelDescription};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Set by [`request_stop`]; read by the stepping loop once per step.
static STOP: AtomicBool = AtomicBool::new(false);

/// Asks every run in this process to stop at its next step boundary (what the command line's
/// Ctrl-C handler calls). The run then flushes and keeps its results and returns
/// [`RunError::Interrupted`]. Returns whether this is the first request.
pub fn request_stop() -> bool {
    !STOP.swap(true, Ordering::SeqCst)
}

/// Whether [`request_stop`] has been called.
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// One value for an input of the first component: its type, value reference and value (an
/// Integer or Enumeration as a whole number, a Boolean as 0 or 1).
pub type ExternalValue = (BaseType, u32, f64);

/// Fills the buffer with the first component's input values at time `t`.
pub type ExternalInputs<'a> = dyn Fn(f64, &mut Vec<ExternalValue>) + 'a;

/// The external inputs of a run that has none.
pub fn no_inputs(_: f64, values: &mut Vec<ExternalValue>) {
    values.clear();
}

/// How far the stepping is, for a caller that shows it: the library draws nothing, so that it
/// can run under a study's own progress, in threads, or without a terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// The stepping starts, `total` communication steps to go.
    Start { total: u64 },
    /// `done` steps are done (reported every 1000 steps).
    Step { done: u64 },
    /// The stepping ended after `done` steps: at the stop time, or earlier (a failure, an
    /// interrupt, an FMU ending the simulation). Always reported after `Start`.
    End { done: u64 },
}

/// Receives [`Progress`] reports.
pub type ProgressFn<'a> = dyn FnMut(Progress) + 'a;

#[derive(Clone)]
pub struct RunOptions {
    pub start: f64,
    pub stop: f64,
    pub step: f64,
    pub algorithm: Algorithm,
    /// Where the results file goes; `None` records nothing.
    pub out_dir: Option<PathBuf>,
    /// The results file's name in `out_dir` (its extension chooses CSV or Parquet).
    pub results: ResultsFile,
    /// Variables to record; `None`: every output of every component.
    pub record: Option<Vec<Endpoint>>,
    /// Recording interval \[s\], a whole number of steps; `None`: every step.
    pub interval: Option<f64>,
    /// Also keep the recorded rows in memory ([`RunSummary::table`]), for the studies.
    pub collect: bool,
    /// Report progress to the callback of [`Cosimulation::run_reporting`] (`run` and
    /// `run_with_inputs` have none to report to).
    pub progress: bool,
    pub log: LogConfig,
    /// The largest results file (bytes, estimated before the run) written without refusal
    /// ([`crate::record::size`]).
    pub max_output: u64,
}

impl RunOptions {
    /// A run from `start` to `stop` in steps of `step`: Gauss-Seidel, nothing recorded or
    /// kept, no progress reports, the default FMU log. Callers change what they need with
    /// struct update syntax, so a new option is defaulted here once.
    pub fn new(start: f64, stop: f64, step: f64) -> RunOptions {
        RunOptions {
            start,
            stop,
            step,
            algorithm: Algorithm::GaussSeidel,
            out_dir: None,
            results: ResultsFile::default(),
            record: None,
            interval: None,
            collect: false,
            progress: false,
            log: LogConfig::default(),
            max_output: crate::record::size::DEFAULT_LIMIT,
        }
    }
}

#[derive(Debug, Clone)]
pub struct RunSummary {
    pub steps: u64,
    pub rows: u64,
    pub results: Option<PathBuf>,
    /// The recorded rows, when [`RunOptions::collect`] asked for them.
    pub table: Option<Table>,
    pub wall: Duration,
    pub final_time: f64,
    /// The instance that ended the run before the stop time: its fmi2DoStep returned
    /// fmi2Discard with fmi2GetBooleanStatus(fmi2Terminated) true. The run then ends cleanly,
    /// as fmpy does: the rows until the last communication point, and one at the instance's
    /// last successful time (`final_time`) when it reported one past that point.
    pub ended_by: Option<String>,
}

/// A loaded system: its FMUs opened and the plan resolved against them. Each run instantiates
/// the FMUs afresh, so one `Cosimulation` can run many times.
pub struct Cosimulation {
    pub system: System,
    fmus: Vec<Fmu>,
    pub plan: Plan,
}

impl Cosimulation {
    /// Opens every FMU and resolves the system against their model descriptions.
    pub fn load(system: System) -> Result<Cosimulation, RunError> {
        if system.components.is_empty() {
            return Err(RunError::Config(format!(
                "system '{}' has no components",
                system.name
            )));
        }
        let mut fmus = vec![];
        for c in &system.components {
            fmus.push(Fmu::open(&c.source)?);
        }
        let mds: Vec<&ModelDescription> = fmus.iter().map(|f| f.model_description()).collect();
        let plan = resolve(&system, &mds)?;
        Ok(Cosimulation { system, fmus, plan })
    }

    pub fn model_descriptions(&self) -> Vec<&ModelDescription> {
        self.fmus.iter().map(|f| f.model_description()).collect()
    }

    /// Adds `component.variable=value` settings (command-line `--set`), checked like the
    /// system's own parameters; they are applied after those, so they win.
    pub fn set(&mut self, name: &Endpoint, text: &str) -> Result<(), RunError> {
        let c = self
            .system
            .components
            .iter()
            .position(|x| x.name == name.component)
            .ok_or_else(|| {
                RunError::Config(format!(
                    "--set {name}={text}: no component '{}'",
                    name.component
                ))
            })?;
        let md = self.fmus[c].model_description();
        let v = md.variable(&name.variable).ok_or_else(|| {
            RunError::Config(format!(
                "--set {name}={text}: component '{}' ({}) has no variable '{}'",
                name.component,
                self.fmus[c].path().display(),
                name.variable
            ))
        })?;
        let s = crate::resolve::setting(c, v, &Value::String(text.to_string()), name.clone())?;
        self.plan.settings.push(s);
        Ok(())
    }

    /// Runs the system; see the module docs.
    pub fn run(&self, opts: &RunOptions) -> Result<RunSummary, RunError> {
        self.run_with_inputs(opts, &no_inputs)
    }

    /// Runs the system with external inputs of the first component: before the step from
    /// `t`, `external(t, buffer)` fills the buffer with (type, value reference, value)
    /// triples, which are set before the component steps (and once at the start, in
    /// initialization mode).
    pub fn run_with_inputs(
        &self,
        opts: &RunOptions,
        external: &ExternalInputs<'_>,
    ) -> Result<RunSummary, RunError> {
        self.run_reporting(opts, external, &mut |_| {})
    }
}

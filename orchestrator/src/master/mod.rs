//! The master: instantiate, initialize with values propagated through the connections, then
//! step every component with a fixed communication step.
//!
//! It is cut along libcosim's seams, so that each concern can be read, changed and tested
//! without the others, and so that nothing here knows what a caller does with a run:
//! - `grid`: the communication points, `start + k * step` from an integer `k`, so they never
//!   drift however long the run (Reference-FMUs #507);
//! - `transfer`: value transfer along the connections, the only work the master adds to every
//!   step, through flat buffers with nothing allocated;
//! - `inputs`: the caller's external inputs, addressed by `component.variable`;
//! - [`Algorithm`]: what one communication step is, Gauss-Seidel (the default) or Jacobi;
//! - [`Observer`]: what the master tells an observer at the start, after each step and at the
//!   end, and how an observer ends a run ([`Flow::Stop`], fmpy's `step_finished` returning
//!   false); `recording` is the observer that owns the results file and the table;
//! - [`StopToken`]: a per-run stop request (Ctrl-C on the command line);
//! - [`Progress`]: reported to a callback, so that a library run draws nothing (the command
//!   line draws its bar, a study its own, a thread nothing);
//! - [`Runner`]: what a run takes besides its options, and the order of its phases that keeps
//!   results safe; `run`: the phases.
//!
//! Reliability: the results file is created (and its header flushed) before any FMU is
//! instantiated, so an unwritable destination or a full disk stops the run before it starts;
//! an FMU failing mid-run, or the run's [`StopToken`] (checked once per step), ends the run at
//! a step boundary with every recorded row kept as whole lines in `results.csv`; a write
//! failing mid-run names the file and the time the run stopped at.

mod algorithm;
mod error;
mod grid;
mod inputs;
mod observer;
mod recording;
mod run;
mod runner;
mod stop;
mod table;
mod transfer;

pub use crate::record::ResultsFile;
pub use algorithm::Algorithm;
pub use error::RunError;
pub use inputs::{InputFn, no_inputs};
pub use observer::{End, Flow, ObserveError, Observer, Values};
pub use runner::Runner;
pub use stop::StopToken;
pub use table::Table;

/// Checks the options' times and step (finite, a positive step, stop not before start, a
/// whole number of steps), as a run does first: a command calls it before it creates anything.
pub fn check_grid(opts: &RunOptions) -> Result<(), RunError> {
    grid::Grid::new(opts).map(|_| ())
}

use crate::resolve::{Plan, ResolveError, resolve};
use crate::system::{Endpoint, System, Value};
use fmi_import::{Fmu, LogConfig};
use model_description::{BaseType, ModelDescription, ScalarVariable};
use std::path::PathBuf;
use std::time::Duration;

/// Where a variable of the system is: its component's index in [`System::components`], its
/// type and value reference. What [`Values`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Address {
    /// Index of the component in [`System::components`] (and of its instance in a run).
    pub component: usize,
    /// The variable's base type, which says which fmi2GetXxx reads it (an Enumeration is
    /// read as an Integer).
    pub base: BaseType,
    /// The variable's value reference in its FMU.
    pub vr: u32,
}

/// How far the stepping is, for a caller that shows it: the library draws nothing, so that it
/// can run under a study's own progress, in threads, or without a terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// The stepping starts, `total` communication steps to go.
    Start {
        /// Communication steps from start to stop.
        total: u64,
    },
    /// `done` steps are done (reported every 1000 steps).
    Step {
        /// Communication steps done so far.
        done: u64,
    },
    /// The stepping ended after `done` steps: at the stop time, or earlier (a failure, an
    /// interrupt, an FMU ending the simulation). Always reported after `Start`.
    End {
        /// Communication steps done in all.
        done: u64,
    },
}

/// Receives [`Progress`] reports.
pub type ProgressFn<'a> = dyn FnMut(Progress) + 'a;

/// What one run does: its time grid, algorithm, what it records and where, and the FMUs'
/// logging. Build it with [`RunOptions::new`] and struct update syntax; the times are checked
/// when the run starts, or before with [`check_grid`].
#[derive(Clone)]
pub struct RunOptions {
    /// Start time \[s\], given to every FMU's fmi2SetupExperiment; finite.
    pub start: f64,
    /// Stop time \[s\], not before `start`, a whole number of steps after it (within 1e-9
    /// relative); also given to fmi2SetupExperiment as the FMUs' stop time.
    pub stop: f64,
    /// Communication step \[s\], finite and above zero.
    pub step: f64,
    /// The co-simulation algorithm.
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
    /// Report progress to the callback given to [`Runner::progress`] (a run without one
    /// reports nothing).
    pub progress: bool,
    /// Which of the FMUs' log messages are shown and which categories are switched on.
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

/// What a run that ended without an error did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Communication steps done.
    pub steps: u64,
    /// Rows recorded (the start row, one per recording interval, and a last one when an
    /// instance ended the run between two communication points); 0 when nothing was recorded.
    pub rows: u64,
    /// The results file, when the run wrote one.
    pub results: Option<PathBuf>,
    /// The recorded rows, when [`RunOptions::collect`] asked for them.
    pub table: Option<Table>,
    /// Wall-clock time the run took, from checking its grid to closing its results.
    pub wall: Duration,
    /// The simulation time the run ended at \[s\]: the stop time, the last communication
    /// point reached, or the last successful time of an instance that ended the run.
    pub final_time: f64,
    /// [`End::StopTime`]; or [`End::Instance`], an instance that ended the run before the stop
    /// time (its fmi2DoStep returned fmi2Discard with fmi2GetBooleanStatus(fmi2Terminated)
    /// true): the run then ends cleanly, as fmpy does, with the rows until the last
    /// communication point and one at the instance's last successful time (`final_time`) when
    /// it reported one past that point; or [`End::Observer`], an observer that stopped the run
    /// after step `steps` (its row recorded). The other ends are errors.
    pub end: End,
}

/// A loaded system: its FMUs opened and the plan resolved against them. Each run instantiates
/// the FMUs afresh, so one `Cosimulation` can run many times. The system and the plan are
/// read through [`Cosimulation::system`] and [`Cosimulation::plan`] and changed only together
/// ([`Cosimulation::set`]), so the plan is always the system's.
pub struct Cosimulation {
    system: System,
    fmus: Vec<Fmu>,
    plan: Plan,
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
            // Shared: a process that runs the same FMUs many times (a study) loads each once
            // while it holds them ([`Fmu::open_shared`]).
            fmus.push(Fmu::open_shared(&c.source)?);
        }
        let mds: Vec<&ModelDescription> = fmus.iter().map(|f| f.model_description()).collect();
        let plan = resolve(&system, &mds)?;
        Ok(Cosimulation { system, fmus, plan })
    }

    /// The system as loaded, with the settings [`Cosimulation::set`] added to its components'
    /// parameters.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The system resolved against its FMUs: connections, settings, stepping order.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The components' model descriptions, in the order of [`System::components`].
    pub fn model_descriptions(&self) -> Vec<&ModelDescription> {
        self.fmus.iter().map(|f| f.model_description()).collect()
    }

    /// The component and variable `e` names, or an error naming what is missing; `context`
    /// says what named it.
    pub(crate) fn find(
        &self,
        e: &Endpoint,
        context: &str,
    ) -> Result<(usize, &ScalarVariable), ResolveError> {
        crate::resolve::find(&self.system, &self.model_descriptions(), e, context)
    }

    /// Where the variable `e` is, for an observer to read it ([`Values::value`]); an unknown
    /// component or variable is an error naming it.
    pub fn address(&self, e: &Endpoint) -> Result<Address, RunError> {
        let (component, v) = self.find(e, &format!("variable {e}"))?;
        Ok(Address {
            component,
            base: v.kind.base_type(),
            vr: v.value_reference,
        })
    }

    /// Adds `component.variable=value` settings (command-line `--set`), checked like the
    /// system's own parameters; they are applied after those, so they win. The setting goes
    /// into the plan and into the component's parameters alike.
    pub fn set(&mut self, name: &Endpoint, text: &str) -> Result<(), RunError> {
        let (c, v) = self.find(name, &format!("--set {name}={text}"))?;
        let value = Value::String(text.to_string());
        let s = crate::resolve::setting(c, v, &value, name.clone())?;
        self.plan.settings.push(s);
        self.system.components[c]
            .parameters
            .push((name.variable.clone(), value));
        Ok(())
    }

    /// A run with `opts`, to be given inputs, observers, a progress callback or a stop token
    /// before [`Runner::run`].
    pub fn runner<'a>(&'a self, opts: &'a RunOptions) -> Runner<'a> {
        Runner::new(self, opts)
    }

    /// Runs the system with nothing but `opts`; see the module docs.
    pub fn run(&self, opts: &RunOptions) -> Result<RunSummary, RunError> {
        self.runner(opts).run()
    }
}

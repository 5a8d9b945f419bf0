//! A run being set up, and the order of its phases in one short function ([`Runner::run`]):
//! the grid checked and the inputs resolved before anything is created, the results file
//! before any instance (an unwritable destination costs nothing), then initialize, step and
//! finish (`run`).

use super::grid::Grid;
use super::inputs::{External, InputFn, no_inputs};
use super::recording::Results;
use super::run::{Observers, Run, fmi};
use super::transfer::Transfers;
use super::{Cosimulation, Observer, ProgressFn, RunError, RunOptions, RunSummary, StopToken};
use crate::system::Endpoint;
use std::time::Instant;

/// A run being set up: [`Cosimulation::runner`], then what the run takes besides its options,
/// then [`Runner::run`]. Without them a run has no external inputs, no observer but the
/// recording its options ask for, no progress reports, and a stop token of its own that
/// nothing sets.
pub struct Runner<'a> {
    cosim: &'a Cosimulation,
    opts: &'a RunOptions,
    inputs: &'a [Endpoint],
    fill: &'a InputFn<'a>,
    observers: Vec<&'a mut dyn Observer>,
    progress: Option<&'a mut ProgressFn<'a>>,
    stop: StopToken,
}

impl<'a> Runner<'a> {
    pub(super) fn new(cosim: &'a Cosimulation, opts: &'a RunOptions) -> Runner<'a> {
        Runner {
            cosim,
            opts,
            inputs: &[],
            fill: &no_inputs,
            observers: Vec::new(),
            progress: None,
            stop: StopToken::new(),
        }
    }

    /// External inputs: before the step from `t` (and once at the start, in initialization
    /// mode), `fill(t, values)` gives one value per input of `names`, in order, and the master
    /// sets them. Each name is a `component.variable` input that no connection feeds; the run
    /// refuses, naming it, an unknown component or variable, or one that is not such an input.
    pub fn inputs(mut self, names: &'a [Endpoint], fill: &'a InputFn<'a>) -> Runner<'a> {
        self.inputs = names;
        self.fill = fill;
        self
    }

    /// Adds an observer, called after the recording (so a row is written before an observer
    /// can stop the run at it) and after the observers added before it.
    pub fn observe(mut self, observer: &'a mut dyn Observer) -> Runner<'a> {
        self.observers.push(observer);
        self
    }

    /// Reports progress to `progress` when [`RunOptions::progress`] asks for it.
    pub fn progress(mut self, progress: &'a mut ProgressFn<'a>) -> Runner<'a> {
        self.progress = Some(progress);
        self
    }

    /// Stops the run at the next step boundary once `stop` is set ([`StopToken::stop`]).
    pub fn stop_on(mut self, stop: &StopToken) -> Runner<'a> {
        self.stop = stop.clone();
        self
    }

    /// Runs the system; see the module docs of [`super`].
    pub fn run(self) -> Result<RunSummary, RunError> {
        let started = Instant::now();
        let (cosim, opts) = (self.cosim, self.opts);
        let grid = Grid::new(opts)?;
        let external = External::new(cosim, self.inputs, self.fill)?;
        let results = Results::new(&cosim.system, &cosim.model_descriptions(), opts, &grid)?;
        let instances = cosim.instantiate(opts)?;
        let mut run = Run {
            grid,
            order: &cosim.plan.order,
            values: Transfers::new(instances.len(), &cosim.plan.links),
            instances,
            external,
            observers: Observers {
                results,
                others: self.observers,
            },
            stop: self.stop,
        };
        run.initialize(opts, &cosim.plan.settings).map_err(fmi)?;
        let flow = run.start()?;
        let progress = if opts.progress { self.progress } else { None };
        let (k, outcome) = run.step_all(opts.algorithm, flow, progress);
        run.finish(k, outcome, started)
    }
}

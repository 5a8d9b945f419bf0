//! A run in its phases: check the grid, open the results, instantiate, initialize with values
//! propagated through the connections, step, and tear down.
//!
//! The phases are kept apart so that the order between them, which is what makes a run
//! reliable, reads in one short function ([`Cosimulation::run_reporting`]): the results file
//! before any instance (an unwritable destination costs nothing), the last row before the file
//! is closed, the file closed before an error is returned (so the error can point to it), and
//! the instances terminated only once the results are safe.

use super::algorithm::{Algorithm, Simulators};
use super::grid::Grid;
use super::observe::{ObserveError, Results};
use super::transfer::{External, Transfers};
use super::{
    Cosimulation, ExternalInputs, Progress, ProgressFn, RunError, RunOptions, RunSummary,
    stop_requested,
};
use crate::resolve::Setting;
use crate::system::Value;
use fmi_import::{FmiError, Instance, fmi2Status};
use std::time::Instant;

/// How the stepping ended.
enum Outcome {
    /// At the stop time.
    Completed,
    /// An FMU failed, in its step or when read for recording.
    Failed(FmiError),
    /// An instance ended the simulation (fmi2Discard with fmi2Terminated true), with its last
    /// successful time if past the last communication point.
    Ended { by: String, at: Option<f64> },
    /// [`super::request_stop`] was called.
    Interrupted,
}

/// An FMU's failure before the stepping: there are no results to point to yet.
fn fmi(error: FmiError) -> RunError {
    RunError::Fmi {
        error,
        results: None,
    }
}

/// What the phases of one run share.
struct Run<'a> {
    grid: Grid,
    /// Producers first ([`crate::resolve::Plan::order`]).
    order: &'a [usize],
    instances: Vec<Instance>,
    values: Transfers,
    external: External<'a>,
    results: Option<Results>,
}

/// The instances with the connections between them, as an algorithm steps them.
struct Connected<'r> {
    instances: &'r mut [Instance],
    values: &'r mut Transfers,
}

impl Simulators for Connected<'_> {
    #[inline]
    fn write_inputs(&mut self, c: usize) -> Result<(), FmiError> {
        self.values.write_inputs(c, &mut self.instances[c])
    }
    #[inline]
    fn do_step(&mut self, c: usize, t: f64, h: f64) -> Result<(), FmiError> {
        self.instances[c].do_step(t, h)
    }
    #[inline]
    fn read_outputs(&mut self, c: usize) -> Result<(), FmiError> {
        self.values.read_outputs(c, &mut self.instances[c])
    }
}

impl Cosimulation {
    /// Runs the system with external inputs (see [`Cosimulation::run_with_inputs`]), and
    /// reports progress to `progress` when [`RunOptions::progress`] asks for it.
    pub fn run_reporting(
        &self,
        opts: &RunOptions,
        external: &ExternalInputs<'_>,
        progress: &mut ProgressFn<'_>,
    ) -> Result<RunSummary, RunError> {
        let started = Instant::now();
        let grid = Grid::new(opts)?;
        let results = Results::new(&self.system, &self.model_descriptions(), opts, &grid)?;
        let instances = self.instantiate(opts)?;
        let mut run = Run {
            grid,
            order: &self.plan.order,
            values: Transfers::new(instances.len(), &self.plan.links),
            instances,
            external: External::new(external),
            results,
        };
        run.initialize(opts, &self.plan.settings).map_err(fmi)?;
        run.observe(run.grid.start)?;
        let (k, outcome) = run.step_all(opts.algorithm, opts.progress.then_some(progress))?;
        run.finish(k, outcome, started)
    }

    fn instantiate(&self, opts: &RunOptions) -> Result<Vec<Instance>, RunError> {
        let mut instances = Vec::with_capacity(self.fmus.len());
        for (c, fmu) in self.system.components.iter().zip(&self.fmus) {
            instances.push(fmu.instantiate(&c.name, opts.log.clone())?);
        }
        Ok(instances)
    }
}

impl Run<'_> {
    /// Experiment setup, the parameters, the external inputs at the start, then the initial
    /// values through the connections: producers first, repeated once per component so that
    /// values reach the end of any chain.
    fn initialize(&mut self, opts: &RunOptions, settings: &[Setting]) -> Result<(), FmiError> {
        let instances = &mut self.instances;
        for inst in instances.iter_mut() {
            inst.setup_experiment(opts.start, Some(opts.stop), None)?;
        }
        for s in settings {
            let inst = &mut instances[s.component];
            match &s.value {
                Value::Real(x) => inst.set_real(&[s.vr], &[*x]),
                Value::Integer(x) => inst.set_integer(&[s.vr], &[*x]),
                Value::Boolean(x) => inst.set_boolean(&[s.vr], &[*x]),
                Value::String(x) => inst.set_string(&[s.vr], &[x.as_str()]),
            }?;
        }
        for inst in instances.iter_mut() {
            inst.enter_initialization_mode()?;
        }
        if let Some(first) = instances.first_mut() {
            self.external.apply(first, opts.start)?;
        }
        for _ in 0..instances.len() {
            for &c in self.order {
                let inst = &mut instances[c];
                self.values.write_inputs(c, inst)?;
                self.values.read_outputs(c, inst)?;
            }
        }
        for &c in self.order {
            instances[c].exit_initialization_mode()?;
        }
        for (c, inst) in instances.iter_mut().enumerate() {
            self.values.read_outputs(c, inst)?;
        }
        Ok(())
    }

    /// A row at `t` outside the stepping (the start, or where an instance ended the run).
    fn observe(&mut self, t: f64) -> Result<(), RunError> {
        match self.results.as_mut() {
            Some(r) => r
                .observe(t, &mut self.instances)
                .map_err(ObserveError::into_run_error),
            None => Ok(()),
        }
    }

    /// Steps until the stop time, a failure, an instance ending the simulation or a stop
    /// request (checked once per step), with progress around it. Returns the steps done and
    /// how the stepping ended; a results write failing is returned at once, as an error.
    fn step_all(
        &mut self,
        algorithm: Algorithm,
        mut progress: Option<&mut ProgressFn<'_>>,
    ) -> Result<(u64, Outcome), RunError> {
        let grid = &self.grid;
        if let Some(p) = progress.as_mut() {
            p(Progress::Start { total: grid.steps });
        }
        let mut k = 0;
        let outcome = loop {
            if k >= grid.steps {
                break Ok(Outcome::Completed);
            }
            if stop_requested() {
                break Ok(Outcome::Interrupted);
            }
            let t = grid.time(k);
            let mut connected = Connected {
                instances: &mut self.instances,
                values: &mut self.values,
            };
            let stepped = self
                .external
                .apply(&mut connected.instances[0], t)
                .and_then(|()| algorithm.step(t, grid.step, self.order, &mut connected));
            if let Err(e) = stepped {
                break Ok(if e.status == fmi2Status::Discard && e.terminated {
                    let at = e.last_successful_time.filter(|a| *a > t && a.is_finite());
                    Outcome::Ended { by: e.instance, at }
                } else {
                    Outcome::Failed(e)
                });
            }
            k += 1;
            if let Some(r) = self.results.as_mut() {
                match r.stepped(k, grid, &mut self.instances) {
                    Ok(()) => {}
                    Err(ObserveError::Fmi(e)) => break Ok(Outcome::Failed(e)),
                    Err(ObserveError::Write(e)) => break Err(e),
                }
            }
            if let Some(p) = progress.as_mut()
                && k.is_multiple_of(1000)
            {
                p(Progress::Step { done: k });
            }
        };
        if let Some(p) = progress.as_mut() {
            p(Progress::End { done: k });
        }
        Ok((k, outcome?))
    }

    /// The last row of a run an instance ended early, the results closed, and the instances
    /// terminated; or the error the run ended with, pointing to the results kept.
    fn finish(
        mut self,
        k: u64,
        outcome: Outcome,
        started: Instant,
    ) -> Result<RunSummary, RunError> {
        let mut final_time = self.grid.time(k);
        let mut outcome = outcome;
        // As fmpy does: a last row at the ending FMU's last successful time, with every
        // component's outputs as they are (in a system, the others' at their last step).
        if let Outcome::Ended { at: Some(at), .. } = &outcome {
            final_time = *at;
            let at = *at;
            match self
                .results
                .as_mut()
                .map(|r| r.observe(at, &mut self.instances))
            {
                None | Some(Ok(())) => {}
                // Reading that row failed: the rows until then are finished and kept, as
                // when an FMU fails mid-run.
                Some(Err(ObserveError::Fmi(e))) => outcome = Outcome::Failed(e),
                Some(Err(ObserveError::Write(e))) => return Err(e),
            }
        }
        let (rows, results, table) = match self.results.take() {
            Some(r) => r.finish()?,
            None => (0, None, None),
        };
        let ended_by = match outcome {
            Outcome::Failed(error) => return Err(RunError::Fmi { error, results }),
            Outcome::Interrupted => {
                for inst in self.instances.iter_mut() {
                    // Terminating is a courtesy here; the interrupt is what the caller hears of.
                    let _ = inst.terminate();
                }
                return Err(RunError::Interrupted {
                    time: self.grid.time(k),
                    steps: k,
                    total: self.grid.steps,
                    rows,
                    results,
                });
            }
            Outcome::Ended { by, .. } => Some(by),
            Outcome::Completed => None,
        };
        for inst in self.instances.iter_mut() {
            inst.terminate().map_err(|error| RunError::Fmi {
                error,
                results: results.clone(),
            })?;
        }
        Ok(RunSummary {
            steps: k,
            rows,
            results,
            table,
            wall: started.elapsed(),
            final_time,
            ended_by,
        })
    }
}

//! A run in its phases: initialize with values propagated through the connections, step, and
//! tear down ([`super::Runner::run`] calls them in order).
//!
//! The phases are kept apart so that the order between them is what makes a run reliable: the
//! last row before the file is closed, the file closed before an error is returned (so the
//! error can point to it), and the instances terminated only once the results are safe.

use super::algorithm::{Algorithm, Simulators};
use super::grid::Grid;
use super::inputs::External;
use super::recording::Results;
use super::transfer::Transfers;
use super::{
    Cosimulation, End, Flow, ObserveError, Observer, Progress, ProgressFn, RunError, RunOptions,
    RunSummary, StopToken, Values,
};
use crate::resolve::Setting;
use crate::system::Value;
use fmi_import::{FmiError, Instance, fmi2Status};
use std::time::Instant;

/// How the stepping ended.
pub(super) enum Outcome {
    /// At the stop time.
    Completed,
    /// An FMU failed, in its step or when read by an observer.
    Failed(FmiError),
    /// An observer failed (the recording: a write); the run stops with its error at once.
    Aborted(RunError),
    /// An instance ended the simulation (fmi2Discard with fmi2Terminated true), with its last
    /// successful time if past the last communication point.
    Ended { by: String, at: Option<f64> },
    /// An observer returned [`Flow::Stop`].
    Stopped,
    /// The run's [`StopToken`] was set.
    Interrupted,
}

impl Outcome {
    fn end(&self) -> End {
        match self {
            Outcome::Completed => End::StopTime,
            Outcome::Failed(_) | Outcome::Aborted(_) => End::Failed,
            Outcome::Ended { by, .. } => End::Instance(by.clone()),
            Outcome::Stopped => End::Observer,
            Outcome::Interrupted => End::Interrupted,
        }
    }
}

/// An FMU's failure before the stepping: there are no results to point to yet.
pub(super) fn fmi(error: FmiError) -> RunError {
    RunError::Fmi {
        error,
        results: None,
    }
}

/// A point where the observers are called.
#[derive(Clone, Copy)]
enum Point {
    Initialized(f64),
    Stepped(u64, f64),
    EndedAt(f64),
}

impl Point {
    /// Calls the observer's method for this point; generic, so that the recording's call is
    /// static (and inlined in the stepping loop) and only the caller's observers are dynamic.
    #[inline]
    fn call<O: Observer + ?Sized>(
        self,
        o: &mut O,
        values: &mut Values<'_>,
    ) -> Result<Flow, ObserveError> {
        match self {
            Point::Initialized(t) => o.initialized(t, values),
            Point::Stepped(k, t) => o.stepped(k, t, values),
            Point::EndedAt(t) => o.ended_at(t, values).map(|()| Flow::Continue),
        }
    }
}

/// The recording (when the options ask for one) and the caller's observers, in the order
/// they are called. A run without observers of its own pays nothing for them.
pub(super) struct Observers<'a> {
    pub results: Option<Results>,
    pub others: Vec<&'a mut dyn Observer>,
}

impl Observers<'_> {
    /// Every observer sees the point, even after one asked to stop; the first error ends the
    /// round.
    #[inline]
    fn each(&mut self, instances: &mut [Instance], point: Point) -> Result<Flow, ObserveError> {
        let mut values = Values::new(instances);
        let mut flow = Flow::Continue;
        if let Some(r) = self.results.as_mut() {
            flow = point.call(r, &mut values)?;
        }
        for o in self.others.iter_mut() {
            if point.call(&mut **o, &mut values)? == Flow::Stop {
                flow = Flow::Stop;
            }
        }
        Ok(flow)
    }
}

/// What the phases of one run share.
pub(super) struct Run<'a> {
    pub grid: Grid,
    /// Producers first ([`crate::resolve::Plan::order`]).
    pub order: &'a [usize],
    pub instances: Vec<Instance>,
    pub values: Transfers,
    pub external: External<'a>,
    pub observers: Observers<'a>,
    pub stop: StopToken,
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
    pub(super) fn instantiate(&self, opts: &RunOptions) -> Result<Vec<Instance>, RunError> {
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
    pub(super) fn initialize(
        &mut self,
        opts: &RunOptions,
        settings: &[Setting],
    ) -> Result<(), FmiError> {
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
        self.external.apply(instances, opts.start)?;
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

    /// The observers at the start time. An FMU failing to be read here reports no results
    /// file (there is nothing in it yet).
    pub(super) fn start(&mut self) -> Result<Flow, RunError> {
        let t = self.grid.start;
        match self
            .observers
            .each(&mut self.instances, Point::Initialized(t))
        {
            Ok(flow) => Ok(flow),
            Err(e) => {
                self.notify_finished(0, t, &End::Failed);
                Err(match e {
                    ObserveError::Fmi(error) => fmi(error),
                    ObserveError::Run(e) => e,
                })
            }
        }
    }

    /// Steps until the stop time, a failure, an instance ending the simulation, an observer's
    /// [`Flow::Stop`] or the stop token (checked once per step), with progress around it.
    /// Returns the steps done and how the stepping ended.
    pub(super) fn step_all(
        &mut self,
        algorithm: Algorithm,
        first: Flow,
        mut progress: Option<&mut ProgressFn<'_>>,
    ) -> (u64, Outcome) {
        let grid = &self.grid;
        if let Some(p) = progress.as_mut() {
            p(Progress::Start { total: grid.steps });
        }
        let mut k = 0;
        let mut flow = first;
        // A run that records nothing and has no observer pays nothing for observing.
        let observed = self.observers.results.is_some() || !self.observers.others.is_empty();
        let outcome = loop {
            if k >= grid.steps {
                break Outcome::Completed;
            }
            if flow == Flow::Stop {
                break Outcome::Stopped;
            }
            if self.stop.is_stopped() {
                break Outcome::Interrupted;
            }
            let t = grid.time(k);
            let mut connected = Connected {
                instances: &mut self.instances,
                values: &mut self.values,
            };
            let stepped = self
                .external
                .apply(connected.instances, t)
                .and_then(|()| algorithm.step(t, grid.step, self.order, &mut connected));
            if let Err(e) = stepped {
                break if e.status == fmi2Status::Discard && e.terminated {
                    let at = e.last_successful_time.filter(|a| *a > t && a.is_finite());
                    Outcome::Ended { by: e.instance, at }
                } else {
                    Outcome::Failed(e)
                };
            }
            k += 1;
            if observed {
                let point = Point::Stepped(k, grid.time(k));
                match self.observers.each(&mut self.instances, point) {
                    Ok(f) => flow = f,
                    Err(ObserveError::Fmi(e)) => break Outcome::Failed(e),
                    Err(ObserveError::Run(e)) => break Outcome::Aborted(e),
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
        (k, outcome)
    }

    /// Tells every observer the stepping is over.
    fn notify_finished(&mut self, k: u64, t: f64, end: &End) {
        if let Some(r) = self.observers.results.as_mut() {
            r.finished(k, t, end);
        }
        for o in self.observers.others.iter_mut() {
            o.finished(k, t, end);
        }
    }

    /// The last row of a run an instance ended early, the observers told, the results closed,
    /// and the instances terminated; or the error the run ended with, pointing to the results
    /// kept.
    pub(super) fn finish(
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
            let ended = self.observers.each(&mut self.instances, Point::EndedAt(at));
            match ended {
                Ok(_) => {}
                // Reading that row failed: the rows until then are finished and kept, as
                // when an FMU fails mid-run.
                Err(ObserveError::Fmi(e)) => outcome = Outcome::Failed(e),
                Err(ObserveError::Run(e)) => outcome = Outcome::Aborted(e),
            }
        }
        self.notify_finished(k, final_time, &outcome.end());
        let outcome = match outcome {
            // A write failed: the results are left as they are (the recorder says where).
            Outcome::Aborted(e) => return Err(e),
            other => other,
        };
        let (rows, results, table) = match self.observers.results.take() {
            Some(r) => r.finish()?,
            None => (0, None, None),
        };
        let end = match outcome {
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
            other => other.end(),
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
            end,
        })
    }
}

//! What the master tells an observer of a run, as libcosim's `observer` interface does
//! (`simulation_initialized`, `step_complete`), and how an observer ends a run early, as fmpy's
//! `step_finished` callback does by returning `False`.
//!
//! The recording of results is one observer ([`super::RunOptions`] asks for it); a caller adds
//! its own with [`super::Runner::observe`]. Observers see the values between steps, never the
//! instances themselves: they read, they do not step or set.

use super::RunError;
use fmi_import::{FmiError, Instance};
use model_description::BaseType;

/// Whether the run goes on after an observer has seen a communication point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Go on to the next communication step (the run still ends at the stop time, a failure
    /// or the stop token).
    Continue,
    /// End the run here, cleanly: the steps until now are kept, the instances terminated, and
    /// the summary says [`End::Observer`].
    Stop,
}

/// How the stepping of a run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum End {
    /// At the stop time.
    StopTime,
    /// This instance ended the simulation: its fmi2DoStep returned fmi2Discard with
    /// fmi2GetBooleanStatus(fmi2Terminated) true (a model reaching its end, as fmpy reads it).
    Instance(String),
    /// An observer returned [`Flow::Stop`].
    Observer,
    /// The run's [`super::StopToken`] was set (Ctrl-C on the command line); the run returns
    /// [`RunError::Interrupted`].
    Interrupted,
    /// An FMU or an observer failed; the run returns the error.
    Failed,
}

/// Why an observation failed.
#[derive(Debug)]
pub enum ObserveError {
    /// Reading an FMU failed: the run ends as if that FMU had failed in its step, keeping what
    /// was recorded until then ([`RunError::Fmi`], exit 3).
    Fmi(FmiError),
    /// The observer itself failed (the recording: a write): the run stops at once with this
    /// error.
    Run(RunError),
}

impl From<FmiError> for ObserveError {
    fn from(e: FmiError) -> Self {
        ObserveError::Fmi(e)
    }
}

/// The values of a running system as an observer reads them, components addressed by their
/// index in [`crate::system::System::components`] and variables by value reference
/// ([`super::Cosimulation::address`] finds both from a name).
///
/// # Panics
/// A component index out of range panics, as slice indexing does: the indices come from the
/// system the observer was made for.
pub struct Values<'a> {
    instances: &'a mut [Instance],
}

impl<'a> Values<'a> {
    pub(super) fn new(instances: &'a mut [Instance]) -> Values<'a> {
        Values { instances }
    }

    /// The number of components.
    pub fn len(&self) -> usize {
        self.instances.len()
    }

    /// Whether the system has no components (never, for a loaded system: it needs one).
    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    /// Component `c`'s Real variables `vr` into `out` (same length, else an error), with one
    /// fmi2GetReal: the way to read many values of one component per step.
    #[inline]
    pub fn get_real(&mut self, c: usize, vr: &[u32], out: &mut [f64]) -> Result<(), FmiError> {
        self.instances[c].get_real(vr, out)
    }

    /// Component `c`'s Integer (or Enumeration) variables `vr` into `out`, with one
    /// fmi2GetInteger.
    #[inline]
    pub fn get_integer(&mut self, c: usize, vr: &[u32], out: &mut [i32]) -> Result<(), FmiError> {
        self.instances[c].get_integer(vr, out)
    }

    /// Component `c`'s Boolean variables `vr` into `out`, with one fmi2GetBoolean.
    #[inline]
    pub fn get_boolean(&mut self, c: usize, vr: &[u32], out: &mut [bool]) -> Result<(), FmiError> {
        self.instances[c].get_boolean(vr, out)
    }

    /// One value as a number, as the results hold it: an Integer or Enumeration as a whole
    /// number, a Boolean as 0 or 1 (a String reads as NaN: it has no number).
    pub fn value(&mut self, a: &super::Address) -> Result<f64, FmiError> {
        Ok(match a.base {
            BaseType::Real => {
                let mut x = [0.0];
                self.get_real(a.component, &[a.vr], &mut x)?;
                x[0]
            }
            BaseType::Integer | BaseType::Enumeration => {
                let mut x = [0];
                self.get_integer(a.component, &[a.vr], &mut x)?;
                f64::from(x[0])
            }
            BaseType::Boolean => {
                let mut x = [false];
                self.get_boolean(a.component, &[a.vr], &mut x)?;
                if x[0] { 1.0 } else { 0.0 }
            }
            BaseType::String => f64::NAN,
        })
    }
}

/// An observer of a run. The master calls it at the start, after every communication step,
/// where an instance ended the run between two points, and once at the end; each call that
/// returns a [`Flow`] can end the run there.
pub trait Observer {
    /// After initialization, at the start time, before the first step.
    fn initialized(&mut self, _time: f64, _values: &mut Values<'_>) -> Result<Flow, ObserveError> {
        Ok(Flow::Continue)
    }

    /// After communication step `step` (counted from 1), at its end time `time`.
    fn stepped(
        &mut self,
        step: u64,
        time: f64,
        values: &mut Values<'_>,
    ) -> Result<Flow, ObserveError>;

    /// An instance ended the simulation and reported its last successful time `time`, past
    /// the last communication point: the values there (fmpy records a last row at that time).
    fn ended_at(&mut self, _time: f64, _values: &mut Values<'_>) -> Result<(), ObserveError> {
        Ok(())
    }

    /// The stepping is over after `steps` steps, at `time`, for the reason `end`; the
    /// instances are still there, about to be terminated (or dropped, after a failure).
    fn finished(&mut self, _steps: u64, _time: f64, _end: &End) {}
}

//! The co-simulation algorithms, apart from everything else a run does, so that what one
//! communication step means can be read (and tested) on its own, as libcosim's algorithm
//! interface is.
//!
//! Gauss-Seidel (the default) steps the components one after another, producers first (the
//! order of [`crate::resolve::Plan::order`]), each seeing its producers' outputs at the end of
//! the step: with the vehicle stepped first, the estimator receives the sensor samples at
//! `t + h`, as it expects. Jacobi sets every input from the outputs at `t`, then steps every
//! component, as a parallel master would; a consumer then lags its producers by one step.

use fmi_import::FmiError;

/// How one communication step orders the components' input writes, steps and output reads
/// (see the module docs); chosen per run ([`super::RunOptions::algorithm`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Algorithm {
    /// Each component in turn: inputs, step, outputs. A consumer sees its producers' outputs
    /// at `t + h`. The default.
    GaussSeidel,
    /// Every input from the outputs at `t`, then every step, then every output: a consumer
    /// lags its producers by one step.
    Jacobi,
}

/// The components an algorithm steps, addressed by their index in the system. A run's are its
/// FMU instances with the connections between them; a test's can be a log of the calls.
pub(super) trait Simulators {
    /// Sets component `c`'s connected inputs from the outputs last read.
    fn write_inputs(&mut self, c: usize) -> Result<(), FmiError>;
    /// Advances component `c` from `t` to `t + h`.
    fn do_step(&mut self, c: usize, t: f64, h: f64) -> Result<(), FmiError>;
    /// Reads component `c`'s connected outputs.
    fn read_outputs(&mut self, c: usize) -> Result<(), FmiError>;
}

impl Algorithm {
    /// One communication step from `t` to `t + h`, stopping at the first failure.
    #[inline]
    pub(super) fn step<S: Simulators>(
        self,
        t: f64,
        h: f64,
        order: &[usize],
        components: &mut S,
    ) -> Result<(), FmiError> {
        match self {
            Algorithm::GaussSeidel => {
                for &c in order {
                    components.write_inputs(c)?;
                    components.do_step(c, t, h)?;
                    components.read_outputs(c)?;
                }
            }
            Algorithm::Jacobi => {
                for &c in order {
                    components.write_inputs(c)?;
                }
                for &c in order {
                    components.do_step(c, t, h)?;
                }
                for &c in order {
                    components.read_outputs(c)?;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmi_import::fmi2Status;

    /// Logs the calls; `do_step` of `fails` fails.
    #[derive(Default)]
    struct Log {
        calls: Vec<String>,
        fails: Option<usize>,
    }

    impl Simulators for Log {
        fn write_inputs(&mut self, c: usize) -> Result<(), FmiError> {
            self.calls.push(format!("set {c}"));
            Ok(())
        }
        fn do_step(&mut self, c: usize, t: f64, h: f64) -> Result<(), FmiError> {
            self.calls.push(format!("step {c} {t} {h}"));
            if self.fails == Some(c) {
                return Err(FmiError {
                    instance: format!("c{c}"),
                    fmu: "stub.fmu".into(),
                    function: "fmi2DoStep",
                    status: fmi2Status::Error,
                    time: Some(t),
                    last_successful_time: None,
                    terminated: false,
                    messages: vec![],
                });
            }
            Ok(())
        }
        fn read_outputs(&mut self, c: usize) -> Result<(), FmiError> {
            self.calls.push(format!("get {c}"));
            Ok(())
        }
    }

    fn one_step(algorithm: Algorithm, fails: Option<usize>) -> (Vec<String>, Option<String>) {
        let mut log = Log {
            fails,
            ..Log::default()
        };
        let r = algorithm.step(0.5, 0.25, &[2, 0, 1], &mut log);
        (log.calls, r.err().map(|e| e.instance))
    }

    #[test]
    fn gauss_seidel_steps_each_component_between_its_inputs_and_outputs_in_order() {
        let (calls, err) = one_step(Algorithm::GaussSeidel, None);
        assert_eq!(err, None);
        assert_eq!(
            calls,
            [
                "set 2",
                "step 2 0.5 0.25",
                "get 2",
                "set 0",
                "step 0 0.5 0.25",
                "get 0",
                "set 1",
                "step 1 0.5 0.25",
                "get 1",
            ]
        );
    }

    #[test]
    fn jacobi_sets_every_input_before_any_step_and_reads_after_every_step() {
        let (calls, err) = one_step(Algorithm::Jacobi, None);
        assert_eq!(err, None);
        assert_eq!(
            calls,
            [
                "set 2",
                "set 0",
                "set 1",
                "step 2 0.5 0.25",
                "step 0 0.5 0.25",
                "step 1 0.5 0.25",
                "get 2",
                "get 0",
                "get 1",
            ]
        );
    }

    #[test]
    fn a_failing_step_stops_the_communication_step_at_once() {
        let (calls, err) = one_step(Algorithm::GaussSeidel, Some(0));
        assert_eq!(err.as_deref(), Some("c0"));
        assert_eq!(
            calls,
            [
                "set 2",
                "step 2 0.5 0.25",
                "get 2",
                "set 0",
                "step 0 0.5 0.25"
            ]
        );
        let (calls, err) = one_step(Algorithm::Jacobi, Some(0));
        assert_eq!(err.as_deref(), Some("c0"));
        assert_eq!(
            calls,
            [
                "set 2",
                "set 0",
                "set 1",
                "step 2 0.5 0.25",
                "step 0 0.5 0.25"
            ]
        );
    }
}

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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Algorithm {
    GaussSeidel,
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

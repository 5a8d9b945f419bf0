//! The filter behind the FMU, for whichever state dimension the alignment prior needs: one
//! enum, so the FMU and the offline processor call one set of methods.

use crate::engine::Engine;
use crate::error::StepError;
use crate::filter::Vec4;
use crate::observability::pbh_rank;
use crate::smoother::smooth;
use crate::statespace::XI;
use serde::{Deserialize, Serialize};

// Both variants are a few kilobytes (matrices by value, as the step needs them); the enum is
// held once per FMU instance, so boxing would only add an indirection per step.
/// The Kalman filter of the chosen alignment prior: 7 states (the paper's random walk) or 8
/// (the alignment's rate too), behind one set of methods.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Core {
    /// The paper's model (random-walk alignment).
    Seven(Engine<7>),
    /// The alignment and its rate in the state.
    Eight(Engine<8>),
}

macro_rules! each {
    ($self:expr, $e:ident => $body:expr) => {
        match $self {
            Core::Seven($e) => $body,
            Core::Eight($e) => $body,
        }
    };
}

impl Core {
    /// One step of `h` \[s\] at `speed` \[m/s\] with the samples `z` (ws_acc_y, ws_yaw_rate,
    /// frame_acc_y, and 0 for the virtual measurement): the NIS of the update, or why the
    /// update was skipped (the prediction kept, [`StepError::Skipped`]) or the gain failed.
    /// The caller holds the filter below `min_speed`; this does not check it.
    pub fn step(&mut self, speed: f64, h: f64, z: &Vec4) -> Result<f64, StepError> {
        each!(self, e => e.step(speed, h, z))
    }

    /// Alignment estimate and its standard deviation.
    pub fn alignment(&self) -> (f64, f64) {
        each!(self, e => e.alignment())
    }

    /// The body states `[y, psi, y_f, ydot, psidot, y_fdot]` and the alignment's rate (0 for the
    /// 7-state model).
    pub fn states(&self) -> ([f64; 6], f64) {
        each!(self, e => {
            let x = &e.filter.x;
            ([x[0], x[1], x[2], x[3], x[4], x[5]], if x.len() > 7 { x[7] } else { 0.0 })
        })
    }

    /// A message, once, when the stationary start fell back to the initial covariance.
    pub fn take_start_note(&mut self) -> Option<String> {
        each!(self, e => e.start_note.take())
    }

    /// The PBH observability rank of the filter's model at `speed`: `(rank, states, eigenvalue
    /// where the rank is smallest)`.
    pub fn observability(&self, speed: f64) -> (usize, usize, nalgebra::Complex<f64>) {
        each!(self, e => {
            let fc = e.space.fc(speed);
            let (rank, lambda) = pbh_rank(&fc, &e.space.measurement(&fc));
            (rank, fc.nrows(), lambda)
        })
    }

    /// The filter covariance P: whether its Cholesky factorization succeeds (P positive
    /// definite), its smallest and largest eigenvalue when `eigenvalues` (a 7 x 7
    /// eigen-decomposition, some microseconds), and its largest asymmetry `max |P - P^T|`:
    /// what a soak test checks. Not part of the FMU's step.
    pub fn covariance_check(&self, eigenvalues: bool) -> (bool, Option<(f64, f64)>, f64) {
        each!(self, e => {
            let p = &e.filter.p;
            let definite = p.cholesky().is_some();
            let eig = eigenvalues.then(|| {
                let v = p.symmetric_eigenvalues();
                (v.min(), v.max())
            });
            (definite, eig, (p - p.transpose()).amax())
        })
    }

    /// Steps whose measurement update was skipped so far (the FMU's `skipped_updates`).
    pub fn skipped(&self) -> i32 {
        each!(self, e => e.skipped)
    }

    /// How many times F, H and Q were rebuilt, on a change of speed or step (the FMU's
    /// `rebuilds`).
    pub fn rebuilds(&self) -> i32 {
        each!(self, e => e.rebuilds)
    }

    /// Keeps every step's predicted and filtered estimates from now on, for the RTS smoother
    /// ([`Core::smoothed_alignment`]); memory grows with the run, so only offline runs do it.
    pub fn record_history(&mut self) {
        each!(self, e => e.record_history())
    }

    /// How many filter steps were recorded for the smoother (0 without a history): a sample
    /// step other than the model's runs more or fewer filter steps than samples.
    pub fn recorded_steps(&self) -> usize {
        each!(self, e => e.history.as_ref().map_or(0, |h| h.x_filt.len()))
    }

    /// The smoothed alignment and its standard deviation at every recorded step (empty if no
    /// history was recorded).
    pub fn smoothed_alignment(&self) -> Vec<(f64, f64)> {
        each!(self, e => match &e.history {
            None => Vec::new(),
            Some(h) => {
                let (xs, ps) = smooth(h);
                xs.iter()
                    .zip(&ps)
                    .map(|(x, p)| (x[XI], p[(XI, XI)].max(0.0).sqrt()))
                    .collect()
            }
        })
    }
}

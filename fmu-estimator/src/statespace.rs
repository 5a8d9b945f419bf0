//! The filter's linear system for a given alignment prior, built once and re-evaluated cheaply
//! at every speed.
//!
//! # State
//! - 7 states (random-walk prior): `[y, psi, y_f, ydot, psidot, y_fdot, xi]`, the paper's;
//! - 8 states (integrated random walk or shaping filter): the same plus `xidot` (index 7).
//!
//! # Speed dependence
//! `F_c(V) = base + per_inv_speed / V + per_speed V + per_speed2 V^2`: the creep damping of the
//! simplified model goes as `1 / V` ([`crate::model::state_matrix_parts`]); the alignment prior,
//! written along the track and mapped to time, goes as `V` and `V^2` ([`crate::prior`]). So a new
//! speed costs four scaled matrix sums, not a model rebuild: that is how the filter follows a speed
//! input that changes at every step. The discrete `F` then follows from the chosen scheme
//! ([`crate::discretize`]): the second-order Taylor scheme is a few more matrix sums; the exact
//! scheme needs a matrix exponential (a few microseconds).
//!
//! # Process noise
//! The body states' noise comes from the calibration file (a discrete `Q` for its step, scaled
//! by `h / step_size`) or from the diagonal intensities (`Q = h diag(q)`); see
//! [`crate::calibration`]. With an 8-state prior the alignment's row and column of that `Q` are
//! replaced by the prior's own block, `q V^3 [h^3/3, h^2/2; h^2/2, h]`.
//!
//! # Measurements
//! `H` holds the acceleration rows of `F_c` for the two accelerometers (they depend on the speed
//! too), a unit entry on `psidot` for the gyroscope, and a unit entry on `xi` for the virtual
//! measurement `0 = xi + v`, or a zero row when the virtual measurement is switched off (then the
//! fourth innovation is always zero and carries no information, exactly as if the row were
//! absent).

use crate::discretize::{Scheme, taylor2};
use crate::model::state_matrix_parts;
use crate::params::Params;
use crate::prior::AlignmentModel;
use nalgebra::{DMatrix, SMatrix};
use serde::{Deserialize, Serialize};

/// Index of the alignment in every state vector.
pub const XI: usize = 6;

/// Process noise of the body states (and, for the paper's model, of the alignment).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum BodyNoise {
    /// Continuous intensities: `Q = h q_rate`.
    Rate(SMatrix<f64, 7, 7>),
    /// A discrete `Q` computed for `step_size`: `Q = q h / step_size`.
    Calibrated {
        /// The calibration file's Q over the paper's 7 states.
        q: SMatrix<f64, 7, 7>,
        /// The step it was computed for \[s\].
        step_size: f64,
    },
}

impl BodyNoise {
    fn for_step(&self, h: f64) -> SMatrix<f64, 7, 7> {
        match self {
            BodyNoise::Rate(q) => q * h,
            BodyNoise::Calibrated { q, step_size } => q * (h / step_size),
        }
    }
}

/// The continuous model, split by speed dependence, and its noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateSpace<const N: usize> {
    base: SMatrix<f64, N, N>,
    per_inv_speed: SMatrix<f64, N, N>,
    per_speed: SMatrix<f64, N, N>,
    per_speed2: SMatrix<f64, N, N>,
    body_noise: BodyNoise,
    /// The prior's intensity along the track `q` (8 states only).
    prior_q: f64,
    virtual_measurement: bool,
}

/// Discrete matrices for one (speed, step).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Discrete<const N: usize> {
    /// The speed they were built for \[m/s\] (compared exactly to decide a rebuild).
    pub speed: f64,
    /// The step they were built for \[s\].
    pub h: f64,
    /// The transition matrix `F` over one step.
    pub f: SMatrix<f64, N, N>,
    /// The measurement matrix `H` (the accelerometer rows taken from `F_c`, so they depend on
    /// the speed).
    pub hm: SMatrix<f64, 4, N>,
    /// The discrete process noise `Q` over one step.
    pub q: SMatrix<f64, N, N>,
}

fn embed<const N: usize>(m: &SMatrix<f64, 7, 7>) -> SMatrix<f64, N, N> {
    SMatrix::<f64, N, N>::from_fn(|i, j| if i < 7 && j < 7 { m[(i, j)] } else { 0.0 })
}

impl StateSpace<7> {
    /// The paper's model (random-walk alignment).
    pub fn paper(p: &Params, body_noise: BodyNoise, virtual_measurement: bool) -> Self {
        let (base, per_inv_speed) = state_matrix_parts(p);
        StateSpace {
            base,
            per_inv_speed,
            per_speed: SMatrix::zeros(),
            per_speed2: SMatrix::zeros(),
            body_noise,
            prior_q: 0.0,
            virtual_measurement,
        }
    }
}

impl StateSpace<8> {
    /// The simplified model with the alignment's rate in the state and the prior `model`
    /// (which must not be the random walk).
    pub fn with_prior(
        p: &Params,
        model: &AlignmentModel,
        body_noise: BodyNoise,
        virtual_measurement: bool,
    ) -> Self {
        let (a1, a0, q) = model
            .second_order()
            .expect("the random-walk prior has 7 states");
        let (b7, i7) = state_matrix_parts(p);
        let mut base = embed::<8>(&b7);
        base[(XI, 7)] = 1.0;
        let mut per_speed = SMatrix::<f64, 8, 8>::zeros();
        per_speed[(7, 7)] = -a1;
        let mut per_speed2 = SMatrix::<f64, 8, 8>::zeros();
        per_speed2[(7, XI)] = -a0;
        StateSpace {
            base,
            per_inv_speed: embed::<8>(&i7),
            per_speed,
            per_speed2,
            body_noise,
            prior_q: q,
            virtual_measurement,
        }
    }
}

impl<const N: usize> StateSpace<N> {
    /// `F_c` at speed `v`.
    pub fn fc(&self, v: f64) -> SMatrix<f64, N, N> {
        let mut f = self.base + self.per_inv_speed * (1.0 / v);
        if N > 7 {
            f += self.per_speed * v + self.per_speed2 * (v * v);
        }
        f
    }

    /// The (position, velocity) row pairs of the second-order scheme.
    fn pairs() -> &'static [(usize, usize)] {
        if N > 7 {
            &[(0, 3), (1, 4), (2, 5), (XI, 7)]
        } else {
            &[(0, 3), (1, 4), (2, 5)]
        }
    }

    /// `F` for one step `h` from `F_c` (see [`crate::discretize`]).
    pub fn transition(
        &self,
        fc: &SMatrix<f64, N, N>,
        h: f64,
        scheme: Scheme,
    ) -> SMatrix<f64, N, N> {
        match scheme {
            Scheme::Exact => {
                let d = DMatrix::from_iterator(N, N, fc.iter().map(|x| x * h)).exp();
                SMatrix::<f64, N, N>::from_iterator(d.iter().copied())
            }
            Scheme::Taylor2 => taylor2(fc, h, Self::pairs()),
        }
    }

    /// `H` (4 x N) from `F_c`.
    pub fn measurement(&self, fc: &SMatrix<f64, N, N>) -> SMatrix<f64, 4, N> {
        let mut h = SMatrix::<f64, 4, N>::zeros();
        h.set_row(0, &fc.row(3));
        h[(1, 4)] = 1.0;
        h.set_row(2, &fc.row(5));
        if self.virtual_measurement {
            h[(3, XI)] = 1.0;
        }
        h
    }

    /// The discrete process noise for speed `v` and step `h`.
    pub fn process_noise(&self, v: f64, h: f64) -> SMatrix<f64, N, N> {
        let mut q = embed::<N>(&self.body_noise.for_step(h));
        if N > 7 {
            for k in 0..N {
                q[(XI, k)] = 0.0;
                q[(k, XI)] = 0.0;
            }
            let qt = self.prior_q * v * v * v;
            q[(XI, XI)] = qt * h * h * h / 3.0;
            q[(XI, 7)] = qt * h * h / 2.0;
            q[(7, XI)] = qt * h * h / 2.0;
            q[(7, 7)] = qt * h;
        }
        q
    }

    /// Everything the filter needs for one (speed, step).
    pub fn discrete(&self, speed: f64, h: f64, scheme: Scheme) -> Discrete<N> {
        let mut d = Discrete {
            speed,
            h,
            f: SMatrix::zeros(),
            hm: SMatrix::zeros(),
            q: SMatrix::zeros(),
        };
        self.rebuild(&mut d, speed, h, scheme);
        d
    }

    /// [`StateSpace::discrete`] written over `d`: under a measured speed the matrices are
    /// rebuilt at almost every sample, and moving a new set of them into place cost more than
    /// building them.
    pub fn rebuild(&self, d: &mut Discrete<N>, speed: f64, h: f64, scheme: Scheme) {
        let fc = self.fc(speed);
        d.speed = speed;
        d.h = h;
        d.f = self.transition(&fc, h, scheme);
        d.hm = self.measurement(&fc);
        d.q = self.process_noise(speed, h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discretize::transition;
    use crate::model::{measurement_matrix, state_matrix};
    use crate::prior::Spectrum;

    fn noise() -> BodyNoise {
        BodyNoise::Rate(SMatrix::<f64, 7, 7>::from_diagonal(&nalgebra::SVector::<
            f64,
            7,
        >::from_column_slice(
            &[0., 0., 0., 1e-4, 1e-4, 1e-4, 1e-5],
        )))
    }

    /// The 7-state system is the paper's model of `crate::model` at every speed.
    #[test]
    fn the_paper_system_matches_the_model_module() {
        let p = Params::default();
        let ss = StateSpace::paper(&p, noise(), true);
        for v in [3.0, 20.0, 55.0] {
            let fc = state_matrix(&p, v);
            let d = ss.discrete(v, 1e-3, Scheme::Taylor2);
            let f = transition(&fc, 1e-3, Scheme::Taylor2);
            assert!((d.f - f).amax() < 1e-12 * f.amax(), "{v}");
            let hm = measurement_matrix(&fc);
            assert!((d.hm - hm).amax() < 1e-12 * hm.amax(), "{v}");
            let e = ss.discrete(v, 1e-3, Scheme::Exact);
            let fe = transition(&fc, 1e-3, Scheme::Exact);
            assert!((e.f - fe).amax() < 1e-12, "{v}");
        }
    }

    /// The 8-state system's body block equals the paper's, and its alignment block is the
    /// prior's oscillator `xi_tt + V a1 xi_t + V^2 a0 xi = 0` (checked on its eigenvalues,
    /// which must be `-V Or` and `-V Oc` for the shaping filter).
    #[test]
    fn the_prior_block_has_the_spectrum_poles_scaled_by_speed() {
        let p = Params::default();
        let s = Spectrum::GERMAN_LOW;
        let ss = StateSpace::with_prior(&p, &AlignmentModel::Shaping(s), noise(), false);
        let v = 20.0;
        let fc8 = ss.fc(v);
        let fc7 = state_matrix(&p, v);
        for i in 0..7 {
            for j in 0..7 {
                assert!((fc8[(i, j)] - fc7[(i, j)]).abs() <= 1e-12 * fc7.amax());
            }
        }
        let block = nalgebra::Matrix2::new(fc8[(6, 6)], fc8[(6, 7)], fc8[(7, 6)], fc8[(7, 7)]);
        let mut eig: Vec<f64> = block.complex_eigenvalues().iter().map(|e| e.re).collect();
        eig.sort_by(f64::total_cmp);
        assert!((eig[0] + v * s.omega_c).abs() < 1e-9, "{eig:?}");
        assert!((eig[1] + v * s.omega_r).abs() < 1e-9, "{eig:?}");
        // No virtual measurement: the fourth row of H is zero.
        assert_eq!(ss.measurement(&fc8).row(3).amax(), 0.0);
    }

    /// The prior's discrete noise is that of white noise of intensity q V^3 on xi_tt
    /// (the standard integrated-random-walk covariance).
    #[test]
    fn the_prior_noise_scales_with_the_cube_of_speed() {
        let p = Params::default();
        let s = Spectrum::GERMAN_LOW;
        let ss =
            StateSpace::with_prior(&p, &AlignmentModel::IntegratedRandomWalk(s), noise(), true);
        let (h, v) = (1e-3, 10.0);
        let q1 = ss.process_noise(v, h);
        let q2 = ss.process_noise(2.0 * v, h);
        assert!((q2[(7, 7)] / q1[(7, 7)] - 8.0).abs() < 1e-12);
        assert!((q1[(6, 6)] * q1[(7, 7)] / (q1[(6, 7)] * q1[(6, 7)]) - 4.0 / 3.0).abs() < 1e-12);
        assert_eq!(q1[(6, 3)], 0.0);
        assert_eq!(q1[(3, 3)], 1e-4 * h);
    }
}

//! One filter step, for any state dimension: rebuild the discrete matrices when the speed or the
//! step changes, predict, update with the sensor samples, and (for offline processing) keep what
//! the smoother needs.
//!
//! Two gains:
//! - [`Gain::TimeVarying`], the Kalman filter proper: `P` is propagated at every step (Joseph
//!   form, [`crate::filter`]).
//! - [`Gain::SteadyState`]: for a constant speed and step the time-varying gain converges to the
//!   gain of the discrete algebraic Riccati equation (DARE)
//!   `P = F P F^T + Q - F P H^T (H P H^T + R)^-1 H P F^T` (`P` the predicted covariance). It is
//!   computed once per (speed, step) by iterating the filter's own Riccati recursion to a fixed
//!   point (checked by the DARE residual), after which a step is two small matrix-vector products:
//!   `x = F x`, `x += K (z - H x)`. What is lost is the filter's transient after start-up (the
//!   gain is the converged one from the first step) and, under a changing speed, the cost: every
//!   new speed solves the DARE again, so use it at constant speed, as on a low-cost on-board target.

use crate::discretize::Scheme;
use crate::filter::{Kalman, Mat4, Vec4};
use crate::smoother::History;
use crate::statespace::{Discrete, StateSpace, XI};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// How the gain is computed (FMI parameter `gain`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Gain {
    /// 1: the Kalman filter's time-varying gain.
    TimeVarying,
    /// 2: the steady-state gain from the DARE.
    SteadyState,
}

impl Gain {
    pub fn from_fmi(code: i32) -> Result<Gain, String> {
        match code {
            1 => Ok(Gain::TimeVarying),
            2 => Ok(Gain::SteadyState),
            other => Err(format!(
                "parameter 'gain' = {other}: use 1 (time-varying Kalman gain) or 2 (steady-state gain from the Riccati equation)"
            )),
        }
    }
}

/// The converged filter for one (speed, step).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SteadyState<const N: usize> {
    /// Gain `K` (N x 4).
    pub k: SMatrix<f64, N, 4>,
    /// Predicted covariance, the DARE's solution.
    pub p_pred: SMatrix<f64, N, N>,
    /// Filtered covariance `(I - K H) P_pred`.
    pub p_filt: SMatrix<f64, N, N>,
    /// Inverse innovation covariance, for the NIS.
    pub s_inv: Mat4,
    /// Riccati iterations it took.
    pub iterations: usize,
}

/// Solves the DARE by iterating the Riccati recursion from `p0` until the predicted covariance
/// stops changing (relative change below 1e-13 for 20 consecutive iterations), then checks the
/// DARE residual.
pub fn steady_state<const N: usize>(
    d: &Discrete<N>,
    r: &Mat4,
    p0: &SMatrix<f64, N, N>,
) -> Result<SteadyState<N>, String> {
    const MAX_ITERATIONS: usize = 2_000_000;
    let mut kf = Kalman::new(SVector::<f64, N>::zeros(), *p0);
    let mut p_pred_prev = SMatrix::<f64, N, N>::zeros();
    let mut quiet = 0;
    for it in 1..=MAX_ITERATIONS {
        kf.predict(&d.f, &d.q);
        let p_pred = kf.p;
        if kf.update(&d.hm, r, &Vec4::zeros()).is_none() {
            return Err(
                "steady-state gain: the innovation covariance is not positive definite".into(),
            );
        }
        if (p_pred - p_pred_prev).amax() <= 1e-13 * p_pred.amax() {
            quiet += 1;
            if quiet == 20 {
                let s = d.hm * p_pred * d.hm.transpose() + r;
                let s_inv = s
                    .try_inverse()
                    .ok_or("steady-state gain: singular innovation covariance")?;
                let k = p_pred * d.hm.transpose() * s_inv;
                let residual = d.f * p_pred * d.f.transpose() + d.q
                    - d.f * p_pred * d.hm.transpose() * s_inv * d.hm * p_pred * d.f.transpose()
                    - p_pred;
                if residual.amax() > 1e-9 * p_pred.amax() {
                    return Err(format!(
                        "steady-state gain: the Riccati iteration stopped with a DARE residual of {:.3e} (relative)",
                        residual.amax() / p_pred.amax()
                    ));
                }
                return Ok(SteadyState {
                    k,
                    p_pred,
                    p_filt: kf.p,
                    s_inv,
                    iterations: it,
                });
            }
        } else {
            quiet = 0;
        }
        p_pred_prev = p_pred;
    }
    Err(format!(
        "steady-state gain: the Riccati iteration did not converge in {MAX_ITERATIONS} steps (is the system detectable?)"
    ))
}

/// Why a measurement update was skipped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Skip {
    /// A sensor sample was NaN or infinite: the prediction is kept.
    NonFinite,
    /// The innovation covariance was not positive definite.
    NotPositiveDefinite,
}

/// The filter state and everything it needs, for `N` states.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Engine<const N: usize> {
    pub space: StateSpace<N>,
    pub scheme: Scheme,
    pub gain: Gain,
    pub r: Mat4,
    pub filter: Kalman<N>,
    pub discrete: Option<Discrete<N>>,
    pub steady: Option<SteadyState<N>>,
    pub rebuilds: i32,
    pub skipped: i32,
    pub history: Option<History<N>>,
}

impl<const N: usize> Engine<N> {
    pub fn new(
        space: StateSpace<N>,
        scheme: Scheme,
        gain: Gain,
        r: Mat4,
        p0: SMatrix<f64, N, N>,
    ) -> Engine<N> {
        Engine {
            space,
            scheme,
            gain,
            r,
            filter: Kalman::new(SVector::zeros(), p0),
            discrete: None,
            steady: None,
            rebuilds: 0,
            skipped: 0,
            history: None,
        }
    }

    /// Keep every step's predicted and filtered estimate for [`crate::smoother`].
    pub fn record_history(&mut self) {
        self.history = Some(History::default());
    }

    /// Rebuilds the discrete matrices (and the steady-state gain) when the speed or the step
    /// differs from the last ones (exact comparison: a constant-speed run builds them once).
    fn ensure_discrete(&mut self, speed: f64, h: f64) -> Result<(), String> {
        if let Some(d) = &self.discrete
            && d.speed == speed
            && d.h == h
        {
            return Ok(());
        }
        let d = self.space.discrete(speed, h, self.scheme);
        if self.gain == Gain::SteadyState {
            let ss = steady_state(&d, &self.r, &self.filter.p)?;
            self.filter.p = ss.p_filt;
            self.steady = Some(ss);
        }
        if let Some(hist) = &mut self.history {
            hist.transitions.push(d.f);
        }
        self.discrete = Some(d);
        self.rebuilds += 1;
        Ok(())
    }

    /// One step of `h` at `speed` with the samples `z` (the fourth is the virtual measurement,
    /// 0). Returns the NIS of the update, or why the update was skipped.
    pub fn step(&mut self, speed: f64, h: f64, z: &Vec4) -> Result<Result<f64, Skip>, String> {
        self.ensure_discrete(speed, h)?;
        let d = self.discrete.as_ref().expect("built above");
        match &self.steady {
            None => self.filter.predict(&d.f, &d.q),
            Some(_) => self.filter.x = d.f * self.filter.x,
        }
        let (x_pred, p_pred) = (self.filter.x, self.filter.p_pred_or(&self.steady));
        let result = if !z.iter().all(|x| x.is_finite()) {
            Err(Skip::NonFinite)
        } else {
            match &self.steady {
                None => self
                    .filter
                    .update(&d.hm, &self.r, z)
                    .ok_or(Skip::NotPositiveDefinite),
                Some(ss) => {
                    let innovation = z - d.hm * self.filter.x;
                    self.filter.x += ss.k * innovation;
                    Ok(innovation.dot(&(ss.s_inv * innovation)))
                }
            }
        };
        if result.is_err() {
            self.skipped += 1;
        }
        if let Some(hist) = &mut self.history {
            let f = hist.transitions.len() - 1;
            hist.push(x_pred, p_pred, self.filter.x, self.filter.p, f);
        }
        Ok(result)
    }

    /// The alignment estimate and its standard deviation.
    pub fn alignment(&self) -> (f64, f64) {
        (self.filter.x[XI], self.filter.p[(XI, XI)].max(0.0).sqrt())
    }
}

impl<const N: usize> Kalman<N> {
    /// The predicted covariance: the propagated one, or the DARE's under a steady-state gain
    /// (where `P` is not propagated).
    fn p_pred_or(&self, steady: &Option<SteadyState<N>>) -> SMatrix<f64, N, N> {
        match steady {
            None => self.p,
            Some(ss) => ss.p_pred,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;
    use crate::prior::{AlignmentModel, Spectrum};
    use crate::statespace::BodyNoise;

    fn noise() -> BodyNoise {
        BodyNoise::Rate(SMatrix::<f64, 7, 7>::from_diagonal(
            &SVector::<f64, 7>::from_column_slice(&[0., 0., 0., 1e-4, 1e-4, 1e-4, 1e-5]),
        ))
    }

    fn r() -> Mat4 {
        Mat4::from_diagonal(&Vec4::new(1e-4, 2.5e-7, 1e-4, 25e-6))
    }

    /// The steady-state solution satisfies the DARE, and the time-varying filter's gain
    /// converges to it.
    #[test]
    fn the_steady_gain_is_the_limit_of_the_kalman_gain() {
        let p = Params::default();
        let model = AlignmentModel::Shaping(Spectrum::GERMAN_LOW);
        let ss = StateSpace::with_prior(&p, &model, noise(), true);
        let d = ss.discrete(20.0, 1e-3, Scheme::Taylor2);
        let p0 = SMatrix::<f64, 8, 8>::identity() * 1e-4;
        let st = steady_state(&d, &r(), &p0).unwrap();
        // Independent check of the fixed point: one more Riccati step leaves P_pred unchanged.
        let s = d.hm * st.p_pred * d.hm.transpose() + r();
        let k = st.p_pred * d.hm.transpose() * s.try_inverse().unwrap();
        let p_filt = (SMatrix::<f64, 8, 8>::identity() - k * d.hm) * st.p_pred;
        let next = d.f * p_filt * d.f.transpose() + d.q;
        assert!((next - st.p_pred).amax() < 1e-10 * st.p_pred.amax());
        // The time-varying filter from another start reaches the same gain.
        let mut kf = Kalman::new(SVector::<f64, 8>::zeros(), p0 * 100.0);
        let mut gain = SMatrix::<f64, 8, 4>::zeros();
        for _ in 0..20_000 {
            kf.predict(&d.f, &d.q);
            let s = d.hm * kf.p * d.hm.transpose() + r();
            gain = kf.p * d.hm.transpose() * s.try_inverse().unwrap();
            kf.update(&d.hm, &r(), &Vec4::zeros()).unwrap();
        }
        assert!(
            (gain - st.k).amax() < 1e-6 * st.k.amax(),
            "{}",
            (gain - st.k).amax()
        );
    }

    /// With the steady-state gain, a run at constant speed matches the time-varying filter once
    /// its transient has died out.
    #[test]
    fn steady_and_time_varying_filters_agree_after_the_transient() {
        let p = Params::default();
        let space = StateSpace::paper(&p, noise(), true);
        let p0 = SMatrix::<f64, 7, 7>::identity() * 1e-6;
        let mut a = Engine::new(space.clone(), Scheme::Taylor2, Gain::TimeVarying, r(), p0);
        let mut b = Engine::new(space, Scheme::Taylor2, Gain::SteadyState, r(), p0);
        let mut max_late = 0.0f64;
        for k in 0..20_000 {
            let t = k as f64 * 1e-3;
            let z = Vec4::new(
                (3.0 * t).sin() * 0.1,
                (5.0 * t).cos() * 1e-3,
                (2.0 * t).sin() * 0.05,
                0.0,
            );
            a.step(20.0, 1e-3, &z).unwrap().unwrap();
            b.step(20.0, 1e-3, &z).unwrap().unwrap();
            if k > 15_000 {
                max_late = max_late.max((a.filter.x - b.filter.x).amax());
            }
        }
        assert!(max_late < 1e-9, "{max_late}");
        assert_eq!(b.rebuilds, 1);
    }

    #[test]
    fn nan_samples_are_skipped_and_counted() {
        let p = Params::default();
        let space = StateSpace::paper(&p, noise(), true);
        let mut e = Engine::new(
            space,
            Scheme::Taylor2,
            Gain::TimeVarying,
            r(),
            SMatrix::identity() * 1e-6,
        );
        let z = Vec4::new(f64::NAN, 0.0, 0.0, 0.0);
        assert_eq!(e.step(20.0, 1e-3, &z).unwrap(), Err(Skip::NonFinite));
        assert_eq!(e.skipped, 1);
        assert!(e.filter.x.iter().all(|x| x.is_finite()));
    }
}

//! The Rauch-Tung-Striebel fixed-interval smoother, for offline processing of a recorded run.
//!
//! The filter estimates the alignment at `t_k` from the samples up to `t_k`; the smoother uses
//! the whole record, so every estimate also sees the samples after it. With the filter's
//! predicted `(x_p, P_p)` and filtered `(x_f, P_f)` estimates and the transition `F` of each
//! step, the backward pass is, from the last step down,
//! ```text
//! C_k   = P_f,k F_k+1^T P_p,k+1^-1
//! x_s,k = x_f,k + C_k (x_s,k+1 - x_p,k+1)
//! P_s,k = P_f,k + C_k (P_s,k+1 - P_p,k+1) C_k^T
//! ```
//! (Rauch, Tung & Striebel 1965; Särkkä, *Bayesian Filtering and Smoothing*, 2013, section 8.2).
//!
//! # Numerical form
//! No covariance is inverted: `C_k^T` is the solution of `P_p,k+1 C_k^T = F_k+1 P_f,k`, found with
//! the Cholesky factor of the symmetric positive definite `P_p,k+1`. If that factorization fails
//! (a predicted covariance that is singular to working precision, as when a state has no process
//! noise and has been measured exactly), the solve falls back to the symmetric eigendecomposition
//! with eigenvalues below `1e-14` of the largest treated as zero, the minimum-norm solution.
//! `P_s` is symmetrized after each step.

use nalgebra::{DMatrix, SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// What the filter kept for the smoother: one entry per filter step.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct History<const N: usize> {
    /// The predicted state of each step, before its update.
    pub x_pred: Vec<SVector<f64, N>>,
    /// Its covariance (under a steady-state gain: the DARE's predicted covariance).
    pub p_pred: Vec<SMatrix<f64, N, N>>,
    /// The filtered state of each step, after its update (the prediction when it was skipped).
    pub x_filt: Vec<SVector<f64, N>>,
    /// Its covariance.
    pub p_filt: Vec<SMatrix<f64, N, N>>,
    /// Index into `transitions` of the `F` that predicted into each step.
    pub transition: Vec<usize>,
    /// The distinct transition matrices, in the order they were built.
    pub transitions: Vec<SMatrix<f64, N, N>>,
}

impl<const N: usize> History<N> {
    /// Appends one step; `transition` indexes [`History::transitions`]. Every vector grows by
    /// one, so they stay of equal length.
    pub fn push(
        &mut self,
        x_pred: SVector<f64, N>,
        p_pred: SMatrix<f64, N, N>,
        x_filt: SVector<f64, N>,
        p_filt: SMatrix<f64, N, N>,
        transition: usize,
    ) {
        self.x_pred.push(x_pred);
        self.p_pred.push(p_pred);
        self.x_filt.push(x_filt);
        self.p_filt.push(p_filt);
        self.transition.push(transition);
    }

    /// Steps recorded.
    pub fn len(&self) -> usize {
        self.x_filt.len()
    }

    /// Whether no step was recorded (the smoother then returns nothing).
    pub fn is_empty(&self) -> bool {
        self.x_filt.is_empty()
    }
}

/// Solves `P X = B` for symmetric positive semi-definite `P` (see the module docs).
fn solve_spd<const N: usize>(p: &SMatrix<f64, N, N>, b: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    if let Some(chol) = p.cholesky() {
        return chol.solve(b);
    }
    let d = DMatrix::from_iterator(N, N, p.iter().copied());
    let eig = d.symmetric_eigen();
    let tol = 1e-14 * eig.eigenvalues.amax();
    let inv = DMatrix::from_diagonal(&eig.eigenvalues.map(|l| if l > tol { 1.0 / l } else { 0.0 }));
    let pinv = &eig.eigenvectors * inv * eig.eigenvectors.transpose();
    let bd = DMatrix::from_iterator(N, N, b.iter().copied());
    SMatrix::<f64, N, N>::from_iterator((pinv * bd).iter().copied())
}

/// The smoothed means and covariances, one per filter step.
pub fn smooth<const N: usize>(h: &History<N>) -> (Vec<SVector<f64, N>>, Vec<SMatrix<f64, N, N>>) {
    let n = h.len();
    let mut xs = h.x_filt.clone();
    let mut ps = h.p_filt.clone();
    for k in (0..n.saturating_sub(1)).rev() {
        let f = &h.transitions[h.transition[k + 1]];
        let c_t = solve_spd(&h.p_pred[k + 1], &(f * h.p_filt[k]));
        let c = c_t.transpose();
        xs[k] = h.x_filt[k] + c * (xs[k + 1] - h.x_pred[k + 1]);
        let p = h.p_filt[k] + c * (ps[k + 1] - h.p_pred[k + 1]) * c_t;
        ps[k] = (p + p.transpose()) * 0.5;
    }
    (xs, ps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::{Kalman, Mat4, Vec4};
    use nalgebra::{Matrix2, Vector2};

    /// A scalar random walk observed with noise: the smoother equals the batch least-squares
    /// (Gaussian posterior mean) solution computed independently from the whole record.
    #[test]
    fn equals_the_batch_posterior_of_a_random_walk() {
        let (q, r, p0) = (0.3, 0.5, 2.0);
        let z = [0.4, -0.2, 1.1, 0.9, 0.3, -0.7, 0.2, 0.5];
        let n = z.len();
        // Filter (1-state, written with N = 1 matrices; the 4-measurement update is used with
        // three zero rows, which carry no information).
        let mut hist = History::<1>::default();
        hist.transitions.push(SMatrix::<f64, 1, 1>::identity());
        let mut kf = Kalman::new(
            SVector::<f64, 1>::zeros(),
            SMatrix::<f64, 1, 1>::new(p0 - q),
        );
        let mut hm = SMatrix::<f64, 4, 1>::zeros();
        hm[(0, 0)] = 1.0;
        let rm = Mat4::from_diagonal(&Vec4::new(r, 1.0, 1.0, 1.0));
        for &zk in &z {
            kf.predict(&SMatrix::identity(), &SMatrix::<f64, 1, 1>::new(q));
            let (xp, pp) = (kf.x, kf.p);
            kf.update(&hm, &rm, &Vec4::new(zk, 0.0, 0.0, 0.0)).unwrap();
            hist.push(xp, pp, kf.x, kf.p, 0);
        }
        let (xs, _) = smooth(&hist);
        // Batch: minimize x0^2/p0 + sum (x_k - x_k-1)^2/q + sum (z_k - x_k)^2/r over x_1..x_n,
        // with x_1 ~ N(0, p0): the normal equations A x = b, solved by nalgebra's LU.
        let mut a = DMatrix::<f64>::zeros(n, n);
        let mut b = nalgebra::DVector::<f64>::zeros(n);
        a[(0, 0)] += 1.0 / p0;
        for k in 0..n {
            a[(k, k)] += 1.0 / r;
            b[k] += z[k] / r;
            if k > 0 {
                a[(k, k)] += 1.0 / q;
                a[(k - 1, k - 1)] += 1.0 / q;
                a[(k, k - 1)] -= 1.0 / q;
                a[(k - 1, k)] -= 1.0 / q;
            }
        }
        let batch = a.lu().solve(&b).unwrap();
        for k in 0..n {
            assert!(
                (xs[k][0] - batch[k]).abs() < 1e-12,
                "{k}: {} vs {}",
                xs[k][0],
                batch[k]
            );
        }
    }

    /// The fallback solve gives the same answer as Cholesky on a well-conditioned matrix and a
    /// finite answer on a singular one.
    #[test]
    fn the_pseudo_inverse_fallback_is_consistent() {
        let p = Matrix2::new(2.0, 0.5, 0.5, 1.0);
        let b = Matrix2::new(1.0, 2.0, 3.0, 4.0);
        let x = solve_spd(&p, &b);
        assert!((p * x - b).amax() < 1e-12);
        let singular = Vector2::new(1.0, 2.0) * Vector2::new(1.0, 2.0).transpose();
        let y = solve_spd(&singular, &b);
        assert!(y.iter().all(|v| v.is_finite()));
    }
}

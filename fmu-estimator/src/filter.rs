//! The Kalman filter of the paper (section 4.1), with the two corrections every implementation
//! needs: the gain uses the *inverse* innovation covariance (the paper prints
//! `K = P H^T (H P H^T + R)` without it), and the covariance update is symmetrized, so `P`
//! stays symmetric in floating point.
//!
//! The update is `P - K (H P)`, which with the optimal gain is the same matrix as Joseph's
//! `(I - K H) P (I - K H)^T + K R K^T` for a fifth of the products (docs/estimator-fmu.md
//! gives the measured difference).
//!
//! The filter is generic in the state dimension `N`: 7 for the paper's model (alignment as a
//! random walk), 8 when the alignment's rate is in the state too (see [`crate::prior`]). The
//! four measurements (two accelerometers, the gyroscope, the virtual alignment measurement) are
//! the same for every model.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

pub type Vec7 = SVector<f64, 7>;
pub type Vec4 = SVector<f64, 4>;
pub type Mat4 = SMatrix<f64, 4, 4>;

/// The filter's estimate: mean `x` and covariance `p`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Kalman<const N: usize> {
    pub x: SVector<f64, N>,
    pub p: SMatrix<f64, N, N>,
}

impl<const N: usize> Kalman<N> {
    pub fn new(x: SVector<f64, N>, p: SMatrix<f64, N, N>) -> Kalman<N> {
        Kalman { x, p }
    }

    /// `x = F x`, `P = F P F^T + Q`.
    pub fn predict(&mut self, f: &SMatrix<f64, N, N>, q: &SMatrix<f64, N, N>) {
        self.x = f * self.x;
        self.p = f * self.p * f.transpose() + q;
    }

    /// The measurement update. Returns the normalized innovation squared
    /// `nu^T S^-1 nu`, or `None` (state untouched) if `S` is not positive definite.
    pub fn update(&mut self, h: &SMatrix<f64, 4, N>, r: &Mat4, z: &Vec4) -> Option<f64> {
        let ph_t = self.p * h.transpose(); // N x 4
        let s = h * ph_t + r;
        let chol = s.cholesky()?;
        let innovation = z - h * self.x;
        // K^T = S^-1 (H P), S and P symmetric.
        let k = chol.solve(&ph_t.transpose()).transpose(); // N x 4
        let nis = innovation.dot(&chol.solve(&innovation));
        self.x += k * innovation;
        // P - K S K^T = P - K (H P): with the optimal gain the same matrix as Joseph's
        // (I - K H) P (I - K H)^T + K R K^T, for a fifth of the products.
        let p = self.p - k * ph_t.transpose();
        self.p = (p + p.transpose()) * 0.5;
        Some(nis)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    type Mat7 = SMatrix<f64, 7, 7>;
    type Mat4x7 = SMatrix<f64, 4, 7>;

    /// A scalar random-walk special case checked against the closed-form scalar filter.
    #[test]
    fn matches_the_scalar_kalman_filter_on_a_decoupled_state() {
        let mut kf = Kalman::new(Vec7::zeros(), Mat7::identity() * 4.0);
        let f = Mat7::identity();
        let q = Mat7::identity() * 0.5;
        let mut h = Mat4x7::zeros();
        h[(3, 6)] = 1.0;
        h[(0, 0)] = 1.0;
        h[(1, 1)] = 1.0;
        h[(2, 2)] = 1.0;
        let r = Mat4::identity() * 2.0;
        let z = Vec4::new(0.0, 0.0, 0.0, 3.0);
        kf.predict(&f, &q);
        let nis = kf.update(&h, &r, &z).unwrap();
        // scalar: p- = 4.5, s = 6.5, k = 4.5/6.5, x = 3k, p+ = (1-k) 4.5
        let k = 4.5 / 6.5;
        assert!((kf.x[6] - 3.0 * k).abs() < 1e-14);
        assert!((kf.p[(6, 6)] - (1.0 - k) * 4.5).abs() < 1e-13);
        assert!((nis - 9.0 / 6.5).abs() < 1e-13);
        assert_eq!(kf.p, kf.p.transpose());
    }

    /// The update against two textbook forms computed here with an explicit inverse: the
    /// standard `(I - K H) P` and Joseph's `(I - K H) P (I - K H)^T + K R K^T`.
    #[test]
    fn the_update_equals_the_standard_and_joseph_forms() {
        let mut kf = Kalman::new(Vec7::zeros(), Mat7::identity());
        let mut h = Mat4x7::zeros();
        for (i, j) in [(0, 0), (0, 3), (1, 4), (2, 5), (2, 1), (3, 6)] {
            h[(i, j)] = 0.3 + i as f64 + j as f64 * 0.1;
        }
        let r = Mat4::from_diagonal(&Vec4::new(0.1, 0.2, 0.3, 0.4));
        let p0 = kf.p;
        let s = h * p0 * h.transpose() + r;
        let k = p0 * h.transpose() * s.try_inverse().unwrap();
        let i_kh = Mat7::identity() - k * h;
        let standard = i_kh * p0;
        let joseph = i_kh * p0 * i_kh.transpose() + k * r * k.transpose();
        kf.update(&h, &r, &Vec4::zeros()).unwrap();
        assert!((kf.p - standard).norm() < 1e-12);
        assert!((kf.p - joseph).norm() < 1e-12);
    }
}

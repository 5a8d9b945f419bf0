//! The Kalman filter of the paper (section 4.1), with the two corrections every implementation
//! needs: the gain uses the *inverse* innovation covariance (the paper prints
//! `K = P H^T (H P H^T + R)` without it), and the covariance update is symmetrized, so `P`
//! stays symmetric in floating point.
//!
//! The update is `P - K (H P)`, which with the optimal gain is the same matrix as Joseph's
//! `(I - K H) P (I - K H)^T + K R K^T` for a fifth of the products. It subtracts two nearly
//! equal matrices, though: where a measurement is much more precise than the prior
//! (`R << H P H^T`) rounding can leave it indefinite, and a negative variance then grows in
//! every later step. So the result is kept only if its Cholesky factorization succeeds (it is
//! positive definite); otherwise the update is redone in Joseph's form, a sum of two positive
//! semi-definite products whatever the rounding. The check costs a 7 x 7 factorization per step
//! (docs/estimator-fmu.md gives the measured costs and how often the fallback runs).
//!
//! The filter is generic in the state dimension `N`: 7 for the paper's model (alignment as a
//! random walk), 8 when the alignment's rate is in the state too (see [`crate::prior`]). The
//! four measurements (two accelerometers, the gyroscope, the virtual alignment measurement) are
//! the same for every model.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// A state of the paper's model, `[y, psi, y_f, ydot, psidot, y_fdot, xi]` (SI units).
pub type Vec7 = SVector<f64, 7>;
/// The four measurements: ws_acc_y \[m/s2\], ws_yaw_rate \[rad/s\], frame_acc_y \[m/s2\] and
/// the virtual alignment measurement \[m\] (always 0).
pub type Vec4 = SVector<f64, 4>;
/// A covariance of the four measurements (R, the innovation covariance).
pub type Mat4 = SMatrix<f64, 4, 4>;

/// The filter's estimate: mean `x` and covariance `p`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Kalman<const N: usize> {
    /// The state estimate, ordered as the model's state.
    pub x: SVector<f64, N>,
    /// Its covariance, kept symmetric (and positive definite by the guarded update).
    pub p: SMatrix<f64, N, N>,
}

impl<const N: usize> Kalman<N> {
    /// A filter starting from `x` with covariance `p` (symmetric positive definite; not
    /// checked).
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
        let p = (p + p.transpose()) * 0.5;
        self.p = if p.cholesky().is_some() {
            p
        } else {
            joseph(&self.p, &k, h, r)
        };
        Some(nis)
    }
}

/// Joseph's form of the updated covariance, `(I - K H) P (I - K H)^T + K R K^T`, symmetrized:
/// positive semi-definite for any gain `k` up to the rounding of the products themselves.
pub fn joseph<const N: usize>(
    p: &SMatrix<f64, N, N>,
    k: &SMatrix<f64, N, 4>,
    h: &SMatrix<f64, 4, N>,
    r: &Mat4,
) -> SMatrix<f64, N, N> {
    let i_kh = SMatrix::<f64, N, N>::identity() - k * h;
    let j = i_kh * p * i_kh.transpose() + k * r * k.transpose();
    (j + j.transpose()) * 0.5
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

    /// A deterministic generator (xorshift64*): the cases below are fixed.
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (u, v) = (self.uniform().max(1e-300), self.uniform());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        }
    }

    /// A random SPD prior with eigenvalues from 1 to 1e4 (a random rotation of them), a random
    /// H, and four nearly exact measurements (R from 1e-14 to 1e-8): the posterior variance
    /// along the measured directions is R, far below the prior's, and `P - K (H P)` subtracts
    /// two matrices that agree to 12-18 digits.
    fn precise_measurement_case(rng: &mut Rng) -> (Mat7, Mat4x7, Mat4) {
        let mut a = Mat7::zeros();
        a.iter_mut().for_each(|x| *x = rng.normal());
        let q = a.qr().q();
        let d = Vec7::from_fn(|_, _| 10f64.powf(4.0 * rng.uniform()));
        let p = q * Mat7::from_diagonal(&d) * q.transpose();
        let mut h = Mat4x7::zeros();
        h.iter_mut().for_each(|x| *x = rng.normal());
        let r = Mat4::from_diagonal(&Vec4::from_fn(|_, _| {
            10f64.powf(-14.0 + 6.0 * rng.uniform())
        }));
        ((p + p.transpose()) * 0.5, h, r)
    }

    fn relative_min_eigenvalue(p: &Mat7) -> f64 {
        let e = p.symmetric_eigenvalues();
        e.min() / e.max()
    }

    /// The oracle is the matrix's spectrum: over 500 precise-measurement cases the cheap form
    /// (computed here as the filter did before the guard) is indefinite far beyond the
    /// eigenvalues' own rounding (a few 1e-16 of the largest) in some of them (22, down to
    /// -5.6e-13), and the guarded update is never.
    #[test]
    fn the_guarded_update_stays_positive_semi_definite_where_the_cheap_form_does_not() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut cheap_indefinite, mut worst_cheap, mut worst_guarded) = (0, 0.0f64, 0.0f64);
        for _ in 0..500 {
            let (p, h, r) = precise_measurement_case(&mut rng);
            let ph_t = p * h.transpose();
            let s = h * ph_t + r;
            let k = s.cholesky().unwrap().solve(&ph_t.transpose()).transpose();
            let cheap = p - k * ph_t.transpose();
            let cheap = (cheap + cheap.transpose()) * 0.5;
            let c = relative_min_eigenvalue(&cheap);
            if c < -1e-14 {
                cheap_indefinite += 1;
            }
            worst_cheap = worst_cheap.min(c);
            let mut kf = Kalman::new(Vec7::zeros(), p);
            kf.update(&h, &r, &Vec4::zeros()).unwrap();
            assert_eq!(kf.p, kf.p.transpose());
            worst_guarded = worst_guarded.min(relative_min_eigenvalue(&kf.p));
        }
        assert!(
            cheap_indefinite >= 10,
            "the cases do not exercise the guard: {cheap_indefinite} indefinite, worst {worst_cheap:e}"
        );
        assert!(
            worst_guarded > -1e-15,
            "guarded update indefinite: {worst_guarded:e} (cheap form's worst {worst_cheap:e}, {cheap_indefinite} of 500 cases)"
        );
    }

    /// Where the cheap form is positive definite the guard keeps it: the same bits as
    /// `P - K (H P)` symmetrized (the FMU's estimates do not change on ordinary runs).
    #[test]
    fn the_guard_keeps_the_cheap_form_where_it_is_positive_definite() {
        let mut kf = Kalman::new(Vec7::zeros(), Mat7::identity());
        let mut h = Mat4x7::zeros();
        for (i, j) in [(0, 0), (0, 3), (1, 4), (2, 5), (2, 1), (3, 6)] {
            h[(i, j)] = 0.3 + i as f64 + j as f64 * 0.1;
        }
        let r = Mat4::from_diagonal(&Vec4::new(0.1, 0.2, 0.3, 0.4));
        let ph_t = kf.p * h.transpose();
        let s = h * ph_t + r;
        let k = s.cholesky().unwrap().solve(&ph_t.transpose()).transpose();
        let cheap = kf.p - k * ph_t.transpose();
        let cheap = (cheap + cheap.transpose()) * 0.5;
        kf.update(&h, &r, &Vec4::zeros()).unwrap();
        assert_eq!(kf.p, cheap);
        assert_ne!(
            kf.p,
            joseph(&Mat7::identity(), &k, &h, &r),
            "the forms differ in rounding here"
        );
    }
}

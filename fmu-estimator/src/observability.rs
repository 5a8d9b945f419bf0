//! Observability by the Popov-Belevitch-Hautus (PBH) test: the pair (F, H) is observable iff
//! `rank [lambda I - F; H] = n` at every eigenvalue `lambda` of `F`. docs/references.md section 1 warns
//! that the power-series matrix `[H; H F; ...; H F^6]` of this model is so badly scaled that a
//! numeric rank routine reports 4 for an observable system; the PBH test works on one
//! well-conditioned matrix per eigenvalue instead.

use nalgebra::{Complex, DMatrix, SMatrix};

/// Iteration cap of the Schur and SVD iterations: nalgebra's defaults iterate until
/// convergence, which a matrix with non-finite or overflowing entries (from absurd parameters,
/// e.g. g = 1e308) never reaches; fmi2ExitInitializationMode then hung (found by fmi-fuzz).
const MAX_ITERATIONS: usize = 10_000;

/// The smallest PBH rank over the eigenvalues of `f`, and the eigenvalue where it occurs.
/// When the decomposition is impossible (non-finite entries, no convergence) the answer is
/// rank 0 at a NaN eigenvalue: observability unknown, reported as not observable.
pub fn pbh_rank<const N: usize>(
    f: &SMatrix<f64, N, N>,
    h: &SMatrix<f64, 4, N>,
) -> (usize, Complex<f64>) {
    let n = N;
    let unknown = (0, Complex::new(f64::NAN, f64::NAN));
    if !f.iter().chain(h.iter()).all(|x| x.is_finite()) {
        return unknown;
    }
    let fd = DMatrix::from_iterator(N, N, f.iter().copied());
    let scale = f.norm().max(h.norm()).max(1.0);
    let mut worst = (n, Complex::new(0.0, 0.0));
    let Some(schur) = fd.try_schur(f64::EPSILON, MAX_ITERATIONS) else {
        return unknown;
    };
    for lambda in schur.complex_eigenvalues().iter() {
        if !(lambda.re.is_finite() && lambda.im.is_finite()) {
            return unknown;
        }
        let mut m = DMatrix::<Complex<f64>>::zeros(n + h.nrows(), n);
        for i in 0..n {
            for j in 0..n {
                let d = if i == j {
                    *lambda
                } else {
                    Complex::new(0.0, 0.0)
                };
                m[(i, j)] = (d - Complex::new(f[(i, j)], 0.0)) / scale;
            }
        }
        for i in 0..h.nrows() {
            for j in 0..n {
                m[(n + i, j)] = Complex::new(h[(i, j)] / scale, 0.0);
            }
        }
        let Some(svd) = m.try_svd(false, false, f64::EPSILON, MAX_ITERATIONS) else {
            return unknown;
        };
        let sv = svd.singular_values;
        let tol = 1e-10 * sv.max();
        let rank = sv.iter().filter(|s| **s > tol).count();
        if rank < worst.0 {
            worst = (rank, *lambda);
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{measurement_matrix, state_matrix};
    use crate::params::Params;

    #[test]
    fn table_2_model_is_observable_at_20_m_per_s() {
        let fc = state_matrix(&Params::default(), 20.0);
        let (rank, _) = pbh_rank(&fc, &measurement_matrix(&fc));
        assert_eq!(rank, 7);
    }

    #[test]
    fn a_frame_without_suspension_is_not_observable() {
        // Without ky and cy the frame neither moves with the wheelset nor shows in any sensor:
        // its position and velocity cannot be observed.
        let p = Params {
            ky: 0.0,
            cy: 0.0,
            ..Params::default()
        };
        let fc = state_matrix(&p, 20.0);
        let (rank, lambda) = pbh_rank(&fc, &measurement_matrix(&fc));
        assert!(rank < 7, "rank {rank}");
        assert!(lambda.norm() < 1e-6, "{lambda}");
    }

    #[test]
    fn absurd_parameters_give_an_answer_instead_of_hanging() {
        // g = f64::MAX overflows the state matrix; the Schur iteration used to loop forever.
        let p = Params {
            g: f64::MAX,
            ..Params::default()
        };
        let fc = state_matrix(&p, 20.0);
        let (rank, lambda) = pbh_rank(&fc, &measurement_matrix(&fc));
        assert_eq!(rank, 0);
        assert!(lambda.re.is_nan());
        let p = Params {
            m: 1e-300,
            ..Params::default()
        };
        let fc = state_matrix(&p, 20.0);
        let (rank, _) = pbh_rank(&fc, &measurement_matrix(&fc));
        assert!(rank <= 7);
    }
}

//! From `F_c` to the discrete transition matrix `F` for one step `h`.
//!
//! - [`Scheme::Taylor2`], the paper's scheme (section 4.1): velocities by forward Euler, positions
//!   by a second-order Taylor expansion, `q_k = q + h qd + h^2/2 qdd`, `qd_k = qd + h qdd`,
//!   `xi_k = xi`, with `qdd = A x` the acceleration rows of `F_c`. So
//!   `F = I + h F_c + h^2/2 S`, where `S` holds `A` in the position rows. Stable for
//!   `h |lambda_max| < 2`, about 4 ms for Table 2 at 20 m/s.
//! - [`Scheme::Exact`], the matrix exponential `F = exp(F_c h)`: exact for the linear model at
//!   any step.

use crate::error::SettingError;
use crate::model::Mat7;
use nalgebra::SMatrix;
use serde::{Deserialize, Serialize};

/// How `F_c` becomes `F` for one step (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scheme {
    /// The paper's second-order Taylor scheme (FMI parameter `discretization = 1`).
    Taylor2,
    /// The matrix exponential (FMI parameter `discretization = 2`).
    Exact,
}

impl Scheme {
    /// The scheme of the FMI parameter `discretization` (1 or 2); another code is refused.
    pub fn from_fmi(code: i32) -> Result<Scheme, SettingError> {
        match code {
            1 => Ok(Scheme::Taylor2),
            2 => Ok(Scheme::Exact),
            other => Err(SettingError::Discretization(other)),
        }
    }
}

/// The paper's 7-state `F` for a step of `h` \[s\]: exact at any step, or the paper's
/// Taylor scheme, stable only for `h |lambda_max| < 2` (about 4 ms with Table 2 at 20 m/s).
pub fn transition(fc: &Mat7, h: f64, scheme: Scheme) -> Mat7 {
    match scheme {
        Scheme::Exact => (fc * h).exp(),
        Scheme::Taylor2 => taylor2(fc, h, &[(0, 3), (1, 4), (2, 5)]),
    }
}

/// The second-order Taylor scheme for any state whose `(position, velocity)` row pairs are
/// `pairs`: `F = I + h F_c + h^2/2 S`, `S` holding each velocity row of `F_c` in its position row.
pub fn taylor2<const N: usize>(
    fc: &SMatrix<f64, N, N>,
    h: f64,
    pairs: &[(usize, usize)],
) -> SMatrix<f64, N, N> {
    let mut s = SMatrix::<f64, N, N>::zeros();
    for &(pos, vel) in pairs {
        s.set_row(pos, &fc.row(vel));
    }
    SMatrix::<f64, N, N>::identity() + fc * h + s * (0.5 * h * h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::state_matrix;
    use crate::params::Params;
    use nalgebra::SVector;

    /// Simulates 1 s of free response with both schemes; the difference must shrink with h
    /// (first order globally, since the Taylor scheme's velocity update is Euler).
    #[test]
    fn the_two_discretizations_agree_as_the_step_shrinks() {
        let fc = state_matrix(&Params::default(), 20.0);
        let x0 = SVector::<f64, 7>::from_column_slice(&[0.002, 0.001, 0.0, 0.0, 0.0, 0.0, 0.003]);
        let diff = |h: f64| {
            let n = (1.0 / h).round() as usize;
            let (ft, fe) = (
                transition(&fc, h, Scheme::Taylor2),
                transition(&fc, h, Scheme::Exact),
            );
            let (mut xt, mut xe) = (x0, x0);
            for _ in 0..n {
                xt = ft * xt;
                xe = fe * xe;
            }
            (xt - xe).norm() / xe.norm().max(1e-12)
        };
        let (d1, d2, d3) = (diff(1e-3), diff(1e-4), diff(1e-5));
        assert!(d2 < d1 / 5.0 && d3 < d2 / 5.0, "{d1} {d2} {d3}");
        assert!(d3 < 1e-3, "{d3}");
    }

    #[test]
    fn exact_scheme_composes_over_steps() {
        // exp(F h)^2 = exp(F 2h): a property the Taylor scheme does not have.
        let fc = state_matrix(&Params::default(), 20.0);
        let a = transition(&fc, 1e-3, Scheme::Exact);
        let b = transition(&fc, 2e-3, Scheme::Exact);
        assert!((a * a - b).norm() < 1e-10 * b.norm());
    }
}

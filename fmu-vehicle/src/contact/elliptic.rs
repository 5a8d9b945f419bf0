//! Complete elliptic integrals K(m) and E(m) by the arithmetic-geometric mean (AGM).
//!
//! With the parameter `m = k^2` (`k` the modulus) and the complementary modulus
//! `k' = sqrt(1 - m)`, the AGM sequence `a0 = 1, b0 = k', c0 = sqrt(m)`,
//! `a(n+1) = (a + b)/2, b(n+1) = sqrt(a b), c(n+1) = (a - b)/2` gives
//!
//! ```text
//! K(m) = pi / (2 a_inf),      K(m) - E(m) = K(m) * S,     S = sum_{n >= 0} 2^(n-1) c_n^2
//! ```
//!
//! (Abramowitz & Stegun, *Handbook of Mathematical Functions*, 17.6; NIST DLMF 19.8.i).
//! `c(n+1)` is computed as `c_n^2 / (4 a(n+1))` (from `c_n^2 = a_n^2 - b_n^2`) instead of the
//! difference `(a - b)/2`, and `c1 = m / (2 (1 + k'))`, so that `K - E` and `E - k'^2 K` carry no
//! cancellation as `m -> 0`. The Hertz ellipse equation needs exactly those two differences
//! for nearly circular contacts.

use std::f64::consts::FRAC_PI_2;

/// The AGM of (1, k') together with the pieces of the sum `S` of the module docs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Agm {
    /// K(m).
    pub k: f64,
    /// The parameter m = 1 - k'^2 (so `S = m / 2 + s1`).
    pub m: f64,
    /// `sum_{n >= 1} 2^(n-1) c_n^2` (the `n = 0` term, `m / 2`, is kept apart).
    pub s1: f64,
}

impl Agm {
    /// Runs the AGM from the complementary modulus `k' = sqrt(1 - m)` in (0, 1].
    pub(crate) fn from_complementary_modulus(kp: f64) -> Agm {
        debug_assert!(
            kp > 0.0 && kp <= 1.0,
            "complementary modulus {kp} outside (0, 1]"
        );
        let m = (1.0 - kp) * (1.0 + kp);
        let mut a = 0.5 * (1.0 + kp);
        let mut b = kp.sqrt();
        let mut c = 0.5 * m / (1.0 + kp); // c1 = (1 - k') / 2 without cancellation
        let mut weight = 1.0; // 2^(n-1) for n = 1
        let mut s1 = 0.0;
        // Quadratic convergence: 6 iterations suffice for k' >= 1e-6, and the loop is bounded.
        for _ in 0..64 {
            s1 += weight * c * c;
            if c <= 1e-10 * a {
                // The next c is ~c^2 / (4 a): a has converged to machine precision and the
                // remaining terms of the sum are below 1e-20 relative.
                break;
            }
            let a_next = 0.5 * (a + b);
            b = (a * b).sqrt();
            c = c * c / (4.0 * a_next);
            a = a_next;
            weight *= 2.0;
        }
        Agm {
            k: FRAC_PI_2 / a,
            m,
            s1,
        }
    }

    /// E(m) = K (1 - m/2 - s1).
    pub(crate) fn e(&self) -> f64 {
        self.k * (1.0 - 0.5 * self.m - self.s1)
    }
}

/// Complete elliptic integral of the first kind, K(m) = int_0^{pi/2} dt / sqrt(1 - m sin^2 t),
/// with the parameter `m = k^2` (the convention of Abramowitz & Stegun and of scipy's `ellipk`).
///
/// Defined for `m < 1` (negative `m` is allowed); `K(1) = +inf`; NaN for `m > 1` or NaN.
pub fn elliptic_k(m: f64) -> f64 {
    if m.is_nan() || m > 1.0 {
        f64::NAN
    } else if m == 1.0 {
        f64::INFINITY
    } else {
        Agm::from_complementary_modulus_general(m).k
    }
}

/// Complete elliptic integral of the second kind, E(m) = int_0^{pi/2} sqrt(1 - m sin^2 t) dt,
/// with the parameter `m = k^2`.
///
/// Defined for `m <= 1` (`E(1) = 1`); NaN for `m > 1` or NaN.
pub fn elliptic_e(m: f64) -> f64 {
    if m.is_nan() || m > 1.0 {
        f64::NAN
    } else if m == 1.0 {
        1.0
    } else {
        Agm::from_complementary_modulus_general(m).e()
    }
}

impl Agm {
    /// The AGM for any parameter m < 1. For m < 0 the complementary modulus exceeds 1, which
    /// the AGM handles as well (a0 = 1, b0 = k' > 1); only the (0, 1] fast path is debug-checked
    /// in `from_complementary_modulus`.
    fn from_complementary_modulus_general(m: f64) -> Agm {
        let kp = (1.0 - m).sqrt();
        if kp <= 1.0 {
            return Agm::from_complementary_modulus(kp);
        }
        // m < 0: plain AGM with differences (no cancellation issue: a0 - b0 = 1 - k' < 0 is
        // computed exactly enough, and nothing downstream needs the small-m limit here).
        let mut a: f64 = 1.0;
        let mut b = kp;
        let mut c2 = m; // c0^2 = m (negative)
        let mut weight = 0.5;
        let mut s = 0.0;
        for _ in 0..64 {
            s += weight * c2;
            let a_next = 0.5 * (a + b);
            let b_next = (a * b).sqrt();
            let c = 0.5 * (a - b);
            a = a_next;
            b = b_next;
            c2 = c * c;
            weight *= 2.0;
            if c.abs() <= 1e-10 * a {
                s += weight * c2;
                break;
            }
        }
        Agm {
            k: FRAC_PI_2 / a,
            m,
            s1: s - 0.5 * m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_limit() {
        assert_eq!(elliptic_k(0.0), FRAC_PI_2);
        assert_eq!(elliptic_e(0.0), FRAC_PI_2);
    }

    #[test]
    fn negative_parameter() {
        // K(-1) = 1.311028777146059905, E(-1) = 1.910098894513856009 (DLMF 19.2, scipy).
        assert!((elliptic_k(-1.0) - 1.311_028_777_146_06).abs() < 1e-13);
        assert!((elliptic_e(-1.0) - 1.910_098_894_513_856).abs() < 1e-13);
    }

    #[test]
    fn small_parameter_series() {
        // K - E = pi/2 (m/2 + 3 m^2/16 + ...), E - (1-m) K = pi/2 (m/2 + m^2/16 + ...).
        for kp in [1.0 - 1e-6, 1.0 - 1e-9, 1.0 - 1e-13] {
            let agm = Agm::from_complementary_modulus(kp);
            let m = agm.m;
            let k_minus_e = agm.k * (0.5 * m + agm.s1);
            let expect = FRAC_PI_2 * (0.5 * m + 3.0 * m * m / 16.0);
            // The truncated series is good to O(m^2) relative.
            let tol = 1e-13 + m * m * 10.0;
            assert!(
                (k_minus_e / expect - 1.0).abs() < tol,
                "{k_minus_e} vs {expect}"
            );
            let e_minus_kp2_k = agm.k * (0.5 * m - agm.s1);
            let expect = FRAC_PI_2 * (0.5 * m + m * m / 16.0);
            assert!(
                (e_minus_kp2_k / expect - 1.0).abs() < tol,
                "{e_minus_kp2_k} vs {expect}"
            );
        }
    }
}

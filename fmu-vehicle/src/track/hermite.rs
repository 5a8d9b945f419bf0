//! Quintic Hermite interpolation on one grid interval from the value, first and second
//! derivative at both ends. The interpolant matches all three at the nodes, so the pieces join
//! with continuous value, slope and curvature (C2), and it reproduces any quintic exactly (error
//! `O(h^6)` in the value, `O(h^4)` in the second derivative).

/// The six basis weights and their first and second derivatives with respect to `u`, for the
/// node data ordered `[p0, h d0, h^2 a0, h^2 a1, h d1, p1]`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Basis {
    w: [f64; 6],
    dw: [f64; 6],
    ddw: [f64; 6],
}

impl Basis {
    /// Basis at the fraction `u` in [0, 1] of the interval.
    #[inline]
    pub(super) fn new(u: f64) -> Basis {
        let u2 = u * u;
        let u3 = u2 * u;
        let u4 = u3 * u;
        let u5 = u4 * u;
        Basis {
            w: [
                1.0 - 10.0 * u3 + 15.0 * u4 - 6.0 * u5,
                u - 6.0 * u3 + 8.0 * u4 - 3.0 * u5,
                0.5 * u2 - 1.5 * u3 + 1.5 * u4 - 0.5 * u5,
                0.5 * u3 - u4 + 0.5 * u5,
                -4.0 * u3 + 7.0 * u4 - 3.0 * u5,
                10.0 * u3 - 15.0 * u4 + 6.0 * u5,
            ],
            dw: [
                -30.0 * u2 + 60.0 * u3 - 30.0 * u4,
                1.0 - 18.0 * u2 + 32.0 * u3 - 15.0 * u4,
                u - 4.5 * u2 + 6.0 * u3 - 2.5 * u4,
                1.5 * u2 - 4.0 * u3 + 2.5 * u4,
                -12.0 * u2 + 28.0 * u3 - 15.0 * u4,
                30.0 * u2 - 60.0 * u3 + 30.0 * u4,
            ],
            ddw: [
                -60.0 * u + 180.0 * u2 - 120.0 * u3,
                -36.0 * u + 96.0 * u2 - 60.0 * u3,
                1.0 - 9.0 * u + 18.0 * u2 - 10.0 * u3,
                3.0 * u - 12.0 * u2 + 10.0 * u3,
                -24.0 * u + 84.0 * u2 - 60.0 * u3,
                60.0 * u - 180.0 * u2 + 120.0 * u3,
            ],
        }
    }

    /// Value and first and second derivative along `s` between the node data `a = [value,
    /// d/ds, d2/ds2]` at the interval start and `b` at its end, interval length `step`.
    #[inline]
    pub(super) fn eval(&self, step: f64, inv_step: f64, a: &[f64], b: &[f64]) -> [f64; 3] {
        let h2 = step * step;
        let d = [a[0], step * a[1], h2 * a[2], h2 * b[2], step * b[1], b[0]];
        let mut v = 0.0;
        let mut dv = 0.0;
        let mut ddv = 0.0;
        for (i, d) in d.iter().enumerate() {
            v += self.w[i] * d;
            dv += self.dw[i] * d;
            ddv += self.ddw[i] * d;
        }
        [v, dv * inv_step, ddv * inv_step * inv_step]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reproduces a quintic polynomial exactly, with its derivatives.
    #[test]
    fn reproduces_quintics() {
        let p = |x: f64| {
            0.3 - 1.2 * x + 0.7 * x * x - 2.0 * x.powi(3) + 0.9 * x.powi(4) - 0.4 * x.powi(5)
        };
        let dp = |x: f64| -1.2 + 1.4 * x - 6.0 * x * x + 3.6 * x.powi(3) - 2.0 * x.powi(4);
        let ddp = |x: f64| 1.4 - 12.0 * x + 10.8 * x * x - 8.0 * x.powi(3);
        let (x0, h) = (0.4, 0.7);
        let a = [p(x0), dp(x0), ddp(x0)];
        let b = [p(x0 + h), dp(x0 + h), ddp(x0 + h)];
        for k in 0..=20 {
            let u = k as f64 / 20.0;
            let [v, d, dd] = Basis::new(u).eval(h, 1.0 / h, &a, &b);
            let x = x0 + u * h;
            assert!((v - p(x)).abs() < 1e-13, "{u}");
            assert!((d - dp(x)).abs() < 1e-12, "{u}");
            assert!((dd - ddp(x)).abs() < 1e-11, "{u}");
        }
    }
}

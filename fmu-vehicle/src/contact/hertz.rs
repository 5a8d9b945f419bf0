//! Hertz normal contact: the contact ellipse of two convex elastic bodies.
//!
//! With the principal relative curvatures summed per direction (the principal directions of
//! wheel and rail coincide on straight track: rolling `x` and lateral `y`),
//! `A = min(Sx, Sy) / 2`, `B = max(Sx, Sy) / 2`, `cos(theta) = (B - A) / (A + B)`, the ratio
//! `k = b/a` of minor to major semi-axis solves (Johnson, *Contact Mechanics*, 1985, eq. 3.46;
//! Timoshenko & Goodier, *Theory of Elasticity*, section 140)
//!
//! ```text
//! B / A = (E(e) / k^2 - K(e)) / (K(e) - E(e)),     e^2 = 1 - k^2,
//! ```
//!
//! and then, with `E*` the contact modulus (`E / (2 (1 - nu^2))` for two equal bodies),
//!
//! ```text
//! major = m c,  minor = n c,  c = [3 N / (4 E* (A + B))]^(1/3),
//! m = [2 E(e) / (pi k^2)]^(1/3),   n = k m = [2 k E(e) / pi]^(1/3).
//! ```
//!
//! (`A + B = p0 E(e) / (E* b)` and `N = 2 pi a b p0 / 3` from Johnson eq. 3.46 give these.)
//! The major axis lies along the direction of the smaller curvature sum. This reproduces the
//! classical tabulated coefficients (m, n = 2.731 / 0.493 at 30 deg, 1.486 / 0.717 at 60 deg;
//! docs/references.md section 4; D. H. Cooper, "Tables of Hertzian contact-stress coefficients",
//! Coordinated Science Laboratory report, Univ. of Illinois, August 1968, which also notes
//! errors in Hertz's own tables).

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::ContactError;
use super::elliptic::Agm;

/// Elastic constants of wheel and rail (both bodies are taken to be of the same material).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Young's modulus \[Pa\].
    pub young: f64,
    /// Poisson's ratio \[-\].
    pub poisson: f64,
}

impl Material {
    /// Rail/wheel steel: E = 2.1e11 Pa, nu = 0.3.
    pub const STEEL: Material = Material {
        young: 2.1e11,
        poisson: 0.3,
    };

    /// Shear modulus G = E / (2 (1 + nu)) \[Pa\]: the modulus Kalker's coefficients multiply.
    pub fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// Contact (reduced) modulus of two equal bodies, E* = E / (2 (1 - nu^2)) \[Pa\], i.e.
    /// 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 with both bodies alike.
    pub fn reduced_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 - self.poisson * self.poisson))
    }

    /// Checks 0 < E < inf and -1 < nu < 0.5 (the range where the moduli above are positive and
    /// finite). Kalker's table covers 0 <= nu <= 0.5 only; see [`kalker_c`](super::kalker_c).
    pub fn check(&self) -> Result<(), ContactError> {
        let ok =
            self.young.is_finite() && self.young > 0.0 && self.poisson > -1.0 && self.poisson < 0.5;
        if ok {
            Ok(())
        } else {
            Err(ContactError::InvalidMaterial {
                young: self.young,
                poisson: self.poisson,
            })
        }
    }
}

impl Default for Material {
    fn default() -> Self {
        Material::STEEL
    }
}

/// Principal radii at the wheel-rail contact \[m\].
///
/// The curvatures summed per direction are: rolling direction `1 / wheel_radius` (the rail is
/// straight: longitudinal curvature 0); lateral direction `1 / wheel_transverse_radius +
/// 1 / rail_crown_radius`. A radius is positive for a convex surface and negative for a
/// concave one (a hollow-worn tread); `f64::INFINITY` means a straight generator (a coned
/// tread, curvature 0). Both sums must be positive (non-conformal contact) for Hertz to apply.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactGeometry {
    /// Wheel rolling radius r0 \[m\].
    pub wheel_radius: f64,
    /// Wheel transverse profile radius \[m\]; `f64::INFINITY` for a cone.
    pub wheel_transverse_radius: f64,
    /// Rail head crown radius (transverse) \[m\].
    pub rail_crown_radius: f64,
}

impl ContactGeometry {
    /// A coned (straight-generator) tread of rolling radius `wheel_radius` on a rail head of
    /// crown radius `rail_crown_radius`.
    pub fn coned(wheel_radius: f64, rail_crown_radius: f64) -> ContactGeometry {
        ContactGeometry {
            wheel_radius,
            wheel_transverse_radius: f64::INFINITY,
            rail_crown_radius,
        }
    }

    /// Curvature sums (rolling direction, lateral direction) \[1/m\].
    pub fn curvature_sums(&self) -> (f64, f64) {
        (
            1.0 / self.wheel_radius,
            1.0 / self.wheel_transverse_radius + 1.0 / self.rail_crown_radius,
        )
    }

    /// Checks that both curvature sums are positive and finite.
    pub fn check(&self) -> Result<(), ContactError> {
        let (sx, sy) = self.curvature_sums();
        if sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0 {
            Ok(())
        } else {
            Err(ContactError::InvalidGeometry {
                rolling_curvature: sx,
                lateral_curvature: sy,
            })
        }
    }
}

/// Semi-axes of the contact ellipse \[m\].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Ellipse {
    /// Semi-axis in the rolling direction \[m\].
    pub a: f64,
    /// Semi-axis in the lateral direction \[m\].
    pub b: f64,
}

impl Ellipse {
    /// The empty contact (no load).
    pub const ZERO: Ellipse = Ellipse { a: 0.0, b: 0.0 };

    /// Area pi a b \[m^2\].
    pub fn area(&self) -> f64 {
        PI * self.a * self.b
    }
}

/// Hertz coefficients (m, n) for the angle `theta` \[rad\] with cos(theta) = |B - A| / (A + B).
///
/// `theta = pi/2` is the circle (m = n = 1); `theta -> 0` the line contact (m -> inf, n -> 0).
/// Values of `theta` outside (0, pi/2] are folded by the absolute value of the cosine; an
/// exactly degenerate angle (cos = 1) returns (inf, 0).
pub fn hertz_coefficients(theta: f64) -> (f64, f64) {
    let c = theta.cos().abs();
    if c >= 1.0 {
        return (f64::INFINITY, 0.0);
    }
    let (m, n, _) = coefficients_for_ratio((1.0 + c) / (1.0 - c));
    (m, n)
}

/// The function `B/A` of the axis ratio `k = b/a` in (0, 1], evaluated without cancellation:
/// `(E/k^2 - K) / (K - E) = (m/2 - s1) / (k^2 (m/2 + s1))` with the AGM sums of the
/// `elliptic` module.
fn curvature_ratio_of_axis_ratio(k: f64) -> f64 {
    let agm = Agm::from_complementary_modulus(k);
    if agm.m == 0.0 {
        return 1.0;
    }
    (0.5 * agm.m - agm.s1) / (k * k * (0.5 * agm.m + agm.s1))
}

/// Solves the Hertz ellipse equation for the curvature ratio `rho = B/A >= 1`; returns
/// (m, n, k = n/m).
pub(crate) fn coefficients_for_ratio(rho: f64) -> (f64, f64, f64) {
    debug_assert!(rho >= 1.0, "curvature ratio {rho} < 1");
    let k = if rho <= 1.0 {
        1.0
    } else {
        // ratio(k) decreases monotonically from +inf (k -> 0) to 1 (k = 1). Bisect in ln k,
        // bracketing around the asymptote a/b ~ (B/A)^(2/3) (Greenwood, J. Tribol. 107, 1985).
        let guess = -(2.0 / 3.0) * rho.ln();
        let mut lo = guess - 1.0; // ratio(e^lo) >= rho wanted
        while curvature_ratio_of_axis_ratio(lo.exp()) < rho {
            lo -= 1.0;
        }
        let mut hi = (guess + 1.0).min(0.0); // ratio(e^hi) <= rho wanted
        while hi < 0.0 && curvature_ratio_of_axis_ratio(hi.exp()) > rho {
            hi = (hi + 1.0).min(0.0);
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if curvature_ratio_of_axis_ratio(mid.exp()) > rho {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).exp()
    };
    let e = Agm::from_complementary_modulus(k).e();
    let m = (2.0 * e / (PI * k * k)).cbrt();
    (m, k * m, k)
}

/// Hertz contact ellipse under the normal load `normal_load` \[N\].
///
/// `normal_load <= 0` (or NaN) gives [`Ellipse::ZERO`] (wheel lift).
///
/// # Panics
/// If the geometry or the material fails its `check` (use [`try_hertz`] to get an error instead).
pub fn hertz(geom: &ContactGeometry, mat: &Material, normal_load: f64) -> Ellipse {
    match try_hertz(geom, mat, normal_load) {
        Ok(e) => e,
        Err(err) => panic!("hertz: {err}"),
    }
}

/// [`hertz`] returning an error for a non-Hertzian geometry or an invalid material.
pub fn try_hertz(
    geom: &ContactGeometry,
    mat: &Material,
    normal_load: f64,
) -> Result<Ellipse, ContactError> {
    geom.check()?;
    mat.check()?;
    if normal_load.is_nan() || normal_load <= 0.0 {
        return Ok(Ellipse::ZERO);
    }
    let (sx, sy) = geom.curvature_sums();
    let (a_curv, b_curv) = (0.5 * sx.min(sy), 0.5 * sx.max(sy));
    let (m, n, _) = coefficients_for_ratio(b_curv / a_curv);
    let c = (3.0 * normal_load / (4.0 * mat.reduced_modulus() * (a_curv + b_curv))).cbrt();
    let (major, minor) = (m * c, n * c);
    // The major axis lies along the direction of the smaller curvature sum.
    Ok(if sx <= sy {
        Ellipse { a: major, b: minor }
    } else {
        Ellipse { a: minor, b: major }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_function_is_monotone_and_continuous_at_the_circle() {
        let mut prev = f64::INFINITY;
        for i in 1..=1000 {
            let k = i as f64 / 1000.0;
            let r = curvature_ratio_of_axis_ratio(k);
            assert!(r < prev, "not decreasing at k = {k}");
            prev = r;
        }
        assert_eq!(curvature_ratio_of_axis_ratio(1.0), 1.0);
        // Near the circle: B/A - 1 ~ 3 e^2 / 4.
        let k: f64 = 1.0 - 1e-7;
        let e2 = (1.0 - k) * (1.0 + k);
        let r = curvature_ratio_of_axis_ratio(k);
        assert!(((r - 1.0) / (0.75 * e2) - 1.0).abs() < 1e-5, "{r}");
    }

    #[test]
    fn nearly_circular_contact_is_smooth() {
        let (m, n, k) = coefficients_for_ratio(1.0 + 1e-12);
        assert!((m - 1.0).abs() < 1e-6 && (n - 1.0).abs() < 1e-6 && k <= 1.0);
        assert_eq!(coefficients_for_ratio(1.0), (1.0, 1.0, 1.0));
    }
}

//! Creep forces: Kalker's linear law, Shen-Hedrick-Elkins saturation, and the flange stop.

use super::kalker::CreepCoefficients;

/// Creepages of one wheel-rail contact.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Creepages {
    /// Longitudinal creepage \[-\].
    pub longitudinal: f64,
    /// Lateral creepage \[-\].
    pub lateral: f64,
    /// Spin creepage \[1/m\].
    pub spin: f64,
}

/// Tangential contact forces on the wheel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CreepForces {
    /// Longitudinal force \[N\].
    pub fx: f64,
    /// Lateral force \[N\].
    pub fy: f64,
    /// Spin moment about the contact normal \[N m\].
    pub mz: f64,
}

impl CreepForces {
    /// Magnitude of the tangential force, sqrt(fx^2 + fy^2) \[N\].
    pub fn tangential(&self) -> f64 {
        self.fx.hypot(self.fy)
    }
}

/// Kalker's linear law: `Fx = -f11 nu_x`, `Fy = -f22 nu_y - f23 phi`,
/// `Mz = f23 nu_y - f33 phi` (docs/references.md section 4).
#[inline]
pub fn linear_creep(c: &CreepCoefficients, nu: &Creepages) -> CreepForces {
    CreepForces {
        fx: -c.f11 * nu.longitudinal,
        fy: -c.f22 * nu.lateral - c.f23 * nu.spin,
        mz: c.f23 * nu.lateral - c.f33 * nu.spin,
    }
}

/// The Shen-Hedrick-Elkins reduction factor eps(u) = F'/F_linear for the normalised linear
/// force `u = |F_linear| / (mu N) >= 0`: `1 - u/3 + u^2/27` for `u <= 3`, else `1/u`.
///
/// Written as the ratio itself (not as `F'(u)/u`) so that it is exact at u = 0; it is
/// continuous with a continuous first derivative at u = 3 (both branches give 1/3 and -1/9).
#[inline]
pub fn she_factor(u: f64) -> f64 {
    if u <= 3.0 {
        1.0 - u / 3.0 + u * u / 27.0
    } else {
        1.0 / u
    }
}

/// Shen-Hedrick-Elkins saturation of linear creep forces at friction coefficient `friction`
/// and normal load `normal_load` \[N\].
///
/// `u = |(Fx, Fy)| / (mu N)`; the saturated magnitude is `mu N (u - u^2/3 + u^3/27)` for
/// `u <= 3` and `mu N` beyond, and Fx, Fy are scaled by the same factor `eps = F'/F_linear`
/// (their direction is kept). `Mz` is scaled by the same `eps`: the spin moment is carried by
/// the same adhesion area, which shrinks as the tangential load approaches `mu N`, and leaving
/// it linear would let it grow without bound under large creepage. This is a common modelling
/// choice, not part of the published law (which is stated for the tangential force); the spin
/// moment is small for tread contact (`f33` is tiny) so the choice hardly matters there.
///
/// `normal_load <= 0` or `friction <= 0` (or NaN) gives zero forces (wheel lift / no adhesion).
#[inline]
pub fn saturate(f: CreepForces, friction: f64, normal_load: f64) -> CreepForces {
    // Also catches NaN.
    if friction.is_nan() || normal_load.is_nan() || friction <= 0.0 || normal_load <= 0.0 {
        return CreepForces::default();
    }
    let limit = friction * normal_load;
    let u = f.tangential() / limit;
    let eps = she_factor(u);
    CreepForces {
        fx: f.fx * eps,
        fy: f.fy * eps,
        mz: f.mz * eps,
    }
}

/// Flange contact, simplest model: no force inside the dead band `|u| <= clearance`, then a
/// linear spring of stiffness `stiffness` \[N/m\] on the excess, restoring.
///
/// `u` is the lateral displacement of the wheelset relative to the track \[m\]; the returned
/// lateral force on the wheelset \[N\] has the opposite sign of `u` (zero inside the band).
/// A negative `clearance` is treated as zero.
#[inline]
pub fn flange_force(u: f64, clearance: f64, stiffness: f64) -> f64 {
    let excess = u.abs() - clearance.max(0.0);
    if excess > 0.0 {
        -u.signum() * stiffness * excess
    } else {
        0.0
    }
}

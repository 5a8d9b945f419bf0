//! The simplified model (SM) of the paper, section 3.3: one wheelset (lateral `y`, yaw `psi`)
//! and a suspended frame (lateral `y_f`) on a straight track with lateral alignment `xi(s)`.
//!
//! # Coordinates and signs
//! A track frame moves with the vehicle at speed `V` along the *ideal* (irregularity-free) track
//! centre line: `x` forward, `y` to the left, `z` up. `y`, `y_f` are lateral displacements from
//! that line, so they are absolute; `psi` is the wheelset yaw, positive counter-clockwise seen
//! from above (leading side turning left). The alignment `xi` displaces both rails laterally
//! (constant gauge), so the wheelset's displacement relative to the rails is `u = y - xi`.
//! The rails do not move, so no creepage contains `d(xi)/dt`: the alignment enters only through
//! the contact geometry (rolling radii and gravitational stiffness), `docs/references.md`
//! section 1.
//!
//! # Energies (Lagrange)
//! - kinetic: `T = 1/2 m ydot^2 + 1/2 I psidot^2 + 1/2 m_f y_fdot^2` (the frame's yaw is
//!   constrained to zero, the wheelset's roll is not a coordinate);
//! - suspension: two longitudinal elements `kx, cx` at `y = +/- l_s` stretch by `-/+ l_s psi`,
//!   giving `V_s = kx l_s^2 psi^2` and `D = cx l_s^2 psidot^2`; one equivalent lateral element
//!   `ky, cy` between wheelset and frame, `1/2 ky (y - y_f)^2` and `1/2 cy (ydot - y_fdot)^2`.
//!   (The paper's figure of the SM is missing from the source; this is our reading of "longitudinal
//!   and lateral primary suspension elements". kx..cy are identified equivalents, so the choice of
//!   one or two lateral elements is absorbed by the identification.)
//!
//! # Contact (knife-edge rails, coned treads, Kalker linear creep; virtual work)
//! Left wheel at `+l`, right at `-l`; rolling radii `r_0 +/- alpha u`. The contact point of the
//! left wheel moves forward at `V - l psidot` while the tread turns at `(V / r_0)(r_0 + alpha u)`,
//! so the creepages are (upper sign left, lower right):
//! - longitudinal `nu_x = -/+ (alpha u / r_0 + l psidot / V)`,
//! - lateral `nu_y = ydot / V - psi` (both wheels),
//! - spin `phi = psidot / V -/+ alpha / r_0`.
//!
//! With `F_x = -f11 nu_x`, `F_y = -f22 nu_y - f23 phi`, `M_z = f23 nu_y - f33 phi` per wheel:
//! - lateral force `-2 f22 (ydot / V - psi) - 2 f23 psidot / V` (the `alpha / r_0` spin terms
//!   cancel between the wheels);
//! - yaw moment `-l F_x,L + l F_x,R = -2 f11 l (l psidot / V + alpha (y - xi) / r_0)` plus the
//!   spin moments `2 f23 (ydot / V - psi) - 2 f33 psidot / V`.
//!
//! Gravitational stiffness: shifting the wheelset by `u` raises its left end by `alpha u` and
//! lowers the right, a roll `alpha u / l`; the two contact normals, inclined `-/+ alpha` to the
//! vertical, roll with it, so with `N_L = N_R = W / 2` their lateral components sum to
//! `-W alpha u / l`, where `W = (m + m_f) g` is the load the wheels carry (wheelset plus
//! suspended mass). The paper writes `2 alpha g (m - m_f) / l`, which with Table 2 masses would
//! be a *destabilizing* stiffness; we use the derived, restoring `W alpha / l` (the textbook
//! value, docs/references.md section 4). The yaw gravitational stiffness `-W alpha l` (docs/references.md
//! section 4) is about 0.3 % of the suspension yaw stiffness `2 kx l_s^2` with Table 2 values
//! (3.6e3 against 1.15e6 N m/rad) and is left out, as in the paper.
//!
//! # Equations of motion, `M qdd + (C_s + C_c) qd + (K_s + K_c) q = K_d xi`, `q = [y, psi, y_f]`
//! ```text
//! M   = diag(m, I, m_f)
//! K_s = [ky, 0, -ky; 0, 2 kx l_s^2, 0; -ky, 0, ky]      C_s likewise with cy, cx
//! K_c = [W alpha / l, -2 f22, 0; 2 f11 l alpha / r_0, 2 f23, 0; 0, 0, 0]
//! C_c = [2 f22 / V, 2 f23 / V, 0; -2 f23 / V, 2 (f11 l^2 + f33) / V, 0; 0, 0, 0]
//! K_d = [W alpha / l; 2 f11 l alpha / r_0; 0]
//! ```
//! The second entry of `K_d` is the paper's; the first differs as explained above.
//!
//! # State space (paper eqs. for F_c and H_c)
//! `x = [y, psi, y_f, ydot, psidot, y_fdot, xi]`, `xdot = F_c x + v`, with `xi` modelled as
//! constant (`xidot = 0`, a random walk through the process noise). The measurements are the
//! wheelset lateral acceleration (row 4 of `F_c`), the wheelset yaw rate, the frame lateral
//! acceleration (row 6 of `F_c`) and the virtual measurement `xi = 0`.

use crate::params::Params;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// A matrix over the paper's 7 states (`F_c`, `F`, `Q`, `P`).
pub type Mat7 = SMatrix<f64, 7, 7>;
/// The measurement matrix `H` of the 7-state model: 4 measurements by 7 states.
pub type Mat4x7 = SMatrix<f64, 4, 7>;

/// The second-order matrices of the SM at speed `v`.
#[derive(Debug, Clone, PartialEq)]
pub struct SecondOrder {
    /// `M = diag(m, I, m_f)` \[kg, kg m2, kg\], over `q = [y, psi, y_f]` (the paper's
    /// section 3.3).
    pub mass: Matrix3<f64>,
    /// `K_s + K_c`: suspension, creep and gravitational stiffness (the creep terms independent
    /// of the speed; the gravitational stiffness `W alpha / l` derived in the module docs, not
    /// the paper's printed one, docs/references.md section 4).
    pub stiffness: Matrix3<f64>,
    /// `C_s + C_c`: suspension and creep damping (the creep terms divided by the speed).
    pub damping: Matrix3<f64>,
    /// Generalized force per unit alignment, `K_d`.
    pub k_d: Vector3<f64>,
}

/// Builds `M`, `K_s + K_c`, `C_s + C_c` and `K_d` (see the module docs for the derivation).
pub fn second_order(p: &Params, v: f64) -> SecondOrder {
    let w = (p.m + p.m_f) * p.g;
    let k_grav = w * p.alpha / p.l;
    let k_yaw_creep = 2.0 * p.f11 * p.l * p.alpha / p.r_0;
    let k_psi = 2.0 * p.kx * p.l_s * p.l_s;
    let c_psi = 2.0 * p.cx * p.l_s * p.l_s;
    let mass = Matrix3::from_diagonal(&Vector3::new(p.m, p.i, p.m_f));
    #[rustfmt::skip]
    let stiffness = Matrix3::new(
        p.ky + k_grav, -2.0 * p.f22,       -p.ky,
        k_yaw_creep,   k_psi + 2.0 * p.f23, 0.0,
        -p.ky,         0.0,                 p.ky,
    );
    #[rustfmt::skip]
    let damping = Matrix3::new(
        p.cy + 2.0 * p.f22 / v,  2.0 * p.f23 / v,                                  -p.cy,
        -2.0 * p.f23 / v,        c_psi + 2.0 * (p.f11 * p.l * p.l + p.f33) / v,    0.0,
        -p.cy,                   0.0,                                              p.cy,
    );
    SecondOrder {
        mass,
        stiffness,
        damping,
        k_d: Vector3::new(k_grav, k_yaw_creep, 0.0),
    }
}

/// `F_c` split by its speed dependence, `F_c(V) = base + per_inv_speed / V`: only the creep
/// damping terms (`2 f22 / V`, ...) depend on the speed. The filter rebuilds `F_c` from these two
/// at every change of speed without recomputing the model.
pub fn state_matrix_parts(p: &Params) -> (Mat7, Mat7) {
    let so = second_order(p, 1.0);
    let structural = second_order(p, f64::INFINITY).damping;
    let creep_times_v = so.damping - structural;
    let m_inv = Matrix3::from_diagonal(&Vector3::new(1.0 / p.m, 1.0 / p.i, 1.0 / p.m_f));
    let mut base = Mat7::zeros();
    let mut per_inv_speed = Mat7::zeros();
    let (a_q, a_qd, a_c, a_xi) = (
        -(m_inv * so.stiffness),
        -(m_inv * structural),
        -(m_inv * creep_times_v),
        m_inv * so.k_d,
    );
    for i in 0..3 {
        base[(i, i + 3)] = 1.0;
        for j in 0..3 {
            base[(i + 3, j)] = a_q[(i, j)];
            base[(i + 3, j + 3)] = a_qd[(i, j)];
            per_inv_speed[(i + 3, j + 3)] = a_c[(i, j)];
        }
        base[(i + 3, 6)] = a_xi[i];
    }
    (base, per_inv_speed)
}

/// The continuous state matrix `F_c` (7x7).
pub fn state_matrix(p: &Params, v: f64) -> Mat7 {
    let so = second_order(p, v);
    // M is diagonal and positive (checked by Params::check), so its inverse is exact.
    let m_inv = Matrix3::from_diagonal(&Vector3::new(1.0 / p.m, 1.0 / p.i, 1.0 / p.m_f));
    let a_q = -(m_inv * so.stiffness);
    let a_qd = -(m_inv * so.damping);
    let a_xi = m_inv * so.k_d;
    let mut f = Mat7::zeros();
    for i in 0..3 {
        f[(i, i + 3)] = 1.0;
        for j in 0..3 {
            f[(i + 3, j)] = a_q[(i, j)];
            f[(i + 3, j + 3)] = a_qd[(i, j)];
        }
        f[(i + 3, 6)] = a_xi[i];
    }
    f
}

/// The measurement matrix `H` (4x7): `[F_c(4,:); e_5; F_c(6,:); e_7]` in the paper's 1-based
/// notation.
pub fn measurement_matrix(fc: &Mat7) -> Mat4x7 {
    let mut h = Mat4x7::zeros();
    h.set_row(0, &fc.row(3));
    h[(1, 4)] = 1.0;
    h.set_row(2, &fc.row(5));
    h[(3, 6)] = 1.0;
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Free wheelset (no suspension, no gravity, no spin creep): the lateral-yaw eigenvalue's
    /// frequency tends to Klingel's kinematic V / (2 pi sqrt(r0 l / alpha)). The dynamic model
    /// departs from the kinematic one by wheelset inertia against creep, a relative error that
    /// grows as V^4 (0.11 % at 20 m/s with Table 2): within 0.1 % at 10 m/s, and 16 times smaller
    /// at half the speed.
    #[test]
    fn klingel_frequency_of_a_free_wheelset() {
        let p = Params {
            kx: 0.0,
            cx: 0.0,
            ky: 0.0,
            cy: 0.0,
            f23: 0.0,
            f33: 0.0,
            g: 0.0,
            ..Params::default()
        };
        let rel_error = |v: f64| {
            let eig = state_matrix(&p, v).complex_eigenvalues();
            // The free wheelset is unstable at every speed (docs/references.md section 5).
            assert!(
                eig.iter().any(|e| e.re > 0.0 && e.im.abs() > 0.0),
                "no unstable mode at {v} m/s"
            );
            let omega = eig.iter().map(|e| e.im).fold(0.0, f64::max);
            let klingel = v / (2.0 * std::f64::consts::PI * (p.r_0 * p.l / p.alpha).sqrt());
            omega / (2.0 * std::f64::consts::PI) / klingel - 1.0
        };
        let (e10, e5) = (rel_error(10.0), rel_error(5.0));
        assert!(e10.abs() < 1e-3, "relative error {e10} at 10 m/s");
        assert!(
            (e10 / e5 - 16.0).abs() < 0.2,
            "error ratio {} should be 16 (V^4)",
            e10 / e5
        );
    }

    /// The 11.22 m Klingel wavelength of docs/references.md section 5 follows from our r_0 = 0.425 m.
    #[test]
    fn klingel_wavelength_with_table_2_geometry() {
        let p = Params::default();
        let l = 2.0 * std::f64::consts::PI * (p.r_0 * p.l / p.alpha).sqrt();
        assert!((l - 11.22).abs() < 0.01, "{l}");
    }

    #[test]
    fn the_speed_split_rebuilds_the_state_matrix() {
        let p = Params::default();
        let (base, inv_v) = state_matrix_parts(&p);
        for v in [0.7, 5.0, 20.0, 83.0] {
            let direct = state_matrix(&p, v);
            let split = base + inv_v / v;
            assert!((direct - split).amax() <= 1e-12 * direct.amax(), "{v}");
        }
    }

    #[test]
    fn equations_conserve_momentum_between_wheelset_and_frame() {
        // The suspension forces on wheelset and frame are equal and opposite: with creep,
        // gravity and alignment off, m ydd + m_f y_fdd = 0 for any state.
        let p = Params {
            f11: 0.0,
            f22: 0.0,
            f23: 0.0,
            f33: 0.0,
            g: 0.0,
            ..Params::default()
        };
        let fc = state_matrix(&p, 20.0);
        let x = nalgebra::SVector::<f64, 7>::from_column_slice(&[
            0.003, 0.001, -0.002, 0.1, -0.2, 0.05, 0.004,
        ]);
        let xd = fc * x;
        assert!((p.m * xd[3] + p.m_f * xd[5]).abs() < 1e-9);
    }
}

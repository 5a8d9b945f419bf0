//! Modal analysis: the vehicle's equations linearized about static equilibrium on a perfect
//! track, their eigenvalues (natural frequencies and damping) at a given speed, and the critical
//! speed at which a lateral mode first becomes unstable.
//!
//! The state matrix `A = [0 I; dqdd/dq dqdd/dqd]` is obtained by central differences of the
//! same right-hand side the simulation integrates, so the modal analysis can never disagree with
//! the time-domain model. On straight track the symmetric vehicle's lateral (lateral, roll, yaw)
//! and vertical (bounce, pitch) motions decouple; [`Modes`] keeps the two sets apart, which is
//! what identifies a mode as lateral.

use crate::dynamics::{Dof, NDOF, Vehicle, WheelsetTrack, dof};
use nalgebra::{Complex, DMatrix};

/// The lateral degrees of freedom: car body and bogies y, roll, yaw; wheelsets y, yaw.
pub fn lateral_dofs() -> Vec<usize> {
    let mut v = vec![];
    for base in [dof::CAR, dof::bogie(0), dof::bogie(1)] {
        v.extend([base + dof::Y, base + dof::ROLL, base + dof::YAW]);
    }
    for j in 0..4 {
        v.extend([dof::wheelset(j), dof::wheelset(j) + 1]);
    }
    v
}

/// The vertical degrees of freedom: car body and bogies bounce and pitch.
pub fn vertical_dofs() -> Vec<usize> {
    let mut v = vec![];
    for base in [dof::CAR, dof::bogie(0), dof::bogie(1)] {
        v.extend([base + dof::Z, base + dof::PITCH]);
    }
    v
}

/// The full 46x46 state matrix at speed `v`.
pub fn state_matrix(vehicle: &Vehicle, v: f64) -> DMatrix<f64> {
    let n = NDOF;
    let track = [WheelsetTrack::default(); 4];
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    for i in 0..n {
        a[(i, n + i)] = 1.0;
    }
    let (q0, qd0) = (Dof::zeros(), Dof::zeros());
    for j in 0..2 * n {
        let eps = if j < n { 1e-7 } else { 1e-6 };
        let (mut qp, mut qdp, mut qm, mut qdm) = (q0, qd0, q0, qd0);
        if j < n {
            qp[j] += eps;
            qm[j] -= eps;
        } else {
            qdp[j - n] += eps;
            qdm[j - n] -= eps;
        }
        let (ap, _) = vehicle.accelerations(&qp, &qdp, v, &track, None);
        let (am, _) = vehicle.accelerations(&qm, &qdm, v, &track, None);
        for i in 0..n {
            a[(n + i, j)] = (ap[i] - am[i]) / (2.0 * eps);
        }
    }
    a
}

/// The rows and columns of `a` for the given degrees of freedom (positions and velocities).
pub fn subsystem(a: &DMatrix<f64>, dofs: &[usize]) -> DMatrix<f64> {
    let n = NDOF;
    let idx: Vec<usize> = dofs
        .iter()
        .copied()
        .chain(dofs.iter().map(|d| d + n))
        .collect();
    DMatrix::from_fn(idx.len(), idx.len(), |i, j| a[(idx[i], idx[j])])
}

/// One mode: eigenvalue, damped frequency \[Hz\] and damping ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    /// The eigenvalue of the state matrix \[1/s\]; a positive real part is an unstable mode.
    pub eigenvalue: Complex<f64>,
    /// Damped natural frequency `|Im| / (2 pi)` \[Hz\]; 0 for an overdamped mode.
    pub frequency: f64,
    /// Damping ratio `-Re / |lambda|` (1 critical, negative unstable).
    pub damping: f64,
}

impl Mode {
    fn from(e: Complex<f64>) -> Mode {
        let norm = e.norm();
        Mode {
            eigenvalue: e,
            frequency: e.im.abs() / (2.0 * std::f64::consts::PI),
            damping: if norm > 0.0 { -e.re / norm } else { 0.0 },
        }
    }
}

/// Eigenvalues of the lateral and vertical subsystems, oscillatory modes once each (positive
/// imaginary part), sorted by frequency; overdamped (real) modes are kept with frequency 0.
#[derive(Debug, Clone)]
pub struct Modes {
    /// The speed the equations were linearized at \[m/s\]: the creep forces, and so the lateral
    /// modes, depend on it.
    pub speed: f64,
    /// Modes of the lateral subsystem (lateral, roll, yaw): where hunting appears.
    pub lateral: Vec<Mode>,
    /// Modes of the vertical subsystem (bounce, pitch).
    pub vertical: Vec<Mode>,
    /// Largest coupling entry between the two subsystems relative to the largest entry of A
    /// (zero for a symmetric vehicle on straight track).
    pub coupling: f64,
}

fn modes_of(a: &DMatrix<f64>) -> Vec<Mode> {
    let mut m: Vec<Mode> = a
        .complex_eigenvalues()
        .iter()
        .filter(|e| e.im >= 0.0)
        .map(|e| Mode::from(*e))
        .collect();
    m.sort_by(|x, y| x.frequency.total_cmp(&y.frequency));
    m
}

/// The modes of `vehicle` at speed `v` \[m/s\], from the state matrix of the same right-hand
/// side the simulation integrates.
pub fn modes(vehicle: &Vehicle, v: f64) -> Modes {
    let a = state_matrix(vehicle, v);
    let (lat, ver) = (lateral_dofs(), vertical_dofs());
    let n = NDOF;
    let mut coupling: f64 = 0.0;
    for &i in lat.iter() {
        for &j in ver.iter() {
            for (r, c) in [(n + i, j), (n + i, n + j), (n + j, i), (n + j, n + i)] {
                coupling = coupling.max(a[(r, c)].abs());
            }
        }
    }
    Modes {
        speed: v,
        lateral: modes_of(&subsystem(&a, &lat)),
        vertical: modes_of(&subsystem(&a, &ver)),
        coupling: coupling / a.amax(),
    }
}

impl Modes {
    /// The largest real part among the lateral eigenvalues (positive: unstable).
    pub fn lateral_max_real(&self) -> f64 {
        self.lateral
            .iter()
            .map(|m| m.eigenvalue.re)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The lowest-frequency lateral mode that can resonate (damping ratio below 0.5): the
    /// paper's "first mode" for its resonance case. Heavily damped and overdamped creep modes
    /// are skipped.
    pub fn first_lateral(&self) -> Option<Mode> {
        self.lateral
            .iter()
            .copied()
            .find(|m| m.frequency > 1e-3 && m.damping < 0.5)
    }
}

/// The critical speed: the lowest speed in `[v_min, v_max]` at which a lateral eigenvalue has a
/// positive real part, found by a scan with step `dv` refined by bisection to 0.01 m/s.
/// `None` if the vehicle is stable over the whole range.
pub fn critical_speed(vehicle: &Vehicle, v_min: f64, v_max: f64, dv: f64) -> Option<f64> {
    let unstable = |v: f64| modes(vehicle, v).lateral_max_real() > 0.0;
    let mut lo = v_min;
    if unstable(lo) {
        return Some(lo);
    }
    let mut v = v_min;
    while v < v_max {
        let next = (v + dv).min(v_max);
        if unstable(next) {
            let mut hi = next;
            lo = v;
            while hi - lo > 0.01 {
                let mid = 0.5 * (lo + hi);
                if unstable(mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Some(hi);
        }
        v = next;
    }
    None
}

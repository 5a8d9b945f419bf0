"""An independent numpy reference of the estimator's simplified model (SM).

Why it exists: the tests need an oracle that does not share code with the FMU. This module is
written from the derivation in the documentation of fmu-estimator/src/model.rs (Lagrange
equations of one wheelset with yaw, plus a suspended frame, on a straight track with lateral
alignment xi), not from the Rust code. It provides

- the second-order matrices M, K, C, K_d and the 7x7 state matrix F_c of the Kalman filter;
- a simulator of the true motion driven by an alignment signal xi(t) (exact for a piecewise
  linear xi: matrix exponential of the system augmented with xi and its slope);
- virtual sensors (wheelset lateral acceleration, wheelset yaw rate, frame lateral
  acceleration) with the paper's optional Gaussian noise;
- alignment generators: harmonic superposition from the German low-disturbance spectrum, and a
  pure harmonic.

Coordinates (model.rs): q = [y, psi, y_f] measured from the ideal track centre line; the
alignment displaces both rails, so it enters only through the contact geometry: the rolling
radius difference alpha (y - xi) / r_0 and the gravitational stiffness W alpha / l, where
W = (m + m_f) g.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

#: Defaults of the FMU's parameters (fmu-estimator variable table; the paper's Table 2 except
#: r_0 = 0.425 m, the rolling radius, where Table 2 prints the diameter). Keys are FMI names.
PARAMS: dict[str, float] = {
    "m": 1109.0,  # wheelset mass [kg]
    "I": 606.0,  # wheelset yaw inertia [kg m2]
    "l": 0.75,  # half distance between contact points [m]
    "l_s": 0.85,  # half distance between longitudinal suspension elements [m]
    "alpha": 0.1,  # conicity [-]
    "r_0": 0.425,  # rolling radius [m]
    "m_f": 3781.0,  # suspended mass carried by the wheelset [kg]
    "f11": 5.5e6,  # Kalker longitudinal [N]
    "f22": 5.0e6,  # Kalker lateral [N]
    "f23": 9.3e3,  # Kalker lateral/spin [N m]
    "f33": 15.0,  # Kalker spin [N m2]
    "kx": 7.95e5,  # longitudinal primary stiffness per side [N/m]
    "cx": 1.47e4,  # longitudinal primary damping per side [N s/m]
    "ky": 4.12e6,  # lateral primary stiffness [N/m]
    "cy": 1.41e5,  # lateral primary damping [N s/m]
    "g": 9.81,  # gravity [m/s2]
}

#: The paper's sensor noise (standard deviations), keyed by the FMU's input names.
SENSOR_SIGMAS: dict[str, float] = {"ws_acc_y": 0.01, "ws_yaw_rate": 0.0005, "frame_acc_y": 0.01}

#: German low-disturbance alignment spectrum (one-sided, angular wavenumber).
LOW_DISTURBANCE_A = 2.119e-7  # m rad
OMEGA_C = 0.8246  # rad/m
OMEGA_R = 0.0206  # rad/m


def params(**overrides: float) -> dict[str, float]:
    """The default parameters with some replaced (unknown names are an error, not a no-op)."""
    unknown = set(overrides) - set(PARAMS)
    if unknown:
        raise KeyError(f"unknown SM parameters: {sorted(unknown)}")
    return {**PARAMS, **overrides}


@dataclass(frozen=True)
class SecondOrder:
    """M qdd + C qd + K q = K_d xi, q = [y, psi, y_f]."""

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    K_d: np.ndarray


def second_order(speed: float, p: dict[str, float] | None = None) -> SecondOrder:
    """The SM's matrices at forward speed `speed` [m/s].

    Suspension: two longitudinal elements at +/- l_s (yaw stiffness 2 kx l_s^2, damping
    2 cx l_s^2) and one lateral element between wheelset and frame. Contact (per wheel, linear
    Kalker, knife-edge rails): lateral creepage ydot/V - psi, longitudinal
    -/+ (alpha u / r_0 + l psidot / V) with u = y - xi, spin psidot/V -/+ alpha/r_0.
    """
    p = PARAMS if p is None else p
    m, inertia, m_f = p["m"], p["I"], p["m_f"]
    l, l_s, alpha, r_0 = p["l"], p["l_s"], p["alpha"], p["r_0"]
    f11, f22, f23, f33 = p["f11"], p["f22"], p["f23"], p["f33"]
    V = speed

    weight = (m + m_f) * p["g"]
    k_gravity = weight * alpha / l  # lateral gravitational stiffness, restoring
    k_yaw_creep = 2.0 * f11 * l * alpha / r_0  # yaw moment per unit y - xi

    M = np.diag([m, inertia, m_f])

    def coupling(k_lat: float, k_yaw: float) -> np.ndarray:
        """A suspension matrix: lateral element wheelset-frame, yaw element on the wheelset."""
        return np.array([[k_lat, 0.0, -k_lat], [0.0, k_yaw, 0.0], [-k_lat, 0.0, k_lat]])

    K_s = coupling(p["ky"], 2.0 * p["kx"] * l_s**2)
    C_s = coupling(p["cy"], 2.0 * p["cx"] * l_s**2)
    # Contact forces moved to the left-hand side. Lateral: -2 f22 (ydot/V - psi) - 2 f23 psidot/V
    # - W alpha (y - xi)/l. Yaw: -2 f11 l (l psidot/V + alpha (y - xi)/r_0)
    # + 2 f23 (ydot/V - psi) - 2 f33 psidot/V.
    K_c = np.array([[k_gravity, -2.0 * f22, 0.0], [k_yaw_creep, 2.0 * f23, 0.0], [0.0, 0.0, 0.0]])
    C_c = np.array(
        [
            [2.0 * f22 / V, 2.0 * f23 / V, 0.0],
            [-2.0 * f23 / V, 2.0 * (f11 * l**2 + f33) / V, 0.0],
            [0.0, 0.0, 0.0],
        ]
    )
    K_d = np.array([k_gravity, k_yaw_creep, 0.0])
    return SecondOrder(M=M, K=K_s + K_c, C=C_s + C_c, K_d=K_d)


def system(speed: float, p: dict[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """First-order form zdot = A z + B xi of the true motion, z = [q, qdot] (6 states)."""
    so = second_order(speed, p)
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3:, :3] = -np.linalg.solve(so.M, so.K)
    A[3:, 3:] = -np.linalg.solve(so.M, so.C)
    B = np.zeros(6)
    B[3:] = np.linalg.solve(so.M, so.K_d)
    return A, B


def state_matrix(speed: float, p: dict[str, float] | None = None) -> np.ndarray:
    """The filter's F_c (7x7): x = [y, psi, y_f, ydot, psidot, y_fdot, xi], xidot = 0."""
    A, B = system(speed, p)
    F = np.zeros((7, 7))
    F[:6, :6] = A
    F[:6, 6] = B
    return F


@dataclass(frozen=True)
class Motion:
    """A simulated run: time, distance, alignment, states z = [q, qdot] and accelerations qdd."""

    t: np.ndarray
    s: np.ndarray
    xi: np.ndarray
    z: np.ndarray  # (N, 6)
    qdd: np.ndarray  # (N, 3)
    speed: float

    @property
    def step(self) -> float:
        return float(self.t[1] - self.t[0])


def simulate(xi: np.ndarray, step: float, speed: float, p: dict[str, float] | None = None) -> Motion:
    """The true SM response to the alignment samples `xi` (at t = k * step), taken as piecewise
    linear in time.

    Exact discretization: with w = [z, xi, xi'] and xi' constant over a step, wdot = Abar w is
    linear and time-invariant, so w(t + h) = expm(Abar h) w(t). The run starts at the static
    equilibrium for xi[0] (K q = K_d xi[0], at rest), which keeps the start-up transient small.
    """
    A, B = system(speed, p)
    Abar = np.zeros((8, 8))
    Abar[:6, :6] = A
    Abar[:6, 6] = B
    Abar[6, 7] = 1.0
    Phi = expm(Abar * step)
    Phi_z, phi_xi, phi_slope = Phi[:6, :6], Phi[:6, 6], Phi[:6, 7]

    xi = np.asarray(xi, dtype=float)
    n = xi.size
    so = second_order(speed, p)
    z = np.zeros((n, 6))
    z[0, :3] = np.linalg.solve(so.K, so.K_d * xi[0])
    slope = np.diff(xi) / step
    for k in range(n - 1):
        z[k + 1] = Phi_z @ z[k] + phi_xi * xi[k] + phi_slope * slope[k]
    zdot = z @ A.T + np.outer(xi, B)
    t = np.arange(n) * step
    return Motion(t=t, s=speed * t, xi=xi, z=z, qdd=zdot[:, 3:], speed=speed)


def sensors(motion: Motion, rng: np.random.Generator | None = None, noise_scale: float = 1.0) -> dict[str, np.ndarray]:
    """The three sensor signals, named like the FMU's inputs; Gaussian noise with the paper's
    sigmas (times `noise_scale`) when a random generator is given."""
    signals = {
        "ws_acc_y": motion.qdd[:, 0].copy(),
        "ws_yaw_rate": motion.z[:, 4].copy(),
        "frame_acc_y": motion.qdd[:, 2].copy(),
    }
    if rng is not None:
        for name, sigma in SENSOR_SIGMAS.items():
            signals[name] += rng.normal(0.0, sigma * noise_scale, signals[name].size)
    return signals


def alignment_spectrum(omega: np.ndarray, A: float = LOW_DISTURBANCE_A) -> np.ndarray:
    """S(Omega) = A Oc^2 / ((Omega^2 + Or^2)(Omega^2 + Oc^2)) [m^2 / (rad/m)], one-sided."""
    omega = np.asarray(omega, dtype=float)
    return A * OMEGA_C**2 / ((omega**2 + OMEGA_R**2) * (omega**2 + OMEGA_C**2))


@dataclass(frozen=True)
class Harmonics:
    """xi(s) = sum_k amplitude_k cos(omega_k s + phase_k)."""

    omega: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray

    def __call__(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        out = np.zeros_like(s)
        for i in range(0, self.omega.size, 256):  # chunks keep the (N, 256) matrix small
            sl = slice(i, i + 256)
            out += np.cos(np.outer(s, self.omega[sl]) + self.phase[sl]) @ self.amplitude[sl]
        return out


def alignment_harmonics(
    rng: np.random.Generator,
    wavelengths: tuple[float, float] = (1.0, 250.0),
    count: int = 2000,
    A: float = LOW_DISTURBANCE_A,
) -> Harmonics:
    """Harmonic superposition of the alignment spectrum over a wavelength band.

    `count` bins of equal width dOmega between 2 pi / lambda_max and 2 pi / lambda_min, one
    harmonic at each bin centre with amplitude sqrt(2 S dOmega) (so its variance is S dOmega)
    and a uniform random phase. The sum repeats after 2 pi / dOmega (about 2 km with the
    defaults), far longer than a 400 m run.
    """
    lo, hi = 2.0 * np.pi / wavelengths[1], 2.0 * np.pi / wavelengths[0]
    d_omega = (hi - lo) / count
    omega = lo + (np.arange(count) + 0.5) * d_omega
    amplitude = np.sqrt(2.0 * alignment_spectrum(omega, A) * d_omega)
    phase = rng.uniform(0.0, 2.0 * np.pi, count)
    return Harmonics(omega=omega, amplitude=amplitude, phase=phase)


def harmonic_alignment(amplitude: float, wavelength: float, phase: float = 0.0) -> Harmonics:
    """A pure harmonic alignment amplitude * cos(2 pi s / wavelength + phase)."""
    return Harmonics(
        omega=np.array([2.0 * np.pi / wavelength]), amplitude=np.array([amplitude]), phase=np.array([phase])
    )


@dataclass(frozen=True)
class SyntheticRun:
    """Everything a test or the demo needs from one synthetic run on a straight track."""

    motion: Motion
    signals: dict[str, np.ndarray]

    @property
    def t(self) -> np.ndarray:
        return self.motion.t

    @property
    def xi(self) -> np.ndarray:
        return self.motion.xi


def synthetic_run(
    alignment: Harmonics,
    speed: float = 20.0,
    duration: float = 20.0,
    step: float = 1e-3,
    noise_rng: np.random.Generator | None = None,
    p: dict[str, float] | None = None,
) -> SyntheticRun:
    """The SM running at constant `speed` over `alignment` for `duration`, sampled every
    `step` (duration/step + 1 samples, t = 0 included), with sensor noise if `noise_rng`."""
    n = int(round(duration / step)) + 1
    t = np.arange(n) * step
    motion = simulate(alignment(speed * t), step, speed, p)
    return SyntheticRun(motion=motion, signals=sensors(motion, noise_rng))

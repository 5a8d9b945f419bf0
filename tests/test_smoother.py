"""`alignment-studies smooth` (the estimator's Kalman filter and Rauch-Tung-Striebel smoother run
offline over a recorded CSV) against a second implementation: a plain numpy Kalman filter and
RTS smoother written here from the textbook equations (Särkkä 2013, sections 4.3 and 8.2), with
the simplified model's matrices from sm_reference (scipy's expm for the exact discretization).
Data: the simplified model itself on a low-disturbance alignment with the paper's sensor noise."""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

import orchestrator_cli as cli
import sm_reference as sm

STEP = 1e-3
SPEED = 20.0
#: The filter's diagonal noise model, given explicitly on both sides.
Q_RATE = {"q_acc_ws": 1e-4, "q_yaw_acc": 1e-4, "q_acc_frame": 1e-4, "q_xi": 1e-5}
SIGMAS = {"sigma_acc_ws": 0.01, "sigma_yaw_rate": 0.0005, "sigma_acc_frame": 0.01, "sigma_xi": 0.005}
P0_SIGMAS = [5e-3, 1e-3, 5e-3, 5e-2, 1e-2, 5e-2, 5e-3]


def numpy_filter_and_smoother(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Alignment estimates (filtered, smoothed) for measurements z (N x 3), x0 = 0."""
    Fc = sm.state_matrix(SPEED, sm.PARAMS)
    F = expm(Fc * STEP)
    H = np.zeros((4, 7))
    H[0], H[1, 4], H[2], H[3, 6] = Fc[3], 1.0, Fc[5], 1.0
    Q = STEP * np.diag([0, 0, 0, Q_RATE["q_acc_ws"], Q_RATE["q_yaw_acc"], Q_RATE["q_acc_frame"], Q_RATE["q_xi"]])
    R = np.diag(np.square(list(SIGMAS.values())))
    n = len(z)
    x, P = np.zeros(7), np.diag(np.square(P0_SIGMAS))
    xp, Pp, xf, Pf = np.zeros((n, 7)), np.zeros((n, 7, 7)), np.zeros((n, 7)), np.zeros((n, 7, 7))
    for k in range(n):
        x, P = F @ x, F @ P @ F.T + Q
        xp[k], Pp[k] = x, P
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        x = x + K @ (np.append(z[k], 0.0) - H @ x)
        P = P - K @ S @ K.T
        xf[k], Pf[k] = x, P
    xs = xf.copy()
    for k in range(n - 2, -1, -1):
        C = np.linalg.solve(Pp[k + 1], F @ Pf[k]).T
        xs[k] = xf[k] + C @ (xs[k + 1] - xp[k + 1])
    return xf[:, 6], xs[:, 6]


def test_smooth_command_equals_a_numpy_filter_and_smoother(tmp_path):
    run = sm.synthetic_run(
        sm.alignment_harmonics(np.random.default_rng(7)), speed=SPEED, duration=4.0, step=STEP,
        noise_rng=np.random.default_rng(8),
    )
    sig = run.signals
    t = run.motion.t
    csv = tmp_path / "recorded.csv"
    header = "time,vehicle.forward_speed,vehicle.ws_acc_y,vehicle.ws_yaw_rate,vehicle.frame_acc_y"
    rows = np.column_stack([t, np.full_like(t, SPEED), sig["ws_acc_y"], sig["ws_yaw_rate"], sig["frame_acc_y"]])
    np.savetxt(csv, rows, delimiter=",", header=header, comments="", fmt="%.17g")
    settings = {
        **sm.PARAMS, **Q_RATE, **SIGMAS,
        "use_calibration_file": "false", "alignment_model": 1, "p0_stationary": "false",
        "discretization": 2, "p0_xi": P0_SIGMAS[6],
    }
    out = tmp_path / "smoothed.csv"
    args = ["smooth", csv, "--out", out]
    for k, v in settings.items():
        args += ["--set", f"{k}={v}"]
    cli.studies(*args)
    result = cli.read_results(out)
    # Every row is a sample, the first one too (docs/recordings.md): the filter steps on each.
    z = np.column_stack([sig["ws_acc_y"], sig["ws_yaw_rate"], sig["frame_acc_y"]])
    assert len(result["time"]) == len(t)
    filtered, smoothed = numpy_filter_and_smoother(z)
    scale = np.sqrt(np.mean(np.square(run.motion.xi)))
    assert np.max(np.abs(result["alignment_filtered"] - filtered)) < 1e-6 * scale
    assert np.max(np.abs(result["alignment_smoothed"] - smoothed)) < 1e-6 * scale
    # Row k's distance is the distance after its step, k + 1 steps, as the FMU counts it.
    assert np.allclose(result["distance"], SPEED * (t + STEP), rtol=1e-12)
    # And the smoother is the better estimate of the truth on this run (whole band).
    truth = run.motion.xi
    err = lambda e: np.sqrt(np.mean(np.square(e - truth)))  # noqa: E731
    assert err(smoothed) < err(filtered)

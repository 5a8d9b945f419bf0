"""The estimate against the truth on data from the simplified model (sm_reference), run through
fmpy.simulate_fmu as a user would. The bounds were set from measured values (in each test's
docstring) with a margin for platform floating-point differences, not for behaviour changes."""

from __future__ import annotations

import numpy as np
import pytest

import evaluation as ev
import sm_reference as sm


def fit_harmonic(t: np.ndarray, x: np.ndarray, frequency: float) -> complex:
    """Least-squares complex amplitude of x(t) at `frequency` [Hz] (with an offset)."""
    w = 2 * np.pi * frequency
    X = np.column_stack([np.cos(w * t), np.sin(w * t), np.ones_like(t)])
    (c, s, _), *_ = np.linalg.lstsq(X, x, rcond=None)
    return complex(c, -s)


def test_estimate_follows_the_truth_in_the_whole_band(fmu_path, noisy_run):
    """Noisy 20 s run at 20 m/s, noise model matched to SM data: measured Jrel 0.43 (J 0.75 mm
    on a 1.75 mm rms alignment) after the 3-200 m band-pass; bound 0.5."""
    result = ev.simulate(fmu_path, noisy_run, start_values=ev.SM_TUNING)
    whole = ev.score(result, noisy_run)["whole"]
    assert whole.Jrel < 0.5, whole


def test_default_noise_model_follows_the_short_wavelengths(fmu_path, noisy_run):
    """With the FMU's defaults (uncalibrated diagonal noise model) the 3-25 m band is estimated:
    measured Jrel 0.35 in D1; bound 0.45. (The whole band is not: Jrel 1.1, because the 5 mm
    virtual measurement pulls the long wavelengths towards zero; see SM_TUNING.)"""
    result = ev.simulate(fmu_path, noisy_run)
    d1 = ev.score(result, noisy_run)["D1"]
    assert d1.Jrel < 0.45, d1
    assert np.all(np.isfinite(result["alignment"])) and np.all(result["alignment_std"] > 0)


def test_harmonic_alignment_amplitude_and_phase_are_recovered(fmu_path):
    """Noise-free data on a pure 1 mm harmonic of 40 m wavelength (0.5 Hz at 20 m/s), SM tuning,
    fitted after the first 5 s: measured amplitude ratio 0.974, phase lead 0.117 rad; bounds
    10 % and 0.2 rad. (With the defaults: ratio 0.84, lead 1.22 rad.)"""
    run = sm.synthetic_run(sm.harmonic_alignment(1e-3, 40.0), speed=20.0, duration=20.0)
    result = ev.simulate(fmu_path, run, start_values=ev.SM_TUNING)
    late = run.t >= 5.0
    frequency = 20.0 / 40.0
    ratio = fit_harmonic(run.t[late], result["alignment"][late], frequency) / fit_harmonic(run.t[late], run.xi[late], frequency)
    assert abs(ratio) == pytest.approx(1.0, abs=0.10)
    assert abs(np.angle(ratio)) < 0.2


def test_fmu_model_agrees_with_the_reference_model(fmu_path):
    """On noise-free data, with the exact discretization and sensor sigmas far below the
    paper's, the D1 estimate is good only if the FMU's F_c and H match the reference's:
    measured Jrel 0.175 on matching data (bound 0.3), and 1.01 when the data come from the
    reference with r_0 = 0.85 m (Table 2 as printed; must exceed 0.6), which shows the test
    would notice a model mismatch."""
    tight = {
        **ev.SM_TUNING,
        "q_acc_ws": 1e-8,
        "q_yaw_acc": 1e-8,
        "q_acc_frame": 1e-8,
        "discretization": 2,
        "sigma_acc_ws": 1e-4,
        "sigma_yaw_rate": 5e-6,
        "sigma_acc_frame": 1e-4,
    }
    alignment = sm.alignment_harmonics(np.random.default_rng(1))
    matching = sm.synthetic_run(alignment, duration=10.0)
    d1 = ev.score(ev.simulate(fmu_path, matching, start_values=tight), matching)["D1"]
    assert d1.Jrel < 0.3, d1
    other = sm.synthetic_run(alignment, duration=10.0, p=sm.params(r_0=0.85))
    d1_other = ev.score(ev.simulate(fmu_path, other, start_values=tight), other)["D1"]
    assert d1_other.Jrel > 0.6, d1_other


def test_distance_is_speed_times_time(fmu_path, noisy_run):
    result = ev.simulate(fmu_path, noisy_run, outputs=("distance",))
    assert np.allclose(result["distance"], 20.0 * noisy_run.t, rtol=1e-12, atol=1e-9)

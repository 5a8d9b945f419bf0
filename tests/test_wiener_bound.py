"""tests/wiener_bound.py's Wiener machinery against the textbook case: a first-order
autoregressive signal seen in white noise, whose non-causal Wiener error spectrum is
`S_y N / (S_y + N)` in closed form, and a second sensor that adds information."""

from __future__ import annotations

import numpy as np
from scipy import signal

from wiener_bound import apply, fir, spectra, wiener

FS = 50.0
A = 0.95
SIGMA = 1.0
NOISE = 4.0 * 2 * SIGMA**2 / FS  # the density at which the signal's DC level is 1/4 of the noise


def ar1(rng: np.random.Generator, n: int) -> np.ndarray:
    return signal.lfilter([1.0], [1.0, -A], SIGMA * rng.standard_normal(n))


def analytic_spectrum(f: np.ndarray) -> np.ndarray:
    """One-sided PSD of the AR(1) process at sample rate FS."""
    return 2 * SIGMA**2 / FS / np.abs(1 - A * np.exp(-2j * np.pi * f / FS)) ** 2


def test_the_wiener_error_is_the_textbook_one_and_the_fir_reaches_it():
    rng = np.random.default_rng(7)
    nperseg = 1024
    runs = []
    for _ in range(8):
        y = ar1(rng, 200_000)
        runs.append(np.array([y, y]))  # channel 0: the sensor (noise-free), 1: the target
    f, s = spectra(runs, FS, nperseg)
    # Welch's estimate, but for the first bins, which the Hann window's main lobe biases.
    np.testing.assert_allclose(s[1, 1].real[3:-1], analytic_spectrum(f)[3:-1], rtol=0.1)

    w, err = wiener(s, 1, (0,), np.array([NOISE, 0.0]))
    sy = analytic_spectrum(f)
    expected = sy * NOISE / (sy + NOISE)
    df = f[1] - f[0]
    assert abs(np.sum(err) * df / (np.sum(expected) * df) - 1) < 0.03
    # Where the signal dominates the weight is near 1, where the noise does near 0.
    assert abs(w[0, 0].real - sy[0] / (sy[0] + NOISE)) < 0.05
    assert abs(w[0, -1]) < 0.1

    # The two-sided FIR on a fresh noisy record reaches the bound's error variance.
    y = ar1(rng, 400_000)
    x = y + np.sqrt(NOISE * FS / 2) * rng.standard_normal(len(y))
    est = apply(fir(w[:1], nperseg), x[None, :])
    inner = slice(nperseg, -nperseg)
    mse = np.mean((est[inner] - y[inner]) ** 2)
    assert abs(mse / (np.sum(expected) * df) - 1) < 0.05
    # Doing nothing and trusting the sensor are both worse.
    assert mse < 0.8 * min(np.var(y), np.mean((x - y) ** 2))


def test_a_second_sensor_with_independent_noise_lowers_the_error_as_two_looks_do():
    rng = np.random.default_rng(11)
    runs = []
    for _ in range(8):
        y = ar1(rng, 200_000)
        runs.append(np.array([y, y, y]))
    f, s = spectra(runs, FS, 1024)
    noise = np.array([NOISE, NOISE, 0.0])
    _, one = wiener(s, 2, (0,), noise)
    _, two = wiener(s, 2, (0, 1), noise)
    # Two looks with independent noise N are one look with noise N / 2.
    sy = analytic_spectrum(f)
    expected = sy * (NOISE / 2) / (sy + NOISE / 2)
    assert abs(np.sum(two) / np.sum(expected) - 1) < 0.03
    assert np.sum(two) < 0.75 * np.sum(one)

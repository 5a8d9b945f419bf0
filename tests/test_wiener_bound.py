"""tests/wiener_bound.py's Wiener machinery against cases whose answer is known: a first-order
autoregressive signal seen in white noise (non-causal Wiener error `S_y N / (S_y + N)` in closed
form), two independent looks at it, a look delayed in time (complex cross-spectra: a transposed
or conjugated solve, or a reversed FIR, fails it), and noise-free exact derivatives of a steep
signal, whose error must be nil (Welch's window loses coherence there unless the channels are
shaped alike)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from wiener_bound import apply, back_to_target, bound, fir, lag_fir, shape, spectra, wiener

FS = 50.0
A = 0.95
SIGMA = 1.0
# The noise density: 4 times the innovation's, so that the signal (100 times the noise at DC)
# dominates below about 1 Hz and the noise above.
NOISE = 4.0 * 2 * SIGMA**2 / FS


def ar1(rng: np.random.Generator, n: int) -> np.ndarray:
    return signal.lfilter([1.0], [1.0, -A], SIGMA * rng.standard_normal(n))


def analytic_spectrum(f: np.ndarray) -> np.ndarray:
    """One-sided PSD of the AR(1) process at sample rate FS."""
    return 2 * SIGMA**2 / FS / np.abs(1 - A * np.exp(-2j * np.pi * f / FS)) ** 2


def white(rng: np.random.Generator, n: int) -> np.ndarray:
    """White noise of one-sided density NOISE at FS."""
    return np.sqrt(NOISE * FS / 2) * rng.standard_normal(n)


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
    assert abs(np.sum(err) / np.sum(expected) - 1) < 0.03
    # The weight follows the signal-to-noise ratio: 0.98 at 0.5 Hz, 0.07 at 20 Hz.
    bins = [int(0.5 / f[1]), int(20 / f[1])]
    np.testing.assert_allclose(w[0, bins].real, (sy / (sy + NOISE))[bins], rtol=0.1)
    assert np.all(np.abs(w[0, bins].imag) < 0.02)

    # The two-sided FIR on a fresh noisy record reaches the bound's error variance.
    y = ar1(rng, 400_000)
    x = y + white(rng, len(y))
    est = apply(fir(w[:1], nperseg), x[None, :])
    inner = slice(nperseg, -nperseg)
    mse = np.mean((est[inner] - y[inner]) ** 2)
    df = f[1] - f[0]
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


def test_a_delayed_look_is_undone_by_the_fir_and_its_error_is_the_bound():
    """A sensor that sees the signal 5 samples late (and a second one 3 samples early) makes the
    cross-spectra complex: only the right orientation of the normal equations and the right
    direction of the FIR give the bound's error on a fresh record."""
    rng = np.random.default_rng(3)
    nperseg = 1024
    late, early = 5, 3

    def looks(n: int) -> tuple[np.ndarray, np.ndarray]:
        y = ar1(rng, n + 16)
        return np.array([y[8 - late: 8 - late + n], y[8 + early: 8 + early + n]]), y[8: 8 + n]

    runs = []
    for _ in range(8):
        x, y = looks(200_000)
        runs.append(np.vstack([x, y]))
    f, s = spectra(runs, FS, nperseg)
    w, err = wiener(s, 2, (0, 1), np.array([NOISE, NOISE, 0.0]))
    x, y = looks(400_000)
    x = x + np.array([white(rng, x.shape[1]), white(rng, x.shape[1])])
    est = apply(fir(w, nperseg), x)
    inner = slice(nperseg, -nperseg)
    mse = np.mean((est[inner] - y[inner]) ** 2)
    df = f[1] - f[0]
    assert abs(mse / (np.sum(err) * df) - 1) < 0.05
    # Two noisy looks, re-aligned: better than either alone would be.
    assert mse < 0.75 * np.mean((x[0, late:] - y[:-late]) ** 2)


def test_shaped_exact_derivatives_leave_no_error():
    """A steep signal (a doubly integrated random walk, falling by decades across each band) and
    its exact derivatives without noise: the alignment is known exactly, so every band's error
    must be nil. Shaped alike (the target differenced twice, the rate once), Welch keeps the
    coherence; unshaped, its window leaves a floor that no noise causes."""
    rng = np.random.default_rng(1)
    fs, speed = FS, 20.0
    b, a = signal.butter(2, 1.5, fs=fs)  # a "suspension" low-pass for the frame channel

    def make(n: int) -> np.ndarray:
        e = rng.standard_normal(n + 20_000)
        y = signal.lfilter([1], [1, -0.999], signal.lfilter([1], [1, -0.999], e))[20_000:]
        acc = np.gradient(np.gradient(y))
        return np.array([np.gradient(y), acc, signal.lfilter(b, a, acc), y])

    orders = (-1, 0, 0, -2)
    runs = [make(14_000) for _ in range(12)]
    shaped = [np.array([shape(c, o, fs) for c, o in zip(r, orders)]) for r in runs]
    nothing = np.zeros(4)

    f, s = spectra(shaped, fs, 4096)
    back = np.abs(back_to_target(orders[3], f, fs, speed)) ** 2
    _, err = wiener(s, 3, (0, 1, 2), nothing)
    for name, j in bound(err * back, s[3, 3].real * back, f, fs, speed).items():
        assert j < 0.005, (name, j)

    f, s = spectra(runs, fs, 4096)
    _, err = wiener(s, 3, (1,), nothing)
    assert bound(err, s[3, 3].real, f, fs, speed)["D3"] > 0.05


def test_the_d3_fir_s_positive_lags_reach_only_the_past():
    """The D3 FIR's lags: positive ones reach the past only. A sensor that leads the target by
    10 s gives it back exactly to a window of positive lags; one that trails it by 10 s (more
    than a D3 period at 20 m/s) does not, but a two-sided window gives that back too. (The lag
    sign only: the zero-phase band-pass of the regressors is legitimate because the metric
    band-passes the estimate alike.)"""
    from wiener_bound import d3_fir

    rng = np.random.default_rng(5)
    fs, shift = FS, 500
    runs = []
    for _ in range(6):
        y = signal.lfilter([1.0], [1.0, -0.99], rng.standard_normal(20_000 + 2 * shift))
        runs.append(np.array([y[2 * shift:], y[:-2 * shift], y[shift:-shift]]))  # leads, trails, target
    past, both = list(range(0, 41)), list(range(-40, 41))
    assert d3_fir(runs, (0,), past, fs)[0] < 0.03
    assert d3_fir(runs, (1,), past, fs)[0] > 0.3
    assert d3_fir(runs, (1,), both, fs)[0] < 0.03


def test_the_causal_fir_is_the_kalman_filter_and_a_late_look_costs_the_prediction_error():
    """`lag_fir` against two textbook answers from the same Welch spectra: a causal window on the
    AR(1) signal in white noise reaches the steady-state Kalman filter's error (the Riccati
    equation's fixed point), a two-sided one the non-causal bound; a noise-free look 5 samples
    late leaves a causal filter the 5-step prediction error `sigma^2 sum_{i<5} a^{2i}` and a
    two-sided one nothing. A reversed lag convention would give the late look back exactly."""
    rng = np.random.default_rng(13)
    nperseg, late = 1024, 5
    runs = []
    for _ in range(8):
        y = ar1(rng, 200_016)
        runs.append(np.array([y[8 - late: 8 - late + 200_000], y[8: 8 + 200_000], y[8: 8 + 200_000]]))
    f, s = spectra(runs, FS, nperseg)
    one = np.ones_like(f)
    variance = SIGMA**2 / (1 - A**2)
    causal, both = range(0, 250), range(-250, 250)

    def mse(sensor: int, noise: float, lags: range) -> float:
        sxx = s[sensor: sensor + 1, sensor: sensor + 1] + noise
        return lag_fir(sxx, s[sensor: sensor + 1, 2], s[2, 2].real, one, nperseg, lags)[1] ** 2 * variance

    r = NOISE * FS / 2  # the noise's variance per sample
    p = 0.0
    for _ in range(200):
        prior = A**2 * p + SIGMA**2
        p = prior * r / (prior + r)
    assert abs(mse(1, NOISE, causal) / p - 1) < 0.05
    _, err = wiener(s, 2, (1,), np.array([0.0, NOISE, 0.0]))
    assert abs(mse(1, NOISE, both) / (np.sum(err) * (f[1] - f[0])) - 1) < 0.05
    assert mse(1, NOISE, both) < 0.8 * p

    predicted = SIGMA**2 * sum(A ** (2 * i) for i in range(late))
    assert abs(mse(0, 0.0, causal) / predicted - 1) < 0.05
    assert mse(0, 0.0, both) < 0.02 * predicted


def test_lag_fir_refuses_a_window_its_covariances_cannot_hold():
    s = np.ones((1, 1, 33))
    with pytest.raises(ValueError, match="span 40 samples"):
        lag_fir(s, s[0], s[0, 0], np.ones(33), 64, range(0, 41))

"""The method of `conicity_likelihood.py` (the Cramer-Rao bound and Whittle's likelihood behind
docs/learned-filter.md, "What the sensors tell of the conicity") against cases whose answer is
known: a closed-form Fisher information, a parameter that is only a level, and the maximum
likelihood's spread over simulated periodograms against the bound it should reach."""

from __future__ import annotations

import numpy as np
import pytest

from conicity_likelihood import cramer_rao, information, whittle_nll


def two_channels(c: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A source of density `u` (per bin) seen by a noise-free channel and, times `c`, by a second
    one: the cross-spectra and their derivative in `ln c`, as `[i, j, bin]`."""
    s = np.array([[u, c * u], [c * u, c * c * u]])
    ds = np.array([[0 * u, c * u], [c * u, 2 * c * c * u]])
    return s, ds


def test_information_has_its_closed_form():
    # With C = [[u, c u], [c u, c^2 u + N]]: tr((C^-1 dC)^2) = 2 c^2 u / N for ln c, 1 for the
    # level, and nothing shared (worked by hand: C^-1 dC_level = [[1, c], [0, 0]]).
    c, noise = 0.3, np.array([0.0, 0.02])
    u = np.array([0.5, 1.0, 2.0, 4.0])
    s, ds = two_channels(c, u)
    info = information(s.astype(complex), [ds.astype(complex)], noise)
    np.testing.assert_allclose(info[:, 0, 0], 2 * c * c * u / noise[1], rtol=1e-10)
    np.testing.assert_allclose(info[:, 1, 1], 1.0, rtol=1e-10)
    np.testing.assert_allclose(info[:, 0, 1], 0.0, atol=1e-9)
    expected = 1 / np.sqrt(3.0 * np.sum(2 * c * c * u / noise[1]))
    for level in ("known", "free"):
        assert cramer_rao(info, 3.0, level) == pytest.approx(expected, rel=1e-10)


def test_a_parameter_that_is_only_a_level_is_not_known_when_the_level_is_free():
    # One channel, S = c g: ln c moves S as its level does. Known level: one unit of information
    # per bin; free level: none left.
    g = np.array([[[1.0, 2.0, 0.5]]], complex)
    c = 0.2
    info = information(c * g, [c * g], np.array([0.0]))
    np.testing.assert_allclose(info, 1.0, rtol=1e-12)
    assert cramer_rao(info, 4.0, "known") == pytest.approx(1 / np.sqrt(12.0))
    with pytest.raises(np.linalg.LinAlgError):
        cramer_rao(info, 4.0, "free")


def test_the_maximum_likelihood_reaches_the_bound():
    # Periodograms drawn from C = level (two channels) + noise at c_true; the estimate of ln c
    # over a grid, the level profiled, over many records: unbiased, and spread as the bound says.
    rng = np.random.default_rng(5)
    c_true, noise = 0.1, np.array([0.0, 0.002])
    u = np.linspace(0.5, 1.5, 20)
    s, ds = two_channels(c_true, u)
    bound = cramer_rao(information(s.astype(complex), [ds.astype(complex)], noise), 1.0, "free")
    grid = np.log(c_true) + np.linspace(-0.3, 0.3, 61)
    models = np.array([np.moveaxis(two_channels(np.exp(g), u)[0], -1, 0) for g in grid]).astype(complex)
    levels = np.exp(np.linspace(-0.3, 0.3, 25))
    chol = np.linalg.cholesky(np.moveaxis(s, -1, 0) + np.diag(noise) + 1e-15 * np.eye(2))
    estimates = []
    for _ in range(200):
        z = (rng.standard_normal((len(u), 2)) + 1j * rng.standard_normal((len(u), 2))) / np.sqrt(2)
        x = np.einsum("nij,nj->ni", chol, z)
        p = np.einsum("ni,nj->nij", x.conj(), x)
        estimates.append(grid[np.argmin(whittle_nll(p, models, noise, levels))])
    err = np.array(estimates) - np.log(c_true)
    assert bound == pytest.approx(1 / np.sqrt(np.sum(2 * c_true**2 * u / noise[1])), rel=1e-9)
    assert abs(err.mean()) < 3 * bound / np.sqrt(len(err)) + 0.01
    assert err.std() == pytest.approx(bound, rel=0.2)

"""The predicted rate ρ: the iteration matrix M = I - (H̃ᵀWH̃)⁻¹H̃ᵀWH, its spectral radius, and
the Gauss-Newton iteration it predicts, on linear models where the prediction is exact."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.od.rate import iteration_matrix, rate_from_matrix

#: Agreement expected of two ways of computing the same 6x6 matrix.
ROUNDING = 1e-10


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261)


def _linear_problem(rng: np.random.Generator, m: int = 40, error: float = 0.3):
    h = rng.standard_normal((m, 6))
    h_approx = h + error * rng.standard_normal((m, 6))
    w = rng.uniform(0.5, 2.0, m)
    return h, h_approx, w


def test_iteration_matrix_is_the_textbook_formula(rng) -> None:
    h, h_approx, w = _linear_problem(rng)
    big_w = np.diag(w)
    expected = np.eye(6) - np.linalg.solve(h_approx.T @ big_w @ h_approx,
                                           h_approx.T @ big_w @ h)
    np.testing.assert_allclose(iteration_matrix(h, h_approx, w), expected, atol=ROUNDING)


def test_exact_partials_give_a_zero_rate(rng) -> None:
    h, _, w = _linear_problem(rng)
    assert rate_from_matrix(iteration_matrix(h, h, w)).rho < ROUNDING


def test_rate_does_not_depend_on_the_state_units(rng) -> None:
    """Scaling the state (km -> m, km/s -> mm/s) is a similarity transform of M."""
    h, h_approx, w = _linear_problem(rng)
    scale = np.array([1e3, 1e3, 1e3, 1e6, 1e6, 1e6])
    rho = rate_from_matrix(iteration_matrix(h, h_approx, w)).rho
    scaled = rate_from_matrix(iteration_matrix(h / scale, h_approx / scale, w)).rho
    assert scaled == pytest.approx(rho, rel=1e-9)


@pytest.mark.parametrize("error", [0.1, 0.6, 1.5])
def test_corrections_obey_the_iteration_matrix(rng, error) -> None:
    """A linear measurement model z = H x + ν solved by Gauss-Newton with H̃: the corrections
    obey δx_(k+1) = M δx_k exactly, whatever the noise (Dennis & Schnabel 1996, §10.2)."""
    h, h_approx, w = _linear_problem(rng, error=error)
    m = iteration_matrix(h, h_approx, w)
    x_true = rng.standard_normal(6)
    z = h @ x_true + 0.01 * rng.standard_normal(h.shape[0])
    x = x_true + rng.standard_normal(6)
    previous = first = None
    for _ in range(8):
        dx = np.linalg.solve(h_approx.T @ (w[:, None] * h_approx), h_approx.T @ (w * (z - h @ x)))
        if previous is None:
            first = np.abs(dx).max()
        else:  # rounding is relative to the state (x - x_true ~ first step), not to dx
            np.testing.assert_allclose(dx, m @ previous, rtol=0,
                                       atol=ROUNDING * max(first, np.abs(dx).max()))
        previous, x = dx, x + dx


@pytest.mark.parametrize("rho", [0.5, 0.9, 1.2])
def test_gauss_newton_contracts_by_rho(rng, rho) -> None:
    """With H = H̃ (I - M₀) the iteration matrix is M₀, built with the eigenvalues ρ, 0.3, ...
    in a random basis: the steps of Gauss-Newton shrink (or grow) by ρ per iteration."""
    basis = rng.standard_normal((6, 6))
    m0 = basis @ np.diag([rho, 0.3, 0.1, -0.2, 0.05, 0.0]) @ np.linalg.inv(basis)
    h_approx = rng.standard_normal((40, 6))
    h = h_approx @ (np.eye(6) - m0)
    w = rng.uniform(0.5, 2.0, 40)
    rate = rate_from_matrix(iteration_matrix(h, h_approx, w))
    assert rate.rho == pytest.approx(rho, rel=1e-9) and not rate.oscillating
    z = h @ rng.standard_normal(6) + 0.01 * rng.standard_normal(40)
    x = rng.standard_normal(6)
    norms = []
    for _ in range(30):
        dx = np.linalg.solve(h_approx.T @ (w[:, None] * h_approx), h_approx.T @ (w * (z - h @ x)))
        norms.append(np.linalg.norm(dx))
        x = x + dx
    observed = (norms[-1] / norms[-11]) ** 0.1
    assert observed == pytest.approx(rho, rel=1e-3)


def test_complex_pair_is_flagged_as_oscillating() -> None:
    rotation = 0.9 * np.array([[np.cos(1.0), -np.sin(1.0)], [np.sin(1.0), np.cos(1.0)]])
    m = np.zeros((6, 6))
    m[:2, :2] = rotation
    m[2, 2] = 0.5
    rate = rate_from_matrix(m)
    assert rate.rho == pytest.approx(0.9) and rate.oscillating
    assert abs(rate.eigenvalues[2]) == pytest.approx(0.5)
    assert not rate_from_matrix(np.diag([0.7, 0.2, 0, 0, 0, 0])).oscillating

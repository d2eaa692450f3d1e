"""The Gauss-Markov a priori of stochastic accelerations against its recursion and a sample.

References: the first-order Gauss-Markov sequence a_{k+1} = ρ_k a_k + w_k, w_k ~ N(0, σ²(1 −
ρ_k²)), is stationary with variance σ² and E[a_j a_k] = σ² Π ρ (Bierman 1977, §VI.4; Tapley,
Schutz & Born 2004, §4.9); with ρ_k = exp(−Δt̄_k/τ) the product is exp(−|t̄_j − t̄_k|/τ).
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.estimation.gauss_markov import StochasticAccelerations, gauss_markov_covariance

DAY_S = 86400.0
#: Uneven intervals (1, 2, 3, 1.5, 2 days) so that mid-time distances differ from starts'.
BOUNDS = (0.0, 1 * DAY_S, 3 * DAY_S, 6 * DAY_S, 7.5 * DAY_S, 9.5 * DAY_S)
SIGMA = 1e-12
TAU_S = 2 * DAY_S
#: Rounding of products of a few exponentials, relative to σ².
ROUNDING = 1e-14


def _spec(components=("R", "I", "C")) -> StochasticAccelerations:
    return StochasticAccelerations("ric", components, BOUNDS, SIGMA, TAU_S)


def _recursion_covariance(mid: np.ndarray, sigma: float, tau: float) -> np.ndarray:
    """E[a_j a_k] of the recursion, propagated as variances and covariances step by step:
    P_{k+1,k+1} = ρ² P_kk + σ²(1 − ρ²), P_{j,k+1} = ρ P_jk (independent of the formula)."""
    n = mid.size
    p = np.zeros((n, n))
    p[0, 0] = sigma**2
    for k in range(n - 1):
        rho = np.exp(-(mid[k + 1] - mid[k]) / tau)
        p[k + 1, k + 1] = rho**2 * p[k, k] + sigma**2 * (1 - rho**2)
        p[: k + 1, k + 1] = rho * p[: k + 1, k]
        p[k + 1, : k + 1] = p[: k + 1, k + 1]
    return p


def test_closed_form_equals_the_recursion_at_the_mid_times():
    spec = _spec()
    mid = spec.mid_s
    np.testing.assert_allclose(mid, [0.5, 2, 4.5, 6.75, 8.5] * np.array(DAY_S))
    closed = gauss_markov_covariance(mid, SIGMA, TAU_S)
    np.testing.assert_allclose(closed, _recursion_covariance(mid, SIGMA, TAU_S),
                               rtol=0, atol=ROUNDING * SIGMA**2)
    # e.g. intervals 1 and 3: mid-times 0.5 and 4.5 days apart by 4 days = 2 τ
    assert closed[0, 2] == pytest.approx(SIGMA**2 * np.exp(-2.0), rel=ROUNDING)


def test_the_parameter_covariance_is_the_time_covariance_per_component_and_none_between():
    spec = _spec()
    p = spec.covariance()
    names = spec.names
    assert names[:4] == ("acc_R_001", "acc_I_001", "acc_C_001", "acc_R_002")
    assert len(names) == 15 and p.shape == (15, 15)
    time = gauss_markov_covariance(spec.mid_s, SIGMA, TAU_S)
    for c in range(3):
        np.testing.assert_array_equal(p[c::3, c::3], time)
        for d in range(3):
            if d != c:
                assert np.all(p[c::3, d::3] == 0)
    # P⁻¹ by Cholesky: P P⁻¹ = I to the conditioning of P (~1e2 here)
    np.testing.assert_allclose(p @ spec.information(), np.eye(15), atol=1e-12)
    assert _spec(("C",)).names == tuple(f"acc_C_{k:03d}" for k in range(1, 6))


def test_a_long_simulated_sequence_has_the_covariance():
    """200,000 independent draws of the 5-interval recursion: each entry of the sample
    covariance within 5 standard errors, sd² = (P_ii P_jj + P_ij²)/N (Gaussian); 15 distinct
    entries, P(any |z| > 5) < 15 x 5.7e-7 = 1e-5 (Bonferroni)."""
    n_draws = 200_000
    mid = _spec().mid_s
    rng = np.random.default_rng(20261126)
    a = np.empty((n_draws, mid.size))
    a[:, 0] = SIGMA * rng.standard_normal(n_draws)
    for k in range(mid.size - 1):
        rho = np.exp(-(mid[k + 1] - mid[k]) / TAU_S)
        a[:, k + 1] = rho * a[:, k] + SIGMA * np.sqrt(1 - rho**2) * rng.standard_normal(n_draws)
    sample = a.T @ a / n_draws
    p = gauss_markov_covariance(mid, SIGMA, TAU_S)
    d = np.diag(p)
    z = np.abs(sample - p) / np.sqrt((np.outer(d, d) + p * p) / n_draws)
    assert np.max(z) < 5.0

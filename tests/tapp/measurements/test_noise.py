"""Fit-world and real-world noise: the rows of AᵀWA, AᵀWMWA exact against the dense M."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.estimation.factors import ar1_whitened, gram
from tapp.measurements.noise import (
    FitNoise,
    RealNoise,
    covariance_block,
    normal_matrices,
    pass_rows,
)

# Round-off of sums of ~100 products, relative to the natural scale sqrt(J_aa J_bb).
ROUND_OFF = 1e-12


def _pass(rng: np.random.Generator, n: int = 80, n_o: int = 7):
    # Irregular times (gaps of 5 to 60 s) exercise the variable decay of the recursion.
    t = np.cumsum(rng.uniform(5.0, 60.0, n))
    a = rng.normal(size=(n, n_o)) * np.logspace(-3, 3, n_o)
    weights = 1.0 / rng.uniform(0.5, 2.0, n) ** 2
    return a, t, weights


def _scaled_error(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.diag(b))
    return float(np.max(np.abs(a - b) / np.outer(d, d)))


def test_the_recursion_gives_the_cholesky_factor_of_the_exponential_kernel() -> None:
    """CᵀB from the O(n) recursion equals Lᵀ B with L = cholesky(K), K the dense kernel."""
    rng = np.random.default_rng(1)
    a, t, _ = _pass(rng, n=40)
    kernel = np.exp(-np.abs(t[:, None] - t[None, :]) / 120.0)
    lower = np.linalg.cholesky(kernel)
    np.testing.assert_allclose(ar1_whitened(a, t, 120.0), lower.T @ a,
                               rtol=1e-12, atol=1e-12 * np.abs(a).max())


@pytest.mark.parametrize("tau_s", [10.0, 300.0, 1e5])
def test_correlated_real_world_equals_the_dense_product(tau_s: float) -> None:
    rng = np.random.default_rng(7)
    a, t, w = _pass(rng)
    real = RealNoise("range_rate", 2e-6, 1e-6, 3e-6, tau_s)
    j_fit, j_real = normal_matrices(a, t, w, real)
    big_w = np.diag(w)
    m = covariance_block(t, real)
    assert _scaled_error(j_fit, a.T @ big_w @ a) < ROUND_OFF
    assert _scaled_error(j_real, a.T @ big_w @ m @ big_w @ a) < ROUND_OFF
    np.testing.assert_array_equal(j_real, j_real.T)  # symmetric as written, not only close


def test_real_world_equal_to_fit_world_and_scaled_white_noise() -> None:
    rng = np.random.default_rng(3)
    a, t, _ = _pass(rng)
    fit = FitNoise("range", 0.015)
    w = np.full(t.size, fit.weight)
    j_fit, j_same = normal_matrices(a, t, w, RealNoise.like(fit))
    assert _scaled_error(j_same, j_fit) < ROUND_OFF
    _, j_three = normal_matrices(a, t, w, RealNoise.like(fit, 3.0))
    assert _scaled_error(j_three, 9.0 * j_fit) < ROUND_OFF


def test_pass_bias_adds_the_rank_one_term() -> None:
    rng = np.random.default_rng(5)
    a, t, w = _pass(rng)
    _, white = normal_matrices(a, t, w, RealNoise("range", 0.01))
    _, biased = normal_matrices(a, t, w, RealNoise("range", 0.01, 0.004))
    s = (w[:, None] * a).sum(axis=0)
    assert _scaled_error(biased - white, 0.004**2 * np.outer(s, s)) < 1e-10


def test_parts_are_the_three_terms_of_the_dense_product_and_sum_to_it() -> None:
    rng = np.random.default_rng(11)
    a, t, w = _pass(rng)
    real = RealNoise("range_rate", 2e-6, 1e-6, 3e-6, 120.0)
    rows = pass_rows(a, t, w, real)
    parts = [gram(p) for p in rows.parts]
    same_fit, j_real = normal_matrices(a, t, w, real)
    assert [p.shape[0] for p in rows.parts] == [t.size, 1, t.size]
    np.testing.assert_array_equal(same_fit, gram(rows.fit))
    np.testing.assert_array_equal(sum(parts), j_real)  # one is the other, summed
    wa = w[:, None] * a
    ones = np.ones((t.size, t.size))
    kernel = np.exp(-np.abs(t[:, None] - t[None, :]) / real.tau_s)
    for part, m in zip(parts, (2e-6**2 * np.eye(t.size), 1e-6**2 * ones, 3e-6**2 * kernel),
                       strict=True):
        # on the scale of the whole AᵀWMWA: a part alone may be small on some parameter
        d = np.sqrt(np.diag(j_real))
        assert np.max(np.abs(part - wa.T @ m @ wa) / np.outer(d, d)) < ROUND_OFF
        np.testing.assert_array_equal(part, part.T)


def test_absent_noise_terms_have_no_rows() -> None:
    rng = np.random.default_rng(13)
    a, t, w = _pass(rng, n=20)
    rows = pass_rows(a, t, w, RealNoise("range", 0.01))
    assert [p.shape for p in rows.parts] == [(20, a.shape[1]), (0, a.shape[1]),
                                              (0, a.shape[1])]


@pytest.mark.parametrize(("make", "field"), [
    (lambda: FitNoise("range", 0.0), "sigma (range)"),
    (lambda: FitNoise("range", -1.0), "sigma (range)"),
    (lambda: FitNoise("phase", 1.0), "kind"),
    (lambda: RealNoise("range", -0.1), "sigma_white (range)"),
    (lambda: RealNoise("range", 0.1, 0.0, 0.1, 0.0), "tau_s (range)"),
])
def test_bad_noise_is_refused(make, field: str) -> None:
    with pytest.raises(InputError) as err:
        make()
    assert err.value.field == field

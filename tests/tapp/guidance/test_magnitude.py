"""|x| of a Gaussian x by Imhof's formula, against the χ² law and an independent quadrature."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, special, stats

from tapp.guidance.magnitude import norm_distribution, norm_mean, norm_percentile, quadratic_cdf

#: Imhof's integral is computed to an absolute 1e-10; percentiles by Brent to 1e-12 relative.
CDF = 1e-9


@pytest.mark.parametrize("k", [1, 2, 3])
@pytest.mark.parametrize("q", [1e-3, 0.3, 1.0, 2.5, 7.0, 30.0])
def test_equal_eigenvalues_give_the_chi_square_law(k, q):
    lam = np.full(k, 2.5)
    assert quadratic_cdf(q, lam) == pytest.approx(stats.chi2.cdf(q / 2.5, k), abs=CDF)


def _cdf_by_conditioning(q: float, lam: np.ndarray) -> float:
    """P(λ1 z1² + λ2 z2² ≤ q) = E_z2[F_χ²₁((q − λ2 z2²)/λ1)], by quadrature over z2."""
    edge = math.sqrt(q / lam[1])
    f = lambda z: stats.chi2.cdf((q - lam[1] * z * z) / lam[0], 1) * stats.norm.pdf(z)  # noqa: E731
    return integrate.quad(f, -edge, edge, epsabs=1e-13, epsrel=1e-13)[0]


@pytest.mark.parametrize("lam", [np.array([3.0, 0.2]), np.array([1.0, 1e-4])])
def test_unequal_eigenvalues_against_an_independent_quadrature(lam):
    for q in (0.05, 0.5, 2.0, 9.0):
        assert quadratic_cdf(q, lam) == pytest.approx(_cdf_by_conditioning(q, lam), abs=CDF)
    # the mean of |x| in two axes: √(2λ₁/π) E(m), E the complete elliptic integral of the
    # second kind, m = 1 − λ₂/λ₁
    mean = math.sqrt(2.0 * lam[0] / math.pi) * special.ellipe(1.0 - lam[1] / lam[0])
    assert norm_mean(lam) == pytest.approx(mean, rel=1e-10)
    r99 = norm_percentile(0.99, lam)
    assert _cdf_by_conditioning(r99 * r99, lam) == pytest.approx(0.99, abs=CDF)


def test_the_maxwell_distribution():
    """σ = 1 in three axes: E|x| = 2√(2/π), E|x|² = 3, percentiles √χ²₃."""
    d = norm_distribution(np.eye(3) * 4.0, (50.0, 90.0, 99.0))
    assert d.mean == pytest.approx(2.0 * 2.0 * math.sqrt(2.0 / math.pi), rel=1e-10)
    assert d.sigma == pytest.approx(2.0 * math.sqrt(3.0 - 8.0 / math.pi), rel=1e-9)
    for p, r in d.percentiles:
        assert r == pytest.approx(2.0 * math.sqrt(stats.chi2.ppf(p / 100, 3)), rel=1e-10)


def test_a_zero_covariance_gives_zero():
    d = norm_distribution(np.zeros((3, 3)), (99.0,))
    assert (d.mean, d.sigma, d.percentiles) == (0.0, 0.0, ((99.0, 0.0),))

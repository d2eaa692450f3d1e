"""Distribution of |x| and of quadratic forms xᵀEx for a zero-mean Gaussian x.

For x ~ N(0, C), Q = |x|² = Σ λ_i χ²₁ (independent), λ_i the eigenvalues of C (for a
quadratic form xᵀEx, the eigenvalues of E^{1/2} C E^{1/2}). Its CDF is computed by Imhof's
exact inversion formula (Imhof 1961, eq. 3.2, central case),

.. math::

    P(Q \\le q) = \\frac12 - \\frac1\\pi \\int_0^\\infty
        \\frac{\\sin\\theta(u)}{u\\,\\rho(u)}\\,du, \\quad
    \\theta(u) = \\tfrac12 \\sum_i \\arctan(\\lambda_i u) - \\tfrac12 q u, \\quad
    \\rho(u) = \\prod_i (1 + \\lambda_i^2 u^2)^{1/4},

integrated with :func:`scipy.integrate.quad` (absolute error below :data:`CDF_TOL`; the
oscillating tail as a Fourier integral, QUADPACK QAWF);
percentiles of |x| by Brent's method on it, bracketed by λ_max χ²₁ ≤ Q ≤ λ_max χ²_r
(r the number of non-zero λ). The mean of |x| is exact too, from
√q = (2√π)⁻¹ ∫₀^∞ (1 − e^{−tq}) t^{−3/2} dt and E[e^{−tQ}] = Π(1 + 2λ_i t)^{−1/2}, with
t = s²:

.. math:: E\\lvert x\\rvert = \\frac{1}{\\sqrt\\pi} \\int_0^\\infty
    \\Big(1 - \\prod_i (1 + 2\\lambda_i s^2)^{-1/2}\\Big)\\,s^{-2}\\,ds,

and E|x|² = Σλ_i gives its σ. Eigenvalues are scaled by λ_max before integrating.

References
----------
J. P. Imhof, "Computing the distribution of quadratic forms in normal variables",
Biometrika 48 (1961) 419-426.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize, stats

#: Absolute error target of the CDF integral.
CDF_TOL = 1e-10
#: Eigenvalues below this fraction of the largest are zero (rank of a singular covariance).
ZERO_EIGENVALUE = 1e-14
_QUAD_LIMIT = 500


def eigenvalues(C: np.ndarray) -> np.ndarray:
    """Return the non-zero eigenvalues of a symmetric PSD matrix (rounding negatives
    dropped), descending."""
    w = np.linalg.eigvalsh(0.5 * (C + C.T))[::-1]
    if w.size == 0 or w[0] <= 0:
        return np.zeros(0)
    return w[w > ZERO_EIGENVALUE * w[0]]


def quadratic_cdf(q: float, lam: np.ndarray) -> float:
    """Return P(Σ λ_i χ²₁ ≤ q) by Imhof's formula (module docstring); λ_i > 0.

    The integral runs over [0, 1] (in units of 1/λ_max) as it stands and over [1, ∞) as two
    Fourier integrals (QUADPACK's QAWF), with sin θ = sin φ cos(qu/2) − cos φ sin(qu/2),
    φ = ½ Σ arctan(λ_i u): the slowly decaying oscillating tail is what QAWF is for.
    """
    if lam.size == 0:
        return 1.0 if q >= 0 else 0.0
    if q <= 0:
        return 0.0
    top = float(lam.max())
    w, x = lam / top, q / top

    def phi(u: float) -> float:
        return 0.5 * float(np.arctan(w * u).sum())

    def rho_u(u: float) -> float:
        return u * float(np.prod((1.0 + (w * u) ** 2) ** 0.25))

    def whole(u: float) -> float:
        if u == 0.0:  # the limit u -> 0: (Σλ − q)/2
            return 0.5 * (float(w.sum()) - x)
        return math.sin(phi(u) - 0.5 * x * u) / rho_u(u)

    head, _ = integrate.quad(whole, 0.0, 1.0, limit=_QUAD_LIMIT, epsabs=CDF_TOL / 4,
                             epsrel=0.0)
    tail_cos, _ = integrate.quad(lambda u: math.sin(phi(u)) / rho_u(u), 1.0, np.inf,
                                 weight="cos", wvar=0.5 * x, limlst=_QUAD_LIMIT,
                                 epsabs=CDF_TOL / 4)
    tail_sin, _ = integrate.quad(lambda u: math.cos(phi(u)) / rho_u(u), 1.0, np.inf,
                                 weight="sin", wvar=0.5 * x, limlst=_QUAD_LIMIT,
                                 epsabs=CDF_TOL / 4)
    value = head + tail_cos - tail_sin
    return min(1.0, max(0.0, 0.5 - value / math.pi))


def norm_percentile(p: float, lam: np.ndarray) -> float:
    """Return r with P(|x| ≤ r) = p, 0 < p < 1, for |x|² = Σ λ_i χ²₁ (module docstring)."""
    if lam.size == 0:
        return 0.0
    top = float(lam.max())
    lo = math.sqrt(top * stats.chi2.ppf(p, 1))
    hi = math.sqrt(top * stats.chi2.ppf(p, lam.size))
    if hi - lo <= 1e-12 * hi:  # one non-zero eigenvalue, or all equal: exact
        return hi
    return optimize.brentq(lambda r: quadratic_cdf(r * r, lam) - p, lo * (1 - 1e-9),
                           hi * (1 + 1e-9), xtol=1e-12 * hi, rtol=1e-12)


def norm_mean(lam: np.ndarray) -> float:
    """Return E|x| for |x|² = Σ λ_i χ²₁ (module docstring)."""
    if lam.size == 0:
        return 0.0
    top = float(lam.max())
    w = lam / top

    def integrand(s: float) -> float:
        if s == 0.0:
            return float(w.sum())
        return (1.0 - np.prod((1.0 + 2.0 * w * s * s) ** -0.5)) / (s * s)

    value, _ = integrate.quad(integrand, 0.0, np.inf, limit=_QUAD_LIMIT, epsabs=1e-12,
                              epsrel=1e-12)
    return math.sqrt(top) * value / math.sqrt(math.pi)


@dataclass(frozen=True, slots=True)
class NormDistribution:
    """Mean, σ and percentiles of |x| for a zero-mean Gaussian x (units of x).

    Attributes
    ----------
    mean, sigma : E|x| and √(E|x|² − (E|x|)²).
    percentiles : (p, r) pairs, p in percent: P(|x| ≤ r) = p/100.
    """

    mean: float
    sigma: float
    percentiles: tuple[tuple[float, float], ...]


def norm_distribution(C: np.ndarray, percents: tuple[float, ...]) -> NormDistribution:
    """Return the distribution of |x|, x ~ N(0, C) (module docstring).

    >>> d = norm_distribution(np.diag([1.0, 1.0, 1.0]), (50.0,))  # Maxwell, σ = 1
    >>> round(d.mean, 9), round(d.percentiles[0][1], 9)  # 2√(2/π); √(χ²₃ median)
    (1.595769122, 1.538172254)
    """
    lam = eigenvalues(C)
    mean = norm_mean(lam)
    sigma = math.sqrt(max(float(lam.sum()) - mean * mean, 0.0))
    return NormDistribution(mean, sigma, tuple((p, norm_percentile(p / 100.0, lam))
                                               for p in percents))


__all__ = ["CDF_TOL", "NormDistribution", "eigenvalues", "norm_distribution", "norm_mean",
           "norm_percentile", "quadratic_cdf"]

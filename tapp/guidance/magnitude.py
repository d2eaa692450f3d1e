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
below x = q/λ_max = :data:`SERIES_BELOW` (a corridor far smaller than the miss), where
QAWF's cycles grow as 1/x and the integral came out wrong (0.257 for a CDF of 3.2e-7, with an
IntegrationWarning), by Ruben's series of χ² distributions instead (Ruben 1962, §4;
Kotz, Johnson & Boyd 1967),

.. math::

    P(Q \\le q) = \\sum_{k \\ge 0} a_k\\,P(\\chi^2_{r+2k} \\le q/\\beta), \\quad
    a_0 = \\prod_i (\\beta/\\lambda_i)^{1/2}, \\quad
    a_k = \\frac{1}{2k} \\sum_{j=0}^{k-1} G_{k-j}\\,a_j, \\quad
    G_m = \\sum_i (1 - \\beta/\\lambda_i)^m,

β = λ_min, all a_k >= 0 summing to 1, so that the terms left out add at most
(1 − Σ a_k) P(χ²_{r+2K} ≤ q/β); summed until that is below :data:`CDF_TOL` / 10;
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
H. Ruben, "Probability content of regions under spherical normal distributions, IV: the
distribution of homogeneous and non-homogeneous quadratic functions of normal variables",
Ann. Math. Statist. 33 (1962) 542-570.
S. Kotz, N. L. Johnson, D. W. Boyd, "Series representations of distributions of quadratic
forms in normal variables. I. Central case", Ann. Math. Statist. 38 (1967) 823-837.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize, special, stats

#: Absolute error target of the CDF integral.
CDF_TOL = 1e-10
#: Eigenvalues below this fraction of the largest are zero (rank of a singular covariance).
ZERO_EIGENVALUE = 1e-14
_QUAD_LIMIT = 500
#: Below this q/λ_max the CDF is Ruben's series (module docstring): Imhof's integral is right
#: to 1e-13 at 1e-5 and fails from 6e-7 on (a corridor 1e-3 of the miss σ).
SERIES_BELOW = 1e-4
#: Most terms of Ruben's series; with q/λ_min = 2000 it converges in ~1,300.
SERIES_TERMS = 5000


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
    if x < SERIES_BELOW:
        series = _ruben_cdf(q, lam)
        if series is not None:
            return series

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


def _ruben_cdf(q: float, lam: np.ndarray) -> float | None:
    """Return P(Σ λ_i χ²₁ ≤ q) by Ruben's series (module docstring), or None when it has not
    converged within :data:`SERIES_TERMS` terms (eigenvalues spread so widely that q/λ_min is
    in the thousands)."""
    beta = float(lam.min())
    y = q / beta
    r = lam.size
    ratio = 1.0 - beta / lam
    a = np.zeros(SERIES_TERMS + 1)
    g = np.zeros(SERIES_TERMS + 1)
    a[0] = float(np.prod(np.sqrt(beta / lam)))
    total, held = a[0] * special.gammainc(0.5 * r, 0.5 * y), a[0]
    for k in range(1, SERIES_TERMS + 1):
        g[k] = float(np.sum(ratio**k))
        a[k] = float(g[k:0:-1] @ a[:k]) / (2 * k)   # Σ_j G_{k−j} a_j, j = 0..k-1
        f = special.gammainc(0.5 * r + k, 0.5 * y)
        total += a[k] * f
        held += a[k]
        if max(0.0, 1.0 - held) * f < 0.1 * CDF_TOL:
            return min(1.0, float(total))
    return None


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


__all__ = ["CDF_TOL", "SERIES_BELOW", "NormDistribution", "eigenvalues", "norm_distribution",
           "norm_mean", "norm_percentile", "quadratic_cdf"]

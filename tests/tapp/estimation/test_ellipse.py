"""Error ellipses (tapp.estimation.ellipse) against the closed-form 2 x 2 eigen solution and a
Monte Carlo of 2-D Gaussian samples.

Closed form (any 2 x 2 symmetric [[a, b], [b, c]]): λ± = (a + c)/2 ± √(((a − c)/2)² + b²),
major axis at θ = ½ atan2(2b, a − c) from the first axis towards the second. Probability
inside the k-σ ellipse: 1 − exp(−k²/2) (χ² with 2 degrees of freedom; Papoulis 1991 §6-4).
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.estimation.ellipse import error_ellipse, probability_inside

#: Eigenvalues of a 2 x 2 by eigh vs the closed form: a few ε relative.
ROUNDING = 1e-12


def _closed_form(cov: np.ndarray) -> tuple[float, float, float]:
    a, b, c = cov[0, 0], cov[0, 1], cov[1, 1]
    mean, half = 0.5 * (a + c), np.hypot(0.5 * (a - c), b)
    return np.sqrt(mean + half), np.sqrt(max(mean - half, 0.0)), 0.5 * np.arctan2(2 * b, a - c)


def _random_covariances(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(2026)
    out = []
    for _ in range(n):
        m = rng.normal(size=(2, 2)) * rng.uniform(0.01, 100.0, size=2)
        out.append(m @ m.T)
    return out


@pytest.mark.parametrize("cov", _random_covariances(20))
def test_axes_and_angle_match_the_closed_form(cov):
    major, minor, theta = _closed_form(cov)
    ell = error_ellipse(cov)
    assert ell.semi_major == pytest.approx(major, rel=ROUNDING)
    assert ell.semi_minor == pytest.approx(minor, rel=1e-9, abs=ROUNDING * major)
    # angles of an axis are defined modulo π; the kernel wraps to (−90°, 90°], as atan2/2 does
    assert -np.pi / 2 < ell.angle_rad <= np.pi / 2
    assert ell.angle_rad == pytest.approx(theta, abs=1e-9)


@pytest.mark.parametrize("cov, angle_deg", [
    (np.diag([4.0, 1.0]), 0.0),        # major along the first axis (T)
    (np.diag([1.0, 4.0]), 90.0),       # along the second (R)
    (np.array([[2.0, 1.0], [1.0, 2.0]]), 45.0),
    (np.array([[2.0, -1.0], [-1.0, 2.0]]), -45.0),
    (np.eye(2) * 3.0, 0.0),            # a circle: no orientation, 0 by convention
])
def test_special_orientations(cov, angle_deg):
    assert error_ellipse(cov).angle_deg == pytest.approx(angle_deg, abs=1e-9)


def test_contour_points_lie_on_the_k_sigma_contour():
    cov = np.array([[9.0, -2.5], [-2.5, 1.5]])
    pts = error_ellipse(cov).points(3.0, 73)
    q = np.einsum("ni,ij,nj->n", pts, np.linalg.inv(cov), pts)
    np.testing.assert_allclose(q, 9.0, rtol=1e-12)
    np.testing.assert_allclose(pts[0], pts[-1], atol=1e-12)


@pytest.mark.parametrize("k", [1.0, 3.0])
def test_monte_carlo_fraction_inside_the_ellipse(k):
    """Fraction of N = 200,000 Gaussian samples inside the k-σ ellipse, tested with the
    ellipse's own axes and angle (not C⁻¹): 1 − e^(−k²/2), within 5 binomial σ
    √(p(1 − p)/N) (1σ: 0.0055; 3σ: 0.0012): a false alarm once in 1.7 million runs."""
    cov = np.array([[0.0324, 0.0123], [0.0123, 0.0090]])  # km², a B-plane-like tilted ellipse
    n = 200_000
    x = np.random.default_rng(30).multivariate_normal([0.0, 0.0], cov, size=n)
    ell = error_ellipse(cov)
    c, s = np.cos(ell.angle_rad), np.sin(ell.angle_rad)
    u, v = c * x[:, 0] + s * x[:, 1], -s * x[:, 0] + c * x[:, 1]
    inside = np.mean((u / ell.semi_major) ** 2 + (v / ell.semi_minor) ** 2 <= k * k)
    p = probability_inside(k)
    assert p == pytest.approx({1.0: 0.3935, 3.0: 0.9889}[k], abs=5e-5)
    assert inside == pytest.approx(p, abs=5.0 * np.sqrt(p * (1 - p) / n))

"""Error ellipses of a 2-D Gaussian: semi-axes and orientation from a 2 x 2 covariance.

For a zero-mean Gaussian x ∈ R² of covariance C with eigenvalues λ₁ >= λ₂ and unit
eigenvectors e₁, e₂, the k-σ ellipse is the contour xᵀ C⁻¹ x = k²: semi-axes k √λ₁ and
k √λ₂ along e₁ and e₂. The probability inside it is the χ² (2 degrees of freedom) mass
below k², 1 − exp(−k²/2): 0.3935 for 1σ, 0.8647 for 2σ, 0.9889 for 3σ (not the 1-D 0.6827
and 0.9973).

The orientation is the angle of e₁ measured from the first axis towards the second, wrapped
to (−90°, 90°]; in the B-plane, with (B·T, B·R) as the axes, from T towards R. A circular
ellipse (λ₁ = λ₂) has no orientation: its angle is 0.

Reference: A. Papoulis, *Probability, Random Variables and Stochastic Processes*, 3rd ed.
(1991), §6-4 (the bivariate normal and its ellipses of concentration).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike


def probability_inside(k: float) -> float:
    """Return 1 − exp(−k²/2): the probability inside the k-σ ellipse of a 2-D Gaussian."""
    return float(-np.expm1(-0.5 * k * k))


@dataclass(frozen=True, slots=True)
class ErrorEllipse:
    """The 1σ ellipse of a 2 x 2 covariance (the k-σ one is k times larger).

    Attributes
    ----------
    semi_major, semi_minor : 1σ semi-axes √λ₁ >= √λ₂, in the unit of the components.
    angle_rad : orientation of the major axis from the first axis towards the second,
        (−π/2, π/2].
    """

    semi_major: float
    semi_minor: float
    angle_rad: float

    @property
    def angle_deg(self) -> float:
        """The orientation in degrees, (−90°, 90°]."""
        return float(np.degrees(self.angle_rad))

    def points(self, k: float = 1.0, n: int = 181) -> np.ndarray:
        """Return (n, 2) points of the k-σ contour, closed (first point = last point)."""
        phi = np.linspace(0.0, 2.0 * np.pi, n)
        c, s = np.cos(self.angle_rad), np.sin(self.angle_rad)
        a, b = k * self.semi_major * np.cos(phi), k * self.semi_minor * np.sin(phi)
        return np.stack([c * a - s * b, s * a + c * b], axis=-1)


def error_ellipse(cov: ArrayLike) -> ErrorEllipse:
    """Return the 1σ error ellipse of a 2 x 2 covariance (module docstring).

    Parameters
    ----------
    cov : (2, 2) symmetric positive semi-definite covariance of (x₁, x₂); its symmetric
        part is used, and negative rounding of an eigenvalue is clipped to 0.
    """
    c = np.asarray(cov, dtype=float)
    w, v = np.linalg.eigh(0.5 * (c + c.T))
    w = np.maximum(w, 0.0)
    major = v[:, 1] if v[0, 1] > 0 or (v[0, 1] == 0 and v[1, 1] > 0) else -v[:, 1]
    # e₁ taken with a positive first component (or (0, 1)): its angle lies in (−π/2, π/2]
    angle = float(np.arctan2(major[1], major[0])) if w[1] > w[0] else 0.0
    return ErrorEllipse(float(np.sqrt(w[1])), float(np.sqrt(w[0])), angle)


__all__ = ["ErrorEllipse", "error_ellipse", "probability_inside"]

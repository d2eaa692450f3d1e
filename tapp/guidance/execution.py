"""Manoeuvre execution errors: a Gates-type model, sampled and in second moments.

The applied velocity change is Δv_a = Δv + ε, with Δv the commanded correction (km/s,
inertial frame of the tape) and, after Gates (1963), the execution error

.. math::

    \\varepsilon = \\sigma_p\\,n\\,\\Delta v
        + \\sigma_\\theta \\lvert\\Delta v\\rvert\\,(I - \\hat u \\hat u^T)\\,g
        + \\sigma_f\\,f, \\qquad \\hat u = \\Delta v / \\lvert\\Delta v\\rvert,

with n ~ N(0, 1), g, f ~ N(0, I₃) independent:

- a magnitude error proportional to |Δv| (σ_p, dimensionless), along Δv;
- a pointing error (σ_θ, rad, small-angle) on each of the two axes perpendicular to Δv,
  proportional to |Δv|: the projection (I − ûûᵀ)g has covariance I − ûûᵀ, i.e. two
  independent unit normals on any orthonormal pair of axes perpendicular to Δv;
- a fixed part (σ_f, km/s per axis, isotropic), independent of |Δv| (shut-off transients,
  attitude-control coupling).

This is Gates' model with his fixed magnitude and fixed pointing errors merged into one
isotropic fixed vector. Given Δv the error has zero mean and the covariance
σ_p² ΔvΔvᵀ + σ_θ² (|Δv|² I − ΔvΔvᵀ) + σ_f² I, so over zero-mean corrections of covariance
P = E[ΔvΔvᵀ] its second moment is exactly

.. math::

    E[\\varepsilon\\varepsilon^T] = \\sigma_p^2 P + \\sigma_\\theta^2
        (\\operatorname{tr}P\\,I - P) + \\sigma_f^2 I,

and ε is uncorrelated with anything Δv is a function of (its conditional mean is zero).

References
----------
C. R. Gates, "A simplified model of midcourse maneuver execution errors", JPL Technical
Report 32-504 (1963).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Standard normals a sample draws per manoeuvre: n (1), g (3), f (3).
NORMALS_PER_MANOEUVRE = 7


@dataclass(frozen=True, slots=True)
class ExecutionErrors:
    """1σ execution errors of every manoeuvre (module docstring).

    Attributes
    ----------
    sigma_proportional : σ_p, magnitude error as a fraction of |Δv|, 0 <= σ_p < 1.
    sigma_pointing_rad : σ_θ, pointing error per perpendicular axis, rad, >= 0.
    sigma_fixed_km_s : σ_f, fixed error per axis, km/s, >= 0.
    """

    sigma_proportional: float = 0.0
    sigma_pointing_rad: float = 0.0
    sigma_fixed_km_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sigma_proportional", "sigma_pointing_rad", "sigma_fixed_km_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name}: expected a finite number >= 0 (got {value!r})")
        if self.sigma_proportional >= 1:
            raise ValueError(f"sigma_proportional: expected a fraction < 1 (got "
                             f"{self.sigma_proportional!r})")


def sample_errors(dv_km_s: np.ndarray, normals: np.ndarray, errors: ExecutionErrors
                  ) -> np.ndarray:
    """Return execution errors ε (n, 3), km/s, of commanded corrections (module docstring).

    Parameters
    ----------
    dv_km_s : (n, 3) commanded corrections Δv, km/s.
    normals : (n, 7) independent standard normals: n, then g (3), then f (3).
    errors : the 1σ values.

    A zero Δv gets no proportional or pointing error. Row i of the result depends on row i
    of the inputs only (element-wise operations), whatever n is.
    """
    magnitude = np.sqrt(np.einsum("si,si->s", dv_km_s, dv_km_s))
    g = normals[:, 1:4]
    along = np.einsum("si,si->s", g, dv_km_s)
    safe = np.where(magnitude > 0, magnitude, 1.0)
    # σ_θ |Δv| (I − ûûᵀ) g = σ_θ (|Δv| g − (g·Δv) Δv / |Δv|)
    pointing = magnitude[:, None] * g - (along / safe)[:, None] * dv_km_s
    return (errors.sigma_proportional * normals[:, :1] * dv_km_s
            + errors.sigma_pointing_rad * pointing
            + errors.sigma_fixed_km_s * normals[:, 4:7])


def error_second_moment(P: np.ndarray, errors: ExecutionErrors) -> np.ndarray:
    """Return E[εεᵀ] (3, 3), km²/s², for zero-mean corrections of covariance ``P``, km²/s².

    .. math:: E[\\varepsilon\\varepsilon^T] = \\sigma_p^2 P
        + \\sigma_\\theta^2 (\\operatorname{tr}P\\,I - P) + \\sigma_f^2 I

    >>> error_second_moment(np.diag([4.0, 1.0, 0.0]), ExecutionErrors(0.5, 0.1, 0.0))
    array([[1.01, 0.  , 0.  ],
           [0.  , 0.29, 0.  ],
           [0.  , 0.  , 0.05]])
    """
    eye = np.eye(3)
    sp, st, sf = errors.sigma_proportional, errors.sigma_pointing_rad, errors.sigma_fixed_km_s
    return sp**2 * P + st**2 * (np.trace(P) * eye - P) + sf**2 * eye


__all__ = ["NORMALS_PER_MANOEUVRE", "ExecutionErrors", "error_second_moment", "sample_errors"]

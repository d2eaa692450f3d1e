"""Manoeuvre execution errors of TAPP II: Gates' model with the fixed errors isotropic.

The applied velocity change is Δv_a = Δv + ε, with Δv the commanded correction (km/s,
inertial frame of the tape) and ε the execution error of Gates (1963) in the four components
of :mod:`tapp.dynamics.gates` (the code TAPP I's manoeuvres use too):

- a magnitude error proportional to |Δv| (σ_p, dimensionless), along Δv;
- a pointing error (σ_θ, rad, small-angle) on each of the two axes perpendicular to Δv,
  proportional to |Δv|;
- a fixed magnitude error and a fixed pointing error, both σ_f (km/s): one isotropic fixed
  vector σ_f f, independent of |Δv| (shut-off transients, attitude-control coupling).

So the guidance file's three σ's are Gates' four with σ₂ = σ₄ = σ_f (:attr:`ExecutionErrors.
gates`). Given Δv the error has zero mean and the covariance
σ_p² ΔvΔvᵀ + σ_θ² (|Δv|² I − ΔvΔvᵀ) + σ_f² I, so over zero-mean corrections of covariance
P = E[ΔvΔvᵀ] its second moment is exactly

.. math::

    E[\\varepsilon\\varepsilon^T] = \\sigma_p^2 P + \\sigma_\\theta^2
        (\\operatorname{tr}P\\,I - P) + \\sigma_f^2 I,

and ε is uncorrelated with anything Δv is a function of (its conditional mean is zero). Two
different fixed σ's would make that moment depend on the distribution of Δv, not only on P
(:meth:`tapp.dynamics.gates.GatesErrors.second_moment`), and TAPP II's linear covariance would
no longer be exact: the guidance file keeps them equal.

References
----------
C. R. Gates, "A simplified model of midcourse maneuver execution errors", JPL Technical
Report 32-504 (1963).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.dynamics.gates import NORMALS_PER_SAMPLE, GatesErrors

#: Standard normals a sample draws per manoeuvre: n (1), g (3), f (3).
NORMALS_PER_MANOEUVRE = NORMALS_PER_SAMPLE


@dataclass(frozen=True, slots=True)
class ExecutionErrors:
    """1σ execution errors of every manoeuvre (module docstring).

    Attributes
    ----------
    sigma_proportional : σ_p, magnitude error as a fraction of |Δv|, 0 <= σ_p < 1.
    sigma_pointing_rad : σ_θ, pointing error per perpendicular axis, rad, 0 <= σ_θ <= 0.2.
    sigma_fixed_km_s : σ_f, fixed error per axis, km/s, 0 <= σ_f <= 1.

    Raises
    ------
    tapp.dynamics.gates.GatesRangeError
        A σ out of its range (the ranges of :class:`~tapp.dynamics.gates.GatesErrors`).
    """

    sigma_proportional: float = 0.0
    sigma_pointing_rad: float = 0.0
    sigma_fixed_km_s: float = 0.0

    def __post_init__(self) -> None:
        self.gates  # noqa: B018  (checks the ranges)

    @property
    def gates(self) -> GatesErrors:
        """Gates' four σ's: (σ_p, σ_f, σ_θ, σ_f)."""
        return GatesErrors(self.sigma_proportional, self.sigma_fixed_km_s,
                           self.sigma_pointing_rad, self.sigma_fixed_km_s)


def sample_errors(dv_km_s: np.ndarray, normals: np.ndarray, errors: ExecutionErrors
                  ) -> np.ndarray:
    """Return execution errors ε (n, 3), km/s, of commanded corrections (module docstring).

    A zero Δv gets no proportional or pointing error. Row i of the result depends on row i
    of the inputs only (element-wise operations), whatever n is.

    Parameters
    ----------
    dv_km_s : (n, 3) commanded corrections Δv, km/s.
    normals : (n, 7) independent standard normals: n, then g (3), then f (3)
        (:meth:`tapp.dynamics.gates.GatesErrors.sample`).
    errors : the 1σ values.
    """
    return errors.gates.sample(dv_km_s, normals)


def proportional_errors(dv_km_s: np.ndarray, normals: np.ndarray, errors: ExecutionErrors
                        ) -> np.ndarray:
    """Return the proportional part p (3, n), km/s, of the execution errors of corrections Δv
    (3, n), km/s, one sample a column, from 3 independent standard normals h (3, n) each.

    .. math:: p = \\sigma_\\theta \\lvert\\Delta v\\rvert\\, h + (\\sigma_p
        - \\sigma_\\theta)\\,\\frac{\\Delta v\\cdot h}{\\lvert\\Delta v\\rvert}
        \\,\\Delta v

    (the quotient taken as 0 for Δv = 0): given Δv, N(0, |Δv|² (σ_p² ûûᵀ + σ_θ² (I − ûûᵀ))),
    û = Δv/|Δv|, the law of Gates' error (module docstring) without its fixed part σ_f f,
    which TAPP II's Monte Carlo draws with the Gaussian part of its outcomes
    (:mod:`tapp.guidance.montecarlo`). Element-wise NumPy operations on rows of n samples,
    with no reduction: column i of the result is the same IEEE arithmetic on column i of the
    inputs whatever n and the memory layout.
    """
    size = np.sqrt(dv_km_s[0] * dv_km_s[0] + dv_km_s[1] * dv_km_s[1]
                   + dv_km_s[2] * dv_km_s[2])
    along = dv_km_s[0] * normals[0] + dv_km_s[1] * normals[1] + dv_km_s[2] * normals[2]
    np.divide(along, size, out=along, where=size > 0)
    s_p, s_t = errors.sigma_proportional, errors.sigma_pointing_rad
    return (s_t * size) * normals + ((s_p - s_t) * along) * dv_km_s


def error_second_moment(P: np.ndarray, errors: ExecutionErrors) -> np.ndarray:
    """Return E[εεᵀ] (3, 3), km²/s², for zero-mean corrections of covariance ``P``, km²/s².

    .. math:: E[\\varepsilon\\varepsilon^T] = \\sigma_p^2 P
        + \\sigma_\\theta^2 (\\operatorname{tr}P\\,I - P) + \\sigma_f^2 I

    >>> error_second_moment(np.diag([4.0, 1.0, 0.0]), ExecutionErrors(0.5, 0.1, 0.0))
    array([[1.01, 0.  , 0.  ],
           [0.  , 0.29, 0.  ],
           [0.  , 0.  , 0.05]])
    """
    return errors.gates.second_moment(P)


__all__ = ["NORMALS_PER_MANOEUVRE", "ExecutionErrors", "error_second_moment",
           "proportional_errors", "sample_errors"]

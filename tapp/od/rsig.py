"""The error-growth signature R(t) of the approximate-STM study.

From P(t) = Φ P(0) Φᵀ with P(0) = I, the square root of the trace of the position block,

.. math::
    R(t) = \\sqrt{\\sum_{i=1}^{3}\\sum_{j=1}^{6} \\varphi_{ij}(t, t_0)^2},

is a statistical measure of the position error growth (study brief, "The error-growth
signature R"). R has mixed units (it sums km/km and km/(km/s) entries) exactly as in the study.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.dynamics import Propagator
from tapp.frames.orientation import EarthOrientation


@dataclass(frozen=True, slots=True)
class RSignature:
    """R(t) on a grid: ``t_s`` (N,) seconds from the epoch, ``r`` (N,)."""

    t_s: np.ndarray
    r: np.ndarray


def r_of_stm(stm: np.ndarray) -> np.ndarray:
    """Return R = sqrt(Σ_{i<3, j<6} Φ_ij²) for STMs (..., 6, 6)."""
    return np.sqrt(np.sum(np.asarray(stm)[..., :3, :] ** 2, axis=(-2, -1)))


def r_signature(propagator: Propagator, x0: np.ndarray, t_s: np.ndarray,
                orientation: EarthOrientation) -> RSignature:
    """Propagate with the propagator's (state, variational) pair, the field oriented by
    ``orientation``, and return R(t)."""
    traj = propagator.propagate(x0, t_s, orientation=orientation)
    return RSignature(traj.t_s, r_of_stm(traj.stm))

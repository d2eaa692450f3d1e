"""Radial / in-track / cross-track (RIC) axes of a state, and covariances rotated into them.

The RIC axes of a state (r, v) in an inertial frame are

.. math::

    \\hat R = \\frac{r}{|r|}, \\qquad \\hat C = \\frac{r \\times v}{|r \\times v|}, \\qquad
    \\hat I = \\hat C \\times \\hat R,

a right-handed triad (R, I, C): R along the radius, C along the orbit normal (the angular
momentum), I in the orbit plane, ahead, along the velocity for a circular orbit. The matrix T
whose rows are R̂, Î, Ĉ takes inertial components to RIC components, δr_ric = T δr.

Velocity components are the projections of the inertial velocity error on the same
instantaneous axes, δv_ric = T δv, *without* the ω × r term of a frame that rotates with the
orbit (ω = h / r²): so the 6 x 6 rotation is blockdiag(T, T), orthogonal, and it preserves
the trace of the position and of the velocity blocks of a covariance. This is the usual choice
for reporting orbit determination covariances (Vallado 2013, §3.3 "RSW" axes; Vallado,
"Covariance transformations for satellite flight dynamics operations", AAS 03-526 (2003),
who treats the ω × r term as an option).

Shapes broadcast over leading axes: positions and velocities (..., 3), rotations (..., 3, 3)
or (..., 6, 6). Units: whatever the state's (km, km/s); the rotation is dimensionless.

References
----------
D. A. Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed. (2013), §3.3.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from tapp.errors import InputError

#: Smallest |r × v| / (|r| |v|) (the sine of the flight-path angle's complement) for which the
#: orbit normal, hence C and I, is defined; below it the state is rectilinear to rounding.
RECTILINEAR_TOL = 1e-12

#: Names of the RIC components of a state (position, then velocity), with their units.
RIC_NAMES = ("R_km", "I_km", "C_km", "vR_km_s", "vI_km_s", "vC_km_s")


def ric_axes(r_km: ArrayLike, v_km_s: ArrayLike) -> np.ndarray:
    """Return T, (..., 3, 3): rows the unit vectors R̂, Î, Ĉ of a state, in its frame.

    Parameters
    ----------
    r_km : (..., 3) position, km (any unit: only its direction is used).
    v_km_s : (..., 3) velocity, km/s.

    Raises
    ------
    InputError
        A zero position or a rectilinear state (r × v = 0: no orbit plane), beyond
        :data:`RECTILINEAR_TOL`.
    """
    r = np.asarray(r_km, dtype=float)
    v = np.asarray(v_km_s, dtype=float)
    h = np.cross(r, v)
    r_norm = np.linalg.norm(r, axis=-1)
    h_norm = np.linalg.norm(h, axis=-1)
    scale = r_norm * np.linalg.norm(v, axis=-1)
    if np.any(~(h_norm > RECTILINEAR_TOL * scale)) or np.any(~(r_norm > 0)):
        raise InputError("nominal state", "r x v", "a state with an orbit plane (|r x v| > "
                         f"{RECTILINEAR_TOL:g} |r| |v|)", np.min(h_norm / np.where(
                             scale > 0, scale, 1.0)))
    rhat = r / r_norm[..., None]
    chat = h / h_norm[..., None]
    ihat = np.cross(chat, rhat)
    return np.stack([rhat, ihat, chat], axis=-2)


def ric_state_rotation(state: ArrayLike) -> np.ndarray:
    """Return blockdiag(T, T), (..., 6, 6): inertial (r, v) components to RIC (module
    docstring: velocity along the same axes, no ω × r term).

    Parameters
    ----------
    state : (..., 6) position (km) and velocity (km/s) whose axes are wanted.
    """
    s = np.asarray(state, dtype=float)
    t = ric_axes(s[..., :3], s[..., 3:6])
    out = np.zeros((*t.shape[:-2], 6, 6))
    out[..., :3, :3] = t
    out[..., 3:, 3:] = t
    return out


def rotate_rows(rotation: np.ndarray, rows: np.ndarray, first: int = 0) -> np.ndarray:
    """Return X with its rows first..first+n rotated: [.., T X[first:first+n], ..].

    Parameters
    ----------
    rotation : (n, n) the rotation T of the orbit rows (:func:`ric_state_rotation`).
    rows : (m, k) X, e.g. a partials matrix whose Gram products are covariances; the rows
        outside first..first+n (constants) are left as they are.
    """
    out = np.array(rows, dtype=float, copy=True)
    n = rotation.shape[-1]
    out[first:first + n] = rotation @ out[first:first + n]
    return out


def rotate_covariance(rotation: np.ndarray, cov: np.ndarray, first: int = 0) -> np.ndarray:
    """Return T̄ P T̄ᵀ, T̄ the identity with T in rows/columns first..first+n.

    .. math:: P_{ric} = \\bar T P \\bar T^T

    Parameters
    ----------
    rotation : (n, n) T.
    cov : (m, m) P with the orbit rows at first..first+n (the cross-covariances with the
        other rows are rotated on their orbit side).
    """
    return rotate_rows(rotation, rotate_rows(rotation, cov, first).T, first).T


__all__ = ["RECTILINEAR_TOL", "RIC_NAMES", "ric_axes", "ric_state_rotation", "rotate_covariance",
           "rotate_rows"]

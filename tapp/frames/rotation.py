"""The gmst Earth rotation model's angle, and its ECI <-> ECEF rotations with their rates.

The ``"gmst"`` Earth orientation (:mod:`tapp.frames.orientation`, the approximate-STM study's)
turns the Earth by

.. math:: \\theta(t) = \\theta_0 + \\omega_\\oplus t,

with :math:`\\theta_0` the GMST IAU-82 at the scenario epoch (UT1 = UTC, see
:mod:`tapp.frames.time`) and :math:`\\omega_\\oplus` = ``OMEGA_EARTH_rad_s``
(:func:`earth_rotation_angle_rad`; the compiled dynamics write the same line symbolically).

Frames: "ECI" is EME2000; "ECEF" is the frame turned from it by :math:`R_3(\\theta)` about the
EME2000 z axis. Precession and nutation since J2000 (about 0.36 deg of longitude by 2026) and
polar motion are neglected: this ECEF is a pseudo Earth-fixed frame, consistent between
dynamics and measurements, not the ITRS (the ``"iau2006"`` model is).
"""

from __future__ import annotations

import numpy as np

from tapp.constants import OMEGA_EARTH_rad_s


def earth_rotation_angle_rad(theta0_rad, t_s, omega_rad_s: float = OMEGA_EARTH_rad_s):
    """Return the Earth rotation angle theta(t) = theta0 + omega t, rad (not wrapped).

    The gmst model's angle (GMST at the epoch, uniform rotation after), not the IAU 2000
    Earth rotation angle of the iau2006 model.

    Parameters
    ----------
    theta0_rad : float or array_like, shape (...)
        GMST at the scenario epoch, rad (e.g. ``Epoch.gmst_rad()``).
    t_s : float or array_like, shape (...)
        Seconds from the scenario epoch; broadcast with ``theta0_rad``.
    omega_rad_s : float
        Earth rotation rate, rad/s.

    Returns
    -------
    numpy.ndarray, shape (...)
        theta, rad, continuous in t (no reduction to [0, 2 pi), so it is smooth to differentiate).
    """
    return np.asarray(theta0_rad, dtype=float) + omega_rad_s * np.asarray(t_s, dtype=float)


def cross_matrix(a):
    """Return [a×], the matrix of y -> a × y, shape (..., 3, 3) from a (..., 3)."""
    a = np.asarray(a, dtype=float)
    out = np.zeros(a.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -a[..., 2], a[..., 1]
    out[..., 1, 0], out[..., 1, 2] = a[..., 2], -a[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -a[..., 1], a[..., 0]
    return out


def r3(angle_rad):
    """Return the frame rotation R3(angle) about z, shape (..., 3, 3).

    .. math:: R_3(\\alpha) = \\begin{pmatrix} \\cos\\alpha & \\sin\\alpha & 0 \\\\
              -\\sin\\alpha & \\cos\\alpha & 0 \\\\ 0 & 0 & 1 \\end{pmatrix}

    Vallado, Fundamentals of Astrodynamics and Applications, eq. 3-15 (ROT3): the coordinates of
    a fixed vector in axes turned by +angle about z.
    """
    angle = np.asarray(angle_rad, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    out[..., 0, 0] = c
    out[..., 0, 1] = s
    out[..., 1, 0] = -s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    return out


def r3_derivative(angle_rad):
    """Return dR3/dangle, shape (..., 3, 3), 1/rad."""
    angle = np.asarray(angle_rad, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    out[..., 0, 0] = -s
    out[..., 0, 1] = c
    out[..., 1, 0] = -c
    out[..., 1, 1] = -s
    return out


def eci_to_ecef_matrix(theta_rad):
    """Return T = R3(theta), shape (..., 3, 3), with r_ecef = T r_eci."""
    return r3(theta_rad)


def eci_to_ecef_matrix_dot(theta_rad, omega_rad_s: float = OMEGA_EARTH_rad_s):
    """Return dT/dt = omega dR3/dtheta, shape (..., 3, 3), 1/s."""
    return omega_rad_s * r3_derivative(theta_rad)


def ecef_to_eci_matrix(theta_rad):
    """Return T^T = R3(-theta), shape (..., 3, 3), with r_eci = T^T r_ecef."""
    return r3(-np.asarray(theta_rad, dtype=float))


def ecef_to_eci_matrix_dot(theta_rad, omega_rad_s: float = OMEGA_EARTH_rad_s):
    """Return d(T^T)/dt, shape (..., 3, 3), 1/s."""
    return np.swapaxes(eci_to_ecef_matrix_dot(theta_rad, omega_rad_s), -1, -2)


def _rotate_state(state, t_mat, t_dot):
    """Return [T r, T v + Ṫ r] for states (..., 6) and rotations T, Ṫ (..., 3, 3)."""
    x = np.asarray(state, dtype=float)
    r = np.einsum("...ij,...j->...i", t_mat, x[..., :3])
    v = np.einsum("...ij,...j->...i", t_mat, x[..., 3:]) + np.einsum(
        "...ij,...j->...i", t_dot, x[..., :3]
    )
    return np.concatenate([r, v], axis=-1)


def eci_to_ecef_state(state_eci, theta_rad, omega_rad_s: float = OMEGA_EARTH_rad_s):
    """Return the Earth-fixed state [r, v] (km, km/s), shape (..., 6).

    .. math:: r_f = T r, \\qquad v_f = T v + \\dot T r = T (v - \\omega \\times r)

    Parameters
    ----------
    state_eci : array_like, shape (..., 6)
        Inertial (EME2000) position km and velocity km/s.
    theta_rad : array_like, shape (...)
        Earth rotation angle (see :func:`earth_rotation_angle_rad`), rad.
    omega_rad_s : float
        Earth rotation rate, rad/s.
    """
    return _rotate_state(state_eci, eci_to_ecef_matrix(theta_rad),
                         eci_to_ecef_matrix_dot(theta_rad, omega_rad_s))


def ecef_to_eci_state(state_ecef, theta_rad, omega_rad_s: float = OMEGA_EARTH_rad_s):
    """Return the inertial (EME2000) state [r, v] (km, km/s), shape (..., 6).

    .. math:: r = T^T r_f, \\qquad v = T^T v_f + \\dot T^T r_f = T^T v_f + \\omega \\times r

    Parameters
    ----------
    state_ecef : array_like, shape (..., 6)
        Earth-fixed position km and velocity km/s.
    theta_rad : array_like, shape (...)
        Earth rotation angle, rad.
    omega_rad_s : float
        Earth rotation rate, rad/s.
    """
    return _rotate_state(state_ecef, ecef_to_eci_matrix(theta_rad),
                         ecef_to_eci_matrix_dot(theta_rad, omega_rad_s))

"""Equinoctial elements of a Cartesian state: non-singular for circular and equatorial orbits.

Element arrays are ``(..., 6)`` = ``[a_km, ex, ey, hx, hy, lambda_m_rad]`` (elliptic,
prograde orbits), TAPP I's "equinoctial" miss parameters. Frames: the inertial frame of the
state. Units: km, km/s, rad.
"""

from __future__ import annotations

import numpy as np


def equinoctial_elements(state, mu_km3_s2: float) -> np.ndarray:
    """Return equinoctial elements (a_km, ex, ey, hx, hy, lambda_m_rad), shape (..., 6).

    .. math::

        e_x + i e_y = e\\,e^{i(\\omega + \\Omega)},\\quad
        h_x + i h_y = \\tan(i/2)\\,e^{i\\Omega},\\quad \\lambda_M = M + \\omega + \\Omega

    Non-singular for circular and equatorial orbits (elliptic, prograde). Computed from the
    eccentricity vector and the equinoctial frame f, g (Broucke & Cefola 1972, Celest. Mech.
    5, 303; names as in Orekit's ``EquinoctialOrbit``): e_x = e·f, e_y = e·g, then the
    eccentric longitude F from the position in (f, g) and Kepler's equation
    λ_M = F + e_y cos F - e_x sin F.

    Parameters
    ----------
    state : array_like, shape (..., 6)
        km, km/s, inertial.
    mu_km3_s2 : float
        Gravitational parameter.
    """
    x = np.asarray(state, dtype=float)
    r, v = x[..., :3], x[..., 3:]
    r_norm = np.linalg.norm(r, axis=-1)
    v2 = np.sum(v * v, axis=-1)
    a = 1.0 / (2.0 / r_norm - v2 / mu_km3_s2)
    e_vec = ((v2 - mu_km3_s2 / r_norm)[..., None] * r
             - np.sum(r * v, axis=-1)[..., None] * v) / mu_km3_s2
    w = np.cross(r, v)
    w = w / np.linalg.norm(w, axis=-1)[..., None]
    hx = -w[..., 1] / (1.0 + w[..., 2])
    hy = w[..., 0] / (1.0 + w[..., 2])
    scale = 1.0 + hx * hx + hy * hy
    f = np.stack([1.0 - hy * hy + hx * hx, 2.0 * hx * hy, -2.0 * hy], axis=-1) / scale[..., None]
    g = np.stack([2.0 * hx * hy, 1.0 + hy * hy - hx * hx, 2.0 * hx], axis=-1) / scale[..., None]
    ex, ey = np.sum(e_vec * f, axis=-1), np.sum(e_vec * g, axis=-1)
    x1, y1 = np.sum(r * f, axis=-1) / a, np.sum(r * g, axis=-1) / a
    beta = 1.0 / (1.0 + np.sqrt(1.0 - ex * ex - ey * ey))
    # [1 - ey² β, ex ey β; ex ey β, 1 - ex² β] (cos F, sin F) = (x1 + ex, y1 + ey)
    m11, m12, m22 = 1.0 - ey * ey * beta, ex * ey * beta, 1.0 - ex * ex * beta
    det = m11 * m22 - m12 * m12
    cos_f = (m22 * (x1 + ex) - m12 * (y1 + ey)) / det
    sin_f = (m11 * (y1 + ey) - m12 * (x1 + ex)) / det
    big_f = np.arctan2(sin_f, cos_f)
    lam = np.mod(big_f + ey * np.cos(big_f) - ex * np.sin(big_f), 2.0 * np.pi)
    return np.stack([a, ex, ey, hx, hy, lam], axis=-1)

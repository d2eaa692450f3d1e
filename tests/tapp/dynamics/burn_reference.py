"""Burns written again for the manoeuvre tests, in NumPy, from their definitions: the RIC and
VNB axes of a state, the executed velocity change of Gates' physical error model (before its
linearisation), a J2 field (Vallado 2013, eq. 8-30) with a finite burn's thrust, and SciPy's
DOP853 on it."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from tapp.constants import GM_EARTH_km3_s2, R_EARTH_km, egm96_coefficients
from tapp.dynamics.gates import pointing_axes

J2 = -np.sqrt(5.0) * egm96_coefficients()[0][2, 0]


def axes(r: np.ndarray, v: np.ndarray, name: str) -> np.ndarray:
    """Columns: the unit vectors of the axes ``name`` at (r, v) (inertial: I)."""
    if name == "inertial":
        return np.eye(3)
    n = np.cross(r, v) / np.linalg.norm(np.cross(r, v))
    if name == "ric":
        rr = r / np.linalg.norm(r)
        return np.column_stack([rr, np.cross(n, rr), n])
    vv = v / np.linalg.norm(v)
    return np.column_stack([vv, n, np.cross(vv, n)])


def turned(d: np.ndarray, a1: float, a2: float) -> np.ndarray:
    """The unit vector d turned by the angles a1 towards ê₁ and a2 towards ê₂ (its triad)."""
    u, e1, e2 = pointing_axes(d)
    return np.cos(a1) * np.cos(a2) * u + np.sin(a1) * np.cos(a2) * e1 + np.sin(a2) * e2


def executed(dv: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The executed velocity change of a commanded ``dv`` with Gates' six errors ``q`` taken
    physically: magnitude |Δv|(1 + q₁) + q₂, direction turned by q_{3,4} + q_{5,6}/|Δv|."""
    m = np.linalg.norm(dv)
    return (m * (1 + q[0]) + q[1]) * turned(dv, q[2] + q[4] / m, q[3] + q[5] / m)


def j2_acceleration(r: np.ndarray) -> np.ndarray:
    """Two-body + J2 acceleration, km/s² (Vallado 2013, eq. 8-30), Earth's equator the xy
    plane (the gmst model at the epoch of J2000 axes: the field is zonal)."""
    rn = np.linalg.norm(r)
    k = 1.5 * J2 * GM_EARTH_km3_s2 * R_EARTH_km**2 / rn**5
    z2 = 5.0 * r[2] ** 2 / rn**2
    return -GM_EARTH_km3_s2 * r / rn**3 + k * r * (z2 - 1.0) - 2.0 * k * np.array([0, 0, r[2]])


def thrust_rhs(thrust_n: float, mass_kg: float, flow_kg_s: float, t_start_s: float,
               direction: np.ndarray, axes_name: str):
    """The right-hand side of a J2 orbit under a thrust F (N) along ``direction`` (unit, in
    the axes) of a mass m₀ − ṁ (t − t₀)."""
    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        mass = mass_kg - flow_kg_s * (t - t_start_s)
        a = thrust_n / mass * 1e-3 * axes(y[:3], y[3:], axes_name) @ direction
        return np.concatenate([y[3:], j2_acceleration(y[:3]) + a])
    return rhs


def scipy_state(rhs, x0: np.ndarray, t0_s: float, t1_s: float, tol: float = 1e-13
                ) -> np.ndarray:
    """SciPy's DOP853 from (t0, x0) to t1 at rtol = atol = ``tol``."""
    sol = solve_ivp(rhs, (t0_s, t1_s), x0, method="DOP853", rtol=tol, atol=tol)
    return sol.y[:, -1]

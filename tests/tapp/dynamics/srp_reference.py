"""An independent integration of a J2 + SRP orbit through the Earth's shadow, for the event
tests: NumPy accelerations written here (J2 as in Vallado 2013, eq. 8-30; SRP and the conical
shadow as in Montenbruck & Gill 2000, §3.4, with the lens area of two discs in the plain acos
form), SciPy's DOP853, the Sun from DE421 (jplephem through tapp's reader, interpolated by a
cubic spline through 10-minute nodes: 2e-5 km over its 1e8 km, a 1e-13 change of the force's
direction), and the integration restarted at every shadow boundary.

A boundary is found by SciPy's event location on the step that crosses it; that step is then
integrated again from its start to the boundary, so that no step of the reference straddles a
boundary (SciPy's own state at a terminal event comes from the dense output of the crossing
step, which carries the kink).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

from tapp.constants import AU_km, GM_EARTH_km3_s2, R_EARTH_km, RADIUS_km, egm96_coefficients
from tapp.dynamics.ephemeris import position_km, utc_to_tdb_jd

P_SUN_N_m2 = 4.56e-6  # Montenbruck & Gill (2000) §3.4.1, at 1 AU
J2 = -math.sqrt(5.0) * egm96_coefficients()[0][2, 0]


def cone_state(r: np.ndarray, r_sun: np.ndarray) -> int:
    """0 lit, 1 penumbra, 2 umbra: Vallado (2013) Algorithm 34 (shadow cones of the Earth),
    at r with the Sun at r_sun (km, Earth-centred)."""
    re, rs = RADIUS_km["earth"], RADIUS_km["sun"]
    d_sun = np.linalg.norm(r_sun)
    alpha_pen = math.asin((rs + re) / d_sun)
    alpha_umb = math.asin((rs - re) / d_sun)
    axis = -r_sun / d_sun
    horiz = np.dot(r, axis)  # along the shadow axis, behind the Earth when > 0
    if horiz <= 0.0:
        return 0
    vert = np.linalg.norm(r - horiz * axis)
    pen_vert = math.tan(alpha_pen) * (re / math.sin(alpha_pen) + horiz)
    if vert > pen_vert:
        return 0
    umb_vert = math.tan(alpha_umb) * (re / math.sin(alpha_umb) - horiz)
    return 2 if vert <= umb_vert else 1


@dataclass(frozen=True)
class SrpOrbit:
    """J2 + cannonball SRP with the Earth's conical shadow; epoch a UTC Julian date, times up
    to ``span_s`` from it."""

    epoch_jd_utc: float
    c_r: float
    area_to_mass_m2_kg: float
    span_s: float

    def __post_init__(self) -> None:
        nodes = np.arange(-3600.0, self.span_s + 7200.0, 600.0)
        sun = position_km("sun", "earth", utc_to_tdb_jd(self.epoch_jd_utc), nodes / 86400.0)
        object.__setattr__(self, "_sun", CubicSpline(nodes, sun))

    def sun_km(self, t_s: float) -> np.ndarray:
        return self._sun(t_s)

    def geometry(self, t_s: float, r: np.ndarray) -> tuple[float, float, float]:
        """Apparent radii of the Sun and the Earth and their separation, rad."""
        s, d = self.sun_km(t_s) - r, -r
        s_n, d_n = np.linalg.norm(s), np.linalg.norm(d)
        a = math.asin(RADIUS_km["sun"] / s_n)
        b = math.asin(R_EARTH_km / d_n)
        c = math.acos(np.clip(np.dot(s, d) / (s_n * d_n), -1.0, 1.0))
        return a, b, c

    def visible_fraction(self, t_s: float, r: np.ndarray) -> float:
        a, b, c = self.geometry(t_s, r)
        if c >= a + b:
            return 1.0
        if c <= b - a:
            return 0.0
        d1 = (c * c + a * a - b * b) / (2 * c)
        d2 = c - d1
        lens = (a * a * math.acos(d1 / a) - d1 * math.sqrt(a * a - d1 * d1)
                + b * b * math.acos(d2 / b) - d2 * math.sqrt(b * b - d2 * d2))
        return 1.0 - lens / (math.pi * a * a)

    def rhs(self, t_s: float, y: np.ndarray) -> np.ndarray:
        r, v = y[:3], y[3:]
        rn = np.linalg.norm(r)
        z2 = (r[2] / rn) ** 2
        k = 1.5 * J2 * GM_EARTH_km3_s2 * R_EARTH_km ** 2 / rn ** 5
        a = -GM_EARTH_km3_s2 * r / rn ** 3 + k * r * np.array([5 * z2 - 1, 5 * z2 - 1,
                                                               5 * z2 - 3])
        u = r - self.sun_km(t_s)
        dist = np.linalg.norm(u)
        p = P_SUN_N_m2 * self.c_r * self.area_to_mass_m2_kg * 1e-3 * (AU_km / dist) ** 2
        a = a + self.visible_fraction(t_s, r) * p * u / dist
        return np.concatenate([v, a])

    def boundaries(self) -> list:
        """Penumbra and umbra boundaries g(t, y) (negative inside), as SciPy events."""
        def penumbra(t, y):
            a, b, c = self.geometry(t, y[:3])
            return c - (a + b)

        def umbra(t, y):
            a, b, c = self.geometry(t, y[:3])
            return c - (b - a)

        return [penumbra, umbra]


@dataclass(frozen=True)
class Solution:
    """The reference trajectory: states (N, 6) on the requested grid, the boundary crossings
    (s), and the state at any time through the pieces' dense outputs."""

    states: np.ndarray
    crossings: np.ndarray
    pieces: tuple

    def state_at(self, t_s: float) -> np.ndarray:
        for start, end, sol in self.pieces:
            if start <= t_s <= end:
                return sol(t_s)
        raise ValueError(f"t = {t_s} s outside the reference")


def integrate(orbit: SrpOrbit, x0: np.ndarray, t_s: np.ndarray, tol: float = 1e-13,
              t0_s: float = 0.0) -> Solution:
    """The reference from (t0_s, x0) through the increasing times ``t_s``, restarting at each
    boundary (module docstring); ``orbit`` gives ``rhs`` and ``boundaries``.

    After a crossing the function just crossed sits at zero to rounding, so it watches only
    for the opposite crossing until another one is met (SciPy's ``direction``).
    """
    kw = dict(method="DOP853", rtol=tol, atol=tol)
    out = np.full((t_s.size, 6), np.nan)
    t, y = t0_s, np.asarray(x0, dtype=float)
    crossings, pieces = [], []
    events = orbit.boundaries()
    for g in events:
        g.terminal, g.direction = True, 0.0
    while True:
        sol = solve_ivp(orbit.rhs, (t, t_s[-1]), y, events=events, dense_output=True, **kw)
        if sol.status != 1:  # reached the end
            todo = t_s > t if crossings else t_s >= t
            out[todo] = sol.sol(t_s[todo]).T
            pieces.append((t, t_s[-1], sol.sol))
            return Solution(out, np.array(crossings), tuple(pieces))
        i = min((k for k, te in enumerate(sol.t_events) if te.size),
                key=lambda k: sol.t_events[k][0])
        t_event, start = sol.t_events[i][0], sol.t[-2]  # -2: the last step before the crossing
        clean = solve_ivp(orbit.rhs, (start, t_event), sol.y[:, -2], dense_output=True, **kw)
        early, late = (t_s >= t) & (t_s <= start), (t_s > start) & (t_s <= t_event)
        if early.any():
            out[early] = sol.sol(t_s[early]).T
        if late.any():
            out[late] = clean.sol(t_s[late]).T
        pieces += [(t, start, sol.sol), (start, t_event, clean.sol)]
        for g in events:
            g.direction = 0.0
        events[i].direction = 1.0 if events[i](start, sol.y[:, -2]) > 0 else -1.0
        t, y = t_event, clean.y[:, -1]
        crossings.append(t_event)

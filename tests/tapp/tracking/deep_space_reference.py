"""An independent integration of deep_space.toml's trajectory with impulsive burns, for the
reference tests (tests/tapp/tracking/test_reference_deep_space.py).

The force model of the scenario written again in NumPy from its sources, and integrated by
SciPy's DOP853 restarted at every shadow boundary (tests/tapp/dynamics/srp_reference.py's
``integrate``) and at every burn:

- the Earth's point mass and J2 (EGM96: Lemoine et al. 1998, NASA/TP-1998-206861), about the
  pole of the ITRS, the third row of ERFA's IAU 2006/2000A celestial-to-terrestrial matrix
  (``erfa.c2t06a``) with astropy's TT, UT1 and polar motion from the IERS table that
  astropy-iers-data ships (no download: tests/tapp/frames/conftest.py); the J2 acceleration
  in the vector form of Vallado (2013) eq. 8-30 about a pole p:
  a = -(3/2) J2 μ R²/r⁵ [(1 - 5 (r·p)²/r²) r + 2 (r·p) p];
- the Sun and the Moon as point masses, with the indirect term (Montenbruck & Gill 2000,
  eq. 3.37), their GM from DE430 (Folkner et al. 2014, IPN PR 42-196, Table 8), their
  positions from DE421 read here by jplephem at astropy's TDB, through cubic splines on
  10-minute nodes (2e-8 km for the Moon);
- solar radiation pressure on a cannonball, a = ν P☉ C_r (A/m) (AU/|r − r☉|)² û with
  P☉ = 4.56e-6 N/m² (M&G §3.4.1), ν the visible fraction of the solar disc behind the Earth's
  and the Moon's discs multiplied (M&G §3.4.2, the lens area in the plain acos form), radii
  from the IAU WGCCRE 2015 report (Archinal et al. 2018; the Earth's EGM96's).

Scenario time t is SI seconds from the UTC epoch, as tapp's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import astropy.units as u
import astropy_iers_data
import erfa
import numpy as np
from astropy.time import Time
from astropy.utils import iers
from jplephem.spk import SPK
from scipy.interpolate import CubicSpline

from tapp.dynamics.ephemeris import de421_path
from tests.tapp.dynamics.burn_reference import axes
from tests.tapp.dynamics.srp_reference import integrate
from tests.tapp.frames.conftest import astropy_eop

GM_EARTH_km3_s2, R_EARTH_km, C20_BAR = 398600.4415, 6378.1363, -0.484165371736e-3
J2 = -math.sqrt(5.0) * C20_BAR
GM_SUN_km3_s2, GM_MOON_km3_s2 = 132712440041.9394, 4902.800066
R_SUN_km, R_MOON_km = 695700.0, 1737.4
AU_km = 149597870.7  # IAU 2012 Resolution B2
P_SUN_N_m2 = 4.56e-6
#: Spacing of the spline nodes of the Sun, the Moon and the pole, s.
NODE_S = 600.0


def _visible(r: np.ndarray, sun: np.ndarray, body: np.ndarray, radius_km: float
             ) -> tuple[float, float, float, float]:
    """(ν, a, b, c): the visible fraction of the Sun's disc behind a body's, the apparent
    radii of the Sun and the body and their separation, rad, seen from r."""
    s, d = sun - r, body - r
    s_n, d_n = np.linalg.norm(s), np.linalg.norm(d)
    a = math.asin(R_SUN_km / s_n)
    b = math.asin(min(radius_km / d_n, 1.0))
    c = math.acos(np.clip(np.dot(s, d) / (s_n * d_n), -1.0, 1.0))
    if c >= a + b:
        return 1.0, a, b, c
    if c <= b - a:
        return 0.0, a, b, c
    if c <= a - b:
        return 1.0 - b * b / (a * a), a, b, c
    d1 = (c * c + a * a - b * b) / (2 * c)
    d2 = c - d1
    lens = (a * a * math.acos(d1 / a) - d1 * math.sqrt(a * a - d1 * d1)
            + b * b * math.acos(d2 / b) - d2 * math.sqrt(b * b - d2 * d2))
    return 1.0 - lens / (math.pi * a * a), a, b, c


@dataclass(frozen=True)
class DeepSpaceOrbit:
    """The scenario's force model (module docstring) from ``epoch`` (UTC, ISO) over
    [0, ``span_s``]."""

    epoch: str
    span_s: float
    c_r: float
    area_to_mass_m2_kg: float

    def __post_init__(self) -> None:
        nodes = np.arange(-3600.0, self.span_s + 7200.0, NODE_S)
        with astropy_eop(astropy_iers_data.IERS_A_FILE):
            t = Time(self.epoch, scale="utc") + nodes * u.s
            tdb, tt, ut1 = t.tdb, t.tt, t.ut1
            xp, yp = iers.earth_orientation_table.get().pm_xy(t)
        kernel = SPK.open(str(de421_path()))
        try:
            earth = (kernel[3, 399].compute(tdb.jd1, tdb.jd2)).T
            moon = (kernel[3, 301].compute(tdb.jd1, tdb.jd2)).T - earth
            sun = (kernel[0, 10].compute(tdb.jd1, tdb.jd2)
                   - kernel[0, 3].compute(tdb.jd1, tdb.jd2)).T - earth
        finally:
            kernel.close()
        c2t = erfa.c2t06a(tt.jd1, tt.jd2, ut1.jd1, ut1.jd2, xp.to_value(u.rad),
                          yp.to_value(u.rad))
        object.__setattr__(self, "_splines", {"sun": CubicSpline(nodes, sun),
                                              "moon": CubicSpline(nodes, moon),
                                              "pole": CubicSpline(nodes, c2t[:, 2, :])})

    def bodies(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The Sun's and the Moon's positions (km, GCRS axes, Earth-centred) and the ITRS
        pole (unit) at t_s."""
        pole = self._splines["pole"](t_s)
        return self._splines["sun"](t_s), self._splines["moon"](t_s), pole / np.linalg.norm(pole)

    def rhs(self, t_s: float, y: np.ndarray) -> np.ndarray:
        r, v = y[:3], y[3:]
        sun, moon, pole = self.bodies(t_s)
        rn = np.linalg.norm(r)
        z = float(np.dot(r, pole))
        k = 1.5 * J2 * GM_EARTH_km3_s2 * R_EARTH_km**2 / rn**5
        a = -GM_EARTH_km3_s2 * r / rn**3 - k * ((1.0 - 5.0 * z * z / rn**2) * r + 2.0 * z * pole)
        for gm, s in ((GM_SUN_km3_s2, sun), (GM_MOON_km3_s2, moon)):
            d = s - r
            a = a + gm * (d / np.linalg.norm(d) ** 3 - s / np.linalg.norm(s) ** 3)
        nu = (_visible(r, sun, np.zeros(3), R_EARTH_km)[0]
              * _visible(r, sun, moon, R_MOON_km)[0])
        w = r - sun
        dist = np.linalg.norm(w)
        p = P_SUN_N_m2 * self.c_r * self.area_to_mass_m2_kg * 1e-3 * (AU_km / dist) ** 2
        return np.concatenate([v, a + nu * p * w / dist])

    def boundaries(self) -> list:
        """The penumbra and umbra boundaries of the Earth's and the Moon's shadows
        g(t, y) (negative inside), as SciPy events."""
        def event(body: str, kind: str):
            def g(t_s, y):
                sun, moon, _ = self.bodies(t_s)
                centre, radius = ((np.zeros(3), R_EARTH_km) if body == "earth"
                                  else (moon, R_MOON_km))
                _, a, b, c = _visible(y[:3], sun, centre, radius)
                return c - (a + b) if kind == "penumbra" else c - (b - a)
            return g

        return [event(b, k) for b in ("earth", "moon") for k in ("penumbra", "umbra")]


@dataclass(frozen=True)
class Burn:
    """An impulsive burn: time (s), axes ("inertial" or "vnb") and Δv (km/s) in them."""

    t_s: float
    axes: str
    dv_km_s: tuple[float, float, float]


def fly(orbit: DeepSpaceOrbit, x0: np.ndarray, burns: list[Burn], grids: list[np.ndarray],
        tol: float) -> list[np.ndarray]:
    """The states (N_k, 6) on each arc's grid (ascending, from the arc's start, at the burn
    that starts it, to its end, at the next), from x0 at t = 0: each arc integrated from the
    state after its burn, the state at its end taken before the next."""
    x, out = np.asarray(x0, dtype=float), []
    starts = [0.0] + [b.t_s for b in burns]
    for k, (t_a, grid) in enumerate(zip(starts, grids, strict=True)):
        if k:
            burn = burns[k - 1]
            x = x + np.r_[0.0, 0.0, 0.0, axes(x[:3], x[3:], burn.axes) @ np.array(burn.dv_km_s)]
        assert grid[0] == t_a
        states = integrate(orbit, x, grid, tol, t0_s=t_a).states
        out.append(states)
        x = states[-1]
    return out

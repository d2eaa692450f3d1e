"""An independent reference for the encounter tests (trajectory and B-plane written here),
and the moved-epoch scenario they run.

The trajectory is integrated by SciPy's DOP853 with a NumPy right-hand side of this module:
the Earth's point mass and J2 about its pole at the epoch, the Sun and the Moon as third bodies
with their indirect terms, from DE421 positions (cubic splines of 600 s samples). The B-plane
is that of the osculating Moon-relative hyperbola at periapsis (the root of r·v), from the
textbook formulas (W. Kizner, Planet. Space Sci. 7 (1961) 125; D. A. Vallado, Fundamentals of
Astrodynamics and Applications, 4th ed., ch. 2): S = ê/e + sqrt(1 - 1/e²) (ĥ × ê),
T = S × ẑ / |S × ẑ|, R = S × T, B = S × h / v∞. What it shares with tapp: the constants, the
ephemeris file and the Earth's pole direction (tapp.frames.orientation), not the integrator,
the force model's code, the periapsis search or the B-plane code.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from tapp.constants import GM_km3_s2, R_EARTH_km
from tapp.dynamics.ephemeris import position_km
from tapp.dynamics.forces import default_parameters
from tapp.tracking.scenario import Scenario

#: Spacing of the DE421 samples the splines interpolate, s (error ~1e-8 km for the Moon).
_SAMPLE_S = 600.0


class Reference:
    """The trajectory of ``x0`` (6,) (km, km/s, GCRS) under ``scenario``'s epoch, to t_end_s."""

    def __init__(self, scenario: Scenario, x0: np.ndarray, t_end_s: float):
        assert scenario.orientation.scales is not None, "an iau2006 scenario"
        grid = np.arange(-2 * _SAMPLE_S, t_end_s + 3 * _SAMPLE_S, _SAMPLE_S)
        tdb = scenario.orientation.scales.tdb(grid)
        self.moon = CubicSpline(grid, position_km("moon", "earth", *tdb), axis=0)
        self.sun = CubicSpline(grid, position_km("sun", "earth", *tdb), axis=0)
        values = default_parameters(scenario.state_model, ("GM_km3_s2", "J2"))
        mu, j2 = float(values["GM_km3_s2"]), float(values["J2"])
        pole = scenario.orientation.pole(np.array([0.0]))[0, 0]

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            r = y[:3]
            rn = np.linalg.norm(r)
            z = r @ pole
            a = -mu * r / rn**3 - 1.5 * j2 * mu * R_EARTH_km**2 / rn**5 * (
                (1.0 - 5.0 * z * z / rn**2) * r + 2.0 * z * pole)
            for gm, s in ((GM_km3_s2["moon"], self.moon(t)), (GM_km3_s2["sun"], self.sun(t))):
                d = s - r
                a += gm * (d / np.linalg.norm(d) ** 3 - s / np.linalg.norm(s) ** 3)
            return np.concatenate([y[3:], a])

        self.solution = solve_ivp(rhs, (0.0, t_end_s), np.asarray(x0, dtype=float),
                                  method="DOP853", rtol=1e-12, atol=1e-9, dense_output=True)
        assert self.solution.success, self.solution.message

    def moon_relative(self, t_s: float) -> np.ndarray:
        """Moon-relative state (6,) at t_s, km and km/s."""
        body = np.concatenate([self.moon(t_s), self.moon(t_s, 1)])
        return self.solution.sol(t_s) - body

    def distance_km(self, t_s: np.ndarray) -> np.ndarray:
        """Distance to the Moon's centre at t_s (N,), km."""
        return np.linalg.norm(self.solution.sol(t_s)[:3].T - self.moon(t_s), axis=1)

    def periapsis_b_plane(self, t_guess_s: float, window_s: float = 3600.0
                          ) -> tuple[float, float, float]:
        """(t s, B·R km, B·T km) at the Moon periapsis within ``window_s`` of t_guess_s."""

        def r_dot_v(t: float) -> float:
            z = self.moon_relative(t)
            return float(z[:3] @ z[3:])

        t_p = brentq(r_dot_v, t_guess_s - window_s, t_guess_s + window_s, xtol=1e-6)
        z = self.moon_relative(t_p)
        r, v, mu = z[:3], z[3:], GM_km3_s2["moon"]
        h = np.cross(r, v)
        v_inf = np.sqrt(v @ v - 2.0 * mu / np.linalg.norm(r))
        e_vec = ((v @ v - mu / np.linalg.norm(r)) * r - (r @ v) * v) / mu
        e = np.linalg.norm(e_vec)
        e_hat, h_hat = e_vec / e, h / np.linalg.norm(h)
        s_hat = e_hat / e + np.sqrt(1.0 - 1.0 / e**2) * np.cross(h_hat, e_hat)
        t_hat = np.cross(s_hat, [0.0, 0.0, 1.0])
        t_hat /= np.linalg.norm(t_hat)
        b_vec = np.cross(s_hat, h) / v_inf
        return t_p, float(b_vec @ np.cross(s_hat, t_hat)), float(b_vec @ t_hat)


#: deep_space.toml's aim point (search_bplane.toml's), reached by its own flyby at its own
#: epoch: B·R, B·T (km) and the flight time to periapsis (s), 2026-03-14T02:05:58.384 UTC.
AIM = {"b_dot_r_km": -2000.0, "b_dot_t_km": 5300.0, "flight_time_s": 309958.384}
#: A [targeting] table for that aim point (tolerances 0.1 km: the tests ask for 1 km).
TARGETING = """
[targeting]                            # retarget the injection to the aim point before TAPP I
first_guess = "conic"

[targeting.targets]
b_dot_r_km = -2000.0
b_dot_t_km = 5300.0
flight_time_s = 309958.384

[targeting.tolerances]
b_dot_r_km = 0.1
b_dot_t_km = 0.1
"""


def moved_deep_space(shipped: str, *, days: int = 1, targeting: str | None = None) -> str:
    """The text of the example ``deep_space.toml`` with its epoch ``days`` later and its
    injection unchanged, cut to 3 days of tracking (no re-epoch), without solar radiation
    pressure (the reference has gravity only; it moves B by ~3 km); with ``targeting`` (a
    [targeting] table) appended and the miss time at "periapsis"."""
    replacements = [("srp = true", "srp = false"),
                    ('dynamic = ["GM_km3_s2", "GM_moon_km3_s2", "Cr"]',
                     'dynamic = ["GM_km3_s2", "GM_moon_km3_s2"]'),
                    ('epoch = "2026-03-10T12:00:00"', f'epoch = "2026-03-{10 + days}T12:00:00"'),
                    ('end = "2026-04-09T12:00:00"', "end = 259200.0"),
                    ('end = "2026-04-09T12:00:00"', "end = 259200.0"),
                    ('epochs = ["2026-03-14T02:05:58.384", 1296000.0]', "epochs = []")]
    if targeting is not None:
        replacements.append(('time = "2026-03-14T02:05:58.384"', 'time = "periapsis"'))
    text = shipped
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text + (targeting or "")

"""Solar radiation pressure: the acceleration and the conical shadow against NumPy written
independently here (lens area of two discs; Vallado's shadow cones), shadow entry and exit
times of a LEO orbit, and ∂x/∂C_r against central differences."""

from __future__ import annotations

import math

import casadi as ca
import mpmath as mp
import numpy as np
import pytest
from scipy.optimize import brentq

from tapp.constants import AU_km, GM_EARTH_km3_s2, RADIUS_km
from tapp.dynamics import Propagator
from tapp.dynamics.ephemeris import position_km, utc_to_tdb_jd
from tapp.dynamics.equations import build_equations
from tapp.dynamics.radiation import shadow_factor, srp_acceleration
from tapp.dynamics.spec import SurfaceForces, earth_model
from tests.tapp.dynamics.conftest import periapsis_state
from tests.tapp.dynamics.srp_reference import cone_state

JD_2026 = 2461041.5  # 2026-01-01T00:00 UTC
P_SUN_N_m2 = 4.56e-6  # Montenbruck & Gill (2000) §3.4.1, at 1 AU
# Two double-precision evaluations of the same closed form (a few asin/acos): rounding only.
ROUNDING = 1e-12
ONE_SECOND = 1.0


def _reference_nu(r, r_sun, r_body, radius_body) -> float:
    """Visible fraction of the solar disc: 1 minus the lens of two circles of apparent radii
    a (Sun) and b (body), centres c apart, over the Sun's disc; in 40-digit mpmath, so the
    reference carries no rounding of its own (the plain acos form loses 1e-10 in doubles)."""
    with mp.workdps(40):
        r, r_sun, r_body = (mp.matrix([mp.mpf(float(v)) for v in vec]) for vec in
                            (r, r_sun, r_body))
        s, d = r_sun - r, r_body - r
        a = mp.asin(RADIUS_km["sun"] / mp.norm(s))
        b = mp.asin(mp.mpf(radius_body) / mp.norm(d))
        c = mp.acos((s.T * d)[0] / (mp.norm(s) * mp.norm(d)))
        if c >= a + b:
            return 1.0
        if c <= b - a:
            return 0.0
        if c <= a - b:
            return float(1 - (b / a) ** 2)
        d1 = (c * c + a * a - b * b) / (2 * c)  # distance of the chord from each centre
        d2 = c - d1
        lens = (a * a * mp.acos(d1 / a) - d1 * mp.sqrt(a * a - d1 * d1)
                + b * b * mp.acos(d2 / b) - d2 * mp.sqrt(b * b - d2 * d2))
        return float(1 - lens / (mp.pi * a * a))


def _numpy_srp(r, r_sun, r_moon, c_r, am):
    nu = _reference_nu(r, r_sun, np.zeros(3), RADIUS_km["earth"]) * _reference_nu(
        r, r_sun, r_moon, RADIUS_km["moon"])
    u = r - r_sun
    dist = np.linalg.norm(u)
    return nu * P_SUN_N_m2 * c_r * am / 1000.0 * (AU_km / dist) ** 2 * u / dist


def _srp_fn() -> ca.Function:
    r, s, m = ca.SX.sym("r", 3), ca.SX.sym("s", 3), ca.SX.sym("m", 3)
    c_r = ca.SX.sym("c_r")
    acc = srp_acceleration(r, s, {"earth": ca.SX.zeros(3), "moon": m}, c_r, 0.02)
    return ca.Function("srp", [r, s, m, c_r], [acc])


def _nu_fn() -> ca.Function:
    r, s, b = ca.SX.sym("r", 3), ca.SX.sym("s", 3), ca.SX.sym("b", 3)
    return ca.Function("nu", [r, s, b], [shadow_factor(r, s, b, RADIUS_km["earth"])])


SUN = np.array([AU_km * 0.98, 0.05 * AU_km, -0.02 * AU_km])
MOON = np.array([-300000.0, 150000.0, 20000.0])
_AXIS = -SUN / np.linalg.norm(SUN)  # anti-Sun direction from the Earth
_SIDE = np.cross(_AXIS, [0.0, 0.0, 1.0])
_SIDE /= np.linalg.norm(_SIDE)
_MOON_AXIS = (MOON - SUN) / np.linalg.norm(MOON - SUN)
_MOON_SIDE = np.cross(_MOON_AXIS, [0.0, 0.0, 1.0]) / np.linalg.norm(
    np.cross(_MOON_AXIS, [0.0, 0.0, 1.0]))


@pytest.mark.parametrize(("r_km", "lit"), [
    (7000.0 * -_AXIS, "full"),                                      # day side
    (7000.0 * _AXIS, "none"),                                       # Earth umbra
    (7000.0 * _AXIS + (RADIUS_km["earth"] + 10.0) * _SIDE, "part"),  # Earth penumbra
    (7000.0 * _AXIS + (RADIUS_km["earth"] - 20.0) * _SIDE, "part"),
    (MOON + 400000.0 * _MOON_AXIS, "part"),                         # annular, by the Moon
    (MOON + 200000.0 * _MOON_AXIS + 1700.0 * _MOON_SIDE, "part"),    # lunar penumbra
    (np.array([42164.0, 1000.0, -500.0]), "full"),
])
def test_srp_acceleration_matches_numpy(r_km: np.ndarray, lit: str) -> None:
    r = np.asarray(r_km)
    got = np.array(_srp_fn()(r, SUN, MOON, 1.3)).ravel()
    ref = _numpy_srp(r, SUN, MOON, 1.3, 0.02)
    unshadowed = P_SUN_N_m2 * 1.3 * 0.02 / 1000.0 * (AU_km / np.linalg.norm(r - SUN)) ** 2
    nu = np.linalg.norm(ref) / unshadowed
    assert {"full": nu == pytest.approx(1.0, abs=ROUNDING), "none": nu == 0.0,
            "part": 0.0 < nu < 1.0 - 1e-6}[lit], nu
    assert np.linalg.norm(got - ref) <= ROUNDING * max(np.linalg.norm(ref), 1e-30)


def test_srp_through_the_state_equations_uses_the_ephemeris_sun_and_moon() -> None:
    """f_state of J0 + SRP minus the point mass equals the NumPy SRP at DE421's Sun and Moon:
    the rb layout (bodies sorted, relative to the centre) reaches the force."""
    model = earth_model("J0", surface=SurfaceForces(1.0, srp=True, c_r=1.5))
    eqs = build_equations(model, model)
    assert eqs.bodies == ("moon", "sun")
    jd = utc_to_tdb_jd(JD_2026)
    moon, sun = (position_km(b, "earth", jd)[0] for b in eqs.bodies)
    for r in (7000.0 * sun / np.linalg.norm(sun), -6800.0 * sun / np.linalg.norm(sun),
              np.array([3000.0, -5000.0, 4000.0])):
        x = np.concatenate([r, [0.0, 7.0, 1.0]])
        acc = np.array(eqs.f_state(0.0, x, [], [0.0], np.concatenate([moon, sun]))).ravel()[3:]
        srp = acc + GM_EARTH_km3_s2 * r / np.linalg.norm(r) ** 3
        ref = _numpy_srp(r, sun, moon, 1.5, 1.0)
        # |a_grav| ~ 8e-3 km/s^2 against |a_srp| ~ 6e-9: the subtraction leaves ~1e-18 km/s^2
        assert np.linalg.norm(srp - ref) <= 1e-8 * 6e-9


def test_shadow_entry_and_exit_times_of_a_leo_orbit_match_the_shadow_cones() -> None:
    """Penumbra entry, umbra entry, umbra exit, penumbra exit on a circular 500 km orbit at
    51.6 deg, DE421 Sun of 2026-01-01 held fixed, to 1 s (the penumbra lasts ~8 s)."""
    sun = position_km("sun", "earth", utc_to_tdb_jd(JD_2026))[0]
    a = RADIUS_km["earth"] + 500.0
    n = math.sqrt(GM_EARTH_km3_s2 / a**3)
    x0 = periapsis_state(a, 0.0, 51.6, raan_deg=100.0)
    p_hat, q_hat = x0[:3] / a, x0[3:] / np.linalg.norm(x0[3:])

    def r_at(t: float) -> np.ndarray:
        return a * (math.cos(n * t) * p_hat + math.sin(n * t) * q_hat)

    nu = _nu_fn()
    module_state = [lambda t: float(nu(r_at(t), sun, np.zeros(3))) - (1.0 - 1e-9),
                    lambda t: float(nu(r_at(t), sun, np.zeros(3))) - 1e-9]
    cone_side = [lambda t: 0.5 - (cone_state(r_at(t), sun) >= 1),
                  lambda t: 0.5 - (cone_state(r_at(t), sun) >= 2)]
    grid = np.arange(0.0, 2 * math.pi / n, 5.0)
    for f_mod, f_cone in zip(module_state, cone_side, strict=True):
        signs = np.sign([f_cone(t) for t in grid])
        edges = np.flatnonzero(np.diff(signs))
        assert len(edges) == 2  # one entry, one exit per orbit
        for k in edges:
            t_cone = brentq(f_cone, grid[k], grid[k + 1], xtol=1e-3)
            t_mod = brentq(f_mod, grid[k] - 5.0, grid[k + 1] + 5.0, xtol=1e-3)
            assert abs(t_mod - t_cone) < ONE_SECOND, (t_mod, t_cone)


@pytest.mark.parametrize(("x0", "t_end_s", "tol", "step", "rel"), [
    # GEO, no eclipse in January: x is linear in C_r to first order; the step 0.05 keeps the
    # cubic term of the central difference at ~3e-10 relative, integration noise far below
    (periapsis_state(42164.0, 0.001, 5.0), 2 * 86400.0, 1e-13, 0.05, 1e-6),
    # LEO through four eclipses, each shadow edge located and restarted at (integration
    # events): 1.7e-7 (DOP853) and 3.8e-7 (rkn12) at the default tolerance, independent of the
    # step from 0.05 to 0.2; before the events, ν's kinks stepped over left 1e-4 of noise
    (periapsis_state(6878.0, 0.01, 51.6, raan_deg=100.0), 6 * 3600.0, 1e-13, 0.1, 1e-6),
])
def test_cr_sensitivity_matches_central_differences(x0, t_end_s, tol, step, rel,
                                                     method) -> None:
    """A sail-like A/m = 1 m^2/kg, with the Sun and Moon as third bodies too."""
    surface = SurfaceForces(1.0, srp=True, c_r=1.3)
    prop = Propagator(earth_model("J2", ("sun", "moon"), surface=surface), params=("Cr",),
                      rtol=tol, atol=tol, method=method)
    t = np.array([0.0, t_end_s])
    kw = dict(epoch_jd_utc=JD_2026)
    col = prop.propagate(x0, t, **kw).sensitivity[-1, :, 0]
    hi = prop.propagate(x0, t, stm=False, param_values={"Cr": 1.3 + step}, **kw).states[-1]
    lo = prop.propagate(x0, t, stm=False, param_values={"Cr": 1.3 - step}, **kw).states[-1]
    fd = (hi - lo) / (2 * step)
    assert np.linalg.norm(col - fd) < rel * np.linalg.norm(fd), (col, fd)


def _symplectic_defect(phi: np.ndarray) -> float:
    """max |Φᵀ Γ Φ − Γ| (zero for the flow of a Hamiltonian, whatever its time dependence)."""
    gamma = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    return float(np.abs(phi.T @ gamma @ phi - gamma).max())


def test_srp_without_shadows_keeps_the_stm_symplectic() -> None:
    """Without shadows SRP is -∇(k/|r - r☉|): Φ is as symplectic as under gravity alone
    (3.6e-9 here, the integration of entries up to 1.8e4) through what would be two eclipses;
    with them ν(r) makes the force non-conservative: 0.08 (A/m = 1 m^2/kg, 500 km, 3 h).
    The Moon is read only for its shadow."""
    x0 = periapsis_state(RADIUS_km["earth"] + 500.0, 0.0, 51.6, raan_deg=100.0)
    t = np.array([0.0, 3 * 3600.0])
    defects = {}
    for shadows in (False, True):
        model = earth_model("J2", ("sun",), surface=SurfaceForces(1.0, srp=True,
                                                                  shadows=shadows))
        assert model.ephemeris_bodies == (("moon", "sun") if shadows else ("sun",))
        phi = Propagator(model).propagate(x0, t, epoch_jd_utc=JD_2026).stm[-1]
        defects[shadows] = _symplectic_defect(phi)
    assert defects[False] < 1e-8 < 1e-3 < defects[True], defects

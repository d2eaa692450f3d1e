"""Atmospheric drag: heights against an exact geodetic conversion, densities and accelerations
against NumPy written here from Montenbruck & Gill §3.5 and Vallado Table 8-4, the King-Hele
decay rate of a circular orbit, and the STM (with ∂a/∂v) and ∂x/∂C_d against central
differences."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tapp.constants import GM_EARTH_km3_s2, OMEGA_EARTH_rad_s
from tapp.dynamics import Propagator
from tapp.dynamics.atmosphere import density_kg_m3, drag_acceleration, height_km
from tapp.dynamics.equations import build_equations
from tapp.dynamics.spec import ExponentialLayer, SurfaceForces, earth_model
from tests.tapp.dynamics.conftest import periapsis_state

JD_2026 = 2461041.5  # 2026-01-01T00:00 UTC
MU = GM_EARTH_km3_s2
WGS84_A, WGS84_F = 6378.137, 1.0 / 298.257223563  # NIMA TR8350.2 Table 3.1
ROUNDING = 1e-12  # two double evaluations of the same closed form
THIRTY_METRES_km = 0.030

# Montenbruck & Gill (2000) Table 3.8, rows typed from the book (height km, ρ_min, ρ_max
# in g/km^3), mean solar activity.
HP_ROWS = {100.0: (497400.0, 497400.0), 170.0: (800.8, 875.8), 400.0: (2.249, 7.492),
           500.0: (0.3916, 2.042), 1000.0: (0.001150, 0.01810)}
HP_NEXT = {100.0: (120.0, 24900.0, 24900.0), 170.0: (180.0, 528.3, 601.0),
           400.0: (420.0, 1.558, 5.684), 500.0: (520.0, 0.2819, 1.605)}


def _geodetic_height(r: np.ndarray) -> float:
    """Height above WGS84 by Newton iteration on the latitude (exact to < 1 mm)."""
    e2 = WGS84_F * (2 - WGS84_F)
    p, z = math.hypot(r[0], r[1]), r[2]
    lat = math.atan2(z, p * (1 - e2))
    for _ in range(10):
        n = WGS84_A / math.sqrt(1 - e2 * math.sin(lat) ** 2)
        h = p / math.cos(lat) - n if abs(lat) < 1.0 else z / math.sin(lat) - n * (1 - e2)
        lat = math.atan2(z, p * (1 - e2 * n / (n + h)))
    return h


@pytest.mark.parametrize("h_km", [100.0, 400.0, 1000.0])
@pytest.mark.parametrize("lat_deg", [0.0, 30.0, 45.0, 60.0, 89.0])
def test_height_is_within_30_m_of_the_geodetic_height(h_km: float, lat_deg: float) -> None:
    e2 = WGS84_F * (2 - WGS84_F)
    lat = math.radians(lat_deg)
    n = WGS84_A / math.sqrt(1 - e2 * math.sin(lat) ** 2)
    r = np.array([(n + h_km) * math.cos(lat) * math.cos(0.4),
                  (n + h_km) * math.cos(lat) * math.sin(0.4),
                  (n * (1 - e2) + h_km) * math.sin(lat)])
    assert _geodetic_height(r) == pytest.approx(h_km, abs=1e-6)
    x = ca.SX.sym("x", 3)
    got = float(ca.Function("h", [x], [height_km(x)])(r))
    assert abs(got - h_km) < THIRTY_METRES_km


def _rho_fn(atmosphere: str) -> ca.Function:
    r, s = ca.SX.sym("r", 3), ca.SX.sym("s", 3)
    return ca.Function("rho", [r, s], [density_kg_m3(atmosphere, r, s)])


def _equatorial(h_km: float, lon_rad: float) -> np.ndarray:
    return (WGS84_A + h_km) * np.array([math.cos(lon_rad), math.sin(lon_rad), 0.0])


@pytest.mark.parametrize("h_km", sorted(HP_ROWS))
def test_harris_priester_reproduces_the_table_at_apex_and_antapex(h_km: float) -> None:
    """On the equator, the Sun in the equator plane: at the bulge apex (30 deg east of the
    Sun) ρ = ρ_max, opposite ρ = ρ_min (cos^n(ψ/2) = 1 and 0)."""
    sun = 1.5e8 * np.array([1.0, 0.0, 0.0])
    lag = math.radians(30.0)
    rho = _rho_fn("harris_priester")
    rho_min, rho_max = (v * 1e-12 for v in HP_ROWS[h_km])
    assert float(rho(_equatorial(h_km, lag), sun)) == pytest.approx(rho_max, rel=ROUNDING)
    assert float(rho(_equatorial(h_km, lag + math.pi), sun)) == pytest.approx(rho_min,
                                                                            rel=ROUNDING)


@pytest.mark.parametrize("h_km", [100.0, 175.0, 403.0, 517.5])
def test_harris_priester_interpolates_exponentially(h_km: float) -> None:
    """M&G eq. for h_i <= h < h_i+1: ρ = ρ_i exp((h_i - h)/H_i), H_i = (h_i - h_i+1)/ln(ρ_i+1/ρ_i),
    the bulge at ψ = 90 deg from the apex: cos^2(45 deg) = 1/2."""
    h_i = max(k for k in HP_NEXT if k <= h_km)
    h_next, next_min, next_max = HP_NEXT[h_i]
    sun = 1.5e8 * np.array([1.0, 0.0, 0.0])
    ref = []
    for rho_i, rho_next in zip(HP_ROWS[h_i], (next_min, next_max), strict=True):
        scale = (h_i - h_next) / math.log(rho_next / rho_i)
        ref.append(rho_i * 1e-12 * math.exp((h_i - h_km) / scale))
    expected = ref[0] + (ref[1] - ref[0]) * 0.5
    got = float(_rho_fn("harris_priester")(_equatorial(h_km, math.radians(120.0)), sun))
    assert got == pytest.approx(expected, rel=ROUNDING)


def test_exponential_density_is_vallados_400_km_band() -> None:
    """Vallado (2013) Table 8-4: h0 = 400 km, ρ0 = 3.725e-12 kg/m^3, H = 58.515 km."""
    for h_km in (300.0, 400.0, 450.0, 700.0):
        got = float(_rho_fn("exponential")(_equatorial(h_km, 1.0), np.ones(3)))
        assert got == pytest.approx(3.725e-12 * math.exp(-(h_km - 400.0) / 58.515),
                                    rel=ROUNDING)


def test_exponential_density_takes_its_layer() -> None:
    """Vallado (2013) Table 8-4's 150 km band as the layer: 2.070e-9 kg/m^3, H = 22.523 km."""
    layer = ExponentialLayer(2.070e-9, 150.0, 22.523)
    r, s = ca.SX.sym("r", 3), ca.SX.sym("s", 3)
    fn = ca.Function("rho", [r, s], [density_kg_m3("exponential", r, s, layer)])
    got = float(fn(_equatorial(172.0, 1.0), np.ones(3)))
    assert got == pytest.approx(2.070e-9 * math.exp(-22.0 / 22.523), rel=ROUNDING)


def test_drag_acceleration_matches_numpy() -> None:
    """a = -1/2 C_d (A/m) ρ |v_r| v_r, v_r = v - ω x r, in SI then converted to km/s^2."""
    r, v, rho, cd = ca.SX.sym("r", 3), ca.SX.sym("v", 3), ca.SX.sym("rho"), ca.SX.sym("cd")
    fn = ca.Function("a", [r, v, rho, cd], [drag_acceleration(r, v, rho, cd, 0.015)])
    r0 = np.array([4000.0, -5000.0, 2500.0])
    v0 = np.array([5.0, 3.5, -4.0])
    v_rel_m_s = 1e3 * (v0 - np.cross([0.0, 0.0, OMEGA_EARTH_rad_s], r0))
    ref_m_s2 = -0.5 * 2.3 * 0.015 * 4e-12 * np.linalg.norm(v_rel_m_s) * v_rel_m_s
    got = np.array(fn(r0, v0, 4e-12, 2.3)).ravel()
    assert np.linalg.norm(got - ref_m_s2 / 1e3) <= ROUNDING * np.linalg.norm(ref_m_s2 / 1e3)


def test_semi_major_axis_decays_at_the_king_hele_rate() -> None:
    """Circular equatorial orbit at 400 km, J0 + exponential drag, A/m = 0.01, C_d = 2.2, one
    day. For a circular orbit da/dt = -C_d (A/m) ρ(a) √(μ a) (King-Hele 1987); the
    co-rotating atmosphere of an equatorial prograde orbit scales v_r by (1 - ω a/v), so
    da/dt gets (1 - ω a/v)^2 (0.875 here). That rate, integrated with SciPy over the day
    (ρ changes by 0.6 %), must match the decay of the osculating a to 1 %."""
    surface = SurfaceForces(0.01, atmosphere="exponential", c_d=2.2)
    prop = Propagator(earth_model("J0", surface=surface))
    a0 = WGS84_A + 400.0
    x0 = np.array([a0, 0.0, 0.0, 0.0, math.sqrt(MU / a0), 0.0])
    t_end = 86400.0
    x1 = prop.propagate(x0, [t_end], stm=False).states[-1]
    a1 = 1.0 / (2.0 / np.linalg.norm(x1[:3]) - x1[3:] @ x1[3:] / MU)

    def rate(_t, a):
        rho = 3.725e-12 * math.exp(-(a[0] - WGS84_A - 400.0) / 58.515)
        factor = (1.0 - OMEGA_EARTH_rad_s * a[0] / math.sqrt(MU / a[0])) ** 2
        return [-2.2 * 0.01 * rho * math.sqrt(MU * 1e9 * a[0] * 1e3) * factor / 1e3]  # km/s

    ref = solve_ivp(rate, (0.0, t_end), [a0], rtol=1e-10, atol=1e-12).y[0, -1]
    assert a0 - ref > 0.3  # a measurable decay (km)
    assert abs((a0 - a1) - (a0 - ref)) < 0.01 * (a0 - ref), (a0 - a1, a0 - ref)


TIGHT = dict(rtol=1e-13, atol=1e-13)
DELTA = np.array([1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5])


# Harris-Priester's ln ρ is piecewise linear in h (M&G's exponential interpolation): ∂ρ/∂h
# jumps at each table height. The integrators locate those heights (integration events) and
# restart there, so the STM agrees with central differences as for the smooth exponential
# atmosphere (measured 3e-9; stepped over, the kinks left 2.5e-4). Drag itself changes these
# STM columns by 1 to 4 % over the 3 h.
@pytest.mark.parametrize(("atmosphere", "rel"), [("exponential", 1e-6),
                                                 ("harris_priester", 1e-7)])
def test_stm_with_drag_matches_central_differences(atmosphere: str, rel: float) -> None:
    """A/m = 0.05 m^2/kg at 300 km, e = 0.001, i = 51.6 deg, 3 h: Φ needs ∂a/∂v."""
    surface = SurfaceForces(0.05, atmosphere=atmosphere, c_d=2.2)
    prop = Propagator(earth_model("J2", surface=surface), **TIGHT)
    x0 = periapsis_state(WGS84_A + 300.0, 0.001, 51.6, raan_deg=30.0)
    t = np.array([0.0, 3 * 3600.0])
    kw = dict(epoch_jd_utc=JD_2026)
    phi = prop.propagate(x0, t, **kw).stm[-1]
    fd = np.empty((6, 6))
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = DELTA[j]
        plus = prop.propagate(x0 + dx, t, stm=False, **kw).states[-1]
        minus = prop.propagate(x0 - dx, t, stm=False, **kw).states[-1]
        fd[:, j] = (plus - minus) / (2 * DELTA[j])
    err = np.linalg.norm(phi - fd, axis=0) / np.linalg.norm(fd, axis=0)
    assert err.max() < rel, err


# x is linear in C_d to first order: Richardson's extrapolation of the central differences
# at steps 0.2 and 0.1, (4 D(0.1) - D(0.2)) / 3, cancels their quadratic term (9e-7 of ∂x/∂C_d
# at 0.2; the extrapolation is within 2e-9 of the difference at a step of 0.01). The
# sensitivity is integrated under step control on all components: with the state's alone it
# is 1.2e-7 off under Harris-Priester (3e-10 for the exponential atmosphere), 1.5e-10 here.
@pytest.mark.parametrize("atmosphere", ["exponential", "harris_priester"])
def test_cd_sensitivity_matches_central_differences(atmosphere: str) -> None:
    """∂x/∂C_d over 6 h at 300 km, A/m = 0.02 m^2/kg, C_d = 2.2, crossing the 300 km table
    height eight times under Harris-Priester."""
    surface = SurfaceForces(0.02, atmosphere=atmosphere, c_d=2.2)
    prop = Propagator(earth_model("J2", surface=surface), params=("Cd",), error_control="all",
                      **TIGHT)
    x0 = periapsis_state(WGS84_A + 300.0, 0.001, 51.6, raan_deg=30.0)
    t = np.array([0.0, 6 * 3600.0])
    kw = dict(epoch_jd_utc=JD_2026)
    traj = prop.propagate(x0, t, **kw)
    assert (len(traj.events) > 0) == (atmosphere == "harris_priester")

    def difference(step: float) -> np.ndarray:
        hi = prop.propagate(x0, t, stm=False, param_values={"Cd": 2.2 + step}, **kw)
        lo = prop.propagate(x0, t, stm=False, param_values={"Cd": 2.2 - step}, **kw)
        return (hi.states[-1] - lo.states[-1]) / (2 * step)

    fd = (4 * difference(0.1) - difference(0.2)) / 3
    col = traj.sensitivity[-1, :, 0]
    assert np.linalg.norm(col - fd) < 1e-7 * np.linalg.norm(fd), (col, fd)


def test_only_a_drag_variational_model_gets_the_velocity_block() -> None:
    """∂a/∂v enters A only when the variational model has drag: a J2 variational model along
    a drag trajectory keeps the zero block (the truncated variational equations)."""
    drag = earth_model("J2", surface=SurfaceForces(0.05, atmosphere="exponential"))
    x0 = periapsis_state(WGS84_A + 300.0, 0.001, 51.6)
    t = np.array([0.0, 3600.0])
    full = Propagator(drag, drag).propagate(x0, t).stm[-1]
    truncated = Propagator(drag, earth_model("J2")).propagate(x0, t).stm[-1]
    assert np.abs(full - truncated).max() > 1e-3 * np.abs(full).max()
    eqs = build_equations(drag, earth_model("J2"))
    assert eqs.bodies == ()

"""ΔDOR: the observable against independent NumPy/SciPy evaluations and far-field theory,
its partials against central differences, and the model's error paths."""

import numpy as np
import pytest
from scipy.optimize import brentq

from tapp.constants import C_LIGHT_km_s, OMEGA_EARTH_rad_s
from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation
from tapp.measurements import LightTime, Station
from tapp.measurements.ddor import DdorModel, projected_baseline_km, quasar_direction

THETA0_rad = 0.7
GOLDSTONE = Station.from_degrees("GOLDSTONE", 35.4267, -116.89, 1.0, 10.0)
CANBERRA = Station.from_degrees("CANBERRA", -35.4014, 148.9817, 0.69, 10.0)
MADRID = Station.from_degrees("MADRID", 40.4314, -4.2481, 0.83, 10.0)
T_s = np.array([0.0, 3600.0, 7200.0])
#: Spacecraft at lunar distance and at 30 000 km, moving 1 km/s (a straight line in tests that
#: need the motion exactly).
R0_km = {"lunar": np.array([-2.0e5, 3.0e5, 1.2e5]), "meo": np.array([1.5e4, -2.4e4, 9.0e3])}
V_km_s = np.array([0.6, -0.5, 0.62])
SEPARATION_rad = np.radians(5.0)
#: The model against the independent evaluations: a light time solved to 4 eps of 1.3 s is
#: 3.5e-10 km; brentq to 1e-16 s is 3e-11 km. Ten micrometres.
TEN_MICROMETRES_km = 1e-8
#: Partials vs central differences: exact partials (no light time) to truncation and rounding
#: (truncation h²/ρ² < 1e-14; rounding a few eps of ρ over the step, checked apart), 1e-6;
#: with light time the neglected dτ/dx, dt_B/dx are relative O(v/c) ~ 1e-5: 1e-4.
EXACT_REL = 1e-6
LIGHT_TIME_REL = 1e-4
STEP_R_km = 1e-3
STEP_V_km_s = 1e-4
#: Station steps: 1 m, and 1e-7 rad (0.5 m) in longitude.
STATION_STEPS = {"cylindrical": (1e-3, 1e-7, 1e-3), "ecef": (1e-3, 1e-3, 1e-3)}


def _orientation():
    return EarthOrientation.gmst_angle(THETA0_rad)


def _line(where):
    """Exact straight-line motion r(t) = r0 + v t, as a state callback and the states at T_s."""
    r0 = R0_km[where]

    def state_at(t_s):
        t = np.asarray(t_s, dtype=float)[..., None]
        return np.concatenate([r0 + V_km_s * t, np.broadcast_to(V_km_s, t.shape[:-1] + (3,))],
                              axis=-1)

    return state_at, state_at(T_s)


def _station_eci(station, t_s):
    """Independent: r = R3(θ0 + ω t)ᵀ r_f, the gmst model written out."""
    theta = THETA0_rad + OMEGA_EARTH_rad_s * np.asarray(t_s, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    x, y, z = station.r_ecef_km
    return np.stack([c * x - s * y, s * x + c * y, np.full_like(theta, z)], axis=-1)


def _quasars(states):
    return quasar_direction(states[:, :3], SEPARATION_rad, np.radians(30.0))


def test_quasar_direction_separation_and_north():
    s = np.array([[1.0, 2.0, 0.5], [-3.0, 0.1, -2.0]])
    q = quasar_direction(s, SEPARATION_rad, 0.0)
    s_hat = s / np.linalg.norm(s, axis=1)[:, None]
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(np.arccos(np.sum(q * s_hat, axis=1)), SEPARATION_rad, rtol=1e-9)
    # Position angle 0 is north: the declination grows by the separation.
    dec = np.arcsin(q[:, 2]) - np.arcsin(s_hat[:, 2])
    np.testing.assert_allclose(dec, SEPARATION_rad, rtol=1e-12)


def test_projected_baseline():
    b = np.array([[3.0, 4.0, 12.0]])
    assert projected_baseline_km(b, [[0.0, 0.0, 5.0]])[0] == pytest.approx(5.0, rel=1e-15)


@pytest.mark.parametrize("where", ["lunar", "meo"])
def test_instantaneous_against_numpy(where):
    _, x = _line(where)
    q = _quasars(x)
    model = DdorModel(GOLDSTONE, CANBERRA, _orientation())
    r_a, r_b = _station_eci(GOLDSTONE, T_s), _station_eci(CANBERRA, T_s)
    expected = (np.linalg.norm(x[:, :3] - r_b, axis=1) - np.linalg.norm(x[:, :3] - r_a, axis=1)
                + np.sum(q * (r_b - r_a), axis=1))
    np.testing.assert_allclose(model.compute(T_s, x, q)[:, 0], expected, rtol=0,
                               atol=TEN_MICROMETRES_km)


def test_light_time_at_lunar_distance_against_brentq():
    """Each equation of the module docstring solved independently by bracketing."""
    state_at, x = _line("lunar")
    q = _quasars(x)
    model = DdorModel(GOLDSTONE, MADRID, _orientation(), LightTime(False, state_at))
    expected = []
    for t, s_q in zip(T_s, q, strict=True):
        r_a = _station_eci(GOLDSTONE, t)

        def pos(time):
            return state_at(np.array([time]))[0, :3]

        tau_a = brentq(lambda tau, t=t, r_a=r_a: C_LIGHT_km_s * tau
                       - np.linalg.norm(pos(t - tau) - r_a), 0.5, 2.0, xtol=1e-16)
        t_e = t - tau_a
        # Solved for t_B - t_e, not t_B: an absolute time of 7200 s rounds to 1e-12 s (0.3 mm).
        tau_b = brentq(lambda tb, t_e=t_e: C_LIGHT_km_s * tb
                       - np.linalg.norm(pos(t_e) - _station_eci(MADRID, t_e + tb)),
                       0.5, 2.0, xtol=1e-16)
        dt_q = brentq(lambda d, t=t, s_q=s_q, r_a=r_a: C_LIGHT_km_s * d
                      + s_q @ (_station_eci(MADRID, t + d) - r_a), -0.1, 0.1, xtol=1e-18)
        expected.append(C_LIGHT_km_s * (tau_b - tau_a) - C_LIGHT_km_s * dt_q)
    np.testing.assert_allclose(model.compute(T_s, x, q)[:, 0], expected, rtol=0,
                               atol=TEN_MICROMETRES_km)


def test_far_field_limit():
    """Quasar along the line of sight of a source at D = 1e9 km: only the wavefront's
    curvature is left, ddor = (|r_B⊥|² - |r_A⊥|²) / (2 D) + O(r_st³ / D²) (1e-6 km)."""
    distance_km = 1e9
    s_hat = np.array([0.48, -0.6, 0.64])
    x = np.tile(np.concatenate([distance_km * s_hat, np.zeros(3)]), (T_s.size, 1))
    q = np.tile(s_hat, (T_s.size, 1))
    got = DdorModel(GOLDSTONE, CANBERRA, _orientation()).compute(T_s, x, q)[:, 0]
    perp2 = [np.sum(r * r, axis=1) - (r @ s_hat) ** 2
             for r in (_station_eci(GOLDSTONE, T_s), _station_eci(CANBERRA, T_s))]
    np.testing.assert_allclose(got, (perp2[1] - perp2[0]) / (2 * distance_km), rtol=0,
                               atol=1e-6)


def _light_time(on):
    return LightTime(two_way=False) if on else None


@pytest.mark.parametrize("light_time", [False, True])
@pytest.mark.parametrize("where", ["lunar", "meo"])
def test_state_partials_against_central_differences(where, light_time):
    _, x = _line(where)
    q = _quasars(x)
    model = DdorModel(GOLDSTONE, CANBERRA, _orientation(), _light_time(light_time))
    h = model.state_partials(T_s, x, q)[:, 0, :]
    fd = np.zeros_like(h)
    for i, step in enumerate([STEP_R_km] * 3 + [STEP_V_km_s] * 3):
        e = np.zeros(6)
        e[i] = step
        diff = model.compute(T_s, x + e, q) - model.compute(T_s, x - e, q)
        fd[:, i] = diff[:, 0] / (2 * step)
    rel = LIGHT_TIME_REL if light_time else EXACT_REL
    for block, step in ((slice(0, 3), STEP_R_km), (slice(3, 6), STEP_V_km_s)):
        size = np.linalg.norm(h[:, block], axis=1)
        err = np.linalg.norm(fd[:, block] - h[:, block], axis=1)
        # Rounding floor of the differences: a few eps of the ranges (|r|) over the step (and
        # the whole error where d/dv is exactly 0, without light time).
        floor = 8 * np.finfo(float).eps * np.linalg.norm(x[:, :3], axis=1) / step
        assert np.all(err <= rel * size + floor), (err, size, floor)


def _moved(station, parameters, i, step):
    p = station.location(parameters)
    p[i] += step
    if parameters == "cylindrical":
        return Station.from_cylindrical(station.name, *p)
    return Station.from_ecef(station.name, p)


@pytest.mark.parametrize("parameters", ["cylindrical", "ecef"])
@pytest.mark.parametrize("light_time", [False, True])
def test_station_partials_against_central_differences(parameters, light_time):
    _, x = _line("lunar")
    q = _quasars(x)
    lt = _light_time(light_time)
    model = DdorModel(GOLDSTONE, MADRID, _orientation(), lt)
    analytic = model.station_partials(T_s, x, q, parameters)
    rel = LIGHT_TIME_REL if light_time else EXACT_REL
    for which, got in enumerate(analytic):
        fd = np.zeros((T_s.size, 3))
        for i, step in enumerate(STATION_STEPS[parameters]):
            values = []
            for sign in (1, -1):
                pair = [GOLDSTONE, MADRID]
                pair[which] = _moved(pair[which], parameters, i, sign * step)
                values.append(DdorModel(*pair, _orientation(), lt).compute(T_s, x, q)[:, 0])
            fd[:, i] = (values[0] - values[1]) / (2 * step)
        np.testing.assert_allclose(got[:, 0, :], fd, rtol=rel,
                                   atol=rel * np.abs(got).max())


def test_quasar_cancels_a_shift_common_to_both_sources():
    """A station error moves the spacecraft's and the quasar's delays alike: with the quasar
    on the line of sight of a distant source, ∂ddor/∂p is ~ the wavefront curvature b/D."""
    distance_km = 1e9
    s_hat = np.array([0.48, -0.6, 0.64])
    x = np.tile(np.concatenate([distance_km * s_hat, np.zeros(3)]), (T_s.size, 1))
    q = np.tile(s_hat, (T_s.size, 1))
    wrt_a, wrt_b = DdorModel(GOLDSTONE, CANBERRA, _orientation()).station_partials(
        T_s, x, q, "ecef")
    assert np.abs(wrt_a).max() < 1e-5 and np.abs(wrt_b).max() < 1e-5


def test_errors():
    with pytest.raises(InputError, match="station_b"):
        DdorModel(GOLDSTONE, Station.from_degrees("G2", 35.4267, -116.89, 1.0), 0.0)
    with pytest.raises(InputError, match="one-way"):
        DdorModel(GOLDSTONE, CANBERRA, 0.0, LightTime(two_way=True))

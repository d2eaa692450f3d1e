"""Observables and their partials: finite differences, time derivatives, light time."""

import doctest

import numpy as np
import pytest

import tapp.measurements.observables
import tapp.measurements.visibility
from tapp.constants import C_LIGHT_km_s, GM_EARTH_km3_s2
from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tapp.measurements import (
    LightTime,
    MeasurementModel,
    Station,
    azimuth_elevation_rad,
    range_km,
    range_rate_km_s,
    solve_light_time,
)
from tapp.measurements.stations import station_state_eci
from tapp.orbit import Elements, kepler_states

ALL_KINDS = ("range", "range_rate", "azimuth", "elevation")
THETA0_rad = 1.3
T_s = np.array([0.0, 600.0, 1800.0])
#: Partials vs central differences: relative error of each (observable, r or v) block.
FD_REL = 1e-6
#: Steps. Position 1 m: truncation h^2 / (6 rho^2) < 1e-12 for rho > 400 km; rounding
#: eps rho / h < 1e-8 relative even at GEO range (4e4 km). Velocity 1 cm/s: range-rate is
#: linear in v (no truncation), rounding eps |v| / h ~ 2e-10.
STEP_R_km = 1e-3
STEP_V_km_s = 1e-5
#: Range-rate vs a 5-point time derivative of range (h = 0.05 s): truncation h^4 rho^(5) / 30
#: < 1e-13 km/s, rounding of 1e-12 km positions / 0.05 s ~ 3e-11 km/s. One micrometre per s.
ONE_MICROMETRE_PER_S_km_s = 1e-9
ONE_MICROMETRE_km = 1e-9
#: The first-order light-time partials neglect d tau / dx: O(v / c) = 3e-5 per block.
LIGHT_TIME_PARTIALS_REL = 1e-4

GEOMETRIES = {
    "LEO": Elements.from_degrees(6878.0, 0.001, 51.6, 30.0, 40.0, 200.0),
    "GEO-ish": Elements.from_degrees(42164.0, 0.01, 5.0, 80.0, 10.0, 120.0),
    "e0.2 periapsis": Elements.from_degrees(8500.0, 0.2, 30.0, 300.0, 60.0, 0.0),
}
STATIONS = {
    "Goldstone": Station.from_degrees("DSS-14", 35.4259, 243.1105, 1.002, 6.0),
    "equator": Station.from_degrees("EQ", 0.0, 10.0, 0.0),
    "Canberra": Station.from_degrees("DSS-43", -35.4024, 148.9813, 0.689, 6.0),
}
CASES = [(g, s) for g in GEOMETRIES for s in STATIONS]
ORIENTATIONS = {"gmst": EarthOrientation.gmst_angle(THETA0_rad),
                "iau2006": EarthOrientation.iau2006(Epoch.from_calendar(2026, 1, 1))}


def _states(geometry):
    return kepler_states(GEOMETRIES[geometry].to_array(), T_s)


def _blockwise_close(fd, analytic, rel):
    """Each (row, r-block) and (row, v-block) within rel of its norm (or ~0 when zero)."""
    for block in (slice(0, 3), slice(3, 6)):
        err = np.linalg.norm(fd[..., block] - analytic[..., block], axis=-1)
        size = np.linalg.norm(analytic[..., block], axis=-1)
        assert np.all(err <= rel * size + 1e-15), (err / np.maximum(size, 1e-300)).max()


def _rounding_floor(x, step):
    """Rounding error of a central difference of the four observables, shape (N, 4).

    A few eps of each observable's scale (range ~ |r|, range-rate ~ |v|, angles ~ 2 pi)
    divided by the step: the floor for partials that are zero or nearly so.
    """
    scale = np.stack([np.linalg.norm(x[:, :3], axis=1), np.linalg.norm(x[:, 3:], axis=1),
                      np.full(len(x), 2 * np.pi), np.full(len(x), 2 * np.pi)], axis=-1)
    return 8 * np.finfo(float).eps * scale / step


def _fd_state_jacobian(model, t_s, x):
    out = np.zeros(x.shape[:1] + (len(model.kinds), 6))
    angle = np.array([k in ("azimuth",) for k in model.kinds])
    for j in range(6):
        h = STEP_R_km if j < 3 else STEP_V_km_s
        dx = np.zeros(6)
        dx[j] = h
        diff = model.compute(t_s, x + dx) - model.compute(t_s, x - dx)
        diff[:, angle] = np.angle(np.exp(1j * diff[:, angle]))
        out[..., j] = diff / (2 * h)
    return out


@pytest.mark.parametrize(("geometry", "station"), CASES)
@pytest.mark.parametrize("orientation", ["gmst", "iau2006"])
def test_state_partials_against_central_differences(geometry, station, orientation):
    model = MeasurementModel(STATIONS[station], ORIENTATIONS[orientation], ALL_KINDS)
    x = _states(geometry)
    analytic = model.state_partials(T_s, x)
    assert analytic.shape == (3, 4, 6)
    _blockwise_close(_fd_state_jacobian(model, T_s, x), analytic, FD_REL)


def _instantaneous(model, t_s, x, r_ecef_km):
    """The instantaneous observables with the station at r_ecef_km, axes held at nominal."""
    attitude = model.orientation.attitude(t_s)
    station = station_state_eci(r_ecef_km, attitude)
    enu = np.einsum("nij,nj->ni", model.station.enu_from_eci(attitude),
                    x[:, :3] - station[:, :3])
    az, el = azimuth_elevation_rad(enu)
    return np.stack([range_km(x, station), range_rate_km_s(x, station), az, el], axis=-1)


@pytest.mark.parametrize(("geometry", "station"), CASES)
@pytest.mark.parametrize("parameters", ["cylindrical", "ecef"])
@pytest.mark.parametrize("orientation", ["gmst", "iau2006"])
def test_station_partials_against_central_differences(geometry, station, parameters,
                                                      orientation):
    model = MeasurementModel(STATIONS[station], ORIENTATIONS[orientation], ALL_KINDS)
    x = _states(geometry)
    analytic = model.station_partials(T_s, x, parameters)
    assert analytic.shape == (3, 4, 3)
    r_f = model.station.r_ecef_km
    if parameters == "cylindrical":
        p0 = model.station.location("cylindrical")
        # 1e-5 rad of longitude (64 m): a smaller step drowns d(range-rate)/d(lon) in the
        # rounding of v - v_st (eps 3 km/s against omega r_s h = 5e-9 km/s at h = 1e-7).
        steps = [STEP_R_km, 1e-5, STEP_R_km]

        def r_of(p):
            return np.array([p[0] * np.cos(p[1]), p[0] * np.sin(p[1]), p[2]])
    else:
        p0, steps = r_f.copy(), [STEP_R_km] * 3

        def r_of(p):
            return p

    for j in range(3):
        dp = np.zeros(3)
        dp[j] = steps[j]
        diff = _instantaneous(model, T_s, x, r_of(p0 + dp)) - _instantaneous(
            model, T_s, x, r_of(p0 - dp)
        )
        diff[:, 2] = np.angle(np.exp(1j * diff[:, 2]))
        fd = diff / (2 * steps[j])
        err = np.abs(fd - analytic[..., j])
        assert np.all(err <= FD_REL * np.abs(analytic[..., j]) + _rounding_floor(x, steps[j]))


def test_kernel_reproduces_the_model():
    model = MeasurementModel(STATIONS["Goldstone"], THETA0_rad, ALL_KINDS)
    x = _states("LEO")
    assert np.allclose(_instantaneous(model, T_s, x, model.station.r_ecef_km),
                       model.compute(T_s, x), rtol=1e-15, atol=1e-15)


def test_bias_partials_and_biases():
    x = _states("GEO-ish")
    plain = MeasurementModel(STATIONS["Canberra"], THETA0_rad, ALL_KINDS)
    biased = MeasurementModel(STATIONS["Canberra"], THETA0_rad, ALL_KINDS, range_bias_km=0.012,
                              range_rate_bias_km_s=-3e-5)
    diff = biased.compute(T_s, x) - plain.compute(T_s, x)
    assert np.allclose(diff, [[0.012, -3e-5, 0.0, 0.0]] * 3, rtol=1e-9, atol=0)
    partials = biased.bias_partials(T_s)
    assert partials.shape == (3, 4, 3)
    assert np.array_equal(partials[0], [[1, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 0]])
    assert np.array_equal(
        MeasurementModel(STATIONS["Canberra"], 0.0, ("elevation", "range")).bias_partials(T_s)[1],
        [[0, 0, 0], [1, 0, 0]],
    )


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
def test_angle_partials_are_zero_in_velocity_and_kinds_select_columns(geometry):
    x = _states(geometry)
    full = MeasurementModel(STATIONS["Goldstone"], THETA0_rad, ALL_KINDS)
    some = MeasurementModel(STATIONS["Goldstone"], THETA0_rad, ("elevation", "range"))
    assert np.array_equal(full.state_partials(T_s, x)[:, 2:, 3:], np.zeros((3, 2, 3)))
    assert np.array_equal(some.compute(T_s, x), full.compute(T_s, x)[:, [3, 0]])
    assert np.array_equal(some.state_partials(T_s, x), full.state_partials(T_s, x)[:, [3, 0]])


def _five_point_derivative(f, t_s, h):
    return (-f(t_s + 2 * h) + 8 * f(t_s + h) - 8 * f(t_s - h) + f(t_s - 2 * h)) / (12 * h)


LIGHT_TIMES = {
    "none": None,
    "two-way, callback": "callback-2",
    "one-way, callback": "callback-1",
}


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
@pytest.mark.parametrize("light", list(LIGHT_TIMES))
def test_range_rate_is_the_time_derivative_of_range_along_a_kepler_arc(geometry, light):
    elements = GEOMETRIES[geometry].to_array()

    def arc(t):
        return kepler_states(elements, t)

    spec = LIGHT_TIMES[light]
    light_time = None if spec is None else LightTime(two_way=spec.endswith("2"), state_at=arc)
    model = MeasurementModel(STATIONS["Goldstone"], THETA0_rad, ("range", "range_rate"),
                             light_time=light_time)

    def rho(t):
        return model.compute(t, arc(t))[:, 0]

    fd = _five_point_derivative(rho, T_s, 0.05)
    computed = model.compute(T_s, arc(T_s))[:, 1]
    assert np.allclose(computed, fd, rtol=0, atol=ONE_MICROMETRE_PER_S_km_s)


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
def test_taylor_light_time_matches_the_exact_arc(geometry):
    # Third-order Taylor expansion: neglected tau^4 |d2a/dt2| / 24, tau^3 |d2a/dt2| / 6 < 1e-12.
    elements = GEOMETRIES[geometry].to_array()

    def arc(t):
        return kepler_states(elements, t)

    x = arc(T_s)
    exact = MeasurementModel(STATIONS["Canberra"], THETA0_rad, ALL_KINDS,
                             light_time=LightTime(state_at=arc)).compute(T_s, x)
    taylor = MeasurementModel(STATIONS["Canberra"], THETA0_rad, ALL_KINDS,
                              light_time=LightTime()).compute(T_s, x)
    assert np.allclose(taylor[:, 0], exact[:, 0], rtol=0, atol=ONE_MICROMETRE_km)
    assert np.allclose(taylor[:, 1], exact[:, 1], rtol=0, atol=ONE_MICROMETRE_PER_S_km_s)
    assert np.allclose(taylor[:, 2:], exact[:, 2:], rtol=0, atol=1e-12)


def test_light_time_of_a_receding_spacecraft_matches_the_closed_form():
    # A station on the pole is fixed in the gmst model (it rotates about z); a spacecraft
    # receding along the line of sight at v: c tau_d = d(t) - v tau_d and tau_u = tau_d, so
    # range = c d / (c + v), rate = c v / (c + v).
    station = Station("POLE", 0.5 * np.pi, 0.0, 0.0)
    u_hat = station.r_ecef_km / np.linalg.norm(station.r_ecef_km)
    d0_km, v_km_s = 20000.0, 10.0

    def arc(t):
        t = np.asarray(t, dtype=float)
        r = station.r_ecef_km + np.outer(d0_km + v_km_s * t, u_hat)
        return np.concatenate([r, np.broadcast_to(v_km_s * u_hat, r.shape)], axis=1)

    light_time = LightTime(two_way=True, state_at=arc)
    model = MeasurementModel(station, 0.0, ("range", "range_rate"), light_time=light_time)
    d_km = d0_km + v_km_s * T_s
    obs = model.compute(T_s, arc(T_s))
    c = C_LIGHT_km_s
    assert np.allclose(obs[:, 0], c * d_km / (c + v_km_s), rtol=0, atol=1e-9)
    assert np.allclose(obs[:, 1], c * v_km_s / (c + v_km_s), rtol=0, atol=1e-12)
    sol = solve_light_time(T_s, arc(T_s), station.r_ecef_km, 0.0, light_time)
    assert np.allclose(sol.tau_up_s, sol.tau_down_s, rtol=1e-14)
    # Without light time the same arc gives the geometric d and v.
    geometric = MeasurementModel(station, 0.0, ("range", "range_rate"))
    assert np.allclose(geometric.compute(T_s, arc(T_s)), np.stack([d_km, d_km * 0 + v_km_s], -1))


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
@pytest.mark.parametrize("two_way", [True, False])
def test_light_time_partials_within_v_over_c(geometry, two_way):
    light_time = LightTime(two_way=two_way)
    model = MeasurementModel(STATIONS["Goldstone"], THETA0_rad, ALL_KINDS, light_time=light_time)
    x = _states(geometry)
    _blockwise_close(_fd_state_jacobian(model, T_s, x), model.state_partials(T_s, x),
                     LIGHT_TIME_PARTIALS_REL)


def test_unknown_kind_is_an_input_error():
    with pytest.raises(InputError, match="kinds"):
        MeasurementModel(STATIONS["equator"], 0.0, ("range", "doppler"))


def test_docstring_examples():
    for module in (tapp.measurements.observables, tapp.measurements.visibility):
        assert doctest.testmod(module).failed == 0


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
@pytest.mark.parametrize("two_way", [True, False])
def test_light_time_station_partials_within_v_over_c(geometry, two_way):
    # Range and range-rate only: a station rebuilt from a moved Earth-fixed position also has
    # slightly turned ENU axes, which the angle partials (axes held fixed) leave out by design.
    kinds = ("range", "range_rate")
    light_time = LightTime(two_way=two_way)
    station = STATIONS["Canberra"]
    x = _states(geometry)
    model = MeasurementModel(station, THETA0_rad, kinds, light_time=light_time)
    analytic = model.station_partials(T_s, x, "ecef")
    for j in range(3):
        dr = np.zeros(3)
        dr[j] = STEP_R_km
        plus, minus = (
            MeasurementModel(Station.from_ecef("moved", station.r_ecef_km + sign * dr),
                             THETA0_rad, kinds, light_time=light_time).compute(T_s, x)
            for sign in (1.0, -1.0)
        )
        fd = (plus - minus) / (2 * STEP_R_km)
        err = np.abs(fd - analytic[..., j])
        floor = _rounding_floor(x, STEP_R_km)[:, :2]
        # The neglected coupling (dh/dt)(d tau/dp) is at most |rho_dot| / c per km in range
        # and |rho_ddot| / c per km in range-rate: bound rho_ddot by |dv|^2 / rho + gravity.
        station_now = model.station_eci(T_s)
        dv2 = np.sum((x[:, 3:] - station_now[:, 3:]) ** 2, axis=1)
        rho_ddot = dv2 / range_km(x, station_now) + GM_EARTH_km3_s2 / np.sum(x[:, :3] ** 2, 1)
        coupling = np.stack([np.sqrt(dv2), rho_ddot], axis=-1) / C_LIGHT_km_s
        assert np.all(err <= LIGHT_TIME_PARTIALS_REL * np.abs(analytic[..., j]) + coupling + floor)


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
def test_range_azimuth_elevation_invert_back_to_the_position(geometry):
    model = MeasurementModel(STATIONS["Goldstone"], THETA0_rad, ("range", "azimuth", "elevation"))
    x = _states(geometry)
    rho, az, el = model.compute(T_s, x).T
    enu = rho[:, None] * np.stack(
        [np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1
    )
    eci_from_enu = np.swapaxes(model.station.enu_from_eci(model.orientation.attitude(T_s)),
                               -1, -2)
    position = model.station_eci(T_s)[:, :3] + np.einsum("nij,nj->ni", eci_from_enu, enu)
    assert np.allclose(position, x[:, :3], rtol=0, atol=ONE_MICROMETRE_km)

"""Partials w.r.t. constant offsets of UT1 − UTC and the pole coordinates (IERS Conventions
2010 ch. 5), and w.r.t. the ΔDOR quasar's position: each against central differences of the
model with the EOP table itself shifted (or the quasar moved), plus the classic figures."""

import dataclasses
from functools import cache

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation, OMEGA_ERA_rad_s
from tapp.frames.time import Epoch
from tapp.io.eop_file import finals2000a
from tapp.measurements import LightTime, MeasurementModel, Station
from tapp.measurements.ddor import DdorModel, quasar_direction
from tapp.measurements.observables import wrap_angle_rad
from tapp.measurements.stations import station_eop_partials, station_state_eci
from tapp.orbit import Elements, kepler_states

EPOCH = Epoch.from_calendar(2026, 3, 10)
T_s = np.array([0.0, 5000.0, 40000.0, 100000.0])
GOLDSTONE = Station.from_degrees("GOLDSTONE", 35.4267, -116.89, 1.0, 10.0)
CANBERRA = Station.from_degrees("CANBERRA", -35.4014, 148.9817, 0.69, 10.0)
EQUATOR = Station.from_degrees("EQ", 0.0, 10.0, 0.0)
#: Central-difference steps: 0.1 s of UT1 − UTC (7e-6 rad) and 1e-5 rad (2") of pole. A
#: constant offset turns the stations rigidly, so the model is smooth in it and the central
#: difference errs by the third-order term, (ω δ)² / 6 < 2e-11 relative; ERFA's era00 rounds
#: ERA (26 turns of 0.0027 T_u since J2000) to ~4e-15 rad, 5e-10 of the UT1 step. A constant
#: shift of the table's column passes unchanged through the linear interpolation and the
#: Chebyshev fits (linear in the data), so the series' 1e-13 rad error cancels.
STEPS = {"ut1_s": ("ut1_minus_utc_s", 0.1), "xp_rad": ("xp_rad", 1e-5),
         "yp_rad": ("yp_rad", 1e-5)}
#: Exact partials against those differences (the brief's figure), above the rounding floor
#: (4 eps of each value over the step, checked apart: :func:`_assert_close`).
FD_REL = 1e-7
#: With light time the chain neglects dτ/dp: relative O(v/c) ~ 3e-5 (as the station
#: partials of test_observables).
LIGHT_TIME_REL = 1e-4
NAMES = tuple(STEPS)


@cache
def _table():
    return finals2000a()


def _shifted(name, sign):
    column, step = STEPS[name]
    table = _table()
    return EarthOrientation.iau2006(
        EPOCH, dataclasses.replace(table, **{column: getattr(table, column) + sign * step}))


def _central(name, evaluate):
    """(f(+h) − f(−h)) / 2h of ``evaluate(orientation)`` with the EOP column shifted."""
    step = STEPS[name][1]
    return (evaluate(_shifted(name, 1.0)) - evaluate(_shifted(name, -1.0))) / (2.0 * step)


def _orientation():
    return EarthOrientation.iau2006(EPOCH, _table())


def _assert_close(analytic, fd, rel, floor=0.0):
    """|analytic − fd| <= rel × the largest |fd| of each column (N, m) over the times, plus
    ``floor`` (the rounding of the differenced values)."""
    scale = np.max(np.abs(fd), axis=0, keepdims=True)
    err = np.abs(analytic - fd)
    assert np.all(err <= rel * scale + floor), np.max((err - floor) / scale)


def _rounding(values, name):
    """4 eps of the largest |value| of each column over the central difference's 2h."""
    return 4 * np.finfo(float).eps * np.max(np.abs(values), axis=0) / (2 * STEPS[name][1])


@pytest.mark.parametrize("station", [GOLDSTONE, CANBERRA, EQUATOR], ids=lambda s: s.name)
def test_station_state_partials_against_shifted_eop_table(station):
    analytic = station_eop_partials(station.r_ecef_km, _orientation().attitude(T_s))
    for j, name in enumerate(NAMES):
        fd = _central(name, lambda o: station_state_eci(station.r_ecef_km, o.attitude(T_s)))
        # Position and velocity, each as a vector; the velocity on the scale ω |dr/dp| (at
        # the equator dv/dx_p = ω ĉ × (g × r) = ω g (ĉ·r) vanishes).
        _assert_close(analytic[:, :3, j].reshape(-1, 1), fd[:, :3].reshape(-1, 1), FD_REL)
        dv_scale = OMEGA_ERA_rad_s * np.max(np.abs(fd[:, :3]))
        assert np.all(np.abs(analytic[:, 3:, j] - fd[:, 3:]) <= FD_REL * dv_scale)


def test_gmst_ut1_partial_is_the_model_clock_and_pole_refused():
    """Under gmst a UT1 offset δ turns θ0 + ω_E t into θ0 + ω_E (t + δ): the station of
    t + δ; the pole coordinates have no meaning there and are refused by name."""
    orientation = EarthOrientation.gmst_angle(1.3)
    analytic = station_eop_partials(GOLDSTONE.r_ecef_km, orientation.attitude(T_s), ("ut1_s",))
    h = 1e-3
    fd = (GOLDSTONE.state_eci(orientation, T_s + h) - GOLDSTONE.state_eci(orientation, T_s - h)
          ) / (2 * h)
    _assert_close(analytic[..., 0], fd, FD_REL)
    model = MeasurementModel(GOLDSTONE, orientation, ("range",))
    x = kepler_states(Elements.from_degrees(42164.0, 0.01, 5.0, 80.0, 10.0, 120.0).to_array(),
                      T_s)
    with pytest.raises(InputError, match="xp_rad"):
        model.eop_partials(T_s, x, ("ut1_s", "xp_rad"))
    with pytest.raises(InputError, match="gmst model has no polar motion"):
        DdorModel(GOLDSTONE, CANBERRA, orientation).eop_partials(T_s, x, x[:, :3], ("yp_rad",))


def test_one_millisecond_of_ut1_is_46_cm_at_the_equator():
    """The classic figure: ω R_e × 1 ms = 7.292e-5 rad/s × 6378.137 km × 1e-3 s = 46.5 cm."""
    dr = station_eop_partials(EQUATOR.r_ecef_km, _orientation().attitude(T_s), ("ut1_s",))
    shift_m = np.linalg.norm(dr[:, :3, 0], axis=-1) * 1e-3 * 1e3
    np.testing.assert_allclose(shift_m, OMEGA_ERA_rad_s * 6378.137 * 1e-3 * 1e3, rtol=1e-6)
    assert 0.465 < shift_m[0] < 0.466


GEOMETRIES = {
    "GEO-ish": Elements.from_degrees(42164.0, 0.01, 5.0, 80.0, 10.0, 120.0),
    "e0.2 periapsis": Elements.from_degrees(8500.0, 0.2, 30.0, 300.0, 60.0, 0.0),
}
KINDS = ("range", "range_rate", "azimuth", "elevation")


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
def test_observable_partials_against_shifted_eop_table(geometry):
    x = kepler_states(GEOMETRIES[geometry].to_array(), T_s)
    analytic = MeasurementModel(CANBERRA, _orientation(), KINDS).eop_partials(T_s, x)
    # Rounding of each kind's value: range; range-rate, from velocities of |v| km/s; angles.
    sizes = np.array([np.max(np.linalg.norm(x[:, :3], axis=1)),
                      np.max(np.linalg.norm(x[:, 3:], axis=1)) + 0.5, 2 * np.pi, np.pi])
    for j, name in enumerate(NAMES):
        fd = _central(name, lambda o: MeasurementModel(CANBERRA, o, KINDS).compute(T_s, x))
        step = STEPS[name][1]
        fd[:, 2] = wrap_angle_rad(fd[:, 2] * 2 * step) / (2 * step)  # azimuth across 0
        _assert_close(analytic[..., j], fd, FD_REL, _rounding(sizes[None, :], name))


@pytest.mark.parametrize(("kinds", "two_way"), [
    (("range", "range_rate"), True), (("range", "range_rate"), False),
    # count-based Doppler: the count difference of its ranges' partials (its row was left
    # zero before: an EOP consider set silently missed the Doppler's share)
    (("range", "doppler"), True)])
def test_light_time_observable_partials_within_v_over_c(kinds, two_way):
    light_time = LightTime(two_way=two_way)
    x = kepler_states(GEOMETRIES["GEO-ish"].to_array(), T_s)
    analytic = MeasurementModel(GOLDSTONE, _orientation(), kinds, light_time).eop_partials(T_s, x)
    for j, name in enumerate(NAMES):
        fd = _central(name, lambda o: MeasurementModel(GOLDSTONE, o, kinds, light_time
                                                       ).compute(T_s, x))
        _assert_close(analytic[..., j], fd, LIGHT_TIME_REL)
        assert np.all(np.abs(fd[:, 1]) > 0.0)


def _deep_space(distance_km=1.0e6):
    """A spacecraft at ``distance_km``, moving 20 km/s: a straight line (exact bounce
    states). 1e6 km keeps the rounding of its ranges (2e-10 km) below the checked figures."""
    r0 = np.array([0.7, -0.6, 0.3]) / np.linalg.norm([0.7, -0.6, 0.3]) * distance_km
    v = np.array([12.0, 15.0, -3.0])

    def state_at(t_s):
        t = np.asarray(t_s, dtype=float)[..., None]
        return np.concatenate([r0 + v * t, np.broadcast_to(v, t.shape[:-1] + (3,))], -1)

    return state_at, state_at(T_s)


@pytest.mark.parametrize("light", [False, True])
def test_ddor_eop_partials_against_shifted_eop_table(light):
    state_at, x = _deep_space()
    light_time = LightTime(False, state_at) if light else None
    q = quasar_direction(x[:, :3], np.radians(5.0), np.radians(30.0))
    analytic = DdorModel(GOLDSTONE, CANBERRA, _orientation(), light_time).eop_partials(T_s, x, q)
    for j, name in enumerate(NAMES):
        fd = _central(name, lambda o: DdorModel(GOLDSTONE, CANBERRA, o, light_time
                                                ).compute(T_s, x, q))
        _assert_close(analytic[..., j], fd, LIGHT_TIME_REL if light else FD_REL,
                      _rounding(np.linalg.norm(x[:, :3], axis=1), name))


def _radec(s):
    return np.arctan2(s[:, 1], s[:, 0]), np.arcsin(s[:, 2])


def _from_radec(ra, dec):
    return np.stack([np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)], -1)


@pytest.mark.parametrize("light", [False, True])
def test_ddor_quasar_partials_against_moved_quasar(light):
    """d ddor / d(Δα cos δ, Δδ) against the quasar moved in right ascension and declination;
    exact for the model with light time too (the delay's own dependence is kept)."""
    state_at, x = _deep_space()
    model = DdorModel(GOLDSTONE, CANBERRA, _orientation(),
                      LightTime(False, state_at) if light else None)
    q = quasar_direction(x[:, :3], np.radians(5.0), np.radians(30.0))
    ra, dec = _radec(q)
    analytic = model.quasar_partials(T_s, x, q)[:, 0]
    h = 1e-5  # rad: 0.1 km of delay on a 1e4 km baseline; truncation h² / 6 ~ 2e-11
    for j, (d_ra, d_dec) in enumerate([(h / np.cos(dec), 0.0 * dec), (0.0 * dec, h)]):
        plus = model.compute(T_s, x, _from_radec(ra + d_ra, dec + d_dec))
        minus = model.compute(T_s, x, _from_radec(ra - d_ra, dec - d_dec))
        fd = (plus - minus)[:, 0] / (2 * h)
        floor = 4 * np.finfo(float).eps * np.max(np.linalg.norm(x[:, :3], axis=1)) / (2 * h)
        _assert_close(analytic[:, j][:, None], fd[:, None], FD_REL, floor)


def test_eop_error_on_goldstone_canberra_as_a_ddor_error():
    """The worked number: a UT1 error worth 20 cm at Goldstone (the 15-30 cm class of EOP
    error) turns the Goldstone-Canberra baseline by δθ = 20 cm / r_s; the quasar 5° away
    removes all but (ŝ_sc − ŝ_q)·(g × b) δ, at most 2 sin(2.5°) |b| δθ ≈ 0.087 × 10,600 km ×
    3.8e-8 rad = 3.5 cm, the ~0.1 ns (3 cm) of the DSN's ΔDOR error budgets' EOP line
    (Thornton & Border 2003, ch. 7). Without the quasar it would be |g × b| δ, 40 cm."""
    _, x = _deep_space(1.496e8)  # 1 AU: the far-field formula below holds to ~1e-4
    q = quasar_direction(x[:, :3], np.radians(5.0), np.radians(30.0))
    model = DdorModel(GOLDSTONE, CANBERRA, _orientation())
    delta_ut1_s = 0.20e-3 / (GOLDSTONE.spin_radius_km * OMEGA_ERA_rad_s)  # 20 cm, km/(km/s)
    ddor_err_m = model.eop_partials(T_s, x, q, ("ut1_s",))[:, 0, 0] * delta_ut1_s * 1e3
    # Independent first-order figure: rotate both stations about the CIP by ω δ.
    attitude = _orientation().attitude(T_s)
    r_a, r_b = (station_state_eci(s.r_ecef_km, attitude)[:, :3] for s in (GOLDSTONE, CANBERRA))
    s_sc = x[:, :3] / np.linalg.norm(x[:, :3], axis=1)[:, None]
    moved_b = OMEGA_ERA_rad_s * delta_ut1_s * np.cross(attitude.spin_axis, r_b - r_a)
    # Far field: ddor ≈ −(ŝ_sc − ŝ_q)·b, so δddor = −(ŝ_sc − ŝ_q)·δb.
    expected_m = -np.sum((s_sc - q) * moved_b, axis=1) * 1e3
    np.testing.assert_allclose(ddor_err_m, expected_m, rtol=1e-3, atol=1e-5)
    assert np.all(np.abs(ddor_err_m) <= 2 * np.sin(np.radians(2.5)) *
                  np.linalg.norm(moved_b, axis=1) * 1e3 * 1.001)
    assert 0.005 < np.max(np.abs(ddor_err_m)) < 0.04  # metres: cm-class, not 40 cm
    assert np.all(np.linalg.norm(moved_b, axis=1) * 1e3 > 0.2)

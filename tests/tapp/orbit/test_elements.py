"""Classical elements <-> Cartesian, the anomalies and Kepler's equation."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tapp.constants import GM_EARTH_km3_s2
from tapp.errors import InputError
from tapp.orbit import (
    Elements,
    cartesian_to_elements,
    eccentric_to_true_anomaly,
    elements_to_cartesian,
    hyperbolic_to_true_anomaly,
    kepler_states,
    mean_to_eccentric_anomaly,
    mean_to_hyperbolic_anomaly,
    mean_to_true_anomaly,
    true_to_eccentric_anomaly,
    true_to_hyperbolic_anomaly,
    true_to_mean_anomaly,
)

#: Vallado's examples use mu = 398600.4418 km^3/s^2.
MU_VALLADO_km3_s2 = 398600.4418
EPS = np.finfo(float).eps
#: State round trips (coe -> rv -> coe -> rv), relative to |r| and |v|: measured maxima over
#: 2e5 random cases are 2.5e-14 (elliptic) and 4.5e-12 (hyperbolic, |M| <= 30: the rebuilt
#: position grows as e^|H| while H carries a fixed relative error).
ELLIPTIC_ROUND_TRIP_REL = 1e-12
HYPERBOLIC_ROUND_TRIP_REL = 1e-10
#: Angles of a non-degenerate orbit (e, sin i >= 1e-3) come back within eps / 1e-3 ~ 1e-13.
ANGLE_ROUND_TRIP_rad = 1e-10


def _angle_diff(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def _assert_same_state(x1, x2, rel):
    x1, x2 = np.atleast_2d(x1), np.atleast_2d(x2)
    dr = np.linalg.norm(x1[:, :3] - x2[:, :3], axis=-1) / np.linalg.norm(x1[:, :3], axis=-1)
    dv = np.linalg.norm(x1[:, 3:] - x2[:, 3:], axis=-1) / np.linalg.norm(x1[:, 3:], axis=-1)
    assert dr.max() < rel and dv.max() < rel, (dr.max(), dv.max())


# --- Published examples ------------------------------------------------------------------------


def test_rv2coe_vallado_example_2_5():
    # Vallado, Fundamentals of Astrodynamics and Applications, Example 2-5:
    # r = (6524.834, 6862.875, 6448.296) km, v = (4.901327, 5.533756, -1.976341) km/s ->
    # p 11067.790 km, a 36127.343 km, e 0.832853, i 87.870, raan 227.898, argp 53.38,
    # nu 92.335 deg. The book works in canonical units and rounds; p and a agree to 0.01 km.
    state = np.array([6524.834, 6862.875, 6448.296, 4.901327, 5.533756, -1.976341])
    el = Elements.from_cartesian(state, MU_VALLADO_km3_s2)
    assert abs(el.p_km - 11067.790) < 0.01
    assert abs(el.a_km - 36127.343) < 0.01
    assert abs(el.e - 0.832853) < 1e-6
    assert abs(np.degrees(el.i_rad) - 87.870) < 1e-3
    assert abs(np.degrees(el.raan_rad) - 227.898) < 1e-3
    assert abs(np.degrees(el.argp_rad) - 53.38) < 5e-3
    assert abs(np.degrees(el.true_anomaly_rad) - 92.335) < 1e-3


def test_coe2rv_vallado_example_2_6():
    # Vallado, Example 2-6: p 11067.790 km, e 0.83285, i 87.87, raan 227.89, argp 53.38,
    # nu 92.335 deg -> r = (6525.368, 6861.532, 6449.119) km,
    # v = (4.902279, 5.533140, -1.975710) km/s (printed to 1 m and 1 mm/s).
    e = 0.83285
    nu = np.radians(92.335)
    el = Elements.from_degrees(11067.790 / (1 - e * e), e, 87.87, 227.89, 53.38, 0.0)
    el = dataclasses.replace(el, M_rad=float(true_to_mean_anomaly(nu, e)))
    state = el.to_cartesian(MU_VALLADO_km3_s2)
    assert np.allclose(state[:3], [6525.368, 6861.532, 6449.119], rtol=0, atol=5e-4)
    assert np.allclose(state[3:], [4.902279, 5.533140, -1.975710], rtol=0, atol=5e-7)


# --- Round trips -------------------------------------------------------------------------------

angle = st.floats(0.0, 2 * np.pi, exclude_max=True)


@settings(max_examples=300)
@given(
    st.floats(6600.0, 50000.0),
    st.floats(0.0, 0.95),
    st.floats(0.0, np.pi),
    angle,
    angle,
    st.floats(-20.0, 20.0),
)
def test_elliptic_round_trip(a, e, i, raan, argp, m):
    el = np.array([a, e, i, raan, argp, m])
    x = elements_to_cartesian(el)
    el2 = cartesian_to_elements(x)
    x2 = elements_to_cartesian(el2)
    _assert_same_state(x, x2, ELLIPTIC_ROUND_TRIP_REL)
    x3 = elements_to_cartesian(cartesian_to_elements(x2))
    _assert_same_state(x2, x3, ELLIPTIC_ROUND_TRIP_REL)
    assert abs(el2[0] / a - 1) < ELLIPTIC_ROUND_TRIP_REL and abs(el2[1] - e) < 1e-12
    assert abs(el2[2] - i) < 1e-12 * (1 + 1 / max(np.sin(i), 1e-4))
    if e > 1e-3 and np.sin(i) > 1e-3:
        assert _angle_diff(el2[3:], el[3:]).max() < ANGLE_ROUND_TRIP_rad


@settings(max_examples=300)
@given(
    st.floats(6600.0, 50000.0),
    st.floats(1.05, 5.0),
    st.floats(0.0, np.pi),
    angle,
    angle,
    st.floats(-30.0, 30.0),
)
def test_hyperbolic_round_trip(r_periapsis_km, e, i, raan, argp, m):
    el = np.array([r_periapsis_km / (1 - e), e, i, raan, argp, m])
    x = elements_to_cartesian(el)
    el2 = cartesian_to_elements(x)
    assert el2[0] < 0 and el2[1] > 1
    _assert_same_state(x, elements_to_cartesian(el2), HYPERBOLIC_ROUND_TRIP_REL)
    assert abs(el2[5] - m) < HYPERBOLIC_ROUND_TRIP_REL * max(1.0, abs(m))  # M keeps its sign
    if np.sin(i) > 1e-3:
        assert _angle_diff(el2[2:5], el[2:5]).max() < ANGLE_ROUND_TRIP_rad


def test_arrays_broadcast_over_leading_axes():
    el = np.array([[7000.0, 0.01, 0.5, 1.0, 2.0, 3.0], [-9000.0, 1.5, 2.0, 0.1, 0.2, -0.3]])
    stack = np.stack([el, el, el])  # (3, 2, 6)
    x = elements_to_cartesian(stack)
    assert x.shape == (3, 2, 6)
    assert np.array_equal(x[1], elements_to_cartesian(el))
    assert cartesian_to_elements(x).shape == (3, 2, 6)


# --- Special cases (module docstring conventions) ---------------------------------------------


def test_circular_inclined_returns_argument_of_latitude():
    el = np.array([7000.0, 0.0, 0.5, 1.0, 2.0, 0.3])
    x = elements_to_cartesian(el)
    el2 = cartesian_to_elements(x)
    assert el2[1] < 1e-14 and el2[4] == 0.0
    assert abs(el2[3] - 1.0) < 1e-13
    assert _angle_diff(el2[5], 2.3) < 1e-13  # M = nu = u = argp + M
    _assert_same_state(x, elements_to_cartesian(el2), ELLIPTIC_ROUND_TRIP_REL)


def test_elliptic_equatorial_returns_longitude_of_periapsis():
    el = np.array([8000.0, 0.1, 0.0, 1.0, 2.0, 0.5])
    el2 = cartesian_to_elements(elements_to_cartesian(el))
    assert el2[2] == 0.0 and el2[3] == 0.0
    assert _angle_diff(el2[4], 3.0) < 1e-13  # longitude of periapsis = raan + argp
    assert _angle_diff(el2[5], 0.5) < 1e-13
    _assert_same_state(elements_to_cartesian(el), elements_to_cartesian(el2), 1e-14)


def test_retrograde_equatorial_measures_longitude_in_the_direction_of_motion():
    el = np.array([8000.0, 0.1, np.pi, 1.0, 2.0, 0.5])
    x = elements_to_cartesian(el)
    el2 = cartesian_to_elements(x)
    assert el2[2] == np.pi and el2[3] == 0.0
    # Periapsis direction (cos(raan - argp), sin(raan - argp), 0) = (cos w', -sin w', 0).
    assert _angle_diff(el2[4], 2.0 - 1.0) < 1e-13
    _assert_same_state(x, elements_to_cartesian(el2), 1e-14)


def test_circular_equatorial_returns_true_longitude():
    el = np.array([42164.0, 0.0, 0.0, 1.0, 2.0, 0.5])
    x = elements_to_cartesian(el)
    el2 = cartesian_to_elements(x)
    assert el2[2] == 0.0 and el2[3] == 0.0 and el2[4] == 0.0
    assert _angle_diff(el2[5], 3.5) < 1e-13
    assert _angle_diff(np.arctan2(x[1], x[0]), 3.5) < 1e-13
    _assert_same_state(x, elements_to_cartesian(el2), 1e-14)


@pytest.mark.parametrize("e", [1.0 - 1e-6, 1.0 + 1e-6, 0.9999, 1.0001])
@pytest.mark.parametrize("m", [0.0, 1e-9, -1e-4, 0.3])
def test_near_parabolic_is_finite_and_round_trips(e, m):
    el = np.array([7000.0 / (1.0 - e), e, 0.4, 0.5, 0.6, m])
    x = elements_to_cartesian(el)
    assert np.all(np.isfinite(x))
    el2 = cartesian_to_elements(x)
    assert np.all(np.isfinite(el2))
    # Near e = 1, a and 1 - e carry relative errors ~ eps / |1 - e| (cartesian_to_elements):
    # measured 5e-10 at |1 - e| = 1e-6, 1e-11 at 1e-4.
    _assert_same_state(x, elements_to_cartesian(el2), 100 * EPS / abs(1.0 - e))


def test_parabola_and_inconsistent_elements_raise():
    with pytest.raises(InputError, match="parabolic"):
        elements_to_cartesian([np.inf, 1.0, 0.1, 0.0, 0.0, 0.0])
    r = 7000.0
    escape = np.array([r, 0.0, 0.0, 0.0, np.sqrt(2 * GM_EARTH_km3_s2 / r), 0.0])
    with pytest.raises(InputError, match="parabolic"):
        cartesian_to_elements(escape)
    with pytest.raises(InputError, match="a_km"):
        elements_to_cartesian([7000.0, 1.5, 0.1, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="e >= 0"):
        elements_to_cartesian([7000.0, -0.1, 0.1, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="rectilinear"):
        cartesian_to_elements([7000.0, 0.0, 0.0, 1.0, 0.0, 0.0])


# --- Anomalies and Kepler's equation -------------------------------------------------------------


@settings(max_examples=500)
@given(st.floats(-50.0, 50.0, allow_subnormal=False), st.floats(0.0, 0.9999))
def test_kepler_equation_residual_elliptic(m, e):
    big_e = mean_to_eccentric_anomaly(m, e)
    # Residual at the rounding level of evaluating E - e sin E - M.
    scale = abs(big_e) + e * abs(np.sin(big_e)) + abs(m)
    assert abs(big_e - e * np.sin(big_e) - m) <= 8 * EPS * scale
    assert abs(big_e - m) <= e + 8 * EPS * scale  # same revolution as M


@settings(max_examples=500)
@given(st.floats(-1e3, 1e3, allow_subnormal=False), st.floats(1.0 + 1e-9, 10.0))
def test_kepler_equation_residual_hyperbolic(m, e):
    big_h = mean_to_hyperbolic_anomaly(m, e)
    scale = e * abs(np.sinh(big_h)) + abs(big_h) + abs(m)
    assert abs(e * np.sinh(big_h) - big_h - m) <= 8 * EPS * scale
    assert np.sign(big_h) == np.sign(m)


@pytest.mark.parametrize("e", [0.99, 0.999999, 1 - 1e-11])
@pytest.mark.parametrize("m", [0.0, 1e-12, 1e-6, 0.01, np.pi, -np.pi, 100.0])
def test_kepler_solver_converges_at_hard_elliptic_cases(e, m):
    big_e = mean_to_eccentric_anomaly(m, e)
    assert abs(big_e - e * np.sin(big_e) - m) <= 8 * EPS * (abs(big_e) + abs(m))


def test_kepler_solvers_vectorise():
    m = np.linspace(-10, 10, 21).reshape(3, 7)
    assert mean_to_eccentric_anomaly(m, 0.5).shape == (3, 7)
    assert mean_to_hyperbolic_anomaly(m, np.full((3, 7), 2.0)).shape == (3, 7)
    assert mean_to_eccentric_anomaly(1.0, np.array([0.1, 0.2])).shape == (2,)


def test_anomaly_conversions_are_inverse():
    nu = np.linspace(-3.0, 3.0, 13)
    for e in (0.0, 0.3, 0.95):
        assert np.allclose(eccentric_to_true_anomaly(true_to_eccentric_anomaly(nu, e), e), nu,
                           atol=1e-13)
        assert np.allclose(mean_to_true_anomaly(true_to_mean_anomaly(nu, e), e), nu, atol=1e-12)
    e = 2.0
    nu_h = np.linspace(-2.0, 2.0, 9)  # inside the asymptotes, acos(-1/2) = 2.094
    assert np.allclose(hyperbolic_to_true_anomaly(true_to_hyperbolic_anomaly(nu_h, e), e), nu_h,
                       atol=1e-13)
    assert np.allclose(mean_to_true_anomaly(true_to_mean_anomaly(nu_h, e), e), nu_h, atol=1e-12)
    # The revolution count is kept on ellipses: 2 pi + nu -> 2 pi + M.
    assert abs(true_to_mean_anomaly(2 * np.pi + 0.5, 0.2) - 2 * np.pi
               - true_to_mean_anomaly(0.5, 0.2)) < 1e-13


# --- The dataclass ------------------------------------------------------------------------------


def test_elements_dataclass_is_frozen_with_slots_and_round_trips():
    el = Elements.from_degrees(6550.524, 0.0, 30.0, 0.0, 0.0, 0.0)  # SATORB2 of the study
    assert not hasattr(el, "__dict__")
    with pytest.raises(dataclasses.FrozenInstanceError):
        el.a_km = 7000.0
    state = el.to_cartesian()
    assert np.allclose(state[:3], [6550.524, 0.0, 0.0], atol=1e-9)
    speed = np.sqrt(GM_EARTH_km3_s2 / 6550.524)
    i = np.radians(30.0)
    assert np.allclose(state[3:], speed * np.array([0.0, np.cos(i), np.sin(i)]))
    assert Elements.from_array(el.to_array()) == el


def test_one_period_of_kepler_motion_returns_to_the_start():
    el = Elements(8500.0, 0.2, 0.7, 0.1, 0.2, 0.0)
    period_s = 2 * np.pi / el.mean_motion_rad_s()
    _assert_same_state(el.to_cartesian(), el.propagated(period_s).to_cartesian(), 1e-12)
    arc = kepler_states(el.to_array(), np.array([0.0, period_s / 2, period_s]))
    assert arc.shape == (3, 6)
    # Apoapsis after half a period: r = a (1 + e).
    assert abs(np.linalg.norm(arc[1, :3]) - 8500.0 * 1.2) < 1e-8

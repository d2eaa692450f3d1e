"""Earth rotation angle, R3 and the ECI <-> ECEF state transformations."""

import numpy as np
import pytest

from tapp.constants import OMEGA_EARTH_rad_s
from tapp.frames import (
    earth_rotation_angle_rad,
    ecef_to_eci_matrix,
    ecef_to_eci_matrix_dot,
    ecef_to_eci_state,
    eci_to_ecef_matrix,
    eci_to_ecef_matrix_dot,
    eci_to_ecef_state,
    r3,
    r3_derivative,
)

#: Orthogonality and round trips: a few ulps of unit-size numbers.
ROUNDING = 1e-14
#: Central differences with a 1e-5 rad (or 1 s = 7.3e-5 rad) step: truncation (h^2/6 < 1e-9)
#: and rounding (eps / h ~ 3e-12) errors are both far below this relative bound.
FD_REL = 1e-8
THETAS_rad = np.array([0.0, 0.3, 2.0, -4.0, 12.0])


def test_earth_rotation_angle_is_linear_and_broadcasts():
    t_s = np.array([0.0, 60.0, 86164.0905])
    theta = earth_rotation_angle_rad(1.25, t_s)
    assert theta.shape == (3,)
    assert theta[0] == 1.25
    # Differences of angles ~7 rad over 60 s steps: rounding of 7 eps / 4e-3 rad ~ 4e-13.
    assert np.allclose(np.diff(theta) / np.diff(t_s), OMEGA_EARTH_rad_s, rtol=1e-12, atol=0)
    assert earth_rotation_angle_rad(np.zeros((2, 1)), t_s).shape == (2, 3)


def test_r3_is_a_frame_rotation():
    # Axes turned +90 deg about z: the old x axis has coordinates (0, -1, 0).
    assert np.allclose(r3(np.pi / 2) @ [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], atol=ROUNDING)
    m = r3(THETAS_rad)
    assert m.shape == (5, 3, 3)
    assert np.allclose(m @ np.swapaxes(m, -1, -2), np.eye(3), atol=ROUNDING)
    assert np.allclose(np.linalg.det(m), 1.0, atol=ROUNDING)
    assert np.allclose(ecef_to_eci_matrix(THETAS_rad) @ eci_to_ecef_matrix(THETAS_rad), np.eye(3),
                       atol=ROUNDING)


def test_r3_derivative_against_central_differences():
    h = 1e-5
    fd = (r3(THETAS_rad + h) - r3(THETAS_rad - h)) / (2 * h)
    assert np.max(np.abs(fd - r3_derivative(THETAS_rad))) < FD_REL


@pytest.mark.parametrize("theta0", [0.0, 1.7])
def test_matrix_rates_against_central_differences_in_time(theta0):
    t_s, h_s = np.array([0.0, 500.0, 4.0e4]), 1.0

    def at(t):
        return earth_rotation_angle_rad(theta0, t)

    fd = (eci_to_ecef_matrix(at(t_s + h_s)) - eci_to_ecef_matrix(at(t_s - h_s))) / (2 * h_s)
    analytic = eci_to_ecef_matrix_dot(at(t_s))
    assert np.max(np.abs(fd - analytic)) < FD_REL * OMEGA_EARTH_rad_s
    fd_t = (ecef_to_eci_matrix(at(t_s + h_s)) - ecef_to_eci_matrix(at(t_s - h_s))) / (2 * h_s)
    assert np.max(np.abs(fd_t - ecef_to_eci_matrix_dot(at(t_s)))) < FD_REL * OMEGA_EARTH_rad_s


def test_state_round_trip_and_broadcasting():
    rng = np.random.default_rng(20260101)
    states = np.concatenate([rng.normal(0, 7000, (5, 3)), rng.normal(0, 7, (5, 3))], axis=1)
    back = ecef_to_eci_state(eci_to_ecef_state(states, THETAS_rad), THETAS_rad)
    assert np.allclose(back, states, rtol=0, atol=ROUNDING * 7000)
    one = eci_to_ecef_state(states[0], THETAS_rad)  # one state at five angles
    assert one.shape == (5, 6)


def test_ecef_velocity_is_the_time_derivative_of_the_ecef_position():
    # An inertial straight line r(t) = r0 + v t, seen from the rotating frame.
    r0, v = np.array([7000.0, -1200.0, 300.0]), np.array([0.5, 7.4, 1.1])
    t_s, h_s = 100.0, 1.0

    def r_ecef(t):
        return eci_to_ecef_matrix(earth_rotation_angle_rad(0.4, t)) @ (r0 + v * t)

    fd = (r_ecef(t_s + h_s) - r_ecef(t_s - h_s)) / (2 * h_s)
    state = eci_to_ecef_state(np.concatenate([r0 + v * t_s, v]), earth_rotation_angle_rad(0.4, t_s))
    assert np.max(np.abs(state[3:] - fd)) < FD_REL * np.linalg.norm(fd)


def test_a_point_fixed_on_earth_has_zero_ecef_velocity():
    r_f = np.array([6378.137, 0.0, 0.0])
    theta = 0.8
    r = ecef_to_eci_matrix(theta) @ r_f
    v = np.cross([0.0, 0.0, OMEGA_EARTH_rad_s], r)
    ecef = eci_to_ecef_state(np.concatenate([r, v]), theta)
    assert np.allclose(ecef[:3], r_f, atol=ROUNDING * 7000)
    assert np.allclose(ecef[3:], 0.0, atol=ROUNDING)

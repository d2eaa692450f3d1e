"""Lambert's problem against a printed example and against Kepler's equation."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

from tapp.constants import GM_EARTH_km3_s2
from tapp.errors import InputError
from tapp.orbit import lambert
from tapp.orbit.elements import kepler_states

#: Curtis prints 4-5 significant digits: half a unit of the last digit.
HALF_LAST_PRINTED_DIGIT_km_s = 5e-5
ONE_MICROMETRE_PER_S_km_s = 1e-9


def test_curtis_example_5_2() -> None:
    """H. D. Curtis, Orbital Mechanics for Engineering Students, 3rd ed., Example 5.2 (mu =
    398600): v1 = (-5.9925, 1.9254, 3.2456), v2 = (-3.3125, -4.1966, -0.38529) km/s."""
    v1, v2 = lambert([5000.0, 10000.0, 2100.0], [-14600.0, 2500.0, 7000.0], 3600.0, 398600.0)
    np.testing.assert_allclose(v1, [-5.9925, 1.9254, 3.2456], atol=HALF_LAST_PRINTED_DIGIT_km_s)
    np.testing.assert_allclose(v2, [-3.3125, -4.1966, -0.38529],
                               atol=HALF_LAST_PRINTED_DIGIT_km_s)


# (a km, e, i, raan, argp, M0 rad, time of flight s): short and long way round an ellipse,
# a near-circular orbit (z ~ 0: the Stumpff series), a hyperbola, a retrograde orbit.
ORBITS = [
    (20000.0, 0.3, 0.5, 0.7, 1.0, 0.2, 7000.0),
    (20000.0, 0.3, 0.5, 0.7, 1.0, 0.2, 21000.0),
    (7000.0, 1e-4, 1.2, 0.1, 0.0, 0.0, 60.0),
    (-30000.0, 1.8, 0.4, 2.0, 0.5, -0.8, 9000.0),
    (42164.0, 0.1, 2.8, 4.0, 3.0, 1.0, 30000.0),
]


@pytest.mark.parametrize("orbit", ORBITS)
def test_velocities_are_those_of_the_kepler_arc_through_both_points(orbit) -> None:
    """r1, r2 taken on a Keplerian arc (tapp.orbit.elements, Kepler's equation): Lambert's
    velocities must be that arc's, with the pole on the side of its angular momentum."""
    *elements, tof = orbit
    states = kepler_states(np.array(elements), np.array([0.0, tof]), GM_EARTH_km3_s2)
    pole = np.cross(states[0, :3], states[0, 3:])
    v1, v2 = lambert(states[0, :3], states[1, :3], tof, GM_EARTH_km3_s2, pole=pole)
    np.testing.assert_allclose(v1, states[0, 3:], rtol=0, atol=ONE_MICROMETRE_PER_S_km_s)
    np.testing.assert_allclose(v2, states[1, 3:], rtol=0, atol=ONE_MICROMETRE_PER_S_km_s)


def test_the_pole_chooses_the_direction_of_motion() -> None:
    r1, r2 = np.array([7000.0, 0.0, 0.0]), np.array([0.0, 9000.0, 0.0])
    prograde, _ = lambert(r1, r2, 3000.0, GM_EARTH_km3_s2)
    retrograde, _ = lambert(r1, r2, 3000.0, GM_EARTH_km3_s2, pole=[0.0, 0.0, -1.0])
    assert np.cross(r1, prograde)[2] > 0 > np.cross(r1, retrograde)[2]


@pytest.mark.parametrize(("args", "field"), [
    (([7000.0, 0.0, 0.0], [-9000.0, 0.0, 0.0], 3000.0), "r2_km"),     # 180 deg: no plane
    (([7000.0, 0.0, 0.0], [14000.0, 0.0, 0.0], 3000.0), "r2_km"),     # 0 deg
    (([7000.0, 0.0, 0.0], [0.0, 9000.0, 0.0], 0.0), "tof_s"),
    (([7000.0, 0.0, 0.0], [0.0, 9000.0, 0.0], math.nan), "tof_s"),
    (([7000.0, 0.0, 0.0], [0.0, 9000.0, 0.0], 1e30), "tof_s"),        # beyond one revolution
    (([0.0, 0.0, 0.0], [0.0, 9000.0, 0.0], 3000.0), "r1_km"),
    (([7000.0, math.inf, 0.0], [0.0, 9000.0, 0.0], 3000.0), "r1_km"),
])
def test_refusals_name_the_argument(args, field: str) -> None:
    with pytest.raises(InputError) as info:
        lambert(*args, GM_EARTH_km3_s2)
    assert info.value.field == field


@pytest.mark.parametrize(("r2", "tof_s"), [([0.0, 9000.0, 0.0], 1e-6), ([0.0, -9000.0, 0.0], 1e-6)])
def test_flights_faster_than_light_are_refused(r2, tof_s: float) -> None:
    """A conic exists for any tof mathematically; one that needs v > c is refused."""
    with pytest.raises(InputError, match="speed of light") as info:
        lambert([7000.0, 0.0, 0.0], r2, tof_s, GM_EARTH_km3_s2)
    assert info.value.field == "tof_s"


def test_a_root_below_the_lowest_z_tried_is_refused(monkeypatch) -> None:
    """The bracket stops at _Z_LOW (cosh must stay finite): a 1 s flight the long way round
    has its root far below a lowered limit of -4."""
    args = ([7000.0, 0.0, 0.0], [0.0, -9000.0, 0.0], 1.0, GM_EARTH_km3_s2)
    assert np.linalg.norm(lambert(*args)[0]) < 2e4  # solvable with the real limit
    monkeypatch.setattr(importlib.import_module("tapp.orbit.lambert"), "_Z_LOW", -4.0)
    with pytest.raises(InputError, match="speed of light"):
        lambert(*args)

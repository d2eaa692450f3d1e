"""Equinoctial elements against their definition from classical elements."""

from __future__ import annotations

import math

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.orbit.elements import elements_to_cartesian
from tapp.orbit.equinoctial import equinoctial_elements


def test_equinoctial_elements_of_an_inclined_eccentric_orbit() -> None:
    a, e, i, raan, argp, m = 8000.0, 0.1, 0.5, 1.0, 2.0, 0.3
    state = elements_to_cartesian(np.array([a, e, i, raan, argp, m]), GM_EARTH_km3_s2)
    out = equinoctial_elements(state, GM_EARTH_km3_s2)
    expected = [a, e * math.cos(argp + raan), e * math.sin(argp + raan),
                math.tan(i / 2) * math.cos(raan), math.tan(i / 2) * math.sin(raan),
                (m + argp + raan) % (2 * math.pi)]
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-12)

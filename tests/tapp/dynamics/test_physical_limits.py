"""Issue 10, class 4: the kernels refuse what is physically impossible, with quantity and limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tapp.dynamics import ForceModel, Propagator, earth_model, parse_gravity
from tapp.dynamics.forces import check_parameter_value
from tapp.dynamics.propagate import TOLERANCE_RANGE, check_tolerance
from tapp.errors import InputError

LEO = np.array([7000.0, 0.0, 0.0, 0.0, 7.546, 0.0])


@pytest.mark.parametrize("tol", [1.0, 1e-5, 1e-16, 0.0, -1e-12, math.inf, math.nan])
def test_tolerances_outside_the_documented_range_are_refused(tol: float) -> None:
    # The example: --tol 1 gave a position 6.6e5 km off with exit 0.
    with pytest.raises(InputError) as info:
        Propagator(earth_model("J2"), rtol=tol, atol=1e-12)
    assert (info.value.source, info.value.field) == ("propagator", "rtol")
    assert "an integrator tolerance in [1e-15, 1e-06]" in info.value.expected
    with pytest.raises(InputError, match="propagator: atol: expected an integrator tolerance"):
        Propagator(earth_model("J2"), rtol=1e-12, atol=tol)


def test_the_ends_of_the_range_are_accepted() -> None:
    lo, hi = TOLERANCE_RANGE
    assert (lo, hi) == (1e-15, 1e-6)
    for tol in (lo, hi):
        assert Propagator(earth_model("J0"), rtol=tol, atol=tol).rtol == tol
    assert check_tolerance(1e-9, "--tol", "value") == 1e-9
    with pytest.raises(InputError, match=r"^--tol: value: expected an integrator tolerance"):
        check_tolerance(True, "--tol", "value")


def test_a_third_body_given_twice_is_refused() -> None:
    # The example: a repeated --third-body sun doubled the Sun's pull.
    with pytest.raises(InputError) as info:
        earth_model("J2", ("sun", "moon", "sun"))
    assert info.value.field == "third_bodies"
    assert "each body once (sun given 2 times" in info.value.expected
    with pytest.raises(InputError, match="each body once"):
        ForceModel(parse_gravity("J0"), "earth", ("moon", "moon"))


@pytest.mark.parametrize("gm", [0.0, -398600.4415, math.nan, math.inf])
def test_a_gm_that_is_not_positive_and_finite_is_refused(gm: float) -> None:
    prop = Propagator(earth_model("J2"), params=("GM_km3_s2", "J2"))
    with pytest.raises(InputError) as info:
        prop.propagate(LEO, np.array([60.0]), stm=False, param_values={"GM_km3_s2": gm})
    assert (info.value.source, info.value.field) == ("propagate", "param_values.GM_km3_s2")
    assert info.value.expected == "a finite GM > 0 km^3/s^2 for GM_km3_s2"
    with pytest.raises(InputError, match="GM_moon_km3_s2: expected a finite GM > 0"):
        check_parameter_value("GM_moon_km3_s2", gm, "model", "GM_moon_km3_s2")


def test_other_parameters_may_be_negative_but_must_be_finite() -> None:
    assert check_parameter_value("J2", -1e-3) == -1e-3
    with pytest.raises(InputError, match="a finite value of J2"):
        check_parameter_value("J2", math.nan)
    prop = Propagator(earth_model("J2"), params=("GM_km3_s2",))
    out = prop.propagate(LEO, np.array([60.0]), stm=False, param_values={"GM_km3_s2": 398600.0})
    assert np.all(np.isfinite(out.states))

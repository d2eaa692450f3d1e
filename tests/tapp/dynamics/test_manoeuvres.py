"""Burns in the dynamics (tapp.dynamics.manoeuvres): the impulsive jump and its Jacobians, and a
finite burn's state and transition, against the tests' own NumPy model
(tests/tapp/dynamics/burn_reference.py) and SciPy's DOP853."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.dynamics import Propagator
from tapp.dynamics.gates import GatesErrors
from tapp.dynamics.manoeuvres import FiniteBurn, ImpulsiveBurn
from tapp.dynamics.spec import earth_model
from tests.tapp.dynamics.burn_reference import (
    axes,
    executed,
    scipy_state,
    thrust_rhs,
)
from tests.tapp.dynamics.conftest import periapsis_state

ERRORS = GatesErrors(0.01, 5e-6, 0.01, 5e-6)
#: An eccentric LEO (e = 0.1) at periapsis and 60° past it.
STATES = [periapsis_state(7500.0, 0.1, 28.5, 40.0, 30.0),
          periapsis_state(7500.0, 0.1, 98.0, 200.0, 0.0)]
#: The jump's Jacobians against central differences of the NumPy jump: steps 1e-3 km and
#: 1e-6 km/s against an axes curvature of 1/|r|, 1/|v|: truncation ~(h/|r|)² ~ 1e-14,
#: rounding ~1e-16 |Δv| / h (measured 9.9e-10 of the largest entry; the errors' 1.2e-10).
JUMP_TOL = 1e-8
#: A finite burn's end state against SciPy's DOP853 at the same 1e-13 on the test's own model
#: (measured 5.9e-12 km, 7.1e-15 km/s).
STATE_TOL_km, STATE_TOL_km_s = 1e-6, 1e-9
#: Its transition against Richardson-extrapolated central differences of SciPy trajectories
#: (steps 1 km, 1 m/s), each column relative to its largest entry (measured 2.9e-11).
PHI_TOL = 1e-7
#: A 1200 s burn of 50 N on 800 kg, 0.02 kg/s: 76 m/s, the mass down 3 %.
BURN = {"t_start_s": 600.0, "duration_s": 1200.0, "thrust_N": 50.0,
        "direction": (0.6, 0.0, 0.8), "mass_kg": 800.0, "mass_flow_kg_s": 0.02}


def _delta(x: np.ndarray, dv: np.ndarray, name: str) -> np.ndarray:
    """Δx of the jump: the velocity change in the axes ``name`` of x (the state itself left
    out of the differences, whose rounding it would dominate)."""
    return np.concatenate([np.zeros(3), axes(x[:3], x[3:], name) @ dv])


@pytest.mark.parametrize("name", ["inertial", "ric", "vnb"])
@pytest.mark.parametrize("x", STATES)
def test_the_jump_of_an_impulsive_burn_and_its_jacobians(name, x):
    dv = np.array([3e-3, -1e-3, 2e-3])
    burn = ImpulsiveBurn(name="B", axes=name, errors=ERRORS, t_s=0.0, dv_km_s=tuple(dv))
    x_plus, jump, d_errors = burn.apply(x)
    np.testing.assert_allclose(x_plus, x + _delta(x, dv, name), rtol=0, atol=1e-15)
    if name == "inertial":
        np.testing.assert_array_equal(jump, np.eye(6))
    else:  # ∂Δx/∂x: the axes move with r and v
        fd = np.empty((6, 6))
        for i in range(6):
            h = 1e-3 if i < 3 else 1e-6
            e = np.zeros(6)
            e[i] = h
            fd[:, i] = (_delta(x + e, dv, name) - _delta(x - e, dv, name)) / (2 * h)
        assert np.max(np.abs(fd - (jump - np.eye(6)))) < JUMP_TOL * np.max(np.abs(fd))
    fd = np.empty((6, 6))
    for i, sigma in enumerate(ERRORS.sigmas):
        e = np.zeros(6)
        e[i] = 1e-3 * sigma
        fd[:, i] = (_delta(x, executed(dv, e), name) - _delta(x, executed(dv, -e), name)) / (
            2e-3 * sigma)
    assert np.max(np.abs(fd - d_errors) / np.max(np.abs(d_errors), axis=0)) < JUMP_TOL


@pytest.mark.parametrize(("name", "method"), [("ric", "dop853"), ("vnb", "dop853"),
                                              ("inertial", "dop853"), ("inertial", "rkn12")])
def test_a_finite_burn_flies_as_scipy_on_the_tests_own_thrust_model(name, method):
    """RIC and VNB axes move with v (∂a/∂v in Φ); in inertial axes the thrust depends on t
    only and rkn12 takes it too."""
    x0 = STATES[0]
    burn = FiniteBurn(name="F", axes=name, errors=ERRORS, **BURN)
    t0, t1 = burn.t_start_s, burn.t_end_s
    prop = Propagator(earth_model("J2"), params=burn.thrust_parameters(), method=method)
    got = prop.propagate(x0, np.array([t1]), t0_s=t0, stm=True,
                         param_values=burn.thrust_values())
    rhs = thrust_rhs(burn.thrust_N, burn.mass_kg, burn.mass_flow_kg_s, t0,
                     np.array(burn.direction), name)
    want = scipy_state(rhs, x0, t0, t1)
    assert np.max(np.abs(got.states[-1, :3] - want[:3])) < STATE_TOL_km
    assert np.max(np.abs(got.states[-1, 3:] - want[3:])) < STATE_TOL_km_s
    # the burn did something: 76 m/s, km of displacement
    coast = Propagator(earth_model("J2")).propagate(x0, np.array([t1]), t0_s=t0, stm=False)
    assert np.linalg.norm(coast.states[-1, 3:] - want[3:]) > 0.05
    phi = got.stm[-1]
    for i in range(6):
        h = 1.0 if i < 3 else 1e-3

        def flown(s, i=i):
            e = np.zeros(6)
            e[i] = s
            return scipy_state(rhs, x0 + e, t0, t1)

        d1 = (flown(h) - flown(-h)) / (2 * h)
        d2 = (flown(h / 2) - flown(-h / 2)) / h
        fd = (4 * d2 - d1) / 3
        assert np.max(np.abs(fd - phi[:, i])) < PHI_TOL * np.max(np.abs(phi[:, i])), i

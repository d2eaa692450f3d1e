"""Empirical accelerations: the RIC axes of the term against a plain NumPy construction, and the
variational equations' B = [0; R] against it."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from tapp.dynamics.empirical import PARAMETERS, empirical_acceleration
from tapp.dynamics.equations import build_equations, initial_augmented, split_augmented
from tapp.dynamics.forces import default_parameters
from tapp.dynamics.spec import earth_model

#: Rounding of a few products and one normalisation, relative.
ROUNDING = 1e-14
#: An eccentric, inclined state (e ≈ 0.2 near periapsis), km and km/s.
STATE = np.array([7000.0, -1200.0, 800.0, 1.1, 8.2, 2.9])


def _ric_numpy(x: np.ndarray) -> np.ndarray:
    """[R̂ Î Ĉ] as columns: R̂ = r/|r|, Ĉ = h/|h|, Î = Ĉ × R̂ (independent of the module)."""
    r, v = x[:3], x[3:]
    radial = r / np.linalg.norm(r)
    h = np.cross(r, v)
    cross = h / np.linalg.norm(h)
    return np.column_stack([radial, np.cross(cross, radial), cross])


@pytest.mark.parametrize("frame", ["ric", "inertial"])
def test_the_acceleration_is_the_components_along_the_frame_axes(frame):
    r, v = ca.SX.sym("r", 3), ca.SX.sym("v", 3)
    q = ca.SX.sym("q", 3)
    names = PARAMETERS[frame]
    f = ca.Function("a", [r, v, q], [empirical_acceleration(r, v, dict(zip(names, ca.vertsplit(q),
                                                                             strict=True)))])
    a = np.array([2e-12, -5e-12, 7e-12])
    axes = _ric_numpy(STATE) if frame == "ric" else np.eye(3)
    got = np.array(f(STATE[:3], STATE[3:], a)).ravel()
    np.testing.assert_allclose(got, axes @ a, rtol=0, atol=ROUNDING * np.linalg.norm(a))
    assert empirical_acceleration(r, v, {}) == 0.0
    assert default_parameters(earth_model("J2"), names) == dict.fromkeys(names, 0.0)


def test_the_variational_b_matrix_is_zero_over_the_ric_rotation():
    """ẏ of the augmented system at S = 0: the S block is B = [0; R] (R the RIC rotation)."""
    model = earth_model("J2")
    eqs = build_equations(model, model, PARAMETERS["ric"])
    y0 = initial_augmented(STATE, 3)
    ydot = np.array(eqs.f_var(0.0, y0, np.zeros(3), [0.0], np.zeros(0))).T
    _, _, b = split_augmented(ydot, 3)
    np.testing.assert_array_equal(b[0, :3], np.zeros((3, 3)))
    np.testing.assert_allclose(b[0, 3:], _ric_numpy(STATE), rtol=0, atol=ROUNDING)

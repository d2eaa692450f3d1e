"""RIC axes and covariance rotation (tapp.frames.ric) against independent constructions.

References: the RIC (RSW) axes of a circular orbit written from its elements (Vallado 2013,
§3.3: R̂ along the radius, Ĉ the orbit normal, Î = Ĉ x R̂ along the velocity), and
P_ric = T P Tᵀ worked by hand for an equatorial state whose axes are a permutation of the
inertial ones.
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.ric import ric_axes, ric_state_rotation, rotate_covariance, rotate_rows

#: The axes are unit vectors built from a few products of doubles: a few ε of rounding.
ROUNDING = 1e-14
MU_EARTH_km3_s2 = 398600.4418


def _circular(a_km: float, inc: float, raan: float, u: float) -> tuple[np.ndarray, ...]:
    """State of a circular orbit and its RIC axes from the elements (Vallado §3.3):
    R̂ = (cosΩ cos u − sinΩ sin u cos i, sinΩ cos u + cosΩ sin u cos i, sin u sin i),
    Î = (−cosΩ sin u − sinΩ cos u cos i, −sinΩ sin u + cosΩ cos u cos i, cos u sin i),
    Ĉ = (sinΩ sin i, −cosΩ sin i, cos i); v = √(μ/a) Î."""
    co, so, ci, si, cu, su = (np.cos(raan), np.sin(raan), np.cos(inc), np.sin(inc), np.cos(u),
                              np.sin(u))
    r_hat = np.array([co * cu - so * su * ci, so * cu + co * su * ci, su * si])
    i_hat = np.array([-co * su - so * cu * ci, -so * su + co * cu * ci, cu * si])
    c_hat = np.array([so * si, -co * si, ci])
    state = np.concatenate([a_km * r_hat, np.sqrt(MU_EARTH_km3_s2 / a_km) * i_hat])
    return state, r_hat, i_hat, c_hat


@pytest.mark.parametrize("inc_deg, raan_deg, u_deg", [(0.0, 0.0, 0.0), (28.5, 40.0, 130.0),
                                                      (98.0, 250.0, 300.0), (63.4, 10.0, 45.0)])
def test_circular_orbit_axes_match_the_elements(inc_deg, raan_deg, u_deg):
    state, r_hat, i_hat, c_hat = _circular(7000.0, *np.radians([inc_deg, raan_deg, u_deg]))
    t = ric_axes(state[:3], state[3:])
    np.testing.assert_allclose(t, np.stack([r_hat, i_hat, c_hat]), atol=ROUNDING)
    # a circular orbit's velocity is all in-track
    rot = ric_state_rotation(state)
    np.testing.assert_allclose(rot @ state, [7000.0, 0, 0, 0, np.sqrt(MU_EARTH_km3_s2 / 7000.0),
                                             0], atol=1e-10)


def test_axes_are_orthonormal_right_handed_and_along_r_and_h():
    rng = np.random.default_rng(21)
    r = rng.normal(size=(50, 3)) * 1e4
    v = rng.normal(size=(50, 3)) * 5.0
    t = ric_axes(r, v)
    assert t.shape == (50, 3, 3)
    np.testing.assert_allclose(t @ np.swapaxes(t, -1, -2), np.broadcast_to(np.eye(3), t.shape),
                               atol=ROUNDING)
    np.testing.assert_allclose(np.linalg.det(t), 1.0, atol=ROUNDING)
    h = np.cross(r, v)
    # R parallel to r, C parallel to h (same sense), I in the orbit plane on the side of v
    np.testing.assert_allclose(np.einsum("ij,ij->i", t[:, 0], r), np.linalg.norm(r, axis=1),
                               rtol=ROUNDING)
    np.testing.assert_allclose(np.einsum("ij,ij->i", t[:, 2], h), np.linalg.norm(h, axis=1),
                               rtol=ROUNDING)
    assert np.all(np.einsum("ij,ij->i", t[:, 1], v) > 0)
    assert np.all(np.abs(np.einsum("ij,ij->i", t[:, 1], h)) < 1e-9 * np.linalg.norm(h, axis=1))


def test_state_rotation_is_blockdiag_and_broadcasts():
    state, *_ = _circular(26560.0, 0.96, 0.3, 2.0)
    states = np.stack([state, 2 * state])
    rot = ric_state_rotation(states)
    assert rot.shape == (2, 6, 6)
    np.testing.assert_array_equal(rot[:, :3, 3:], 0.0)
    np.testing.assert_array_equal(rot[:, 3:, :3], 0.0)
    np.testing.assert_array_equal(rot[:, :3, :3], rot[:, 3:, 3:])
    np.testing.assert_allclose(rot[0], rot[1], atol=ROUNDING)  # axes do not depend on scale


def test_rectilinear_state_is_refused():
    with pytest.raises(InputError, match="orbit plane"):
        ric_axes([7000.0, 0, 0], [3.0, 0, 0])


def test_covariance_rotation_by_hand():
    # r along +y, v along −x: R̂ = ŷ, Ĉ = (r x v)/|r x v| = ẑ, Î = Ĉ x R̂ = −x̂, so
    # P_RR = P_yy, P_II = P_xx, P_CC = P_zz, P_RI = ŷᵀ P (−x̂) = −P_xy, P_IC = −P_xz, and the
    # same for velocity; the constant (7th row) keeps its variance, its covariance with x
    # changes sign as I = −x.
    state = np.array([0.0, 7000.0, 0.0, -7.5, 0.0, 0.0])
    p = np.diag([1.0, 4.0, 9.0, 1e-6, 4e-6, 9e-6, 25.0])
    p[0, 1] = p[1, 0] = 0.5
    p[0, 2] = p[2, 0] = 0.25
    p[0, 6] = p[6, 0] = 0.75
    rot = ric_state_rotation(state)
    out = rotate_covariance(rot, p)
    expect = np.diag([4.0, 1.0, 9.0, 4e-6, 1e-6, 9e-6, 25.0])
    expect[0, 1] = expect[1, 0] = -0.5
    expect[1, 2] = expect[2, 1] = -0.25
    expect[1, 6] = expect[6, 1] = -0.75
    np.testing.assert_allclose(out, expect, atol=ROUNDING)


def test_covariance_rotation_keeps_traces_and_matches_the_full_matrix():
    rng = np.random.default_rng(5)
    a = rng.normal(size=(9, 9))
    p = a @ a.T
    state, *_ = _circular(42164.0, 0.1, 1.0, 4.0)
    rot = ric_state_rotation(state)
    full = np.eye(9)
    full[:6, :6] = rot
    out = rotate_covariance(rot, p)
    # T̄ P T̄ᵀ formed as a plain product: rounding of a 9 x 9 product, relative 1e-13
    np.testing.assert_allclose(out, full @ p @ full.T, rtol=1e-13, atol=1e-13 * np.max(p))
    assert np.trace(out[:3, :3]) == pytest.approx(np.trace(p[:3, :3]), rel=1e-14)
    assert np.trace(out[3:6, 3:6]) == pytest.approx(np.trace(p[3:6, 3:6]), rel=1e-14)
    np.testing.assert_array_equal(out[6:, 6:], p[6:, 6:])
    np.testing.assert_allclose(rotate_rows(rot, a), full @ a, rtol=1e-13, atol=1e-13)

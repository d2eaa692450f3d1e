"""The geopotential against independent evaluations (closed-form J2, scipy Legendre)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.special import lpmv

from tapp.constants import GM_EARTH_km3_s2, R_EARTH_km, egm96_coefficients
from tapp.dynamics.forces import acceleration, central_potential, field_coefficients
from tapp.dynamics.spec import earth_model, parse_gravity
from tapp.errors import InputError

# Relative agreement of two double-precision evaluations of the same sum of ~50 terms.
ROUNDING = 1e-12


def _potential_fn(spec: str) -> ca.Function:
    model = earth_model(spec)
    r = ca.SX.sym("r", 3)
    u = central_potential(model, r, GM_EARTH_km3_s2, field_coefficients(model, {}))
    return ca.Function("u", [r], [u])


def _accel_fn(spec: str) -> ca.Function:
    model = earth_model(spec)
    r = ca.SX.sym("r", 3)
    t = ca.SX.sym("t")
    return ca.Function("a", [t, r], [acceleration(model, t, r, ca.SX(0.0), {}, {})])


def _reference_potential(r_km: np.ndarray, degree: int, order: int) -> float:
    """U = GM/r sum (R/r)^n P_nm(sin phi) N_nm (C cos m lam + S sin m lam), via scipy."""
    c_bar, s_bar = egm96_coefficients()
    x, y, z = r_km
    r = np.linalg.norm(r_km)
    sin_phi, lam = z / r, math.atan2(y, x)
    total = 1.0
    for n in range(2, degree + 1):
        for m in range(0, min(n, order) + 1):
            norm = math.sqrt((2 - (m == 0)) * (2 * n + 1) * math.factorial(n - m)
                             / math.factorial(n + m))
            # scipy includes the Condon-Shortley phase (-1)^m; geodesy does not.
            p_nm = (-1) ** m * lpmv(m, n, sin_phi) * norm
            total += (R_EARTH_km / r) ** n * p_nm * (c_bar[n, m] * math.cos(m * lam)
                                                     + s_bar[n, m] * math.sin(m * lam))
    return GM_EARTH_km3_s2 / r * total


@pytest.mark.parametrize("spec", ["J2", "J5", "5x5", "8x8", "8x3"])
@pytest.mark.parametrize("r_km", [[7000.0, 0.0, 0.0], [-3000.0, 4000.0, 5000.0],
                                  [100.0, -200.0, 6900.0], [26000.0, 1000.0, -3000.0]])
def test_potential_matches_legendre_sum(spec: str, r_km: list[float]) -> None:
    g = parse_gravity(spec)
    u = float(_potential_fn(spec)(r_km))
    ref = _reference_potential(np.array(r_km), g.degree, g.order)
    assert abs(u - ref) <= ROUNDING * abs(ref)


@pytest.mark.parametrize("r_km", [[7000.0, 0.0, 0.0], [-3000.0, 4000.0, 5000.0],
                                  [1000.0, 2000.0, -6500.0]])
def test_j2_acceleration_matches_closed_form(r_km: list[float]) -> None:
    """Vallado (2013) eq. 8-30: a = -mu r/r^3 - 3/2 J2 mu R^2/r^5 [...]."""
    r = np.array(r_km)
    j2 = -math.sqrt(5.0) * egm96_coefficients()[0][2, 0]
    rn = np.linalg.norm(r)
    f = 1.5 * j2 * GM_EARTH_km3_s2 * R_EARTH_km**2 / rn**5
    zz = 5.0 * r[2] ** 2 / rn**2
    ref = -GM_EARTH_km3_s2 * r / rn**3 - f * r * np.array([1 - zz, 1 - zz, 3 - zz])
    got = np.array(_accel_fn("J2")(0.0, r)).ravel()
    assert np.linalg.norm(got - ref) <= ROUNDING * np.linalg.norm(ref)


def test_tesseral_field_rotates_with_the_earth() -> None:
    """At t = pi/(2 omega) the field seen at R3(-90 deg) r equals the field at t=0 at r."""
    from tapp.constants import OMEGA_EARTH_rad_s

    acc = _accel_fn("4x4")
    r0 = np.array([6800.0, 500.0, 1200.0])
    quarter = 0.5 * math.pi / OMEGA_EARTH_rad_s
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # +90 deg about z
    a0 = np.array(acc(0.0, r0)).ravel()
    a1 = np.array(acc(quarter, rot @ r0)).ravel()
    assert np.linalg.norm(a1 - rot @ a0) <= ROUNDING * np.linalg.norm(a0)


@pytest.mark.parametrize("bad", ["J9", "9x9", "3x4", "K2", "", "5x"])
def test_bad_gravity_spec_is_rejected(bad: str) -> None:
    with pytest.raises(InputError, match="gravity"):
        parse_gravity(bad)

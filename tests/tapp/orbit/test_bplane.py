"""B-plane parameters against hyperbolas built by hand from (|a|, e, F).

The reference states are made in the perifocal frame from the hyperbolic anomaly F
(Vallado 2013, ch. 2):

    r = |a| (e - cosh F, sqrt(e^2 - 1) sinh F, 0),   dF/dt = n / (e cosh F - 1),
    v = dF/dt |a| (-sinh F, sqrt(e^2 - 1) cosh F, 0), n = sqrt(mu / |a|^3),

for which, by hand: b = |B| = |a| sqrt(e^2 - 1), v_inf = sqrt(mu / |a|), r_p = |a| (e - 1),
the incoming asymptote S = (1, sqrt(e^2 - 1), 0) / e, the time to periapsis
(F - e sinh F) / n, and LTOF = -r.S / v_inf, which reduces to
LTOF - t_p = (e^F / e - 1 - F) / n.
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.constants import GM_km3_s2
from tapp.errors import InputError, NotHyperbolicError
from tapp.orbit.bplane import (
    ECLIPTIC_POLE_EME2000,
    OBLIQUITY_J2000_IAU1976_rad,
    b_plane,
    pole_from_ra_dec,
)

MU_MARS = GM_km3_s2["mars"]
MU_EARTH = GM_km3_s2["earth"]

# Rounding in these states is ~1e-16 relative on km-scale (1e4-1e6 km) quantities, i.e.
# 1e-10 km at worst; one millimetre (also nyx's default B-plane targeting tolerance) is a
# physically meaningful bound far above it.
one_mm = 1e-6  # km
# Times here are 1e3-1e6 s; rounding gives ~1e-10 s. One microsecond bounds it with margin.
one_us = 1e-6  # s
# Unit vectors and dimensionless ratios: rounding is a few eps.
unit_atol = 1e-14


def _rot_x(angle_rad: float) -> np.ndarray:
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_z(angle_rad: float) -> np.ndarray:
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _perifocal_state(a_abs_km: float, e: float, F: float, mu: float):
    k = np.sqrt(e * e - 1.0)
    n = np.sqrt(mu / a_abs_km**3)
    f_dot = n / (e * np.cosh(F) - 1.0)
    r = a_abs_km * np.array([e - np.cosh(F), k * np.sinh(F), 0.0])
    v = f_dot * a_abs_km * np.array([-np.sinh(F), k * np.cosh(F), 0.0])
    return r, v


def _asymptote_to_x(e: float) -> np.ndarray:
    """Rotation about z taking the perifocal incoming asymptote S = (1, k, 0)/e onto +x."""
    return _rot_z(-np.arctan2(np.sqrt(e * e - 1.0), 1.0))


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


# ------------------------------------------------------------------ hyperbolas by hand
@pytest.mark.parametrize("omega_deg", [0.0, 37.0, 200.0])
@pytest.mark.parametrize("F", [-2.0, 0.0, 0.6])
def test_hyperbola_in_the_reference_plane(omega_deg, F):
    a_abs, e = 20_000.0, 1.5
    r_pf, v_pf = _perifocal_state(a_abs, e, F, MU_EARTH)
    rot = _rot_z(np.radians(omega_deg))  # periapsis anywhere in the equator plane
    bp = b_plane(rot @ r_pf, rot @ v_pf, MU_EARTH)
    b = a_abs * np.sqrt(e * e - 1.0)
    assert bp.b_mag_km == pytest.approx(b, abs=one_mm)
    assert bp.b_dot_t_km == pytest.approx(b, abs=one_mm)  # prograde: B along +T
    assert bp.b_dot_r_km == pytest.approx(0.0, abs=one_mm)
    assert bp.eccentricity == pytest.approx(e, abs=unit_atol)
    assert bp.v_inf_km_s == pytest.approx(np.sqrt(MU_EARTH / a_abs), rel=1e-14)
    assert bp.periapsis_radius_km == pytest.approx(a_abs * (e - 1.0), abs=one_mm)
    s_expected = rot @ np.array([1.0, np.sqrt(e * e - 1.0), 0.0]) / e
    np.testing.assert_allclose(bp.s_hat, s_expected, atol=unit_atol)
    np.testing.assert_allclose(bp.r_hat, [0.0, 0.0, -1.0], atol=unit_atol)  # S x T, T in plane


def test_retrograde_hyperbola_in_the_reference_plane_has_negative_b_dot_t():
    a_abs, e = 50_000.0, 3.0
    r_pf, v_pf = _perifocal_state(a_abs, e, -1.0, MU_MARS)
    mirror = np.diag([1.0, -1.0, 1.0])  # reflect y: same path, angular momentum along -z
    bp = b_plane(mirror @ r_pf, mirror @ v_pf, MU_MARS)
    b = a_abs * np.sqrt(e * e - 1.0)
    assert bp.b_dot_t_km == pytest.approx(-b, abs=one_mm)
    assert bp.b_dot_r_km == pytest.approx(0.0, abs=one_mm)
    assert bp.b_angle_rad == pytest.approx(np.pi, abs=unit_atol)


@pytest.mark.parametrize("inc_deg", [0.0, 30.0, 90.0, 150.0])
def test_inclined_hyperbola_splits_b_by_the_inclination(inc_deg):
    # S along +x in the reference plane; the orbit plane tilted by i about S gives
    # h_hat = (0, -sin i, cos i), B = b S x h_hat = b (0, -cos i, -sin i),
    # T = S x z = -y, R = S x T = -z: B.T = b cos i, B.R = b sin i.
    a_abs, e, inc = 30_000.0, 2.0, np.radians(inc_deg)
    r_pf, v_pf = _perifocal_state(a_abs, e, -1.5, MU_MARS)
    rot = _rot_x(inc) @ _asymptote_to_x(e)
    bp = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS)
    b = a_abs * np.sqrt(e * e - 1.0)
    assert bp.b_dot_t_km == pytest.approx(b * np.cos(inc), abs=one_mm)
    assert bp.b_dot_r_km == pytest.approx(b * np.sin(inc), abs=one_mm)
    np.testing.assert_allclose(bp.s_hat, [1.0, 0.0, 0.0], atol=unit_atol)
    np.testing.assert_allclose(bp.t_hat, [0.0, -1.0, 0.0], atol=unit_atol)
    np.testing.assert_allclose(
        bp.b_vec_km, b * np.array([0.0, -np.cos(inc), -np.sin(inc)]), atol=one_mm
    )


def test_ecliptic_reference_plane():
    # Build the inclined case in ecliptic coordinates, express it in EME2000 (rotation about x
    # by the obliquity), and ask for the ecliptic B-plane: the same split must come back.
    a_abs, e, inc = 30_000.0, 2.0, np.radians(25.0)
    r_pf, v_pf = _perifocal_state(a_abs, e, -1.5, MU_MARS)
    ecl_to_eq = _rot_x(OBLIQUITY_J2000_IAU1976_rad)
    rot = ecl_to_eq @ _rot_x(inc) @ _asymptote_to_x(e)
    bp = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS, reference="ecliptic")
    b = a_abs * np.sqrt(e * e - 1.0)
    assert bp.b_dot_t_km == pytest.approx(b * np.cos(inc), abs=one_mm)
    assert bp.b_dot_r_km == pytest.approx(b * np.sin(inc), abs=one_mm)
    assert bp.t_hat @ ECLIPTIC_POLE_EME2000 == pytest.approx(0.0, abs=unit_atol)
    # The same state against the Earth equator gives a different split but the same |B|.
    eq = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS)
    assert abs(eq.b_dot_r_km - bp.b_dot_r_km) > 1000.0
    assert eq.b_mag_km == pytest.approx(bp.b_mag_km, abs=one_mm)


def test_body_equator_reference_plane_from_its_pole():
    # Mars pole at J2000, IAU WGCCRE 2015 (Archinal et al. 2018): alpha0 = 317.68143 deg,
    # delta0 = 52.88650 deg. Build the inclined case in a frame whose z is that pole.
    pole = pole_from_ra_dec(np.radians(317.68143), np.radians(52.88650))
    x_axis = np.cross([0.0, 0.0, 1.0], pole)
    x_axis /= np.linalg.norm(x_axis)
    body_to_eq = np.column_stack([x_axis, np.cross(pole, x_axis), pole])
    a_abs, e, inc = 8_000.0, 1.3, np.radians(60.0)
    r_pf, v_pf = _perifocal_state(a_abs, e, -0.8, MU_MARS)
    rot = body_to_eq @ _rot_x(inc) @ _asymptote_to_x(e)
    bp = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS, reference=2.0 * pole)  # normalised inside
    b = a_abs * np.sqrt(e * e - 1.0)
    assert bp.b_dot_t_km == pytest.approx(b * np.cos(inc), abs=one_mm)
    assert bp.b_dot_r_km == pytest.approx(b * np.sin(inc), abs=one_mm)


def test_obliquity_constant_and_ecliptic_pole():
    # IAU 1976: 23 deg 26' 21.448"; the ecliptic pole is at RA 270 deg, Dec 90 deg - eps.
    eps_deg = 23.0 + 26.0 / 60.0 + 21.448 / 3600.0
    assert np.degrees(OBLIQUITY_J2000_IAU1976_rad) == pytest.approx(eps_deg, rel=1e-15)
    expected = pole_from_ra_dec(np.radians(270.0), np.radians(90.0 - eps_deg))
    np.testing.assert_allclose(ECLIPTIC_POLE_EME2000, expected, atol=unit_atol)


# ---------------------------------------------------------------- invariance and LTOF
def test_rotating_state_and_pole_together_changes_no_scalar():
    rng = np.random.default_rng(20240611)
    r_pf, v_pf = _perifocal_state(15_000.0, 1.8, -1.2, MU_MARS)
    tilt = _rot_x(0.4)
    ref = b_plane(tilt @ r_pf, tilt @ v_pf, MU_MARS)
    for _ in range(5):
        q = _random_rotation(rng)
        rot = q @ tilt
        bp = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS, reference=q @ [0.0, 0.0, 1.0])
        assert bp.b_dot_t_km == pytest.approx(ref.b_dot_t_km, abs=one_mm)
        assert bp.b_dot_r_km == pytest.approx(ref.b_dot_r_km, abs=one_mm)
        assert bp.ltof_s == pytest.approx(ref.ltof_s, abs=one_us)
        np.testing.assert_allclose(bp.s_hat, q @ ref.s_hat, atol=unit_atol)
        # rotating the state but not the pole keeps |B| (only the T/R split moves)
        moved = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS)
        assert moved.b_mag_km == pytest.approx(ref.b_mag_km, abs=one_mm)


@pytest.mark.parametrize("F", [-4.0, -1.0, 0.0, 0.8])
def test_time_to_periapsis_and_ltof_against_kepler(F):
    a_abs, e = 12_000.0, 1.4
    n = np.sqrt(MU_MARS / a_abs**3)
    r_pf, v_pf = _perifocal_state(a_abs, e, F, MU_MARS)
    rot = _rot_x(0.3) @ _rot_z(1.1)
    bp = b_plane(rot @ r_pf, rot @ v_pf, MU_MARS)
    t_p = (F - e * np.sinh(F)) / n
    assert bp.time_to_periapsis_s == pytest.approx(t_p, abs=one_us)
    assert bp.ltof_s == pytest.approx(t_p + (np.exp(F) / e - 1.0 - F) / n, abs=one_us)
    assert bp.ltof_s == pytest.approx(-(rot @ r_pf) @ bp.s_hat / bp.v_inf_km_s, abs=one_us)


# ------------------------------------------------------------------------- the Jacobian
JACOBIAN_STATES = {
    "planar far approach": (40_000.0, 1.5, -4.0, 0.0, 0.0),
    "inclined approach": (20_000.0, 2.5, -1.0, 0.7, 0.3),
    "e=1.2 near periapsis": (10_000.0, 1.2, 0.05, 1.2, -0.5),
    "after periapsis": (5_000.0, 4.0, 0.9, 2.0, 2.0),
}


@pytest.mark.parametrize("state", JACOBIAN_STATES.values(), ids=JACOBIAN_STATES.keys())
def test_velocity_jacobian_against_central_differences(state):
    a_abs, e, F, inc, raan = state
    r_pf, v_pf = _perifocal_state(a_abs, e, F, MU_MARS)
    rot = _rot_z(raan) @ _rot_x(inc) @ _rot_z(0.4)
    r, v = rot @ r_pf, rot @ v_pf
    J = b_plane(r, v, MU_MARS).jacobian_v
    dv = 1e-6  # km/s (1 mm/s)
    J_cd = np.empty((3, 3))
    for k in range(3):
        step = np.zeros(3)
        step[k] = dv
        p, m = b_plane(r, v + step, MU_MARS), b_plane(r, v - step, MU_MARS)
        J_cd[:, k] = [
            (p.b_dot_r_km - m.b_dot_r_km) / (2 * dv),
            (p.b_dot_t_km - m.b_dot_t_km) / (2 * dv),
            (p.ltof_s - m.ltof_s) / (2 * dv),
        ]
    # Central differences at 1 mm/s: truncation ~ f''' dv^2 / 6 and rounding ~ eps |f| / dv
    # are both below 1e-8 of the largest entry of each row for these states; 1e-7 bounds them.
    cd_rtol = 1e-7
    scale = np.max(np.abs(J_cd), axis=1, keepdims=True)
    assert np.all(np.abs(J - J_cd) <= cd_rtol * scale)


# ------------------------------------------------------------------------ broadcasting
def test_a_leading_time_axis_broadcasts():
    states = [_perifocal_state(20_000.0, 1.5, F, MU_MARS) for F in (-2.0, -1.0, 0.0, 1.0)]
    rot = _rot_x(0.5)
    r = np.stack([rot @ s[0] for s in states])
    v = np.stack([rot @ s[1] for s in states])
    bp = b_plane(r, v, MU_MARS)
    assert bp.b_dot_t_km.shape == (4,) and bp.s_hat.shape == (4, 3)
    assert bp.jacobian_v.shape == (4, 3, 3)
    for i in range(4):
        one = b_plane(r[i], v[i], MU_MARS)
        assert one.b_dot_t_km.shape == ()
        assert bp.b_dot_r_km[i] == pytest.approx(one.b_dot_r_km, abs=one_mm)
        assert bp.ltof_s[i] == pytest.approx(one.ltof_s, abs=one_us)
        np.testing.assert_allclose(bp.jacobian_v[i], one.jacobian_v, rtol=1e-12)
    # all four points lie on one conic: same B-plane
    np.testing.assert_allclose(bp.b_dot_t_km, bp.b_dot_t_km[0], atol=one_mm)


# ------------------------------------------------------------------------------ errors
def test_elliptic_and_circular_states_are_not_hyperbolic():
    r = np.array([7_000.0, 0.0, 0.0])
    v_circ = np.sqrt(MU_EARTH / 7_000.0)
    with pytest.raises(NotHyperbolicError, match=r"e = 0(\.0+\d*)?, energy = -2\d\.\d+ km"):
        b_plane(r, [0.0, v_circ, 0.0], MU_EARTH)
    states_v = np.array([[0.0, 12.0, 0.0], [0.0, 11.0, 0.0], [0.0, 1.2 * v_circ, 0.0]])
    with pytest.raises(NotHyperbolicError, match=r"state \(2,\) has e = 0\.44.*1 of 3 states"):
        b_plane(r, states_v, MU_EARTH)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"r_km": [7000.0, 0.0]}, "r_km"),
        ({"v_km_s": [[0.0, 12.0]]}, "v_km_s"),
        ({"v_km_s": [0.0, np.nan, 0.0]}, "v_km_s"),
        ({"r_km": [0.0, 0.0, 0.0]}, "r_km"),
        ({"gm_km3_s2": -1.0}, "gm_km3_s2"),
        ({"reference": "galactic"}, "reference"),
        ({"reference": [0.0, 0.0, 0.0]}, "reference"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    args = {"r_km": [7000.0, 0.0, 0.0], "v_km_s": [0.0, 12.0, 0.0], "gm_km3_s2": MU_EARTH}
    args.update(kwargs)
    with pytest.raises(InputError) as info:
        b_plane(args.pop("r_km"), args.pop("v_km_s"), args.pop("gm_km3_s2"), **args)
    assert info.value.field == field


def test_pole_along_the_asymptote_is_refused():
    r_pf, v_pf = _perifocal_state(20_000.0, 1.5, -1.0, MU_MARS)
    s_hat = np.array([1.0, np.sqrt(1.25), 0.0]) / 1.5
    with pytest.raises(InputError, match="not parallel to the incoming asymptote"):
        b_plane(r_pf, v_pf, MU_MARS, reference=s_hat)

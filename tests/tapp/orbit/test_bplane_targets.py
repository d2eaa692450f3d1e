"""Targets of issue 31: the B-plane in the target body's own equator, and the entry flight-path
angle, against formulas and an integration written here.

- The Mars B-plane with ``reference = "body_equator"``: the asymptote from the eccentricity
  vector (Vallado 2013, ch. 2), B as the foot of the perpendicular from the focus to the
  incoming asymptote through the hyperbola's centre, T from the IAU 2015 Mars pole of
  Archinal et al. (2018), Celest. Mech. Dyn. Astron. 130:22, Table 2, written out below.
- The entry flight-path angle: a two-body integration (scipy DOP853) from the state to the
  interface radius, where sin(gamma) = r.v / (r v).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tapp.constants import GM_km3_s2
from tapp.dynamics import Propagator
from tapp.dynamics.spec import ForceModel, earth_model, parse_gravity
from tapp.errors import InputError
from tapp.frames.time import parse_epoch
from tapp.orbit.bplane import b_plane, entry_flight_path_angle
from tapp.targeting.program import BPlaneProgram

MU_MARS = GM_km3_s2["mars"]
EPOCH = "2026-11-20T06:00:00"
T_S = 5400.0  # the B-plane's time, s after the epoch
# TT - UTC in 2026: 37 s of leap seconds + 32.184 s (TAI - UTC, TT - TAI; TDB - TT < 2 ms
# moves the Mars pole by < 1e-14 rad).
TT_MINUS_UTC_s = 69.184

# A Mars approach 5e5 km out at v_inf ~ 3 km/s aimed 3,300 km off the centre (an arrival:
# periapsis ~1,000 km), km and km/s, EME2000 axes, Mars-relative.
R_APPROACH_km = np.array([340_000.0, 366_000.0, 30_000.0])
V_APPROACH_km_s = np.array([-2.02, -2.20, -0.17])

# B·R, B·T of ~3e3 km from 5e5-km vectors: rounding ~1e-16 x 5e5 / 3e3 relative per step, a
# few dozen steps: ~1e-12 (measured 6e-15). 1e-9 of |B| (3 micrometres) leaves margin and
# still sees a pole off by 1e-9 rad.
B_RTOL = 1e-9
# DOP853 at rtol 1e-12 over ~1e5 km: the state at the interface to ~1e-10 relative, so the
# angle to ~1e-10 rad; the event root is found on the dense output at the same accuracy.
# 1e-8 rad (a 0.2 mm lateral offset over the 20 km the spacecraft travels per 10 s) bounds it.
FPA_ATOL_rad = 1e-8


def _mars_pole(jd_tdb: float) -> np.ndarray:
    """The IAU 2015 Mars pole (Archinal et al. 2018, Table 2; Kuchynka et al. 2014), unit
    vector in ICRF axes, T in Julian centuries of TDB from J2000, angles in degrees."""
    t = (jd_tdb - 2451545.0) / 36525.0
    d = np.radians
    alpha = (317.269202 - 0.10927547 * t
             + 0.000068 * np.sin(d(198.991226 + 19139.4819985 * t))
             + 0.000238 * np.sin(d(226.292679 + 38280.8511281 * t))
             + 0.000052 * np.sin(d(249.663391 + 57420.7251593 * t))
             + 0.000009 * np.sin(d(266.183510 + 76560.6367950 * t))
             + 0.419057 * np.sin(d(79.398797 + 0.5042615 * t)))
    delta = (54.432516 - 0.05827105 * t
             + 0.000051 * np.cos(d(122.433576 + 19139.9407476 * t))
             + 0.000141 * np.cos(d(43.058401 + 38280.8753272 * t))
             + 0.000031 * np.cos(d(57.663379 + 57420.7517205 * t))
             + 0.000005 * np.cos(d(79.476401 + 76560.6495004 * t))
             + 1.591274 * np.cos(d(166.325722 + 0.5042615 * t)))
    a, dl = d(alpha), d(delta)
    return np.array([np.cos(dl) * np.cos(a), np.cos(dl) * np.sin(a), np.sin(dl)])


def _b_plane_by_hand(r: np.ndarray, v: np.ndarray, mu: float, pole: np.ndarray):
    """(B·R, B·T) km: S from e and h, B from the hyperbola's centre, T, R from the pole."""
    rm = np.linalg.norm(r)
    e_vec = ((v @ v - mu / rm) * r - (r @ v) * v) / mu
    e = np.linalg.norm(e_vec)
    e_hat = e_vec / e
    h_hat = np.cross(r, v) / np.linalg.norm(np.cross(r, v))
    s_hat = e_hat / e + np.sqrt(1.0 - 1.0 / e**2) * np.cross(h_hat, e_hat)
    a_abs = mu / (v @ v - 2.0 * mu / rm)  # |a| = mu / v_inf^2
    centre = a_abs * e * e_hat  # the centre lies beyond periapsis, |a| e from the focus
    b_vec = centre - (centre @ s_hat) * s_hat  # closest point of the asymptote to the focus
    t_hat = np.cross(s_hat, pole) / np.linalg.norm(np.cross(s_hat, pole))
    r_hat = np.cross(s_hat, t_hat)
    return np.array([b_vec @ r_hat, b_vec @ t_hat])


@pytest.fixture(scope="module")
def mars_program() -> BPlaneProgram:
    epoch = parse_epoch(EPOCH)
    return BPlaneProgram(epoch, np.array([7000.0, 0.0, 0.0]),
                         Propagator(earth_model("J2", ("sun", "mars"))), target="mars",
                         reference="body_equator")


def test_mars_b_plane_in_its_own_equator_against_the_closed_form(mars_program) -> None:
    jd_tdb = parse_epoch(EPOCH).jd + (TT_MINUS_UTC_s + T_S) / 86400.0
    pole = _mars_pole(jd_tdb)
    program_pole = mars_program.reference_pole(T_S)[0]
    # The same IAU series at TT instead of TDB: a few 1e-16 rad.
    np.testing.assert_allclose(program_pole, pole, rtol=0.0, atol=1e-13)
    bp = b_plane(R_APPROACH_km, V_APPROACH_km_s, MU_MARS, reference=program_pole)
    assert 2.9 < float(bp.v_inf_km_s) < 3.1
    expected = _b_plane_by_hand(R_APPROACH_km, V_APPROACH_km_s, MU_MARS, pole)
    got = np.array([float(bp.b_dot_r_km), float(bp.b_dot_t_km)])
    rel = np.abs(got - expected) / np.linalg.norm(expected)
    assert rel.max() < B_RTOL, (got, expected, rel)
    # The plane matters: T in the Earth's equator is turned by 37 deg about S, which moves
    # (B·R, B·T) by thousands of km, so a reference ignored would fail above.
    earth = b_plane(R_APPROACH_km, V_APPROACH_km_s, MU_MARS, reference="earth_equator")
    moved = np.array([float(earth.b_dot_r_km), float(earth.b_dot_t_km)]) - expected
    assert np.linalg.norm(moved) > 1000.0, moved


def test_body_equator_of_the_earth_is_the_eme2000_equator() -> None:
    """A Moon-centred program aiming at the Earth: its body_equator pole is the EME2000 z
    axis at every time, the plane of "earth_equator"."""
    program = BPlaneProgram(parse_epoch(EPOCH), np.array([0.0, 7000.0, 0.0]),
                            Propagator(ForceModel(parse_gravity("J0"), "moon", ("earth",))),
                            target="earth", reference="body_equator")
    np.testing.assert_array_equal(program.reference_pole([0.0, 3.0e6]),
                                  [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])


def test_body_equator_of_a_body_without_a_pole_model_is_refused() -> None:
    with pytest.raises(InputError, match=r"earth, mars, moon, venus") as info:
        BPlaneProgram(parse_epoch(EPOCH), np.array([7000.0, 0.0, 0.0]),
                      Propagator(earth_model("J2", ("sun", "jupiter"))), target="jupiter",
                      reference="body_equator")
    assert info.value.field == "reference"


def _integrated_fpa(r0: np.ndarray, v0: np.ndarray, mu: float, r_e: float) -> float:
    """Flight-path angle (rad) where the two-body motion first reaches |r| = r_e."""
    def rhs(_t, y):
        r = y[:3]
        return np.concatenate([y[3:], -mu * r / np.linalg.norm(r) ** 3])

    def reach(_t, y):
        return np.linalg.norm(y[:3]) - r_e

    reach.terminal, reach.direction = True, -1.0
    sol = solve_ivp(rhs, (0.0, 1e6), np.concatenate([r0, v0]), method="DOP853", rtol=1e-12,
                    atol=1e-12, events=reach)
    y = sol.y_events[0][0]
    r, v = y[:3], y[3:]
    return float(np.arcsin((r @ v) / (np.linalg.norm(r) * np.linalg.norm(v))))


# Mars entry: 100,000 km out at v_inf ~ 3 km/s, aimed 5,000 km off the centre (periapsis
# ~2,300 km, below the 125 km interface and the surface).
R_ENTRY_km = np.array([-100_000.0, 3_000.0, 4_000.0])
V_ENTRY_km_s = np.array([3.02, 0.0, 0.0])
# The interface 125 km above the IAU mean radius of Mars (3389.5 km), and a higher one.
INTERFACE_km = np.array([3389.5 + 125.0, 4500.0])


def test_entry_flight_path_angle_against_a_two_body_integration() -> None:
    got = entry_flight_path_angle(R_ENTRY_km, V_ENTRY_km_s, MU_MARS, INTERFACE_km)
    assert got.shape == (2,)
    expected = np.array([_integrated_fpa(R_ENTRY_km, V_ENTRY_km_s, MU_MARS, r_e)
                         for r_e in INTERFACE_km])
    assert np.all(expected < 0.0)
    np.testing.assert_allclose(got, expected, rtol=0.0, atol=FPA_ATOL_rad)


def test_entry_flight_path_angle_refusals_name_the_radius() -> None:
    r_p = float(b_plane(R_ENTRY_km, V_ENTRY_km_s, MU_MARS).periapsis_radius_km)
    with pytest.raises(InputError, match=rf"periapsis radius {r_p:.3f} km") as info:
        entry_flight_path_angle(R_ENTRY_km, V_ENTRY_km_s, MU_MARS, r_p - 1.0)
    assert info.value.field == "entry_radius_km"
    # At the periapsis radius itself the conic grazes it: a horizontal velocity.
    assert abs(float(entry_flight_path_angle(R_ENTRY_km, V_ENTRY_km_s, MU_MARS,
                                             r_p + 1e-6))) < 1e-3
    for radius in (0.0, -5.0, np.linalg.norm(R_ENTRY_km), np.nan):
        with pytest.raises(InputError) as info:
            entry_flight_path_angle(R_ENTRY_km, V_ENTRY_km_s, MU_MARS, radius)
        assert info.value.field == "entry_radius_km"

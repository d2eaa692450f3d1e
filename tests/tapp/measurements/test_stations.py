"""Stations: Earth-fixed location, inertial state, and partials w.r.t. the location."""

import dataclasses

import numpy as np
import pytest

from tapp.constants import OMEGA_EARTH_rad_s, WGS84_A_km
from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tapp.measurements import STATION_PARAMETER_NAMES, Station, station_state_partials
from tapp.measurements.stations import station_state_eci

#: Positions rebuilt through geodetic coordinates: 1 um.
ONE_MICROMETRE_km = 1e-9
#: Central differences (steps below): relative error of the partials.
FD_REL = 1e-6
GOLDSTONE = Station.from_degrees("DSS-14", 35.4259, 243.1105, 1.002, elev_mask_deg=6.0)


def test_equatorial_station_at_theta0_zero_rotates_at_omega():
    station = Station("EQ0", 0.0, 0.0, 0.0)
    t_s = np.array([0.0, 100.0, 0.5 * np.pi / OMEGA_EARTH_rad_s, 3.0e4])
    state = station.state_eci(0.0, t_s)
    assert state.shape == (4, 6)
    assert np.allclose(state[0], [WGS84_A_km, 0, 0, 0, OMEGA_EARTH_rad_s * WGS84_A_km, 0],
                       rtol=0, atol=ONE_MICROMETRE_km)
    assert np.allclose(state[2, :3], [0.0, WGS84_A_km, 0.0], rtol=0, atol=ONE_MICROMETRE_km)
    angle = np.unwrap(np.arctan2(state[:, 1], state[:, 0]))
    assert np.allclose(angle, OMEGA_EARTH_rad_s * t_s, rtol=0, atol=1e-13)
    assert np.allclose(np.linalg.norm(state[:, :3], axis=1), WGS84_A_km, rtol=1e-15)
    # v = omega x r everywhere.
    omega = np.array([0.0, 0.0, OMEGA_EARTH_rad_s])
    assert np.allclose(state[:, 3:], np.cross(omega, state[:, :3]), rtol=0, atol=1e-15)


def test_theta0_shifts_the_station_in_right_ascension():
    r0 = GOLDSTONE.state_eci(0.0, [0.0])[0, :3]
    r1 = GOLDSTONE.state_eci(0.0, [1000.0])[0, :3]
    shifted = GOLDSTONE.state_eci(1000.0 * OMEGA_EARTH_rad_s, [0.0])[0, :3]
    assert np.allclose(shifted, r1, atol=ONE_MICROMETRE_km)
    assert r0[2] == pytest.approx(GOLDSTONE.z_km)


@pytest.mark.parametrize("parameters", ["cylindrical", "ecef"])
@pytest.mark.parametrize("orientation", [EarthOrientation.gmst_angle(0.9),
                                         EarthOrientation.iau2006(Epoch.from_calendar(2026, 1, 1))],
                         ids=["gmst", "iau2006"])
def test_state_partials_against_central_differences(parameters, orientation):
    # Steps: 1 m in r_s, x, y, z and 1e-7 rad (0.5 m) in longitude. The station state is
    # linear in r_s, x, y, z (differences exact to rounding, eps * 6e3 km / 1e-3 km ~ 1e-12)
    # and trigonometric in longitude (truncation h^2/6 ~ 2e-15).
    t_s = np.array([0.0, 3600.0, 5.0e4])
    attitude = orientation.attitude(t_s)
    r_f = GOLDSTONE.r_ecef_km
    if parameters == "cylindrical":
        p0 = GOLDSTONE.location("cylindrical")
        steps = np.array([1e-3, 1e-7, 1e-3])

        def r_of(p):
            return np.array([p[0] * np.cos(p[1]), p[0] * np.sin(p[1]), p[2]])
    else:
        p0 = r_f.copy()
        steps = np.full(3, 1e-3)

        def r_of(p):
            return p

    assert np.allclose(r_of(p0), r_f, atol=ONE_MICROMETRE_km)
    analytic = GOLDSTONE.state_partials(orientation, t_s, parameters)
    assert analytic.shape == (3, 6, 3)
    for j in range(3):
        dp = np.zeros(3)
        dp[j] = steps[j]
        fd = (station_state_eci(r_of(p0 + dp), attitude)
              - station_state_eci(r_of(p0 - dp), attitude)) / (2 * steps[j])
        state = station_state_eci(r_f, attitude)
        for block in (slice(0, 3), slice(3, 6)):
            err = np.linalg.norm(fd[:, block] - analytic[:, block, j], axis=-1)
            # Rounding floor of the difference: 8 eps |block| / step (a near-zero partial,
            # e.g. dv/dz = omega (c x z) ~ 1e-10 with iau2006, is below it).
            floor = 8 * np.finfo(float).eps * np.linalg.norm(state[:, block], axis=-1) / steps[j]
            assert np.all(err <= FD_REL * np.linalg.norm(analytic[:, block, j], axis=-1) + floor)


def test_constructors_agree():
    again = Station.from_ecef("DSS-14", GOLDSTONE.r_ecef_km, GOLDSTONE.elev_mask_rad)
    assert np.allclose(again.r_ecef_km, GOLDSTONE.r_ecef_km, atol=ONE_MICROMETRE_km)
    assert again.lat_rad == pytest.approx(GOLDSTONE.lat_rad, abs=1e-13)
    cyl = Station.from_cylindrical("DSS-14", *GOLDSTONE.location("cylindrical"))
    assert np.allclose(cyl.r_ecef_km, GOLDSTONE.r_ecef_km, atol=ONE_MICROMETRE_km)
    assert GOLDSTONE.lon_rad == pytest.approx(np.radians(243.1105))
    assert GOLDSTONE.elev_mask_rad == pytest.approx(np.radians(6.0))
    assert STATION_PARAMETER_NAMES["cylindrical"] == ("spin_radius_km", "lon_rad", "z_km")


def test_station_is_frozen_hashable_and_validated():
    with pytest.raises(dataclasses.FrozenInstanceError):
        GOLDSTONE.h_km = 0.0
    assert not GOLDSTONE.r_ecef_km.flags.writeable
    assert hash(GOLDSTONE) == hash(Station.from_degrees("DSS-14", 35.4259, 243.1105, 1.002, 6.0))
    with pytest.raises(InputError, match="lat_rad"):
        Station("bad", 2.0, 0.0, 0.0)
    with pytest.raises(InputError, match="parameters"):
        station_state_partials(GOLDSTONE.r_ecef_km, EarthOrientation.gmst_angle(0.0).attitude(0.0),
                               "geodetic")
    with pytest.raises(InputError, match="parameters"):
        GOLDSTONE.location("spherical")

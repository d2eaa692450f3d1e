"""The seed examples' cheap body: direct-ascent geometry against hand-computed values."""

from __future__ import annotations

import math

import pytest

from tapp.targeting.launch_azimuth import launch_azimuth_case

ONE_MICRODEGREE_deg = 1e-6
ONE_MM_PER_S_km_s = 1e-6
CAPE = {"latitude_deg": 28.5, "east_longitude_deg": -80.6, "altitude_km": 185.0}


def test_due_east_from_the_equator_saves_the_whole_pad_speed():
    out = launch_azimuth_case(0.0, 90.0, latitude_deg=0.0, east_longitude_deg=0.0,
                              altitude_km=185.0)
    assert out["inclination_deg"] == pytest.approx(0.0, abs=ONE_MICRODEGREE_deg)
    # Hand: omega R = 7.292115e-5 rad/s x 6378.1363 km = 0.4651010 km/s;
    # v_c = sqrt(398600.4415 / 6563.1363) = 7.7931525 km/s.
    assert out["rotation_gain_km_s"] == pytest.approx(0.4651010, abs=ONE_MM_PER_S_km_s)
    assert out["circular_speed_km_s"] == pytest.approx(7.7931525, abs=ONE_MM_PER_S_km_s)


def test_due_east_gives_the_latitude_as_inclination_and_the_node_90_deg_back():
    # At J2000.0 the Greenwich sidereal angle is 280.46061837 deg (Meeus eq. 12.4); due east
    # the site is at the orbit's highest latitude, 90 deg past the ascending node.
    out = launch_azimuth_case(0.0, 90.0, latitude_deg=28.5, east_longitude_deg=0.0,
                              altitude_km=185.0)
    assert out["inclination_deg"] == pytest.approx(28.5, abs=ONE_MICRODEGREE_deg)
    assert out["raan_deg"] == pytest.approx(190.46061837, abs=ONE_MICRODEGREE_deg)


def test_seed_first_azimuth_inclination():
    # Hand: cos i = cos 28.5 deg x sin 96 deg = 0.8788171 x 0.9945219 = 0.8740030 -> 29.07282 deg.
    out = launch_azimuth_case(5730.0, 96.0, **CAPE)
    assert out["inclination_deg"] == pytest.approx(29.07282, abs=1e-5)


def test_mirror_azimuths_share_inclination_and_delta_v_not_node():
    north = launch_azimuth_case(5730.0, 84.0, **CAPE)
    south = launch_azimuth_case(5730.0, 96.0, **CAPE)
    assert north["inclination_deg"] == pytest.approx(south["inclination_deg"], rel=1e-12)
    assert north["delta_v_km_s"] == pytest.approx(south["delta_v_km_s"], rel=1e-12)
    assert abs(north["raan_deg"] - south["raan_deg"]) > 1.0


def test_a_day_later_the_node_moves_by_the_sidereal_excess():
    # One solar day turns the Earth by 360.98564736629 deg: the node moves 0.98564736629 deg.
    day_0 = launch_azimuth_case(5730.0, 99.0, **CAPE)["raan_deg"]
    day_1 = launch_azimuth_case(5731.0, 99.0, **CAPE)["raan_deg"]
    assert math.remainder(day_1 - day_0, 360.0) == pytest.approx(0.98564736629, abs=1e-9)

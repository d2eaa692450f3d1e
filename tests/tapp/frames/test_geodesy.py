"""Geodetic <-> Earth-fixed coordinates on WGS84, and the local ENU axes."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from tapp.constants import WGS84_F, WGS84_A_km
from tapp.frames import ecef_to_geodetic, enu_matrix, geodetic_to_ecef

B_km = WGS84_A_km * (1.0 - WGS84_F)
E2 = WGS84_F * (2.0 - WGS84_F)
#: Round trips: double precision on positions up to 1e5 km is ~1e-11 km; one micrometre.
ONE_MICROMETRE_km = 1e-9
#: Angles recovered to 1e-12 rad (6 um on the ground).
ANGLE_rad = 1e-12


def test_equator_and_poles():
    assert np.allclose(geodetic_to_ecef(0.0, 0.0, 0.0), [WGS84_A_km, 0, 0], atol=ONE_MICROMETRE_km)
    assert np.allclose(geodetic_to_ecef(0.0, np.pi / 2, 1.0), [0, WGS84_A_km + 1, 0],
                       atol=ONE_MICROMETRE_km)
    assert np.allclose(geodetic_to_ecef(np.pi / 2, 0.3, 0.0), [0, 0, B_km], atol=ONE_MICROMETRE_km)
    assert np.allclose(geodetic_to_ecef(-np.pi / 2, 0.0, 2.0), [0, 0, -B_km - 2],
                       atol=ONE_MICROMETRE_km)
    lat, lon, h = ecef_to_geodetic([0.0, 0.0, B_km + 5.0])
    assert abs(lat - np.pi / 2) < ANGLE_rad and abs(h - 5.0) < ONE_MICROMETRE_km
    lat, lon, h = ecef_to_geodetic([0.0, 0.0, -B_km])
    assert abs(lat + np.pi / 2) < ANGLE_rad and abs(h) < ONE_MICROMETRE_km
    lat, lon, h = ecef_to_geodetic([0.0, -WGS84_A_km - 3.0, 0.0])
    assert abs(lat) < ANGLE_rad and abs(lon + np.pi / 2) < ANGLE_rad and abs(h - 3.0) < 1e-9


def test_surface_points_lie_on_the_meridian_ellipse():
    # On the ellipsoid, z / p = (1 - e^2) tan(lat) and p^2/a^2 + z^2/b^2 = 1.
    lat = np.radians([-80.0, -45.0, 10.0, 45.0, 89.0])
    r = geodetic_to_ecef(lat, 0.7, 0.0)
    p = np.hypot(r[:, 0], r[:, 1])
    assert np.allclose(r[:, 2] / p, (1 - E2) * np.tan(lat), rtol=1e-14)
    assert np.allclose(p**2 / WGS84_A_km**2 + r[:, 2] ** 2 / B_km**2, 1.0, rtol=0, atol=1e-14)


def test_vallado_example_3_3():
    # Vallado, Fundamentals of Astrodynamics and Applications, Example 3-3:
    # r = (6524.834, 6862.875, 6448.296) km -> lat_gd 34.352496 deg, lon 46.4464 deg,
    # h_ellp 5085.22 km. Tolerances: the printed digits, plus Vallado's e = 0.081819221456
    # against WGS84's 0.0818191908426 (2e-7 deg of latitude at this point).
    lat, lon, h = ecef_to_geodetic([6524.834, 6862.875, 6448.296])
    assert abs(np.degrees(lat) - 34.352496) < 1e-6
    assert abs(np.degrees(lon) - 46.4464) < 5e-5
    assert abs(h - 5085.22) < 5e-3


@given(
    st.floats(-np.pi / 2, np.pi / 2),
    st.floats(-np.pi, np.pi, exclude_min=True),
    st.floats(-10.0, 1.0e5),
)
def test_geodetic_round_trip(lat, lon, h):
    r = geodetic_to_ecef(lat, lon, h)
    lat2, lon2, h2 = ecef_to_geodetic(r)
    assert np.linalg.norm(geodetic_to_ecef(lat2, lon2, h2) - r) < ONE_MICROMETRE_km
    assert abs(lat2 - lat) < ANGLE_rad
    assert abs(h2 - h) < ONE_MICROMETRE_km
    if abs(lat) < np.pi / 2 - 1e-6:  # longitude is undefined on the axis
        assert abs(np.angle(np.exp(1j * (lon2 - lon)))) < ANGLE_rad / np.cos(lat)


def test_geodetic_functions_broadcast():
    lat = np.radians([[10.0, 20.0, 30.0], [40.0, 50.0, 60.0]])
    r = geodetic_to_ecef(lat, 0.2, 0.5)
    assert r.shape == (2, 3, 3)
    lat2, lon2, h2 = ecef_to_geodetic(r)
    assert lat2.shape == (2, 3) and np.allclose(lat2, lat, atol=ANGLE_rad)


def test_enu_axes_are_orthonormal_and_up_is_the_ellipsoid_normal():
    lat, lon = np.radians([-33.0, 0.0, 40.4, 89.0]), np.radians([149.0, 0.0, -4.25, 10.0])
    m = enu_matrix(lat, lon)
    assert np.allclose(m @ np.swapaxes(m, -1, -2), np.eye(3), atol=1e-15)
    assert np.allclose(np.linalg.det(m), 1.0)
    # Normal to x^2/a^2 + y^2/a^2 + z^2/b^2 = 1 at the surface point.
    r = geodetic_to_ecef(lat, lon, 0.0)
    normal = r / np.array([WGS84_A_km**2, WGS84_A_km**2, B_km**2])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    assert np.allclose(m[:, 2, :], normal, atol=1e-15)
    # East is horizontal and points along increasing longitude; north has z >= 0.
    assert np.allclose(m[:, 0, 2], 0.0)
    assert np.all(m[:, 1, 2] >= 0.0)

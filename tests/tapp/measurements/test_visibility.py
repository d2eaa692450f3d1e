"""Hand-checked topocentric geometry, visibility above the mask, and pass grouping."""

import numpy as np
import pytest

from tapp.frames.orientation import EarthOrientation
from tapp.measurements import (
    MeasurementModel,
    Station,
    find_passes,
    is_visible,
    pass_labels,
    residual,
    wrap_angle_rad,
)
from tapp.measurements.stations import station_state_eci
from tapp.orbit import Elements, kepler_states

#: Angles from exactly constructed geometry: rounding of unit vectors (1e-16) over lengths of
#: 1e3 km; a nanoradian.
NANORADIAN = 1e-9
THETA0_rad = 0.7
T_s = np.array([0.0, 1234.5])
STATION = Station.from_degrees("Madrid-like", 40.4272, -4.2506, 0.834, elev_mask_deg=10.0)


def _spacecraft_along(enu_direction, distance_km):
    """Inertial states (N, 6) at T_s placed along a local ENU direction of STATION."""
    attitude = EarthOrientation.gmst_angle(THETA0_rad).attitude(T_s)
    station = station_state_eci(STATION.r_ecef_km, attitude)
    enu_to_eci = np.swapaxes(STATION.enu_from_eci(attitude), -1, -2)
    offset = distance_km * enu_to_eci @ (np.asarray(enu_direction) / np.linalg.norm(enu_direction))
    return np.concatenate([station[:, :3] + offset, station[:, 3:]], axis=1)


def _az_el(states):
    model = MeasurementModel(STATION, THETA0_rad, ("azimuth", "elevation"))
    obs = model.compute(T_s, states)
    return obs[:, 0], obs[:, 1]


def test_spacecraft_straight_overhead_is_at_90_deg_elevation():
    az, el = _az_el(_spacecraft_along([0, 0, 1], 800.0))
    assert np.allclose(el, np.pi / 2, rtol=0, atol=NANORADIAN)
    assert np.all(is_visible(el, STATION.elev_mask_rad))


@pytest.mark.parametrize(
    ("direction", "azimuth_deg"),
    [([0, 1, 0], 0.0), ([1, 0, 0], 90.0), ([0, -1, 0], 180.0), ([-1, 0, 0], 270.0),
     ([1, 1, 0], 45.0)],
)
def test_on_the_horizon_plane_elevation_is_zero_and_azimuth_known(direction, azimuth_deg):
    az, el = _az_el(_spacecraft_along(direction, 2000.0))
    assert np.allclose(el, 0.0, rtol=0, atol=NANORADIAN)
    assert np.allclose(wrap_angle_rad(az - np.radians(azimuth_deg)), 0.0, rtol=0, atol=NANORADIAN)
    assert not np.any(is_visible(el, STATION.elev_mask_rad))


def test_below_the_mask_is_not_visible_above_it_is():
    mask = STATION.elev_mask_rad
    for elevation_deg, seen in [(5.0, False), (9.99, False), (10.01, True), (15.0, True)]:
        e = np.radians(elevation_deg)
        _, el = _az_el(_spacecraft_along([0, np.cos(e), np.sin(e)], 3000.0))
        assert np.allclose(el, e, rtol=0, atol=NANORADIAN)
        assert np.all(is_visible(el, mask) == seen)


def test_on_the_mask_exactly_is_not_visible():
    assert not is_visible(np.array([0.2]), 0.2)[0]


def test_passes_from_a_constructed_elevation_sequence():
    elevation = np.array([-0.1, 0.2, 0.3, 0.05, -0.2, -0.1, 0.3, 0.4, 0.11, 0.0])
    visible = is_visible(elevation, 0.1)
    assert visible.tolist() == [False, True, True, False, False, False, True, True, True, False]
    passes = find_passes(visible)
    assert passes.tolist() == [[1, 3], [6, 9]]
    assert passes.dtype == np.int64
    assert pass_labels(visible).tolist() == [-1, 0, 0, -1, -1, -1, 1, 1, 1, -1]


def test_passes_at_the_ends_empty_and_full():
    assert find_passes([True, True, False, True]).tolist() == [[0, 2], [3, 4]]
    assert find_passes([True] * 4).tolist() == [[0, 4]]
    assert find_passes([False] * 3).shape == (0, 2)
    assert find_passes([]).shape == (0, 2)


def test_a_time_gap_splits_a_pass():
    t_s = np.array([0.0, 10.0, 20.0, 500.0, 510.0, 520.0])
    visible = np.ones(6, dtype=bool)
    assert find_passes(visible).tolist() == [[0, 6]]
    assert find_passes(visible, t_s, max_gap_s=60.0).tolist() == [[0, 3], [3, 6]]
    assert pass_labels(visible, t_s, 60.0).tolist() == [0, 0, 0, 1, 1, 1]


def test_residual_wraps_azimuth_only():
    kinds = ("range", "azimuth", "elevation")
    observed = np.array([[1000.0, np.radians(359.9), 0.5]])
    computed = np.array([[999.0, np.radians(0.1), 0.4]])
    res = residual(observed, computed, kinds)
    assert res[0, 0] == pytest.approx(1.0)
    assert res[0, 1] == pytest.approx(np.radians(-0.2))
    assert res[0, 2] == pytest.approx(0.1)
    assert wrap_angle_rad(np.pi) == pytest.approx(np.pi)
    assert wrap_angle_rad(-np.pi) == pytest.approx(np.pi)
    assert wrap_angle_rad(3 * np.pi / 2) == pytest.approx(-np.pi / 2)


def test_passes_of_an_equatorial_leo_over_an_equatorial_station():
    # SATORB1 of the approximate-STM study (a = 6550.524 km, e = i = 0), seen from the
    # equator: each pass is a run above the mask bounded by samples at or below it.
    station = Station.from_degrees("EQ", 0.0, 20.0, 0.0, elev_mask_deg=5.0)
    model = MeasurementModel(station, THETA0_rad, ("elevation",))
    t_s = np.arange(0.0, 6 * 3600.0, 10.0)
    states = kepler_states(Elements.from_degrees(6550.524, 0, 0, 0, 0, 0).to_array(), t_s)
    visible = model.visible(t_s, states)
    elevation = model.elevation_rad(t_s, states)
    passes = find_passes(visible)
    assert len(passes) >= 3
    for start, stop in passes:
        assert np.all(elevation[start:stop] > station.elev_mask_rad)
        assert start == 0 or elevation[start - 1] <= station.elev_mask_rad
        assert stop == len(t_s) or elevation[stop] <= station.elev_mask_rad
    assert visible.sum() == sum(stop - start for start, stop in passes)

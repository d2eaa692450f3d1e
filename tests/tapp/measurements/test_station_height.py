"""Issue 10, class 4: a ground station's height lies in a plausible band."""

from __future__ import annotations

import math

import pytest

from tapp.errors import InputError
from tapp.measurements.stations import HEIGHT_RANGE_km, Station


@pytest.mark.parametrize("h_km", [1e9, 10.001, -0.501, -6378.0, math.inf, math.nan])
def test_a_height_outside_the_band_is_refused_with_the_band(h_km: float) -> None:
    # The example: a station 1e9 km high got no observations and no word.
    with pytest.raises(InputError) as info:
        Station.from_degrees("HIGH", 10.0, 20.0, h_km)
    assert (info.value.source, info.value.field) == ("station HIGH", "h_km")
    assert info.value.expected == ("a ground-station height in [-0.5, 10] km above the WGS84 "
                                   "ellipsoid")


def test_the_band_runs_from_the_dead_sea_to_above_everest() -> None:
    assert HEIGHT_RANGE_km == (-0.5, 10.0)
    assert Station.from_degrees("DEAD_SEA", 31.5, 35.5, -0.43).h_km == -0.43
    assert Station.from_degrees("EVEREST", 27.99, 86.93, 8.85).h_km == 8.85


def test_a_station_built_from_ecef_far_from_the_ground_is_refused() -> None:
    with pytest.raises(InputError, match="h_km: expected a ground-station height"):
        Station.from_ecef("FAR", [1e6, 0.0, 0.0])

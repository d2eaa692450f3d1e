"""The bands' carriers fall in the DSN's deep-space allocations (810-005, module 201)."""

import pytest

from tapp.measurements.bands import BAND_NAMES, BANDS, DEFAULT_BAND

#: Deep-space (category B) allocations, MHz: uplink, downlink (810-005 module 201, table 1).
ALLOCATIONS_MHz = {"S": ((2110.0, 2120.0), (2290.0, 2300.0)),
                   "X": ((7145.0, 7190.0), (8400.0, 8450.0)),
                   "Ka": ((34200.0, 34700.0), (31800.0, 32300.0))}


@pytest.mark.parametrize("name", BAND_NAMES)
def test_uplink_and_coherent_downlink_lie_in_the_allocations(name):
    band = BANDS[name]
    (up_lo, up_hi), (down_lo, down_hi) = ALLOCATIONS_MHz[name]
    assert up_lo <= band.uplink_hz / 1e6 <= up_hi
    assert down_lo <= band.downlink_hz / 1e6 <= down_hi


def test_the_default_band_is_one_of_them():
    assert DEFAULT_BAND in BANDS and set(BANDS) == set(BAND_NAMES)

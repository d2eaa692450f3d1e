"""tapp's media (tapp.measurements.media) against Orekit 13: Niell's mapping functions
(``NiellMappingFunctionModel``) and the single-layer ionosphere (``EstimatedIonosphericModel``
with ``SingleLayerModelMappingFunction``), two stations, two dates, elevations 5-90 deg.

Orekit's zenith delays (its Saastamoinen variants: 0.002277 P with a B(h) tan² z term, no
latitude and height term) are not the Davis form: test_media.py checks the zenith delay against
the published 2.3070 m instead.
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.frames.time import Epoch
from tapp.measurements.bands import BANDS
from tapp.measurements.media import (
    IONO_KM_HZ2_PER_TECU,
    day_of_year,
    niell_hydrostatic,
    niell_wet,
    single_layer,
)

pytest.importorskip("orekit_jpype")
from tests import orekit_session  # noqa: E402  (after the skip: it needs Orekit)

ELEVATIONS_rad = np.radians([5.0, 7.5, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0, 90.0])
#: DSS-63 (Madrid) and DSS-43 (Canberra): geodetic latitude deg, height km.
SITES = {"madrid": (40.4313, 0.865), "canberra": (-35.4023, 0.689)}
#: Dates within the Orekit world's span (tests/orekit_session.py), 0h UTC.
DATES = ((2026, 3, 20), (2026, 7, 15))


def _orekit_niell(lat_deg: float, h_km: float, date: tuple[int, int, int]) -> np.ndarray:
    orekit_session.world()
    from org.orekit.bodies import GeodeticPoint
    from org.orekit.models.earth.troposphere import NiellMappingFunctionModel
    from org.orekit.time import AbsoluteDate, TimeScalesFactory
    from org.orekit.utils import TrackingCoordinates

    utc = TimeScalesFactory.getUTC()
    model = NiellMappingFunctionModel(utc)
    point = GeodeticPoint(float(np.radians(lat_deg)), 0.3, h_km * 1e3)
    when = AbsoluteDate(*date, 0, 0, 0.0, utc)
    return np.array([list(model.mappingFactors(TrackingCoordinates(0.0, float(e), 1e6), point,
                                               when)) for e in ELEVATIONS_rad])


@pytest.mark.parametrize("site", SITES)
@pytest.mark.parametrize("date", DATES, ids=["march", "july"])
def test_niell_mapping_functions_match_orekit(site, date):
    lat_deg, h_km = SITES[site]
    lat = np.radians(lat_deg)
    orekit = _orekit_niell(lat_deg, h_km, date)
    s = np.sin(ELEVATIONS_rad)
    doy = day_of_year(Epoch.from_calendar(*date))
    # Wet: no season, no height: the same to rounding.
    np.testing.assert_allclose(niell_wet(s, lat).m, orekit[:, 1], rtol=1e-14)
    # Hydrostatic at the same date: Orekit's season phase is half a day behind Niell's
    # day count (t from January 0.0) north, and takes the southern half year as 183 days
    # instead of 365.25 / 2: 1.7e-4 at 5 deg at most, 0.4 mm of a 2.3 m zenith delay.
    mine = niell_hydrostatic(s, lat, doy, h_km).m
    np.testing.assert_allclose(mine, orekit[:, 0], atol=2e-4, rtol=0)
    # ... and the same to rounding with Orekit's phase.
    phase = doy - 0.5 - (183.0 - 0.5 * 365.25 if lat < 0 else 0.0)
    np.testing.assert_allclose(niell_hydrostatic(s, lat, phase, h_km).m, orekit[:, 0],
                               rtol=1e-13)
    # The slant delay of the same zenith delays (2.1 m dry, 0.15 m wet) within 1 mm.
    dry_m, wet_m = 2.1, 0.15
    slant = dry_m * mine + wet_m * niell_wet(s, lat).m
    assert np.abs(slant - (dry_m * orekit[:, 0] + wet_m * orekit[:, 1])).max() < 1e-3


@pytest.mark.parametrize("band", ["S", "X"])
@pytest.mark.parametrize("shell_height_km", [350.0, 450.0])
def test_single_layer_ionosphere_matches_orekit(band, shell_height_km):
    orekit_session.world()
    from org.orekit.models.earth.ionosphere import (
        EstimatedIonosphericModel,
        SingleLayerModelMappingFunction,
    )

    tec = 30.0
    model = EstimatedIonosphericModel(SingleLayerModelMappingFunction(shell_height_km * 1e3), tec)
    m = single_layer(np.sin(ELEVATIONS_rad), shell_height_km).m
    for f in (BANDS[band].uplink_hz, BANDS[band].downlink_hz):
        orekit_m = np.array([model.pathDelay(float(e), f, [tec]) for e in ELEVATIONS_rad])
        mine_m = 1e3 * IONO_KM_HZ2_PER_TECU * tec * m / f**2
        # S band at 5 deg: 7 m; the two agree to rounding (Orekit's R is 6371 km too).
        assert np.abs(mine_m - orekit_m).max() < 1e-3
        np.testing.assert_allclose(mine_m, orekit_m, rtol=1e-13)

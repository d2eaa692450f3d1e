"""The frames of trajectory files turned into the scenario's (tapp.frames.file_frames): the
frame bias against the IERS Conventions' angles (conftest.iers_frame_bias), the ITRF against
astropy."""

from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import GCRS, ITRS, CartesianDifferential, CartesianRepresentation

from tapp.errors import InputError
from tapp.frames.file_frames import gcrs_from_scenario, to_scenario_frame
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tapp.io.eop_file import finals2000a
from tests.tapp.frames.conftest import astropy_times, iers_frame_bias, without_cip_offsets

EPOCH = Epoch.from_calendar(2026, 3, 7, 5, 17, 3.25)
T_S = np.array([0.0, 4000.0, 1.3 * 86400.0])
STATES = np.array([[6778.137, 120.0, -35.5, -0.15, 7.5, 0.9],
                   [-26000.0, 30500.0, 1200.0, -2.2, -1.9, 0.05],
                   [4000.0, -5000.0, 3000.0, 5.1, 2.2, -4.0]])
#: B from the IERS angles against ERFA's IAU 2006 bias (Fukushima-Williams angles): measured
#: 9.8e-13 rad (0.2 µas); 2.5e-12 rad allowed, 1e-7 km on the 40,000 km state.
BIAS_KM = 1e-7
#: ITRF → GCRS against astropy (dX = dY = 0, as astropy): positions 1 mm (the station test's
#: bound; measured 0.029 mm); velocities 0.1 mm/s: tapp's rigid rotation leaves out the CIP's
#: own motion, up to 6e-12 rad/s × |r| (0.25 mm/s at GEO), and the length-of-day excess
#: (measured 0.023 mm/s).
ONE_MM_km = 1e-6
TENTH_MM_PER_S_km_s = 1e-7


@pytest.mark.parametrize("model", ["iau2006", "gmst"])
def test_inertial_frames_into_the_scenarios(model: str) -> None:
    orientation = EarthOrientation.of(model, EPOCH)
    b = iers_frame_bias()
    rotate = lambda m, x: np.concatenate([x[:, :3] @ m.T, x[:, 3:] @ m.T], axis=1)  # noqa: E731
    gcrs = {"iau2006": STATES, "gmst": rotate(b, STATES)}[model]  # what GCRS states become
    for frame in ("GCRF", "ICRF"):
        got = to_scenario_frame(frame, T_S, STATES, orientation)
        np.testing.assert_allclose(got, gcrs, rtol=0, atol=BIAS_KM)
    eme = {"iau2006": rotate(b.T, STATES), "gmst": STATES}[model]
    np.testing.assert_allclose(to_scenario_frame("EME2000", T_S, STATES, orientation), eme,
                               rtol=0, atol=BIAS_KM)
    # and back to the GCRS (what an SPK holds)
    np.testing.assert_allclose(gcrs_from_scenario(to_scenario_frame("GCRF", T_S, STATES,
                                                                    orientation), orientation),
                               STATES, rtol=0, atol=BIAS_KM)


@pytest.mark.usefixtures("astropy_shipped_eop")
@pytest.mark.parametrize("frame", ["ITRF", "ITRF2014", "ITRF-93"])
def test_itrf_states_into_the_gcrs_as_astropy_does(frame: str) -> None:
    orientation = EarthOrientation.iau2006(EPOCH, without_cip_offsets(finals2000a()))
    got = to_scenario_frame(frame, T_S, STATES, orientation)
    times = astropy_times([EPOCH.calendar()], T_S)[0]
    rep = CartesianRepresentation(STATES[:, :3].T * u.km, differentials=CartesianDifferential(
        STATES[:, 3:].T * u.km / u.s))
    gcrs = ITRS(rep, obstime=times).transform_to(GCRS(obstime=times))
    r = gcrs.cartesian.xyz.to_value(u.km).T
    v = gcrs.cartesian.differentials["s"].d_xyz.to_value(u.km / u.s).T
    assert np.linalg.norm(got[:, :3] - r, axis=1).max() < ONE_MM_km
    assert np.linalg.norm(got[:, 3:] - v, axis=1).max() < TENTH_MM_PER_S_km_s


@pytest.mark.parametrize("frame", ["TOD", "TEME", "J2000", "ITRF3"])
def test_frames_not_read_are_refused_naming_what_is(frame: str) -> None:
    with pytest.raises(InputError) as err:
        to_scenario_frame(frame, T_S, STATES, EarthOrientation.of("gmst", EPOCH), "m.oem",
                          "line 12: REF_FRAME")
    assert str(err.value) == ("m.oem: line 12: REF_FRAME: expected a frame tapp reads (GCRF, "
                              f"ICRF, EME2000 or an ITRF (ITRF2014, ITRF-93, ...)) (got '{frame}')")

"""Earth orientation (tapp.frames.orientation) against the SOFA cookbook and astropy.

References
----------
- SOFA Board, "SOFA Tools for Earth Attitude", software version 18, document revision 1.64,
  §5 (the worked example): the GCRS → ITRS matrix on 2007-04-05 12:00 UTC, IAU 2006/2000A,
  CIO based, using the X, Y series.
- astropy ``EarthLocation.get_gcrs_posvel`` (offline, on the same IERS finals2000A table: see
  conftest), for station positions and velocities in the GCRS.
"""

import astropy.units as u
import erfa
import numpy as np
import pytest
from astropy.coordinates import EarthLocation

from tapp.errors import InputError
from tapp.frames.eop import MJD_OFFSET, ARCSEC_rad, EopTable, MAS_rad
from tapp.frames.geodesy import geodetic_to_ecef
from tapp.frames.orientation import EarthOrientation, OMEGA_ERA_rad_s
from tapp.frames.rotation import r3
from tapp.frames.time import Epoch
from tapp.io.eop_file import finals2000a
from tests.tapp.frames.conftest import (
    ERFA_DUBIOUS_YEAR,
    FUTURE_EPOCHS,
    SHIPPED_EPOCHS,
    SCENARIO_TIMES_s,
    astropy_times,
    without_cip_offsets,
)

#: The cookbook prints the matrix to 15 decimals (half a unit: 5e-16); allow 1e-14 (measured
#: 2.7e-15).
COOKBOOK_PRINT = 1e-14
#: Station GCRS position against astropy: 1 mm. Measured 0.01-0.04 mm with attitude() and
#: attitude_exact(); 0.03-0.05 mm on the synthetic 2030-2050 table.
ONE_MM_km = 1e-6
#: Station GCRS velocity against astropy: 1 μm/s (measured ≤ 0.011 μm/s).
ONE_UM_PER_S_km_s = 1e-9
#: attitude() (Chebyshev series) against attitude_exact() (ERFA): 1e-13 rad, which is
#: 0.6 μm at the Earth's surface (measured 8e-16 rad; the 12 h segments lie on the
#: 0h/12h UTC grid, so the EOP's daily kinks fall on their boundaries).
SERIES_ANGLE_rad = 1e-13
#: erfa.c2t06a takes X, Y from the IAU 2006/2000A matrix, tapp from the X, Y series (xy06):
#: the two differ by about a microarcsecond (measured 5e-12 rad); allow 3e-11 rad (6 μas).
XY_SERIES_VS_MATRIX_rad = 3e-11
#: v = ω ĉ × r leaves out the CIP's own motion (precession-nutation, ≤ 4e-5 m/s) and the
#: length-of-day excess (≤ 1e-5 m/s): against d/dt of the position, 1e-4 m/s.
RIGID_ROTATION_VELOCITY_km_s = 1e-7

#: Stations (geodetic latitude deg, longitude deg east, height km on WGS84).
STATIONS = {
    "Goldstone DSS-14": (35.4266, -116.89, 1.0),
    "Canberra DSS-43": (-35.4021, 148.9813, 0.689),
    "Madrid DSS-63": (40.4313, -4.2480, 0.865),
    "South Pole": (-89.998, 139.27, 2.835),
    "Equator, Ecuador": (0.0, -78.45, 2.8),
}


def _station_itrs_km() -> np.ndarray:
    lat, lon, h = np.array(list(STATIONS.values())).T
    return geodetic_to_ecef(np.radians(lat), np.radians(lon), h)  # (5, 3)


def _angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Small rotation angle between rotation matrices (N, 3, 3): max |A Bᵀ − I|, rad."""
    return np.abs(a @ np.swapaxes(b, -1, -2) - np.eye(3)).max(axis=(-1, -2))


def _station_gcrs(epochs, table: EopTable):
    """tapp's station GCRS states (n_station, n_epoch, n_t, 3) km, km/s, from attitude()."""
    r_itrs = _station_itrs_km()
    t = np.array(SCENARIO_TIMES_s)
    r, v, cip = [], [], []
    for calendar in epochs:
        orientation = EarthOrientation.iau2006(Epoch.from_calendar(*calendar), table)
        attitude = orientation.attitude(t)  # the cached Chebyshev series, as the code runs
        r_gcrs = np.einsum("nij,sj->sni", attitude.gcrs_from_itrs, r_itrs)
        r.append(r_gcrs)
        v.append(attitude.omega_rad_s * np.cross(attitude.spin_axis[None], r_gcrs))
        eop = table.at(orientation.scales.utc_mjd(t))
        cip.append(np.hypot(eop.dx_rad, eop.dy_rad))
    return np.stack(r, 1), np.stack(v, 1), np.array(cip)


def _astropy_station_gcrs(epochs):
    """astropy's station GCRS states (n_station, n_epoch, n_t, 3) km, km/s."""
    r_itrs = _station_itrs_km()
    location = EarthLocation.from_geocentric(*r_itrs.T, unit=u.km).reshape(-1, 1, 1)
    position, velocity = location.get_gcrs_posvel(astropy_times(epochs, SCENARIO_TIMES_s)[None])
    return (np.moveaxis(position.xyz.to_value(u.km), 0, -1),
            np.moveaxis(velocity.xyz.to_value(u.km / u.s), 0, -1))


# --- SOFA cookbook ----------------------------------------------------------------------------

def test_gcrs_to_itrs_matrix_matches_the_sofa_cookbook():
    # SOFA Tools for Earth Attitude (software version 18, document revision 1.64), §5:
    # 2007 April 5, 12:00:00 UTC; UT1 − UTC = −0.072073685 s; x_p = 0.0349282", y_p = 0.4833163";
    # dX = 0.1750 mas, dY = −0.2259 mas; IAU 2006/2000A, CIO based, using the X, Y series.
    # Constant EOP over the day, by hand.
    mjd = np.array([54195.0, 54196.0])  # 2007-04-05, 2007-04-06
    const = np.ones(2)
    eop = EopTable(mjd, -0.072073685 * const, 0.0349282 * ARCSEC_rad * const,
                   0.4833163 * ARCSEC_rad * const, 0.1750 * MAS_rad * const,
                   -0.2259 * MAS_rad * const, np.inf, "SOFA cookbook §5")
    expected = np.array([
        [+0.973104317697536, +0.230363826239128, -0.000703163481769],
        [-0.230363800456036, +0.973104570632801, +0.000118545368117],
        [+0.000711560162594, +0.000046626402444, +0.999999745754024]])
    orientation = EarthOrientation.iau2006(Epoch.from_calendar(2007, 4, 5, 12), eop)
    exact = orientation.attitude_exact(0.0)
    series = orientation.attitude(0.0)
    assert exact.itrs_from_gcrs.shape == (1, 3, 3)
    assert np.abs(exact.itrs_from_gcrs[0] - expected).max() < COOKBOOK_PRINT
    assert np.abs(series.itrs_from_gcrs[0] - expected).max() < COOKBOOK_PRINT
    # The spin axis is the CIP: in the ITRS it is W e_z (W the polar motion matrix), so in the
    # GCRS it is Mᵀ W e_z with M the cookbook matrix.
    w = erfa.pom00(0.0349282 * ARCSEC_rad, 0.4833163 * ARCSEC_rad, 0.0)
    cip_in_gcrs = expected.T @ w @ np.array([0.0, 0.0, 1.0])
    assert np.abs(exact.spin_axis[0] - cip_in_gcrs).max() < COOKBOOK_PRINT
    assert np.abs(series.spin_axis[0] - cip_in_gcrs).max() < COOKBOOK_PRINT
    assert np.allclose(exact.itrs_from_gcrs[0] @ exact.gcrs_from_itrs[0], np.eye(3),
                       rtol=0, atol=1e-15)


# --- astropy ----------------------------------------------------------------------------------

@pytest.mark.usefixtures("astropy_shipped_eop")
def test_station_gcrs_states_match_astropy_1990_to_2026():
    r, v, _ = _station_gcrs(SHIPPED_EPOCHS, without_cip_offsets(finals2000a()))
    r_ref, v_ref = _astropy_station_gcrs(SHIPPED_EPOCHS)
    assert r.shape == r_ref.shape == (len(STATIONS), len(SHIPPED_EPOCHS), 4, 3)
    assert np.linalg.norm(r - r_ref, axis=-1).max() < ONE_MM_km
    assert np.linalg.norm(v - v_ref, axis=-1).max() < ONE_UM_PER_S_km_s


@pytest.mark.usefixtures("astropy_shipped_eop")
def test_cip_offsets_are_the_whole_difference_from_astropy():
    # With the IERS dX, dY (which astropy leaves out), tapp moves the station by at most
    # |r| · |(dX, dY)| from astropy's position, and by more than 1 mm somewhere: the zeroing
    # above is what makes the comparison sub-millimetre.
    r, _, cip_rad = _station_gcrs(SHIPPED_EPOCHS, finals2000a())
    r_ref, _ = _astropy_station_gcrs(SHIPPED_EPOCHS)
    miss = np.linalg.norm(r - r_ref, axis=-1)
    allowed = np.linalg.norm(r_ref, axis=-1) * cip_rad[None] + ONE_MM_km
    assert np.all(miss <= allowed)
    assert miss.max() > 10 * ONE_MM_km


@pytest.mark.filterwarnings(ERFA_DUBIOUS_YEAR)
@pytest.mark.usefixtures("astropy_future_eop")
def test_station_gcrs_states_match_astropy_2030_to_2050_on_a_synthetic_table(future_eop_path):
    # Beyond the IERS predictions: a made-up, smooth finals2000A table (conftest) read by both.
    table = finals2000a(future_eop_path)
    assert np.all(table.dx_rad == 0.0) and np.all(table.dy_rad == 0.0)
    r, v, _ = _station_gcrs(FUTURE_EPOCHS, table)
    r_ref, v_ref = _astropy_station_gcrs(FUTURE_EPOCHS)
    assert np.linalg.norm(r - r_ref, axis=-1).max() < ONE_MM_km
    assert np.linalg.norm(v - v_ref, axis=-1).max() < ONE_UM_PER_S_km_s


# --- the Chebyshev series of the slow terms ------------------------------------------------

def _series_error_rad(epoch: Epoch) -> float:
    orientation = EarthOrientation.iau2006(epoch)
    t = np.random.default_rng(20070405).uniform(0.0, 10 * 86400.0, 400)
    series, exact = orientation.attitude(t), orientation.attitude_exact(t)
    assert np.abs(series.spin_axis - exact.spin_axis).max() < SERIES_ANGLE_rad
    return float(_angle_between(series.itrs_from_gcrs, exact.itrs_from_gcrs).max())


def test_series_matches_erfa_over_ten_days_epoch_at_0h_utc():
    # 12 h segments from 0h UTC: the daily EOP kinks fall on segment ends (measured 1e-16 rad).
    assert _series_error_rad(Epoch.from_calendar(2026, 1, 1)) < SERIES_ANGLE_rad


def test_series_matches_erfa_over_ten_days_epoch_off_0h_utc():
    assert _series_error_rad(Epoch.from_calendar(2020, 3, 7, 5, 17, 3.25)) < SERIES_ANGLE_rad


def test_attitude_near_the_end_of_the_table():
    table = finals2000a()
    last = Epoch(np.floor(table.mjd[-1]) + MJD_OFFSET - 1.0, 0.75)  # 18:00 UTC, last day but one
    orientation = EarthOrientation.iau2006(last, table)
    t = np.array([0.0, 3600.0])  # both inside the table
    orientation.attitude_exact(t)
    orientation.attitude(t)


def test_station_velocity_is_the_rigid_rotation_about_the_cip():
    orientation = EarthOrientation.iau2006(Epoch.from_calendar(2026, 1, 1))
    r_itrs = _station_itrs_km()
    t = np.array([1000.0, 50000.0])
    h_s = 1.0
    attitude = orientation.attitude_exact(t)
    assert attitude.omega_rad_s == OMEGA_ERA_rad_s
    r = np.einsum("nij,sj->sni", attitude.gcrs_from_itrs, r_itrs)
    v = attitude.omega_rad_s * np.cross(attitude.spin_axis[None], r)
    ahead, behind = orientation.attitude_exact(t + h_s), orientation.attitude_exact(t - h_s)
    v_numeric = np.einsum("nij,sj->sni", ahead.gcrs_from_itrs - behind.gcrs_from_itrs,
                          r_itrs) / (2 * h_s)
    assert np.abs(v - v_numeric).max() < RIGID_ROTATION_VELOCITY_km_s


# --- bad input, the zero table, predictions ------------------------------------------------

def test_epoch_outside_the_table_is_an_input_error_naming_epoch_span_and_eop_none():
    table = finals2000a()
    with pytest.raises(InputError) as info:
        EarthOrientation.iau2006(Epoch.from_calendar(2060, 1, 1, 6), source="run.toml")
    message = str(info.value)
    assert message.startswith("run.toml:")
    assert "2060-01-01T06:00:00 UTC" in message
    first = Epoch(table.mjd[0] + MJD_OFFSET, 0.0).iso(0)
    last = Epoch(table.mjd[-1] + MJD_OFFSET, 0.0).iso(0)
    assert f"{first} UTC .. {last} UTC" in message
    assert 'eop = "none"' in message
    # Later scenario times are checked too.
    orientation = EarthOrientation.iau2006(Epoch.from_calendar(2026, 1, 1))
    with pytest.raises(InputError, match='eop = "none"'):
        orientation.attitude(np.array([0.0, 3 * 365.25 * 86400.0]))


def test_epoch_before_1972_is_an_input_error():
    with pytest.raises(InputError, match="1972-01-01"):
        EarthOrientation.iau2006(Epoch.from_calendar(1968, 5, 1), EopTable.zero())
    with pytest.raises(InputError, match="1972-01-01"):
        EarthOrientation.of("iau2006", Epoch.from_calendar(1971, 12, 31, 23))


def test_unknown_model_is_an_input_error_naming_the_models():
    with pytest.raises(InputError, match='"iau2006" or "gmst"') as info:
        EarthOrientation.of("iau1980", Epoch.from_calendar(2026, 1, 1), source="scenario.toml")
    assert info.value.got == "iau1980" and info.value.source == "scenario.toml"


def test_zero_table_works_beyond_any_table_with_ut1_equal_to_utc():
    epoch = Epoch.from_calendar(2060, 1, 1, 6)
    orientation = EarthOrientation.iau2006(epoch, EopTable.zero())
    assert orientation.eop_note.startswith("none")
    assert not orientation.uses_predicted_eop(np.array([0.0, 86400.0]))
    t = np.array([0.0, 7200.0, 86400.0 * 2.25])
    assert np.all(orientation.scales.ut1_minus_tai_s(t)
                  + orientation.scales.tai_minus_utc_epoch_s == 0.0)  # UT1 − UTC exactly 0
    # ERA of UT1 = UTC (to the rounding of the day fraction), and no polar motion: the whole
    # matrix is ERFA's c2t06a with UT1 = UTC and x_p = y_p = 0.
    assert orientation.theta0_rad == pytest.approx(
        float(erfa.era00(epoch.jd_whole, epoch.jd_fraction)), abs=1e-15)
    exact = orientation.attitude_exact(t)
    tt, ut1 = orientation.scales.tt(t), orientation.scales.ut1(t)
    by_erfa = erfa.c2t06a(tt[0], tt[1], ut1[0], ut1[1], 0.0, 0.0)
    assert _angle_between(exact.itrs_from_gcrs, by_erfa).max() < XY_SERIES_VS_MATRIX_rad
    attitude = orientation.attitude(t)
    assert _angle_between(attitude.itrs_from_gcrs, exact.itrs_from_gcrs).max() < (
        SERIES_ANGLE_rad)


def test_uses_predicted_eop_past_the_predictions_only():
    table = finals2000a()
    before = EarthOrientation.iau2006(Epoch(table.predicted_from_mjd + MJD_OFFSET - 3.0, 0.0))
    assert not before.uses_predicted_eop(np.array([0.0, 86400.0]))
    assert before.uses_predicted_eop(np.array([0.0, 4 * 86400.0]))
    after = EarthOrientation.iau2006(Epoch(table.predicted_from_mjd + MJD_OFFSET + 10.0, 0.0))
    assert after.uses_predicted_eop(0.0)
    assert after.eop_note == "finals2000A.all"


# --- the gmst model -----------------------------------------------------------------------

def test_gmst_model_is_r3_of_gmst_plus_omega_t():
    epoch = Epoch.from_calendar(2026, 3, 7, 5, 17, 3.25)
    orientation = EarthOrientation.of("gmst", epoch)
    assert orientation.scales is None and orientation.eop_note == ""
    theta0 = epoch.gmst_rad()
    assert orientation.theta0_rad == theta0
    t = np.array([0.0, 1.5, 4000.0, 86400.0 * 30.0 + 0.125, -3600.0])
    attitude = orientation.attitude(t)
    assert np.array_equal(attitude.itrs_from_gcrs, r3(theta0 + 7.292115e-5 * t))  # exactly
    assert np.array_equal(attitude.spin_axis, np.tile([0.0, 0.0, 1.0], (t.size, 1)))
    assert attitude.omega_rad_s == 7.292115e-5
    assert np.array_equal(orientation.attitude_exact(t).itrs_from_gcrs, attitude.itrs_from_gcrs)
    # No EOP: any date, never predictions.
    far = EarthOrientation.of("gmst", Epoch.from_calendar(2060, 1, 1))
    assert not far.uses_predicted_eop(np.array([0.0, 1e6]))
    far.attitude(np.array([0.0, 1e6]))

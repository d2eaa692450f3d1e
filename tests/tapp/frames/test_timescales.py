"""Time scales of scenario time (tapp.frames.timescales) against astropy on the same IERS tables.

Reference: astropy ``Time(..., scale="utc") + t * u.s`` and its ``.tai``, ``.tt``, ``.tdb``,
``.ut1`` (astropy offline, on the same finals2000A file and leap seconds; see conftest).
"""

import astropy.units as u
import erfa
import numpy as np
import pytest
from astropy.time import Time

from tapp.errors import InputError
from tapp.frames.eop import MJD_OFFSET, EopTable
from tapp.frames.time import Epoch
from tapp.frames.timescales import (
    DTDB_STEP_s,
    TimeScales,
    TT_MINUS_TAI_s,
    topocentric_tdb_minus_tt_s,
)
from tapp.io.eop_file import finals2000a
from tests.tapp.frames.conftest import (
    ERFA_DUBIOUS_YEAR,
    FUTURE_EPOCHS,
    SHIPPED_EPOCHS,
    SCENARIO_TIMES_s,
    astropy_times,
)

#: TDB: both geocentric (ERFA dtdb without the topocentric terms, ≤ 2 μs, which astropy also
#: leaves out without a location), same series: 1 μs; measured 0.04 ns.
ONE_MICROSECOND_s = 1e-6
#: UT1: same table, same linear interpolation; measured 0.04 ns (12 ns inside a leap second,
#: where astropy looks UT1 − UTC up on its stretched UTC day and tapp on the next day).
UT1_TOLERANCE_s = 1e-6
#: TAI, TT: pure offsets of a two-part JD; 1 ns (measured 0.04 ns).
ONE_NANOSECOND_s = 1e-9
#: A day fraction near 1 carries 1 ulp = 2.2e-16 d = 19 ps; allow 4 ulp.
DAY_FRACTION_ROUNDING_s = 4 * np.finfo(float).eps * 86400.0


def _seconds_between(ours: tuple, theirs: Time) -> np.ndarray:
    """(ours − theirs) in s for a two-part JD and an astropy Time of the same shape."""
    return ((ours[0] - theirs.jd1) + (ours[1] - theirs.jd2)) * 86400.0


def _compare_with_astropy(epochs, eop: EopTable) -> dict:
    t = np.array(SCENARIO_TIMES_s)
    reference = astropy_times(epochs, t)
    worst = dict.fromkeys(("tai", "tt", "tdb", "ut1"), 0.0)
    for k, calendar in enumerate(epochs):
        scales = TimeScales.of(Epoch.from_calendar(*calendar), eop)
        for name in worst:
            ours = getattr(scales, name)(t)
            diff = _seconds_between(ours, getattr(reference[k], name))
            worst[name] = max(worst[name], float(np.abs(diff).max()))
    return worst


@pytest.mark.usefixtures("astropy_shipped_eop")
def test_tai_tt_tdb_ut1_match_astropy_1990_to_2026():
    worst = _compare_with_astropy(SHIPPED_EPOCHS, finals2000a())
    assert worst["tai"] < ONE_NANOSECOND_s and worst["tt"] < ONE_NANOSECOND_s
    assert worst["tdb"] < ONE_MICROSECOND_s
    assert worst["ut1"] < UT1_TOLERANCE_s


@pytest.mark.filterwarnings(ERFA_DUBIOUS_YEAR)
@pytest.mark.usefixtures("astropy_future_eop")
def test_tdb_ut1_match_astropy_2030_to_2050_on_a_synthetic_table(future_eop_path):
    worst = _compare_with_astropy(FUTURE_EPOCHS, finals2000a(future_eop_path))
    assert worst["tai"] < ONE_NANOSECOND_s and worst["tt"] < ONE_NANOSECOND_s
    assert worst["tdb"] < ONE_MICROSECOND_s
    assert worst["ut1"] < UT1_TOLERANCE_s


def test_offsets_and_the_split_julian_date():
    epoch = Epoch.from_calendar(2012, 6, 30, 12)
    scales = TimeScales.of(epoch, finals2000a())
    assert scales.tai_minus_utc_epoch_s == 34.0  # IERS Bulletin C: 34 s until 2012-07-01
    t = np.array([0.0, 86400.5])
    tai, tt = scales.tai(t), scales.tt(t)
    assert np.all(tai[0] == epoch.jd_whole) and np.all(tt[0] == epoch.jd_whole)
    assert np.abs((tt[1] - tai[1]) * 86400.0 - TT_MINUS_TAI_s).max() < DAY_FRACTION_ROUNDING_s
    assert abs(tai[1][0] * 86400.0 - (43200.0 + 34.0)) < DAY_FRACTION_ROUNDING_s
    assert scales.utc_mjd(0.0) == epoch.jd - MJD_OFFSET


@pytest.mark.usefixtures("astropy_shipped_eop")
def test_leap_second_day_2016_12_31():
    # Scenario epoch 2016-12-31T23:59:30 UTC; the leap second 23:59:60 is t = 30..31 s.
    t = np.arange(0.0, 60.25, 0.25)
    scales = TimeScales.of(Epoch.from_calendar(2016, 12, 31, 23, 59, 30.0), finals2000a())
    # TT (and TAI) advance exactly t: scenario time is TAI-uniform.
    tt_whole, tt_fraction = scales.tt(t)
    assert np.all(tt_whole == tt_whole[0])
    assert np.abs((tt_fraction - tt_fraction[0]) * 86400.0 - t).max() < DAY_FRACTION_ROUNDING_s
    # 60 s of TAI after 23:59:30 UTC is 00:00:29 UTC the next day: one leap second inserted.
    utc_60 = scales.utc_mjd(60.0)
    assert abs((utc_60 - (57754.0 + 29.0 / 86400.0)) * 86400.0) < 1e-6  # MJD ulp: 0.6 μs
    assert scales.leaps.at_utc(scales.utc_mjd(0.0)) == 36.0 and scales.leaps.at_utc(utc_60) == 37.0
    # UT1 − UTC jumps by +1 s, UT1 − TAI (hence UT1) is continuous: it drifts by < 1 μs in
    # the minute (length-of-day excess ~1 ms/day), where a missed leap would show 1 s.
    eop_jump = np.diff(scales.eop.at([scales.utc_mjd(0.0), utc_60]).ut1_minus_utc_s)[0]
    assert 0.9 < eop_jump < 1.1
    ut1_minus_tai = scales.ut1_minus_tai_s(t)
    assert np.ptp(ut1_minus_tai) < 1e-6
    # And against astropy through the leap second.
    reference = Time("2016-12-31T23:59:30", scale="utc") + t * u.s
    assert reference[-1].iso == "2017-01-01 00:00:29.000"
    assert np.abs(_seconds_between(scales.ut1(t), reference.ut1)).max() < UT1_TOLERANCE_s
    assert np.abs(_seconds_between(scales.tt(t), reference.tt)).max() < ONE_NANOSECOND_s
    assert np.abs(_seconds_between(scales.tdb(t), reference.tdb)).max() < ONE_MICROSECOND_s


#: TDB − TT interpolated (cubic Lagrange) between day-table nodes DTDB_STEP_s apart, against
#: the series at every time. The interpolation's truncation is 9e-17 s at 1800 s; the series
#: itself is noisy at that level, growing with the distance from J2000 (its arguments ω t
#: reach ~300 rad in 2049, rounded by 6e-14 rad: 1e-16 s on a 1.7 ms term): measured 2e-17 s
#: in 2000, 5e-17 s in 2026, 2e-16 s in 2049. 5e-16 s is 1.5e-10 mm of light time.
INTERPOLATED_TDB_s = 5e-16


@pytest.mark.parametrize("calendar", [(1975, 3, 1), (2000, 1, 1, 12), (2026, 3, 10, 12),
                                      (2049, 11, 30)])
def test_tdb_minus_tt_interpolates_the_series_to_5e_16_s(calendar):
    scales = TimeScales.of(Epoch.from_calendar(*calendar), EopTable.zero())
    t = np.sort(np.random.default_rng(7).uniform(-5 * 86400.0, 55 * 86400.0, 10_000))
    many = scales.tdb_minus_tt_s(t.reshape(50, 200))
    assert many.shape == (50, 200)
    series = erfa.dtdb(*scales.tt(t), 0.0, 0.0, 0.0, 0.0)
    assert np.abs(many.ravel() - series).max() < INTERPOLATED_TDB_s
    # At the nodes the interpolation returns the series itself, bit for bit.
    nodes = DTDB_STEP_s * np.array([-3.0, 0.0, 7.0, 48.0 * 40 + 5])
    assert np.array_equal(scales.tdb_minus_tt_s(nodes), erfa.dtdb(*scales.tt(nodes), 0, 0, 0, 0))


def test_topocentric_terms_are_erfas():
    """The closed-form topocentric terms against ERFA's series with the site minus without
    it, at the three DSN complexes and random dates and solar times over ±8 years: equal to
    the difference's rounding (values of 1.7e-3 s: 2e-19 s; measured 1.1e-19 s)."""
    rng = np.random.default_rng(3)
    fraction, ut = rng.uniform(-3000.0, 3000.0, 1000), rng.uniform(0.0, 1.0, 1000)
    whole = 2462129.0
    for site in ((-2.04, 5204.0, 3677.0), (2.60, 5205.0, -3674.0), (-0.074, 4862.0, 4115.0)):
        erfa_terms = erfa.dtdb(whole, fraction, ut, *site) - erfa.dtdb(whole, fraction, ut, 0,
                                                                        0, 0)
        terms = topocentric_tdb_minus_tt_s((whole, fraction), ut, site)
        assert np.abs(erfa_terms).max() > 1e-6  # the diurnal term, ~1.7 us, is there
        assert np.abs(terms - erfa_terms).max() < 1e-18


def test_before_1972_is_an_input_error():
    with pytest.raises(InputError, match="1972-01-01") as info:
        TimeScales.of(Epoch.from_calendar(1971, 6, 1), EopTable.zero(), "scenario.toml")
    assert "1971-06-01T00:00:00 UTC" in str(info.value)
    assert info.value.source == "scenario.toml"


def test_ut1_of_an_epoch_outside_the_table_is_an_input_error():
    scales = TimeScales.of(Epoch.from_calendar(2060, 1, 1), finals2000a())
    scales.tdb(0.0)  # TDB needs no EOP
    with pytest.raises(InputError, match="2060-01-01T00:00:00 UTC"):
        scales.ut1(0.0)


def test_zero_table_gives_ut1_equal_to_utc_in_2060():
    epoch = Epoch.from_calendar(2060, 1, 1, 6)
    scales = TimeScales.of(epoch, EopTable.zero())
    t = np.array([0.0, 3600.0, 86400.0 * 3.5])
    ut1_minus_utc = scales.ut1_minus_tai_s(t) + scales.tai_minus_utc_epoch_s
    assert np.all(ut1_minus_utc == 0.0)  # exactly
    ut1 = scales.ut1(t)
    utc_fraction = epoch.jd_fraction + t / 86400.0
    assert np.abs((ut1[0] - epoch.jd_whole) + (ut1[1] - utc_fraction)).max() * 86400.0 < (
        DAY_FRACTION_ROUNDING_s * 4)

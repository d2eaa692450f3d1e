"""Dates of trajectory files as scenario time, and SPICE's ET (tapp.frames.timesystems), against
astropy's time scales (an independent implementation; offline, no EOP needed for these)."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.time import Time, TimeDelta

from tapp.errors import InputError
from tapp.frames.time import calendar_to_jd, parse_epoch
from tapp.frames.timesystems import (
    TIME_SYSTEMS,
    et_from_scenario,
    et_split,
    from_et,
    scenario_seconds,
    to_et,
)

EPOCH_TEXT = "2026-01-01T00:00:00"
EPOCH = parse_epoch(EPOCH_TEXT)
#: Dates read in each system: across a day, and one 400 days on.
DATES = ("2026-01-01T00:00:00", "2026-03-10T12:34:56.789", "2027-02-05T23:59:59.5")
#: astropy and tapp agree to the rounding of a two-part date 400 days long: 10 ns allowed
#: (measured: UTC 0, TAI 2.2e-12, GPS 2.0e-12, TT 9.3e-10, TCG 9.3e-10, TCB 1.2e-11, TDB
#: 7.5e-9 s, ERFA's dtdb in both).
TEN_NS = 1e-8
#: Rounding of 7000 km positions, a few units in the last place (measured 5.5e-12 km).
ROUNDING_KM = 1e-11
#: ET against astropy's TDB: 1 µs allowed, a float ET's spacing is 1.2e-7 s (measured 0).
ONE_US = 1e-6


def _jd(text: str) -> tuple[float, float]:
    date, clock = text.split("T")
    y, m, d = (int(v) for v in date.split("-"))
    hh, mm, ss = clock.split(":")
    return calendar_to_jd(y, m, d, int(hh), int(mm), float(ss))


def _astropy_seconds(text: str, system: str) -> float:
    """Seconds from the UTC epoch of a date in ``system``, by astropy: both instants in TAI
    (a difference in the date's own scale would count TDB, TCG or TCB seconds)."""
    start = Time(EPOCH_TEXT, scale="utc").tai
    if system == "GPS":  # astropy's GPS is a format: seconds from 1980-01-06 UTC, no leaps
        since = Time(text, scale="tai") - Time("1980-01-06T00:00:00", scale="tai")
        gps = Time(since.jd1 * 86400.0, since.jd2 * 86400.0, format="gps")  # two parts: 1 ns
        return (gps.tai - start).sec
    return (Time(text, scale=system.lower()).tai - start).sec


@pytest.mark.parametrize("system", TIME_SYSTEMS)
def test_dates_in_each_time_system_as_astropy_counts_them(system: str) -> None:
    whole, fraction = np.array([_jd(d) for d in DATES]).T
    got = scenario_seconds(whole, fraction, system, EPOCH)
    want = np.array([_astropy_seconds(d, system) for d in DATES])
    np.testing.assert_allclose(got, want, rtol=0, atol=TEN_NS)


def test_a_utc_date_across_a_leap_second_counts_it() -> None:
    epoch = parse_epoch("2016-12-31T23:59:00")
    got = scenario_seconds(*np.array([_jd("2017-01-01T00:00:30")]).T, "UTC", epoch)
    assert got[0] == pytest.approx(91.0, abs=TEN_NS)  # 60 s + the leap second + 30 s


def test_et_is_astropys_tdb_seconds_past_j2000() -> None:
    t = np.array([0.0, 3600.5, 86400.0 * 45.25])
    j2000 = Time("2000-01-01T12:00:00", scale="tdb")
    # astropy adds SI seconds to the UTC date; the ET of each time is its TDB minus J2000 TDB
    want = np.array([((Time(EPOCH_TEXT, scale="utc") + TimeDelta(s, format="sec")).tdb
                      - j2000).sec for s in t])
    np.testing.assert_allclose(et_from_scenario(t, EPOCH), want, rtol=0, atol=ONE_US)


def test_the_remainder_of_the_rounded_et_is_what_the_double_leaves_out() -> None:
    t = np.linspace(0.0, 86400.0, 1001) + 1e-3
    et, remainder = et_split(t, EPOCH)
    spacing = np.spacing(et)
    assert np.all(np.abs(remainder) <= 0.5 * spacing * (1 + 1e-6))
    assert np.abs(remainder).max() > 0.1 * spacing.max()  # not all zero: something to keep


def test_states_to_et_and_back() -> None:
    """A circular orbit: to_et moves each state to the instant its rounded ET names (and its
    velocity to TDB seconds), from_et moves it back; together they give the states again."""
    t = np.arange(0.0, 5400.0, 30.0)
    n = 2 * np.pi / 5400.0
    r = 7000.0
    x = np.stack([r * np.cos(n * t), r * np.sin(n * t), 0 * t, -r * n * np.sin(n * t),
                  r * n * np.cos(n * t), 0 * t], axis=1)
    et, moved = to_et(t, x, EPOCH)
    _, remainder = et_split(t, EPOCH)
    shifted = np.stack([r * np.cos(n * (t - remainder)), r * np.sin(n * (t - remainder))], 1)
    # positions moved by -remainder (the instant et names), to first order
    np.testing.assert_allclose(moved[:, :2], shifted, rtol=0, atol=ROUNDING_KM)
    np.testing.assert_allclose(from_et(t, moved, EPOCH), x, rtol=0, atol=ROUNDING_KM)


def test_an_unknown_time_system_is_refused() -> None:
    with pytest.raises(InputError) as err:
        scenario_seconds(np.array([2461041.5]), np.array([0.0]), "UT1", EPOCH, "f.oem",
                         "line 9: TIME_SYSTEM")
    assert str(err.value).startswith("f.oem: line 9: TIME_SYSTEM: expected a time system "
                                     "tapp reads (UTC, TAI, TT, GPS, TDB, TCG, TCB) (got 'UT1')")

"""Calendar <-> Julian date, ISO parsing and GMST IAU-82 against published values."""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tapp.errors import InputError
from tapp.frames import Epoch, calendar_to_jd, gmst_rad, jd_to_calendar, parse_epoch

#: The split JD keeps the time of day to one ulp of 86400 s (1.5e-11 s); allow 1 ns.
ONE_NANOSECOND_s = 1e-9
#: Vallado prints JDs to 1e-8 d (0.9 ms).
VALLADO_JD_PRINT_d = 5e-9
#: Vallado's Example 3-5 GMST: the 2nd ed. prints 152.578787886 deg, the 4th 152.578787810;
#: exact evaluation of eq. 3-45 gives 152.5787878517. 1e-7 deg = 0.36 mas covers both prints.
VALLADO_GMST_PRINT_deg = 1e-7
#: Against an exact rational evaluation of the same polynomial: double precision only.
ONE_PICORADIAN = 1e-12


def _seconds_of_day(epoch: Epoch) -> float:
    return epoch.jd_fraction * 86400.0


def test_julian_date_of_j2000_and_unix_epoch():
    assert calendar_to_jd(2000, 1, 1, 12) == (2451544.5, 0.5)
    assert sum(calendar_to_jd(2000, 1, 1, 12)) == 2451545.0
    assert calendar_to_jd(1970, 1, 1) == (2440587.5, 0.0)


def test_julian_date_vallado_example_3_4():
    # Vallado, Fundamentals of Astrodynamics and Applications, Example 3-4:
    # 1996 October 26, 14:20:00 UT -> JD 2,450,383.097 222 22.
    whole, fraction = calendar_to_jd(1996, 10, 26, 14, 20, 0.0)
    assert whole == 2450382.5
    assert abs((whole - 2450383.0) + fraction - 0.09722222) < VALLADO_JD_PRINT_d


@given(
    st.integers(1900, 2100),
    st.integers(1, 12),
    st.integers(1, 28),
    st.integers(0, 23),
    st.integers(0, 59),
    st.integers(0, 59_999_999),
)
def test_calendar_round_trip(year, month, day, hour, minute, microseconds_x10):
    second = microseconds_x10 * 1e-6
    whole, fraction = calendar_to_jd(year, month, day, hour, minute, second)
    y, mo, d, h, mi, s = jd_to_calendar(whole, fraction)
    assert (y, mo, d, h, mi) == (year, month, day, hour, minute)
    assert abs(s - second) < ONE_NANOSECOND_s


def test_jd_to_calendar_accepts_any_split_and_carries_days():
    assert jd_to_calendar(2451545.0) == (2000, 1, 1, 12, 0, 0.0)
    y, mo, d, h, mi, s = jd_to_calendar(2451544.5, 1.25)  # fraction past one day
    assert (y, mo, d, h, mi) == (2000, 1, 2, 6, 0) and abs(s) < ONE_NANOSECOND_s
    assert jd_to_calendar(2460675.5)[:3] == (2024, 12, 31)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("2026-01-01T00:00:00", (2026, 1, 1, 0, 0, 0.0)),
        ("2026-01-01", (2026, 1, 1, 0, 0, 0.0)),
        ("2026-01-01 12:30", (2026, 1, 1, 12, 30, 0.0)),
        ("2026-01-01T12:30:15.25Z", (2026, 1, 1, 12, 30, 15.25)),
        ("2024-02-29T23:59:59+00:00", (2024, 2, 29, 23, 59, 59.0)),
    ],
)
def test_parse_epoch_accepts_iso_forms(text, expected):
    epoch = parse_epoch(text)
    reference = Epoch.from_calendar(*expected)
    assert epoch.jd_whole == reference.jd_whole
    assert abs(_seconds_of_day(epoch) - _seconds_of_day(reference)) < ONE_NANOSECOND_s


def test_parse_epoch_keeps_sub_microsecond_digits():
    epoch = parse_epoch("2026-01-01T00:00:00.123456789")
    assert abs(_seconds_of_day(epoch) - 0.123456789) < ONE_NANOSECOND_s


@pytest.mark.parametrize(
    "text",
    ["yesterday", "2026-13-01", "2023-02-29", "1900-02-29", "2026-01-01T24:00:00",
     "2026-01-01T12:60", "2026-01-01T00:00:60", "2026-01-01T00:00:00+02:00"],
)
def test_parse_epoch_rejects_bad_dates_naming_source(text):
    with pytest.raises(InputError, match="scenario.toml: epoch"):
        parse_epoch(text, source="scenario.toml")


def test_iso_round_trip_and_rounding_carry():
    epoch = parse_epoch("2026-03-04T05:06:07.891011")
    assert epoch.iso() == "2026-03-04T05:06:07.891011"
    assert parse_epoch("2026-12-31T23:59:59.9999996").iso() == "2027-01-01T00:00:00.000000"
    assert parse_epoch("2026-12-31T23:59:59.4").iso(0) == "2026-12-31T23:59:59"
    assert epoch.calendar()[:5] == (2026, 3, 4, 5, 6)


def test_gmst_vallado_example_3_5():
    # Vallado, Example 3-5: 1992 August 20, 12:14 UT1 -> GMST = 152.578787886 deg (2nd ed.).
    epoch = Epoch.from_calendar(1992, 8, 20, 12, 14, 0.0)
    assert abs(np.degrees(epoch.gmst_rad()) - 152.578787886) < VALLADO_GMST_PRINT_deg


def test_gmst_matches_exact_rational_evaluation_of_eq_3_45():
    whole, fraction = calendar_to_jd(1992, 8, 20, 12, 14, 0.0)
    jd = Fraction(whole) + Fraction(12 * 60 + 14, 1440)
    t = (jd - 2451545) / 36525
    theta_s = (
        Fraction("67310.54841")
        + (Fraction(876600 * 3600) + Fraction("8640184.812866")) * t
        + Fraction("0.093104") * t**2
        - Fraction("6.2e-6") * t**3
    ) % 86400
    exact_rad = float(theta_s / 86400) * 2.0 * np.pi
    assert abs(gmst_rad(whole, fraction) - exact_rad) < ONE_PICORADIAN


def test_gmst_at_j2000_and_one_day_later():
    # At J2000.0 the polynomial reduces to 67310.54841 s = 280.460618375 deg.
    assert abs(np.degrees(gmst_rad(2451545.0)) - 280.460618375) < 1e-9
    # One solar day advances GMST by 360.98564736629 deg (Vallado eq. 3-46 rate), mod 360.
    step = np.degrees(gmst_rad(2451546.0) - gmst_rad(2451545.0))
    assert abs(step - 0.98564736629) < 1e-9


def test_gmst_broadcasts_and_is_split_invariant():
    whole = np.full((2, 3), 2461041.5)
    fraction = np.linspace(0.0, 0.9, 6).reshape(2, 3)
    theta = gmst_rad(whole, fraction)
    assert theta.shape == (2, 3)
    assert np.all((theta >= 0.0) & (theta < 2.0 * np.pi))
    moved = gmst_rad(whole - 10.0, fraction + 10.0)
    assert np.max(np.abs(moved - theta)) < ONE_PICORADIAN

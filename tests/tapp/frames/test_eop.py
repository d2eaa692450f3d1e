"""IERS EOP table and leap seconds (tapp.frames.eop, .iers; tapp.io.eop_file) against astropy and
ERFA on the same files.

References: astropy's ``iers.IERS_A`` reading of the same ``finals2000A`` files (astropy-iers-data's
``finals2000A.all`` and synthetic files written here in the byte layout of ``ReadMe.finals2000A``),
and ERFA's ``dat`` (the SOFA compiled-in leap-second table) for TAI − UTC.
"""

import math
import re

import astropy_iers_data
import erfa
import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.eop import MJD_OFFSET, ARCSEC_rad, EopTable, MAS_rad
from tapp.frames.iers import leap_seconds
from tapp.frames.time import Epoch
from tapp.io.eop_file import finals2000a
from tests.tapp.frames.conftest import (
    EPOCH_LINE,
    FUTURE_MJD,
    FUTURE_PREDICTED_FROM_MJD,
    astropy_iers_a,
    put_field,
    user_eop_table,
    write_finals2000a,
)

#: Same file, same linear interpolation: agreement to the rounding of the arcsec/mas to rad
#: conversion (1 ulp of 1e-6 rad is 2e-22 rad; allow 1e-20 rad = 2e-15 mas).
CONVERSION_ROUNDING_rad = 1e-20
#: UT1 − UTC in seconds: no conversion, so bit-equal; allow one ulp of 1 s.
ONE_ULP_OF_A_SECOND_s = np.finfo(float).eps


def _iso(mjd: float) -> str:
    return Epoch(math.floor(mjd) + MJD_OFFSET, mjd - math.floor(mjd)).iso(0) + " UTC"


def test_shipped_table_rows_equal_astropys_reading():
    ours = finals2000a()
    theirs = astropy_iers_a(astropy_iers_data.IERS_A_FILE)
    assert ours.source.endswith("finals2000A.all")
    assert ours.mjd[0] == 41684.0  # finals2000A.all starts on 1973-01-02
    assert np.all(np.diff(ours.mjd) == 1.0)  # daily, no gap
    assert np.array_equal(ours.mjd, theirs["MJD"].value)
    # Bulletin B replaces A where present, in both readers.
    assert np.abs(ours.ut1_minus_utc_s - theirs["UT1_UTC"].to_value("s")).max() == 0.0
    assert np.abs(ours.xp_rad - theirs["PM_x"].to_value("arcsec") * ARCSEC_rad).max() == 0.0
    assert np.abs(ours.yp_rad - theirs["PM_y"].to_value("arcsec") * ARCSEC_rad).max() == 0.0
    for mine, column in ((ours.dx_rad, "dX_2000A"), (ours.dy_rad, "dY_2000A")):
        values = theirs[column].to_value("mas")
        given = np.isfinite(values)
        assert np.abs(mine[given] - values[given] * MAS_rad).max() == 0.0
        assert np.all(mine[~given] == 0.0)  # far predictions carry no dX, dY: taken as 0
    # The first predicted row: astropy takes the earlier of the pole and UT1 flags.
    assert ours.predicted_from_mjd == theirs.meta["predictive_mjd"]
    assert ours.mjd[0] < ours.predicted_from_mjd < ours.mjd[-1]


def test_linear_interpolation_equals_astropys():
    ours = finals2000a()
    theirs = astropy_iers_a(astropy_iers_data.IERS_A_FILE)
    rng = np.random.default_rng(1973)
    # Random dates over the table, the day of the 2016 leap second around its end, and rows.
    # (astropy counts the last row itself as outside its range; tapp accepts it.)
    mjd = np.concatenate([rng.uniform(ours.mjd[0], ours.mjd[-1], 2000),
                          [57753.0, 57753.5, 57753.999999, 57754.0, 57754.25, 47892.0],
                          [ours.mjd[0], ours.mjd[-1] - 1e-6]])
    jd1, jd2 = MJD_OFFSET + np.floor(mjd), mjd - np.floor(mjd)
    got = ours.at(mjd)
    assert abs(got.ut1_minus_utc_s - theirs.ut1_utc(jd1, jd2).to_value("s")).max() <= (
        ONE_ULP_OF_A_SECOND_s)
    xp, yp = theirs.pm_xy(jd1, jd2)
    assert abs(got.xp_rad - xp.to_value("arcsec") * ARCSEC_rad).max() <= CONVERSION_ROUNDING_rad
    assert abs(got.yp_rad - yp.to_value("arcsec") * ARCSEC_rad).max() <= CONVERSION_ROUNDING_rad
    dx, dy = theirs.dcip_xy(jd1, jd2)
    given = np.isfinite(dx.value) & np.isfinite(dy.value)
    assert given.sum() > 1900
    assert abs(got.dx_rad[given] - dx.to_value("mas")[given] * MAS_rad).max() <= (
        CONVERSION_ROUNDING_rad)
    assert abs(got.dy_rad[given] - dy.to_value("mas")[given] * MAS_rad).max() <= (
        CONVERSION_ROUNDING_rad)


def test_leap_second_is_a_jump_not_a_slope():
    # 2017-01-01 (MJD 57754): UT1 − UTC steps from −0.41 s to +0.59 s; across the day before,
    # it drifts by about a millisecond only.
    start, end, next_day = finals2000a().at([57753.0, 57753.999999, 57754.0]).ut1_minus_utc_s
    assert abs(end - start) < 2e-3
    assert 0.9 < next_day - end < 1.1


def test_leap_seconds_match_erfa_dat():
    leaps = leap_seconds()
    assert leaps.start_mjd[0] == 41317.0 and leaps.tai_minus_utc_s[0] == 10.0  # 1972-01-01
    assert re.fullmatch(r"\d{1,2} \w+ \d{4}", leaps.expires)
    # On each leap day and the day before it, and on dates between, against SOFA's table.
    mjd = np.unique(np.concatenate([leaps.start_mjd, leaps.start_mjd[1:] - 0.5,
                                    np.arange(41317.0, 61400.0, 97.3)]))
    for day in mjd:
        year, month, dom, fraction = erfa.jd2cal(MJD_OFFSET, day)
        assert leaps.at_utc(day) == erfa.dat(year, month, dom, fraction), _iso(day)


def test_tai_lookup_steps_at_the_tai_instant_of_the_new_utc_day():
    leaps = leap_seconds()
    # 2017-01-01T00:00:00 UTC is 00:00:37 TAI; 23:59:60 UTC is 00:00:36 TAI.
    one_s = 1.0 / 86400.0
    assert leaps.at_tai(57754.0 + 36.5 * one_s) == 36.0
    assert leaps.at_tai(57754.0 + 37.0 * one_s) == 37.0
    assert leaps.at_utc(57753.99999) == 36.0 and leaps.at_utc(57754.0) == 37.0


def test_before_1972_is_an_input_error():
    with pytest.raises(InputError, match="1972-01-01") as info:
        leap_seconds().at_utc(np.array([41316.5]), "scenario.toml")
    assert "1971-12-31T12:00:00 UTC" in str(info.value)
    assert info.value.source == "scenario.toml"


def test_epoch_outside_the_table_names_epoch_span_and_the_way_out():
    table = finals2000a()
    mjd_2060 = 73459.25  # 2060-01-01T06:00:00 UTC
    with pytest.raises(InputError) as info:
        table.check_covers([60000.0, mjd_2060], "run.toml")
    message = str(info.value)
    assert "2060-01-01T06:00:00 UTC" in message
    assert f"{_iso(table.mjd[0])} .. {_iso(table.mjd[-1])}" in message
    assert "1973-01-02T00:00:00 UTC" in message
    assert 'eop = "none"' in message and "finals2000A.all" in message
    with pytest.raises(InputError, match="2060-01-01T06:00:00 UTC"):
        table.at(mjd_2060)
    with pytest.raises(InputError, match="1972-12-31T00:00:00 UTC"):
        table.at(41682.0)  # before the first row


def test_zero_table_is_no_eop_at_every_date():
    zero = EopTable.zero()
    assert zero.is_zero and zero.source == "none"
    assert not zero.uses_predictions([73459.25])
    zero.check_covers([73459.25, 30000.0])  # nothing to cover
    values = zero.at(np.array([73459.25, 80000.0]))
    for v in (values.ut1_minus_utc_s, values.xp_rad, values.yp_rad, values.dx_rad,
              values.dy_rad):
        assert v.shape == (2,) and np.all(v == 0.0)


def test_synthetic_file_read_like_astropy_with_bulletin_b_and_predictions(tmp_path):
    mjd = np.arange(61406.0, 61436.0)
    rng = np.random.default_rng(7)
    ut1 = 0.1 - 1e-3 * np.arange(mjd.size)
    xp, yp = rng.uniform(-0.2, 0.3, mjd.size), rng.uniform(0.2, 0.5, mjd.size)
    dx, dy = rng.uniform(-0.3, 0.3, mjd.size), rng.uniform(-0.3, 0.3, mjd.size)
    # Bulletin B 0.2 ms off A: a real revision (a jump would be refused as a length of day)
    bulletin_b = {k: (0.1 + 0.001 * k, 0.4, ut1[k] - 2e-4, 0.123, -0.456) for k in range(5)}
    path = write_finals2000a(tmp_path / "finals2000A.test", mjd, ut1, xp, yp, dx, dy,
                             predicted_from_mjd=61420.0, bulletin_b=bulletin_b)
    ours = finals2000a(path)
    theirs = astropy_iers_a(str(path))
    assert ours.source == str(path)
    assert np.array_equal(ours.mjd, mjd) and np.array_equal(theirs["MJD"].value, mjd)
    assert ours.predicted_from_mjd == theirs.meta["predictive_mjd"] == 61420.0
    # Bulletin B replaces A in the first five rows; the rest are A, as printed (6-7 digits).
    assert np.allclose(ours.ut1_minus_utc_s[:5], ut1[:5] - 2e-4, rtol=0, atol=0.5e-7)
    assert np.allclose(ours.ut1_minus_utc_s[5:], ut1[5:], rtol=0, atol=0.5e-7)
    assert np.allclose(ours.xp_rad[:5] / ARCSEC_rad, 0.1 + 0.001 * np.arange(5), atol=1e-12)
    assert np.allclose(ours.xp_rad[5:] / ARCSEC_rad, xp[5:], rtol=0, atol=0.5e-6)
    assert np.allclose(ours.dx_rad[:5] / MAS_rad, 0.123) and np.allclose(
        ours.dy_rad[:5] / MAS_rad, -0.456)
    assert np.allclose(ours.dy_rad[5:] / MAS_rad, dy[5:], rtol=0, atol=0.5e-3)
    for mine, column, unit in ((ours.ut1_minus_utc_s, "UT1_UTC", 1.0),
                               (ours.xp_rad, "PM_x", ARCSEC_rad),
                               (ours.yp_rad, "PM_y", ARCSEC_rad),
                               (ours.dx_rad, "dX_2000A", MAS_rad),
                               (ours.dy_rad, "dY_2000A", MAS_rad)):
        assert np.abs(mine - theirs[column].value * unit).max() <= CONVERSION_ROUNDING_rad


def test_future_synthetic_table_spans_2027_to_2050(future_eop_path):
    table = finals2000a(future_eop_path)
    assert (table.mjd[0], table.mjd[-1]) == FUTURE_MJD
    assert table.predicted_from_mjd == FUTURE_PREDICTED_FROM_MJD
    # No leap second is needed: |UT1 − UTC| < 0.9 s throughout.
    assert np.abs(table.ut1_minus_utc_s).max() < 0.9
    assert not table.uses_predictions([61700.0]) and table.uses_predictions([61800.0])


@pytest.mark.parametrize("content", [b"", b"\n\n",
                                     b"271216 61755.00" + b" " * 170 + b"\n"])  # MJD only
def test_file_without_rows_is_an_input_error_naming_it(tmp_path, content):
    path = tmp_path / "empty_finals2000A.all"
    path.write_bytes(content)
    with pytest.raises(InputError, match="at least two daily EOP rows") as info:
        finals2000a(path)
    assert str(path) in str(info.value)


def test_missing_file_is_an_input_error_naming_it(tmp_path):
    path = tmp_path / "no_such_finals2000A.all"
    with pytest.raises(InputError, match="an existing IERS finals2000A file") as info:
        finals2000a(path)
    assert str(path) in str(info.value)


# --- a user's table is checked like any input (issue "Hardening, second round", item 2) ----

def _user_table(tmp_path, edit=lambda lines: lines, name="finals2000A.user"):
    return user_eop_table(tmp_path / name, edit)


def _at_epoch(column: str, text: str):
    def edit(lines):
        lines[EPOCH_LINE - 1] = put_field(lines[EPOCH_LINE - 1], column, text)
        return lines
    return edit


@pytest.mark.parametrize(("edit", "says"), [
    (lambda ls: ls[:14] + [ls[15], ls[14]] + ls[16:],  # two rows swapped
     "line 16, MJD: expected dates in increasing order (after 61041 on line 15) (got 61040.0)"),
    (lambda ls: ls[::-1], "line 2, MJD: expected dates in increasing order (after 61056 on "
     "line 1) (got 61055.0)"),
    (_at_epoch("ut1_a", "5000.0"), "line 16, UT1-UTC (Bulletin A): expected |UT1 − UTC| < 0.9 s"
     " (leap seconds keep UTC so) (got 5000.0)"),
    (_at_epoch("xp_a", "1e300"), "line 16, x_p (Bulletin A): expected a pole within 1 arcsec "
     "(got 1e+300)"),
    (_at_epoch("dy_a", "120.0"), "line 16, dY (Bulletin A): expected a CIP offset within 50 "
     "mas (got 120.0)"),
    (_at_epoch("ut1_a", "nan"), "line 16, UT1-UTC (Bulletin A): expected a finite number "
     "(got 'nan')"),
    (_at_epoch("ut1_a", "0.3"), "line 16, UT1-UTC: expected a change from the row before "
     "(line 15) of at most 10 ms a day besides a leap second (the length of day) (got "
     "'0.2344 s in 1 days')"),
    (_at_epoch("mjd", "1e300"), "line 16, MJD: expected a date from 1960-01-01T00:00:00 UTC "
     "to 2100-01-01T00:00:00 UTC (got 1e+300)"),
    (_at_epoch("mjd", "abc"), "line 16, MJD (bytes 8-15): expected a number (got 'abc')"),
    (lambda ls: ["this is not an EOP table at all, but text"] * 3, "line 1, MJD (bytes 8-15): "
     "expected a number (got 'not an')"),
])
def test_a_user_table_with_a_defect_is_refused_naming_file_line_and_field(tmp_path, edit,
                                                                            says):
    path = _user_table(tmp_path, edit)
    with pytest.raises(InputError) as info:
        finals2000a(path)
    assert str(info.value) == f"{path}: {says}"


def test_a_binary_file_is_one_error_naming_the_first_line(tmp_path):
    path = tmp_path / "finals2000A.bin"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(InputError, match=r"finals2000A.bin: line 1, MJD \(bytes 8-15\): "
                                         r"expected a number"):
        finals2000a(path)


def test_a_leap_second_between_rows_is_not_a_length_of_day(tmp_path):
    def leap(lines):  # UT1 − UTC from −0.44 s jumps by +1 s at the epoch, as on 2017-01-01
        for k, line in enumerate(lines):
            value = float(line[58:68]) - 0.5 + (1.0 if k >= EPOCH_LINE - 1 else 0.0)
            lines[k] = put_field(line, "ut1_a", f"{value:10.7f}")
        return lines

    table = finals2000a(_user_table(tmp_path, leap))
    assert np.diff(table.ut1_minus_utc_s)[EPOCH_LINE - 2] == pytest.approx(1.0 - 6e-4)


def test_gaps_are_refused_over_the_span_an_arc_uses_only(tmp_path):
    # 20 days of rows missing around the epoch (lines 6..25 gone): the values there would be
    # interpolated across 21 days
    wide = finals2000a(_user_table(tmp_path, lambda ls: ls[:5] + ls[25:], "gap.user"))
    with pytest.raises(InputError) as info:
        wide.check_covers([61041.0, 61042.0], "leo.toml")
    assert str(info.value) == (
        f"{wide.source}: line 6, MJD: expected rows at most 1 day apart over the span used "
        "(2026-01-01T00:00:00 UTC .. 2026-01-02T00:00:00 UTC): values are interpolated between "
        "rows (got '21 days after the row before')")
    # a row without UT1 − UTC inside the span is such a gap; a gap away from the arc is not
    blank = finals2000a(_user_table(tmp_path, _at_epoch("ut1_a", ""), "blank.user"))
    with pytest.raises(InputError, match="line 17, MJD: expected rows at most 1 day apart"):
        blank.check_covers([61040.5, 61042.0])
    blank.check_covers([61045.0, 61050.0])


def test_a_table_without_predictions_outside_the_epoch_names_its_span(tmp_path):
    table = finals2000a(_user_table(tmp_path))
    assert table.predicted_from_mjd == math.inf  # formatting it overflowed
    with pytest.raises(InputError) as info:
        table.check_covers([61100.0], "leo.toml")
    assert str(info.value) == (
        "leo.toml: epoch: expected an epoch within the IERS EOP table 2025-12-17T00:00:00 UTC "
        "..  2026-01-16T00:00:00 UTC (finals2000A.user; no predictions), or eop = \"none\" for "
        "a study beyond the predictions (got '2026-03-01T00:00:00 UTC')".replace("..  ", ".. "))

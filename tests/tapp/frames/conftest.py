"""Shared helpers for the Earth-orientation tests: astropy as an offline reference, and
synthetic IERS ``finals2000A`` files.

astropy is the independent reference (a test-only dependency). It is made to read the same
EOP table as tapp and never to download: ``iers.conf.auto_download = False`` and the table set
with ``iers.earth_orientation_table``; both are restored when the context ends.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from functools import cache
from pathlib import Path

import astropy.units as u
import astropy_iers_data
import erfa
import numpy as np
import pytest
from astropy.time import Time
from astropy.utils import iers

from tapp.frames.eop import EopTable, MAS_rad
from tapp.frames.time import Epoch

#: Columns of a finals2000A line, bytes 1-based inclusive, with their Fortran formats
#: (``ReadMe.finals2000A`` in astropy-iers-data's data directory).
FINALS_COLUMNS = {
    "year": (1, 2, "{:2d}"), "month": (3, 4, "{:2d}"), "day": (5, 6, "{:2d}"),
    "mjd": (8, 15, "{:8.2f}"),
    "pm_flag": (17, 17, "{}"), "xp_a": (19, 27, "{:9.6f}"), "e_xp_a": (28, 36, "{:9.6f}"),
    "yp_a": (38, 46, "{:9.6f}"), "e_yp_a": (47, 55, "{:9.6f}"),
    "ut1_flag": (58, 58, "{}"), "ut1_a": (59, 68, "{:10.7f}"), "e_ut1_a": (69, 78, "{:10.7f}"),
    "nut_flag": (96, 96, "{}"), "dx_a": (98, 106, "{:9.3f}"), "e_dx_a": (107, 115, "{:9.3f}"),
    "dy_a": (117, 125, "{:9.3f}"), "e_dy_a": (126, 134, "{:9.3f}"),
    "xp_b": (135, 144, "{:10.6f}"), "yp_b": (145, 154, "{:10.6f}"),
    "ut1_b": (155, 165, "{:11.7f}"), "dx_b": (166, 175, "{:10.3f}"), "dy_b": (176, 185, "{:10.3f}"),
}


def finals2000a_line(**fields) -> str:
    """One fixed-width finals2000A line; fields not given stay blank (``None`` too)."""
    line = [" "] * 185
    for name, value in fields.items():
        if value is None:
            continue
        first, last, fmt = FINALS_COLUMNS[name]
        text = fmt.format(value)
        width = last - first + 1
        assert len(text) <= width, (name, text)
        line[first - 1:last] = text.rjust(width)
    return "".join(line).rstrip()


def write_finals2000a(path: Path, mjd, ut1_utc_s, xp_arcsec, yp_arcsec, dx_mas, dy_mas,
                      predicted_from_mjd: float = math.inf, bulletin_b=None) -> Path:
    """Write daily rows (Bulletin A columns, flag P from ``predicted_from_mjd`` on).

    ``bulletin_b``: optional dict row index -> (x_p ", y_p ", UT1 − UTC s, dX mas, dY mas).
    """
    bulletin_b = bulletin_b or {}
    rows = []
    for k, day in enumerate(np.asarray(mjd, dtype=float)):
        year, month, dom, _ = erfa.jd2cal(2400000.5, day)
        flag = "P" if day >= predicted_from_mjd else "I"
        b = bulletin_b.get(k, (None,) * 5)
        rows.append(finals2000a_line(
            year=int(year) % 100, month=int(month), day=int(dom), mjd=day,
            pm_flag=flag, xp_a=xp_arcsec[k], e_xp_a=0.001, yp_a=yp_arcsec[k], e_yp_a=0.001,
            ut1_flag=flag, ut1_a=ut1_utc_s[k], e_ut1_a=0.0001,
            nut_flag=flag, dx_a=dx_mas[k], e_dx_a=0.1, dy_a=dy_mas[k], e_dy_a=0.1,
            xp_b=b[0], yp_b=b[1], ut1_b=b[2], dx_b=b[3], dy_b=b[4]))
    path.write_text("\n".join(rows) + "\n")
    return path


#: A synthetic daily table around the LEO scenario's epoch, 2026-01-01 (MJD 61041): 31 rows
#: 2025-12-17 .. 2026-01-16, UT1 − UTC drifting 0.6 ms a day, the row of the epoch on line 16.
USER_MJD = np.arange(61026.0, 61057.0)
EPOCH_LINE = 16


def put_field(line: str, column: str, text: str) -> str:
    """``line`` with the field ``column`` (:data:`FINALS_COLUMNS`) replaced by ``text``."""
    first, last, _ = FINALS_COLUMNS[column]
    line = line.ljust(185)
    return line[:first - 1] + text.rjust(last - first + 1) + line[last:]


def user_eop_table(path: Path, edit=lambda lines: lines) -> Path:
    """Write the synthetic table (:data:`USER_MJD`) at ``path``, its lines passed through
    ``edit`` (a list of text lines: line k is lines[k-1]) first."""
    n = USER_MJD.size
    write_finals2000a(path, USER_MJD, 0.074 - 6e-4 * np.arange(n), np.full(n, 0.11),
                      np.full(n, 0.33), np.full(n, 0.3), np.full(n, -0.1))
    lines = path.read_text().splitlines()
    path.write_text("\n".join(edit(lines)) + "\n")
    return path


#: Span of the synthetic future table: 2027-01-01 .. 2051-01-01 (UTC MJD), beyond the IERS
#: predictions shipped in astropy-iers-data; rows flagged P from 2028-01-01.
FUTURE_MJD = (61406.0, 70172.0)
FUTURE_PREDICTED_FROM_MJD = 61771.0


def synthetic_future_eop(path: Path) -> Path:
    """Write a made-up, smooth finals2000A table for 2027-2050 and return its path.

    UT1 − UTC stays within ±0.62 s (a 13-year swing plus an annual term), so no leap second is
    needed beyond those in Leap_Second.dat; the pole runs on a 0.15" Chandler (433 d) plus a
    0.08" annual circle about (0.04", 0.35"); dX = dY = 0 (astropy ignores them, see
    test_orientation).
    """
    mjd = np.arange(FUTURE_MJD[0], FUTURE_MJD[1] + 1.0)
    chandler = 2.0 * np.pi * (mjd - 60000.0) / 433.0
    annual = 2.0 * np.pi * (mjd - 60000.0) / 365.25
    ut1 = 0.6 * np.sin(2.0 * np.pi * (mjd - 60000.0) / (13.0 * 365.25)) + 0.02 * np.sin(annual)
    xp = 0.04 + 0.15 * np.cos(chandler) + 0.08 * np.cos(annual)
    yp = 0.35 + 0.15 * np.sin(chandler) + 0.08 * np.sin(annual)
    zero = np.zeros(mjd.size)
    return write_finals2000a(path, mjd, ut1, xp, yp, zero, zero, FUTURE_PREDICTED_FROM_MJD)


@pytest.fixture(scope="session")
def future_eop_path(tmp_path_factory) -> Path:
    """The synthetic 2027-2050 finals2000A file (:func:`synthetic_future_eop`)."""
    return synthetic_future_eop(tmp_path_factory.mktemp("eop") / "finals2000A.future")


@cache
def astropy_iers_a(path: str) -> iers.IERS_A:
    """astropy's reading of a finals2000A file (read once per file: setting it is cheap, so the
    fixtures below are function-scoped and each test sees exactly the table it asks for)."""
    return iers.IERS_A.open(path)


@contextlib.contextmanager
def astropy_eop(path: str | Path):
    """Within the context, astropy uses the EOP of ``path`` and downloads nothing."""
    with iers.conf.set_temp("auto_download", False), \
            iers.earth_orientation_table.set(astropy_iers_a(str(path))):
        yield


@pytest.fixture
def astropy_shipped_eop():
    """astropy on astropy-iers-data's finals2000A.all, the table tapp reads by default."""
    with astropy_eop(astropy_iers_data.IERS_A_FILE):
        yield


@pytest.fixture
def astropy_future_eop(future_eop_path):
    """astropy on the synthetic 2027-2050 table."""
    with astropy_eop(future_eop_path):
        yield


#: Epochs (UTC calendar) of the comparisons with astropy: on the shipped table (1990-2026;
#: off 0h UTC on purpose; 2012-06-30 12:00 + 1.3 d crosses that night's leap second) and on
#: the synthetic future table. Scenario times are taken from each.
SHIPPED_EPOCHS = [(1990, 3, 7, 5, 17, 3.25), (1999, 12, 31, 23, 0, 0.0), (2005, 8, 14, 10),
                  (2012, 6, 30, 12, 0, 0.0), (2016, 11, 2, 19, 45, 12.5), (2020, 2, 29, 1),
                  (2026, 3, 7, 5, 17, 3.25)]
FUTURE_EPOCHS = [(2030, 1, 15, 7, 30), (2040, 7, 4, 16, 12, 42.0), (2050, 3, 7, 5, 17, 3.25)]
#: Scenario times at each epoch, s: the epoch, an hour later, across a day boundary, 2.7 d on.
SCENARIO_TIMES_s = (0.0, 4000.0, 1.3 * 86400.0, 2.7 * 86400.0 + 123.456)
#: ERFA calls a UTC date past its leap-second knowledge "dubious" (any UTC from about 2028 on);
#: astropy passes the warning on. The future tests go there on purpose, with no new leap second.
ERFA_DUBIOUS_YEAR = r"ignore:ERFA function \"\w+\" yielded \d+ of \"dubious year:erfa.ErfaWarning"


def astropy_times(epochs, t_s):
    """astropy UTC Times (n_epoch, n_t): each epoch (UTC calendar tuple) plus t_s SI seconds.

    The epochs go to astropy as ISO strings, not JDs: on a day with a leap second astropy
    reads a UTC JD fraction as a fraction of the 86 401 s day (ERFA's quasi-JD), tapp as
    seconds / 86 400, so the same JD is 0.5 s apart at noon of 2012-06-30.
    """
    iso = np.array([Epoch.from_calendar(*e).iso(6) for e in epochs])[:, None]
    return Time(iso, format="isot", scale="utc") + np.asarray(t_s)[None, :] * u.s


def without_cip_offsets(table: EopTable) -> EopTable:
    """The table with dX = dY = 0.

    astropy's GCRS ↔ ITRS goes through ``erfa.c2i06a`` and ignores the IERS celestial pole
    offsets dX, dY (they are in its table but not used), so it matches tapp only with them
    zeroed; with them, the two differ by |r| · |(dX, dY)|, 1-90 mm (test below), and that
    difference is astropy's omission, not an error of tapp.
    """
    return dataclasses.replace(table, dx_rad=np.zeros_like(table.dx_rad),
                               dy_rad=np.zeros_like(table.dy_rad))


#: IERS Conventions (2010), §5.5.1 eq. 5.21 and Table 5.1 footnote: the frame bias from the
#: GCRS to the mean equator and equinox of J2000.0, B = R1(−η0) R2(ξ0) R3(dα0).
XI0_mas, ETA0_mas, DALPHA0_mas = -16.6170, -6.8192, -14.6


def _r(axis: int, angle: float) -> np.ndarray:
    """The frame rotation R_axis(angle) of the IERS Conventions (a passive rotation)."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis - 1]
    m = np.eye(3)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = s, -s
    return m


def iers_frame_bias() -> np.ndarray:
    """B (3, 3): r_EME2000 = B r_GCRS, from the IERS Conventions' published angles."""
    return _r(1, -ETA0_mas * MAS_rad) @ _r(2, XI0_mas * MAS_rad) @ _r(3, DALPHA0_mas * MAS_rad)

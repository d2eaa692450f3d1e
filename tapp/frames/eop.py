"""IERS Earth orientation parameters and leap seconds, read offline from astropy-iers-data.

The registry package ``astropy-iers-data`` ships the IERS tables astropy itself uses; nothing is
downloaded at run time. Two files are read:

- ``Leap_Second.dat`` (IERS Bulletin C): TAI − UTC from each leap second on, and the date the
  file expires (past it a leap second could have been announced that the file does not hold).
- ``finals2000A.all`` (IERS Rapid Service / Bulletin A, with Bulletin B values where they
  exist, IAU 2000A nutation): daily values at 0h UTC of UT1 − UTC (s), the pole coordinates
  x_p, y_p (arcsec) and the celestial pole offsets dX, dY (mas), measured up to a date and
  predicted for about a year after it (flag ``P``). Columns (fixed width, bytes 1-based) are
  those of the file's ReadMe (``ReadMe.finals2000A`` in the same package): MJD 8-15, flags 17
  (pole) and 58 (UT1), x_p 19-27, y_p 38-46, UT1−UTC 59-68, dX 98-106, dY 117-125 (Bulletin A)
  and x_p 135-144, y_p 145-154, UT1−UTC 155-165, dX 166-175, dY 176-185 (Bulletin B). As
  astropy does, Bulletin B replaces A where present.

Between the daily values each quantity is interpolated linearly in UTC (astropy's choice,
so the two agree exactly); across a leap second the 1 s jump of UT1 − UTC is taken out of the
slope. Linear interpolation of UT1 − UTC errs by at most about 0.05 ms (2 cm at the equator)
against the IERS' recommended Lagrange interpolation with tidal terms; say so where it matters.

Outside the table :class:`EopTable` raises :class:`~tapp.errors.InputError` naming the
epoch and the table's span; :meth:`EopTable.predicted_from_mjd` tells where predictions start.
:meth:`EopTable.zero` is the no-EOP table (UT1 = UTC, no polar motion, no CIP offsets) for
studies beyond the predictions, where the true values are unknowable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from tapp.errors import InputError

#: Arcseconds and milliarcseconds to radians.
ARCSEC_rad = math.pi / (180.0 * 3600.0)
MAS_rad = ARCSEC_rad / 1000.0
#: Modified Julian date = Julian date - MJD_OFFSET.
MJD_OFFSET = 2400000.5


def iers_data_dir() -> Path:
    """Directory of the IERS tables inside the ``astropy-iers-data`` package."""
    import astropy_iers_data

    return Path(astropy_iers_data.__file__).parent / "data"


def _iso_of_mjd(mjd: float) -> str:
    from tapp.frames.time import Epoch

    whole = math.floor(mjd) + MJD_OFFSET
    return Epoch(whole, mjd - math.floor(mjd)).iso(0) + " UTC"


@dataclass(frozen=True, slots=True)
class LeapSeconds:
    """TAI − UTC (s) from each UTC MJD in ``start_mjd`` on (IERS Bulletin C)."""

    start_mjd: np.ndarray
    tai_minus_utc_s: np.ndarray
    expires: str

    def at_utc(self, mjd_utc, source: str = "epoch") -> np.ndarray:
        """Return TAI − UTC (s) at UTC MJDs, shape of the input.

        Raises
        ------
        InputError
            For a date before 1972-01-01 (UTC then ran at a different rate from TAI).
        """
        mjd = np.asarray(mjd_utc, dtype=float)
        if np.any(~(mjd >= self.start_mjd[0])):
            bad = float(mjd.ravel()[np.argmax(~(mjd.ravel() >= self.start_mjd[0]))])
            raise InputError(source, "date", "a UTC date on or after 1972-01-01 (leap-second "
                             "UTC)", _iso_of_mjd(bad) if math.isfinite(bad) else bad)
        index = np.searchsorted(self.start_mjd, mjd, side="right") - 1
        return self.tai_minus_utc_s[index]

    def at_tai(self, mjd_tai) -> np.ndarray:
        """Return TAI − UTC (s) at TAI MJDs (the step is at the TAI instant of the new day)."""
        mjd = np.asarray(mjd_tai, dtype=float)
        start_tai = self.start_mjd + self.tai_minus_utc_s / 86400.0
        index = np.clip(np.searchsorted(start_tai, mjd, side="right") - 1, 0, None)
        return self.tai_minus_utc_s[index]


@cache
def leap_seconds(path: Path | None = None) -> LeapSeconds:
    """Read ``Leap_Second.dat`` (default: the one in astropy-iers-data)."""
    path = path or iers_data_dir() / "Leap_Second.dat"
    expires = ""
    rows = []
    for line in path.read_text().splitlines():
        if line.startswith("#"):
            if "File expires on" in line:
                expires = line.split("File expires on", 1)[1].strip()
            continue
        fields = line.split()
        if len(fields) == 5:
            rows.append((float(fields[0]), float(fields[4])))
    data = np.array(rows)
    return LeapSeconds(data[:, 0], data[:, 1], expires)


@dataclass(frozen=True, slots=True)
class EopValues:
    """Earth orientation parameters at N epochs: UT1 − UTC (s), x_p, y_p, dX, dY (rad)."""

    ut1_minus_utc_s: np.ndarray
    xp_rad: np.ndarray
    yp_rad: np.ndarray
    dx_rad: np.ndarray
    dy_rad: np.ndarray


@dataclass(frozen=True, slots=True)
class EopTable:
    """Daily EOP at 0h UTC, interpolated linearly (see the module docstring).

    Attributes
    ----------
    mjd : (n,) UTC MJD of the values; empty for the zero table.
    ut1_minus_utc_s, xp_rad, yp_rad, dx_rad, dy_rad : (n,) the values.
    predicted_from_mjd : first MJD whose UT1 − UTC is a prediction (inf if none).
    source : file the values came from ("none" for the zero table).
    """

    mjd: np.ndarray
    ut1_minus_utc_s: np.ndarray
    xp_rad: np.ndarray
    yp_rad: np.ndarray
    dx_rad: np.ndarray
    dy_rad: np.ndarray
    predicted_from_mjd: float
    source: str

    @staticmethod
    def zero() -> EopTable:
        """The no-EOP table: UT1 = UTC, x_p = y_p = dX = dY = 0 at every date."""
        empty = np.zeros(0)
        return EopTable(empty, empty, empty, empty, empty, empty, math.inf, "none")

    @property
    def is_zero(self) -> bool:
        return self.mjd.size == 0

    def check_covers(self, mjd_utc, source: str = "epoch") -> None:
        """Raise InputError unless every UTC MJD lies within the table.

        The message names the first epoch outside, the table's span and the way out
        (``eop = "none"``, for a study beyond the predictions).
        """
        if self.is_zero:
            return
        mjd = np.atleast_1d(np.asarray(mjd_utc, dtype=float))
        outside = ~((mjd >= self.mjd[0]) & (mjd <= self.mjd[-1]))
        if np.any(outside):
            bad = float(mjd[np.argmax(outside)])
            raise InputError(source, "epoch", f"an epoch within the IERS EOP table "
                             f"{_iso_of_mjd(self.mjd[0])} .. {_iso_of_mjd(self.mjd[-1])} "
                             f"({Path(self.source).name}; predictions from "
                             f"{_iso_of_mjd(self.predicted_from_mjd)}), or eop = \"none\" "
                             "for a study beyond the predictions",
                             _iso_of_mjd(bad) if math.isfinite(bad) else bad)

    def uses_predictions(self, mjd_utc) -> bool:
        """True if any of the UTC MJDs lies past the last measured value."""
        return bool(np.any(np.asarray(mjd_utc, dtype=float) >= self.predicted_from_mjd))

    def at(self, mjd_utc, source: str = "epoch") -> EopValues:
        """Return the EOP at UTC MJDs (N,), linearly interpolated.

        Raises
        ------
        InputError
            For an epoch outside the table (:meth:`check_covers`).
        """
        mjd = np.atleast_1d(np.asarray(mjd_utc, dtype=float))
        if self.is_zero:
            zeros = np.zeros(mjd.shape)
            return EopValues(zeros, zeros, zeros, zeros, zeros)
        self.check_covers(mjd, source)
        i = np.clip(np.searchsorted(self.mjd, mjd, side="right") - 1, 0, self.mjd.size - 2)
        w = (mjd - self.mjd[i]) / (self.mjd[i + 1] - self.mjd[i])

        def lerp(values: np.ndarray, leap: bool = False) -> np.ndarray:
            step = values[i + 1] - values[i]
            if leap:
                step = step - np.round(step)  # a leap second is a 1 s jump, not a slope
            return values[i] + w * step

        return EopValues(lerp(self.ut1_minus_utc_s, leap=True), lerp(self.xp_rad),
                         lerp(self.yp_rad), lerp(self.dx_rad), lerp(self.dy_rad))


def _column(lines: list[bytes], first: int, last: int) -> np.ndarray:
    """Float column of bytes first..last (1-based, inclusive); blank fields are NaN."""
    out = np.full(len(lines), np.nan)
    for k, line in enumerate(lines):
        text = line[first - 1:last].strip()
        if text:
            out[k] = float(text)
    return out


@cache
def finals2000a(path: Path | None = None) -> EopTable:
    """Read an IERS ``finals2000A`` file (default: ``finals2000A.all`` of astropy-iers-data).

    Rows without UT1 − UTC or a pole (the empty tail of the file) are dropped; a missing
    dX, dY (old rows, far predictions) is taken as 0.

    Raises
    ------
    InputError
        For a file with no usable row.
    """
    path = Path(path) if path else iers_data_dir() / "finals2000A.all"
    try:
        lines = path.read_bytes().splitlines()
    except OSError as err:
        raise InputError(str(path), "file", "a readable IERS finals2000A file",
                         err.strerror) from err
    lines = [line.ljust(185) for line in lines if line.strip()]
    mjd = _column(lines, 8, 15)

    def a_or_b(a: tuple[int, int], b: tuple[int, int]) -> np.ndarray:
        value_a, value_b = _column(lines, *a), _column(lines, *b)
        return np.where(np.isnan(value_b), value_a, value_b)

    ut1 = a_or_b((59, 68), (155, 165))
    xp = a_or_b((19, 27), (135, 144))
    yp = a_or_b((38, 46), (145, 154))
    dx = np.nan_to_num(a_or_b((98, 106), (166, 175)))
    dy = np.nan_to_num(a_or_b((117, 125), (176, 185)))
    flags = np.array([line[57:58] for line in lines])
    keep = np.isfinite(mjd) & np.isfinite(ut1) & np.isfinite(xp) & np.isfinite(yp)
    if keep.sum() < 2:
        raise InputError(str(path), "rows", "at least two daily EOP rows (finals2000A format)",
                         int(keep.sum()))
    predicted = mjd[keep & (flags == b"P")]
    return EopTable(mjd[keep], ut1[keep], xp[keep] * ARCSEC_rad, yp[keep] * ARCSEC_rad,
                    dx[keep] * MAS_rad, dy[keep] * MAS_rad,
                    float(predicted.min()) if predicted.size else math.inf, str(path))

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

A table read from a file is checked like every other input, each refusal one
:class:`~tapp.errors.InputError` naming the file, the line and the field: a field that is
not a number (text garbage, a binary file, ``nan``); dates not strictly increasing or outside
:data:`MJD_RANGE`; values outside their physical bounds (:data:`MAX_UT1_MINUS_UTC_s`,
:data:`MAX_POLE_ARCSEC`, :data:`MAX_CIP_OFFSET_MAS`, :data:`MAX_LOD_s`, the last also
between consecutive rows: the change of UT1 − UTC in a day, leap seconds aside); and, over the
span an arc uses, rows more than :data:`MAX_GAP_DAYS` apart (a row without UT1 − UTC or a pole
inside the span is such a gap). The file is read as a regular file of at most
:data:`MAX_EOP_BYTES` (:mod:`iter.inputfile`).

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

from iter.inputfile import read_bytes
from tapp.errors import InputError

#: Arcseconds and milliarcseconds to radians.
ARCSEC_rad = math.pi / (180.0 * 3600.0)
MAS_rad = ARCSEC_rad / 1000.0
#: Modified Julian date = Julian date - MJD_OFFSET.
MJD_OFFSET = 2400000.5
#: Largest EOP file read, bytes: finals2000A.all is 3.8 MB (1973-2026) and grows by ~68 kB a
#: year; the 51,135 daily rows that MJD_RANGE allows take 9.6 MB in this format. Measured:
#: the shipped file reads in 0.5 s, 51,135 rows in 0.4 s with 23 MB (2 shared cores).
MAX_EOP_BYTES = 16 * 2**20
#: Dates of an EOP row, UTC MJD: 1960-01-01 (the IERS and BIH series start in 1962) to
#: 2100-01-01 (no measurement, nor any prediction of the IERS, reaches it).
MJD_RANGE = (36934.0, 88069.0)
#: |UT1 − UTC| bound, s: leap seconds keep UTC within 0.9 s of UT1 (ITU-R TF.460-6).
MAX_UT1_MINUS_UTC_s = 0.9
#: |x_p|, |y_p| bound, arcsec: the Chandler and annual wobbles and the drift of the pole
#: reached 0.6" since 1900 (0.60" in the shipped finals2000A.all).
MAX_POLE_ARCSEC = 1.0
#: |dX|, |dY| bound, mas (offsets of the CIP from IAU 2006/2000A): below 1.3 mas since 2007
#: (free core nutation and model errors) but up to 20 mas in the VLBI of the 1970s, all in the
#: shipped table; 50 mas accepts every published row and refuses arcsec read as mas.
MAX_CIP_OFFSET_MAS = 50.0
#: Bound of the excess length of day, s (|LOD| column, and the change of UT1 − UTC from one
#: row to the next per day, leap seconds aside): observed −1.7 .. +4.0 ms since 1973.
MAX_LOD_s = 0.01
#: Largest step between rows over the span an arc uses, days: finals2000A tables are daily,
#: and the interpolation error stated above holds for daily values.
MAX_GAP_DAYS = 1.0


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
    line : (n,) line numbers (1-based) of the rows in ``source``, for the messages; None for
        a table made in memory.
    """

    mjd: np.ndarray
    ut1_minus_utc_s: np.ndarray
    xp_rad: np.ndarray
    yp_rad: np.ndarray
    dx_rad: np.ndarray
    dy_rad: np.ndarray
    predicted_from_mjd: float
    source: str
    line: np.ndarray | None = None

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
            predicted = (f"predictions from {_iso_of_mjd(self.predicted_from_mjd)}"
                         if math.isfinite(self.predicted_from_mjd) else "no predictions")
            raise InputError(source, "epoch", f"an epoch within the IERS EOP table "
                             f"{_iso_of_mjd(self.mjd[0])} .. {_iso_of_mjd(self.mjd[-1])} "
                             f"({Path(self.source).name}; {predicted}), or eop = \"none\" "
                             "for a study beyond the predictions",
                             _iso_of_mjd(bad) if math.isfinite(bad) else bad)
        self._check_gaps(float(mjd.min()), float(mjd.max()))

    def _check_gaps(self, lo_mjd: float, hi_mjd: float) -> None:
        """Raise InputError naming the file and the line after the first step of more than
        :data:`MAX_GAP_DAYS` between the rows that bracket lo..hi (both in the table)."""
        first = max(int(np.searchsorted(self.mjd, lo_mjd, side="right")) - 1, 0)
        last = int(np.searchsorted(self.mjd, hi_mjd, side="left"))
        steps = np.diff(self.mjd[first:last + 1])
        wide = np.flatnonzero(steps > MAX_GAP_DAYS)
        if wide.size:
            row = first + int(wide[0]) + 1
            where = f"row {row + 1}" if self.line is None else f"line {self.line[row]}"
            raise InputError(self.source, f"{where}, MJD", f"rows at most {MAX_GAP_DAYS:g} "
                             f"day apart over the span used ({_iso_of_mjd(lo_mjd)} .. "
                             f"{_iso_of_mjd(hi_mjd)}): values are interpolated between rows",
                             f"{steps[wide[0]]:g} days after the row before")

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


@dataclass(frozen=True, slots=True)
class _Field:
    """A fixed-width column of finals2000A: name, bytes first..last (1-based, inclusive),
    bound of |value| (in the file's unit) and why."""

    name: str
    first: int
    last: int
    bound: float = math.inf
    why: str = ""


_MJD = _Field("MJD", 8, 15)
_UT1 = f"|UT1 − UTC| < {MAX_UT1_MINUS_UTC_s:g} s (leap seconds keep UTC so)"
_POLE = f"a pole within {MAX_POLE_ARCSEC:g} arcsec"
_CIP = f"a CIP offset within {MAX_CIP_OFFSET_MAS:g} mas"
#: The columns read, Bulletin A then B ("ReadMe.finals2000A"); LOD (ms) is only checked.
_FIELDS = {
    "xp": (_Field("x_p (Bulletin A)", 19, 27, MAX_POLE_ARCSEC, _POLE),
           _Field("x_p (Bulletin B)", 135, 144, MAX_POLE_ARCSEC, _POLE)),
    "yp": (_Field("y_p (Bulletin A)", 38, 46, MAX_POLE_ARCSEC, _POLE),
           _Field("y_p (Bulletin B)", 145, 154, MAX_POLE_ARCSEC, _POLE)),
    "ut1": (_Field("UT1-UTC (Bulletin A)", 59, 68, MAX_UT1_MINUS_UTC_s, _UT1),
            _Field("UT1-UTC (Bulletin B)", 155, 165, MAX_UT1_MINUS_UTC_s, _UT1)),
    "dx": (_Field("dX (Bulletin A)", 98, 106, MAX_CIP_OFFSET_MAS, _CIP),
           _Field("dX (Bulletin B)", 166, 175, MAX_CIP_OFFSET_MAS, _CIP)),
    "dy": (_Field("dY (Bulletin A)", 117, 125, MAX_CIP_OFFSET_MAS, _CIP),
           _Field("dY (Bulletin B)", 176, 185, MAX_CIP_OFFSET_MAS, _CIP)),
    "lod": (_Field("LOD (Bulletin A)", 80, 86, MAX_LOD_s * 1e3,
                   f"an excess length of day within {MAX_LOD_s * 1e3:g} ms"),),
}


class _Rows:
    """The non-blank lines of a finals2000A file and their line numbers, for the messages."""

    def __init__(self, data: bytes, source: str):
        self.source = source
        numbered = [(k, line) for k, line in enumerate(data.splitlines(), start=1)
                    if line.strip()]
        self.number = np.array([k for k, _ in numbered], dtype=np.int64)
        self.lines = [line.ljust(185) for _, line in numbered]

    def fail(self, row: int, field: str, expected: str, got: object) -> InputError:
        return InputError(self.source, f"line {self.number[row]}, {field}", expected, got)

    def column(self, field: _Field, *, required: bool = False) -> np.ndarray:
        """Float column of ``field``; a blank field is NaN (refused if ``required``), any
        other text that is not a finite number within the field's bound is refused."""
        out = np.full(len(self.lines), np.nan)
        for k, line in enumerate(self.lines):
            text = line[field.first - 1:field.last].strip()
            if not text and not required:
                continue
            shown = text.decode("ascii", "replace")
            try:
                value = float(text)
            except ValueError:
                raise self.fail(k, f"{field.name} (bytes {field.first}-{field.last})",
                                "a number", shown) from None
            if not math.isfinite(value):
                raise self.fail(k, field.name, "a finite number", shown)
            if abs(value) >= field.bound:
                raise self.fail(k, field.name, field.why, value)
            out[k] = value
        return out

    def check_dates(self, mjd: np.ndarray) -> None:
        lo, hi = MJD_RANGE
        outside = np.flatnonzero((mjd < lo) | (mjd > hi))
        if outside.size:
            raise self.fail(int(outside[0]), "MJD", f"a date from {_iso_of_mjd(lo)} to "
                            f"{_iso_of_mjd(hi)}", float(mjd[outside[0]]))
        back = np.flatnonzero(np.diff(mjd) <= 0)
        if back.size:
            row = int(back[0]) + 1
            raise self.fail(row, "MJD", f"dates in increasing order (after {mjd[row - 1]:g} "
                            f"on line {self.number[row - 1]})", float(mjd[row]))

    def check_day_to_day(self, mjd: np.ndarray, ut1: np.ndarray, kept: np.ndarray) -> None:
        """The change of UT1 − UTC between consecutive kept rows (indices ``kept``), less a
        leap second, is at most :data:`MAX_LOD_s` a day."""
        step = np.diff(ut1[kept])
        drift = np.abs(step - np.clip(np.round(step), -1.0, 1.0))
        wild = np.flatnonzero(drift > MAX_LOD_s * np.diff(mjd[kept]))
        if wild.size:
            before, row = (int(k) for k in kept[wild[0]:wild[0] + 2])
            raise self.fail(row, "UT1-UTC", f"a change from the row before (line "
                            f"{self.number[before]}) of at most {MAX_LOD_s * 1e3:g} ms a day "
                            "besides a leap second (the length of day)",
                            f"{step[wild[0]]:.7g} s in {mjd[row] - mjd[before]:g} days")


@cache
def finals2000a(path: Path | None = None) -> EopTable:
    """Read an IERS ``finals2000A`` file (default: ``finals2000A.all`` of astropy-iers-data).

    Rows without UT1 − UTC or a pole (the empty tail of the file) are dropped; a missing
    dX, dY (old rows, far predictions) is taken as 0. The file is checked as the module
    docstring says (the gaps when an arc uses the table: :meth:`EopTable.check_covers`).

    Raises
    ------
    InputError
        Naming the file (and the line and field): not a regular file, larger than
        :data:`MAX_EOP_BYTES`, a field that is not a finite number, dates out of order or
        range, values beyond their bounds, or no usable row.
    """
    path = Path(path) if path else iers_data_dir() / "finals2000A.all"
    rows = _Rows(read_bytes(path, "IERS finals2000A file", max_bytes=MAX_EOP_BYTES,
                            error=InputError), str(path))
    mjd = rows.column(_MJD, required=True)
    rows.check_dates(mjd)

    def a_or_b(name: str) -> np.ndarray:
        value_a, value_b = (rows.column(field) for field in _FIELDS[name])
        return np.where(np.isnan(value_b), value_a, value_b)

    ut1, xp, yp = a_or_b("ut1"), a_or_b("xp"), a_or_b("yp")
    dx, dy = np.nan_to_num(a_or_b("dx")), np.nan_to_num(a_or_b("dy"))
    rows.column(_FIELDS["lod"][0])
    flags = np.array([line[57:58] for line in rows.lines])
    keep = np.isfinite(ut1) & np.isfinite(xp) & np.isfinite(yp)
    if keep.sum() < 2:
        raise InputError(str(path), "rows", "at least two daily EOP rows (finals2000A format)",
                         int(keep.sum()))
    rows.check_day_to_day(mjd, ut1, np.flatnonzero(keep))
    predicted = mjd[keep & (flags == b"P")]
    return EopTable(mjd[keep], ut1[keep], xp[keep] * ARCSEC_rad, yp[keep] * ARCSEC_rad,
                    dx[keep] * MAS_rad, dy[keep] * MAS_rad,
                    float(predicted.min()) if predicted.size else math.inf, str(path),
                    rows.number[keep])

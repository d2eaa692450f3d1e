"""The IERS tables shipped in astropy-iers-data: their two formats, parsed and checked.

The registry package ``astropy-iers-data`` ships the IERS tables astropy itself uses; nothing is
downloaded at run time. Two files are read, into the tables of :mod:`tapp.frames.eop`:

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

:func:`parse_finals2000a` takes the bytes of a finals2000A file (the shipped one here, a user's
through :mod:`tapp.io.eop_file`, which opens it) and checks it like every other input, each
refusal one :class:`~tapp.errors.InputError` naming the file, the line and the field: a field
that is not a number (text garbage, a binary file, ``nan``); dates not strictly increasing or
outside :data:`MJD_RANGE`; values outside their physical bounds (:data:`MAX_UT1_MINUS_UTC_s`,
:data:`MAX_POLE_ARCSEC`, :data:`MAX_CIP_OFFSET_MAS`, :data:`MAX_LOD_s`, the last also
between consecutive rows: the change of UT1 − UTC in a day, leap seconds aside). The gaps
between rows over the span an arc uses are checked when it uses the table
(:meth:`tapp.frames.eop.EopTable.check_covers`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from tapp.errors import InputError
from tapp.frames.eop import ARCSEC_rad, EopTable, LeapSeconds, MAS_rad, iso_of_mjd

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


def iers_data_dir() -> Path:
    """Directory of the IERS tables inside the ``astropy-iers-data`` package."""
    import astropy_iers_data

    return Path(astropy_iers_data.__file__).parent / "data"


@cache
def leap_seconds() -> LeapSeconds:
    """Read the ``Leap_Second.dat`` of astropy-iers-data."""
    path = iers_data_dir() / "Leap_Second.dat"
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
            raise self.fail(int(outside[0]), "MJD", f"a date from {iso_of_mjd(lo)} to "
                            f"{iso_of_mjd(hi)}", float(mjd[outside[0]]))
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



def parse_finals2000a(data: bytes, source: str) -> EopTable:
    """The table of an IERS ``finals2000A`` file's bytes; ``source`` names it in errors.

    Rows without UT1 − UTC or a pole (the empty tail of the file) are dropped; a missing
    dX, dY (old rows, far predictions) is taken as 0. The file is checked as the module
    docstring says.

    Raises
    ------
    InputError
        Naming ``source`` (and the line and field): a field that is not a finite number,
        dates out of order or range, values beyond their bounds, or no usable row.
    """
    rows = _Rows(data, source)
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
        raise InputError(source, "rows", "at least two daily EOP rows (finals2000A format)",
                         int(keep.sum()))
    rows.check_day_to_day(mjd, ut1, np.flatnonzero(keep))
    predicted = mjd[keep & (flags == b"P")]
    return EopTable(mjd[keep], ut1[keep], xp[keep] * ARCSEC_rad, yp[keep] * ARCSEC_rad,
                    dx[keep] * MAS_rad, dy[keep] * MAS_rad,
                    float(predicted.min()) if predicted.size else math.inf, source,
                    rows.number[keep])


@cache
def shipped_finals2000a() -> EopTable:
    """The ``finals2000A.all`` of astropy-iers-data, read once (the default EOP table)."""
    path = iers_data_dir() / "finals2000A.all"
    return parse_finals2000a(path.read_bytes(), str(path))

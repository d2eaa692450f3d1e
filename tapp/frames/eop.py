"""IERS Earth orientation parameters and leap seconds as tables: arrays in, arrays out.

:class:`LeapSeconds` gives TAI − UTC at any UTC or TAI date from 1972 on; :class:`EopTable`
the daily values at 0h UTC of UT1 − UTC (s), the pole coordinates x_p, y_p and the celestial
pole offsets dX, dY (rad), measured up to a date and predicted after it. The tables are read
from the IERS files by :mod:`tapp.frames.iers` (the ones shipped in astropy-iers-data) and
:mod:`tapp.io.eop_file` (a finals2000A file of the user's).

Between the daily values each quantity is interpolated linearly in UTC (astropy's choice,
so the two agree exactly); across a leap second the 1 s jump of UT1 − UTC is taken out of the
slope. Linear interpolation of UT1 − UTC errs by at most about 0.05 ms (2 cm at the equator)
against the IERS' recommended Lagrange interpolation with tidal terms; say so where it matters.

Over the span an arc uses, rows more than :data:`MAX_GAP_DAYS` apart are refused (a row
without UT1 − UTC or a pole inside the span is such a gap), naming the file and the line.
Outside the table :class:`EopTable` raises :class:`~tapp.errors.InputError` naming the
epoch and the table's span; :meth:`EopTable.predicted_from_mjd` tells where predictions start.
:meth:`EopTable.zero` is the no-EOP table (UT1 = UTC, no polar motion, no CIP offsets) for
studies beyond the predictions, where the true values are unknowable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tapp.errors import InputError

#: Arcseconds and milliarcseconds to radians.
ARCSEC_rad = math.pi / (180.0 * 3600.0)
MAS_rad = ARCSEC_rad / 1000.0
#: Modified Julian date = Julian date - MJD_OFFSET.
MJD_OFFSET = 2400000.5
#: Largest step between rows over the span an arc uses, days: finals2000A tables are daily,
#: and the interpolation error stated above holds for daily values.
MAX_GAP_DAYS = 1.0


def iso_of_mjd(mjd: float) -> str:
    """A UTC MJD as an ISO date and time to the second, "... UTC" (for messages)."""
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
                             "UTC)", iso_of_mjd(bad) if math.isfinite(bad) else bad)
        index = np.searchsorted(self.start_mjd, mjd, side="right") - 1
        return self.tai_minus_utc_s[index]

    def at_tai(self, mjd_tai) -> np.ndarray:
        """Return TAI − UTC (s) at TAI MJDs (the step is at the TAI instant of the new day)."""
        mjd = np.asarray(mjd_tai, dtype=float)
        start_tai = self.start_mjd + self.tai_minus_utc_s / 86400.0
        index = np.clip(np.searchsorted(start_tai, mjd, side="right") - 1, 0, None)
        return self.tai_minus_utc_s[index]



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
            predicted = (f"predictions from {iso_of_mjd(self.predicted_from_mjd)}"
                         if math.isfinite(self.predicted_from_mjd) else "no predictions")
            raise InputError(source, "epoch", f"an epoch within the IERS EOP table "
                             f"{iso_of_mjd(self.mjd[0])} .. {iso_of_mjd(self.mjd[-1])} "
                             f"({Path(self.source).name}; {predicted}), or eop = \"none\" "
                             "for a study beyond the predictions",
                             iso_of_mjd(bad) if math.isfinite(bad) else bad)
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
                             f"day apart over the span used ({iso_of_mjd(lo_mjd)} .. "
                             f"{iso_of_mjd(hi_mjd)}): values are interpolated between rows",
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


"""Earth orientation offsets per UTC day: the days of a tracking window and which day each
observation falls in.

A scenario with ``[parameters] earth_orientation_per = "day"`` puts in q one offset of each
EOP parameter per UTC calendar day of its tracking window (``eop.<name>.<YYYY-MM-DD>``),
instead of one over the whole arc: the IERS publishes one value a day, and the errors of
the values a navigation team uses (predictions, the rapid service) are nearly independent
from day to day (the DSN's "per day" Earth-orientation consider parameters). Each offset
moves only the observations of its day, with the same partials as the constant offset
(:meth:`tapp.measurements.MeasurementModel.eop_partials`): between two days the orientation
jumps by the difference of the offsets, as the piecewise-constant model says.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.frames.time import Epoch
from tapp.frames.timescales import seconds_after

#: Most days a scenario may have per-day offsets for (a 3-year cruise).
MAX_EOP_DAYS = 1100


@dataclass(frozen=True, slots=True)
class EopDays:
    """The UTC days of per-day EOP offsets.

    Attributes
    ----------
    dates : each day, ``YYYY-MM-DD`` (UTC).
    bounds_s : 0h UTC of each day and of the day after the last, s from the scenario epoch
        (SI seconds, a leap second counted): day i covers [bounds_s[i], bounds_s[i + 1]).
    """

    dates: tuple[str, ...]
    bounds_s: tuple[float, ...]

    def index(self, t_s) -> np.ndarray:
        """Return the day of each time (N,), int: positions in :attr:`dates`.

        Raises
        ------
        ValueError
            A time before the first day or after the last one (a caller's bug: the days
            cover the tracking window).
        """
        t = np.asarray(t_s, dtype=float)
        day = np.searchsorted(self.bounds_s, t, side="right") - 1
        if np.any(day < 0) or np.any(day >= len(self.dates)):
            raise ValueError(f"times outside the EOP days {self.dates[0]}..{self.dates[-1]}")
        return day

    def names(self, eop: tuple[str, ...]) -> tuple[str, ...]:
        """The parameters ``eop.<name>.<date>``, day after day, each day's in ``eop`` order."""
        return tuple(parameter_name(name, date) for date in self.dates for name in eop)


def parameter_name(name: str, date: str) -> str:
    """The name in q of the offset of EOP parameter ``name`` on day ``date``."""
    return f"eop.{name}.{date}"


def eop_days(epoch: Epoch, start_s: float, end_s: float) -> EopDays:
    """Return the UTC days that meet the window [start_s, end_s] (s from ``epoch``).

    Raises
    ------
    ValueError
        More than :data:`MAX_EOP_DAYS` days (the caller names its field).
    """
    def start(k: int) -> float:  # 0h UTC of day k after the epoch's
        return seconds_after(epoch, Epoch(epoch.jd_whole + k, 0.0))

    k = int(np.floor(epoch.jd_fraction + start_s / 86400.0)) - 1  # a day early: leap seconds
    while start(k + 1) <= start_s:
        k += 1
    dates, bounds = [], [start(k)]
    while bounds[-1] <= end_s:
        if len(dates) == MAX_EOP_DAYS:
            raise ValueError(f"more than {MAX_EOP_DAYS} days")
        dates.append(Epoch(epoch.jd_whole + k, 0.0).iso(0)[:10])
        k += 1
        bounds.append(start(k))
    return EopDays(tuple(dates), tuple(bounds))

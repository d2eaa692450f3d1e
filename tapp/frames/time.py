"""UTC calendar dates, Julian dates split in whole + fraction, ISO parsing, GMST (IAU-82).

Time scales: scenario epochs are UTC calendar dates; inside the code time is seconds from that
epoch. Earth rotation uses GMST IAU-82 evaluated with UT1 = UTC (|UT1 - UTC| < 0.9 s, i.e. at
most 6.6e-5 rad = 0.4 km at the equator in station longitude). Leap seconds are not modelled:
a scenario must not straddle one.

Julian dates are carried as two floats (``jd_whole``, ``jd_fraction``), in the manner of sgp4's
``jdsatepoch`` + ``jdsatepochF``: ``jd_whole`` is the Julian date of the preceding 0h UTC
(so it ends in .5), ``jd_fraction`` the fraction of the day, so that 1 us survives.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError

#: Julian date of J2000.0 (2000 Jan 1 12h), the origin of the GMST polynomial.
JD_J2000 = 2451545.0
DAYS_PER_JULIAN_CENTURY = 36525.0
NANOSECONDS_PER_DAY = 86_400 * 10**9

_ISO = re.compile(
    r"^\s*(\d{4})-(\d{2})-(\d{2})"
    r"(?:[T ](\d{2}):(\d{2})(?::(\d{2}(?:\.\d*)?))?)?"
    r"\s*(Z|UTC|[+-]00:?00)?\s*$"
)


def _days_in_month(year: int, month: int) -> int:
    if month == 2:
        leap = year % 4 == 0 and (year % 100 != 0 or year % 400 == 0)
        return 29 if leap else 28
    return 30 if month in (4, 6, 9, 11) else 31


def calendar_to_jd(
    year: int, month: int, day: int, hour: int = 0, minute: int = 0, second: float = 0.0
) -> tuple[float, float]:
    """Return the Julian date of a Gregorian UTC calendar date as (whole, fraction) days.

    Parameters
    ----------
    year, month, day : int
        Gregorian calendar date (proleptic before 1582).
    hour, minute : int
        Time of day.
    second : float
        Seconds of the minute, 0 <= second < 60 (leap seconds are not represented).

    Returns
    -------
    jd_whole : float
        Julian date of 0h of the day (ends in .5), days.
    jd_fraction : float
        Fraction of the day, ``(3600 hour + 60 minute + second) / 86400``.

    Notes
    -----
    Day number by Fliegel & Van Flandern (1968), Comm. ACM 11(10) 657, in integer arithmetic
    (valid for every Gregorian date with year > -4800). Checked against Vallado, Fundamentals of
    Astrodynamics and Applications, Example 3-4 (1996 Oct 26 14:20 -> JD 2450383.09722222).
    """
    a = (14 - month) // 12
    y = year + 4800 - a
    m = month + 12 * a - 3
    jdn = day + (153 * m + 2) // 5 + 365 * y + y // 4 - y // 100 + y // 400 - 32045
    return float(jdn) - 0.5, (3600.0 * hour + 60.0 * minute + second) / SECONDS_PER_DAY


def jd_to_calendar(
    jd_whole: float, jd_fraction: float = 0.0
) -> tuple[int, int, int, int, int, float]:
    """Return the Gregorian UTC calendar date (year, month, day, hour, minute, second) of a JD.

    Parameters
    ----------
    jd_whole, jd_fraction : float
        Julian date in days, split anywhere (the sum is what counts; the split keeps precision).

    Returns
    -------
    tuple
        ``(year, month, day, hour, minute, second)``, second a float in [0, 60), resolved to
        1 ns (the split Julian date itself holds about 1e-11 s).

    Notes
    -----
    Inverse of :func:`calendar_to_jd` (Richards, in Explanatory Supplement to the Astronomical
    Almanac, 3rd ed., 2013, section 15.11.3, algorithm for the Gregorian calendar).
    """
    # Move to days counted from 0h so the day number is the floor of the whole part; resolve
    # the time of day to integer nanoseconds so that 00:33:00 does not print as 00:32:59.999...
    whole = float(jd_whole) + 0.5
    day_number = np.floor(whole)
    day_fraction = (whole - day_number) + float(jd_fraction)
    carry, nanoseconds = divmod(round(day_fraction * NANOSECONDS_PER_DAY), NANOSECONDS_PER_DAY)
    jdn = int(day_number) + carry
    f = jdn + 1401 + (((4 * jdn + 274277) // 146097) * 3) // 4 - 38
    e = 4 * f + 3
    g = (e % 1461) // 4
    h = 5 * g + 2
    day = (h % 153) // 5 + 1
    month = (h // 153 + 2) % 12 + 1
    year = e // 1461 - 4716 + (12 + 2 - month) // 12
    hour, nanoseconds = divmod(nanoseconds, 3600 * 10**9)
    minute, nanoseconds = divmod(nanoseconds, 60 * 10**9)
    second = nanoseconds / 1e9
    return year, month, day, hour, minute, second


@dataclass(frozen=True, slots=True)
class Epoch:
    """A UTC instant as a Julian date split into whole + fraction (days).

    Attributes
    ----------
    jd_whole : float
        Julian date of 0h UTC of the day, days (ends in .5 when built by the constructors).
    jd_fraction : float
        Fraction of the day in [0, 1).
    """

    jd_whole: float
    jd_fraction: float

    @classmethod
    def from_calendar(
        cls, year: int, month: int, day: int, hour: int = 0, minute: int = 0, second: float = 0.0
    ) -> Epoch:
        """Return the epoch of a UTC calendar date (see :func:`calendar_to_jd`)."""
        return cls(*calendar_to_jd(year, month, day, hour, minute, second))

    @property
    def jd(self) -> float:
        """Julian date (UTC) as one float, days (about 40 us resolution)."""
        return self.jd_whole + self.jd_fraction

    def calendar(self) -> tuple[int, int, int, int, int, float]:
        """Return ``(year, month, day, hour, minute, second)``, UTC."""
        return jd_to_calendar(self.jd_whole, self.jd_fraction)

    def iso(self, decimals: int = 6) -> str:
        """Return ``YYYY-MM-DDThh:mm:ss.ffffff`` (UTC) with ``decimals`` digits of seconds."""
        scale = 10**decimals
        units_per_day = 86400 * scale
        carry, units = divmod(round(self.jd_fraction * SECONDS_PER_DAY * scale), units_per_day)
        year, month, day, _, _, _ = jd_to_calendar(self.jd_whole + carry)
        hour, units = divmod(units, 3600 * scale)
        minute, units = divmod(units, 60 * scale)
        second, sub = divmod(units, scale)
        text = f"{year:04d}-{month:02d}-{day:02d}T{hour:02d}:{minute:02d}:{second:02d}"
        return f"{text}.{sub:0{decimals}d}" if decimals > 0 else text

    def iso_after(self, t_s: float, decimals: int = 6) -> str:
        """Return :meth:`iso` of the date ``t_s`` seconds after this epoch (t_s / 86400 days
        added to the fraction, as the scenario's times count)."""
        return Epoch(self.jd_whole, self.jd_fraction + t_s / SECONDS_PER_DAY).iso(decimals)

    def gmst_rad(self) -> float:
        """GMST IAU-82 at this epoch, rad in [0, 2 pi), taking UT1 = UTC (see :func:`gmst_rad`)."""
        return float(gmst_rad(self.jd_whole, self.jd_fraction))


def parse_epoch(text: str, source: str = "epoch") -> Epoch:
    """Return the :class:`Epoch` of an ISO 8601 UTC date string.

    Accepted: ``YYYY-MM-DD``, ``YYYY-MM-DDThh:mm``, ``YYYY-MM-DDThh:mm:ss[.fff...]``, a space
    instead of ``T``, and an optional ``Z``, ``UTC`` or zero offset. Fractional seconds keep all
    their digits (no rounding to microseconds).

    Parameters
    ----------
    text : str
        The date, e.g. ``"2026-01-01T00:00:00"``.
    source : str
        Where the text came from (file or option), for the error message.

    Raises
    ------
    InputError
        If the text is not such a date or a field is out of range.
    """
    expected = "an ISO 8601 UTC date YYYY-MM-DD[Thh:mm[:ss[.fff]]][Z]"
    match = _ISO.match(text) if isinstance(text, str) else None
    if match is None:
        raise InputError(source, "epoch", expected, text)
    year, month, day = (int(g) for g in match.group(1, 2, 3))
    hour = int(match.group(4) or 0)
    minute = int(match.group(5) or 0)
    second = float(match.group(6) or 0.0)
    if not 1 <= month <= 12 or not 1 <= day <= _days_in_month(year, month):
        raise InputError(source, "epoch", f"{expected} with a valid calendar date", text)
    if hour > 23 or minute > 59 or second >= 60.0:
        raise InputError(source, "epoch", f"{expected} with hh<24, mm<60, ss<60", text)
    return Epoch.from_calendar(year, month, day, hour, minute, second)


def gmst_rad(jd_ut1_whole: np.ndarray | float, jd_ut1_fraction: np.ndarray | float = 0.0):
    """Return the Greenwich mean sidereal time IAU-82, rad in [0, 2 pi).

    .. math::

        \\theta_{GMST} = 67310.54841^s + (876600^h + 8640184.812866^s) T_{UT1}
                         + 0.093104^s T_{UT1}^2 - 6.2 \\times 10^{-6\\,s} T_{UT1}^3,
        \\qquad T_{UT1} = (JD_{UT1} - 2451545.0) / 36525

    Parameters
    ----------
    jd_ut1_whole, jd_ut1_fraction : float or array_like, shape (...)
        UT1 Julian date split in two parts (any split), days; broadcast together.
        Pass UTC here under the project's UT1 = UTC assumption.

    Returns
    -------
    numpy.ndarray or float, shape (...)
        GMST, rad.

    Notes
    -----
    Vallado, Fundamentals of Astrodynamics and Applications, eq. 3-45 (2nd ed.; 3-47 in the 4th),
    from Aoki et al. (1982), A&A 105, 359. The 876600 h T term equals 86400 s times the days since
    J2000, so it is evaluated as the fractional day from the split date: no precision is lost to
    the large Julian date. Example 3-5 (1992 Aug 20 12:14 UT1) gives 152.578787886 deg (2nd ed.;
    the 4th ed. prints 152.578787810 deg from a JD rounded to 1e-6 d).
    """
    whole = np.asarray(jd_ut1_whole, dtype=float) - JD_J2000
    fraction = np.asarray(jd_ut1_fraction, dtype=float)
    t_cent = (whole + fraction) / DAYS_PER_JULIAN_CENTURY
    day_fraction = np.mod(whole, 1.0) + fraction
    theta_s = (
        67310.54841
        + SECONDS_PER_DAY * day_fraction
        + (8640184.812866 + (0.093104 - 6.2e-6 * t_cent) * t_cent) * t_cent
    )
    return np.mod(theta_s, SECONDS_PER_DAY) * (2.0 * np.pi / SECONDS_PER_DAY)

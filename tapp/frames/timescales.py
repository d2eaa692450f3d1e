"""Time scales of scenario time: UTC, TAI, TT, TDB and UT1, each a two-part Julian date.

Scenario time t is SI seconds elapsed from the scenario epoch, a UTC calendar date; it runs
with TAI, so an arc across a leap second is handled (the UTC labels step back, t does not):

.. math::
    TAI(t) = UTC_0 + ΔAT(UTC_0) + t,\\quad TT = TAI + 32.184\\,s,\\quad
    TDB = TT + Δ_{TDB-TT}(TT),\\quad UT1 = TAI + (UT1 - UTC) - ΔAT,

with ΔAT = TAI − UTC from the IERS leap-second table, UT1 − UTC from the IERS EOP table
(:mod:`tapp.frames.eop`) and TDB − TT from ERFA's ``dtdb`` (Fairhead & Bretagnon 1990 series,
geocentre: the topocentric terms, ≤ 2 μs, are left out, as astropy does without a location).
UT1 − TAI is continuous across a leap second (the jumps of UT1 − UTC and ΔAT cancel), so the
Earth rotation angle is too. Every returned date is (whole, fraction) days with whole the
epoch's 0h, so 1 ns survives.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import erfa
import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.frames.eop import MJD_OFFSET, EopTable, LeapSeconds
from tapp.frames.iers import leap_seconds
from tapp.frames.time import Epoch

#: TT − TAI, s (IAU 1991 Resolution A4).
TT_MINUS_TAI_s = 32.184
#: Node spacing (s) of the day tables of ERFA's geocentric TDB − TT that every reader
#: interpolates (cubic Lagrange, :func:`geocentric_tdb_minus_tt_s`): the series' fastest
#: terms leave at most 9e-17 s at 1800 s (3e-16 s at 3600 s, 5e-15 s at 7200 s), measured
#: at every 0.37 of a node over 2028-2036 (tests/tapp/frames/test_timescales.py).
DTDB_STEP_s = 1800.0
_DTDB_PER_DAY = round(SECONDS_PER_DAY / DTDB_STEP_s)
_DEG = math.pi / 180.0
#: Days per Julian millennium, and the J2000 Julian date (the series' time argument).
_DAYS_PER_MILLENNIUM = 365250.0
_J2000_JD = 2451545.0


def seconds_after(epoch: Epoch, when: Epoch, source: str = "epoch") -> float:
    """Return the scenario time of the UTC date ``when``: SI seconds elapsed since ``epoch``, s.

    .. math:: t = 86400\\,(JD_{when} - JD_{epoch}) + ΔAT(when) - ΔAT(epoch)

    (Julian dates differenced whole and fraction apart; a leap second between them counted).

    Raises
    ------
    InputError
        Naming ``source``: a date before 1972 (no leap-second UTC).
    """
    days = (when.jd_whole - epoch.jd_whole) + (when.jd_fraction - epoch.jd_fraction)
    leaps = leap_seconds()
    step = (leaps.at_utc(when.jd - MJD_OFFSET, source)
            - leaps.at_utc(epoch.jd - MJD_OFFSET, source))
    return days * SECONDS_PER_DAY + float(step)


@functools.lru_cache(maxsize=8192)
def _dtdb_day(tt0_whole: float, tt0_fraction: float, day: int) -> np.ndarray:
    """ERFA's geocentric TDB − TT (s) at the nodes of one day: (day D + i / 48) days of TT
    after the Julian date tt0, i = 0 ... 47 (:data:`DTDB_STEP_s` apart)."""
    t_s = (day * _DTDB_PER_DAY + np.arange(_DTDB_PER_DAY)) * DTDB_STEP_s
    return erfa.dtdb(tt0_whole, tt0_fraction + t_s / SECONDS_PER_DAY, 0.0, 0.0, 0.0, 0.0)


def geocentric_tdb_minus_tt_s(tt0_jd: tuple[float, float], t_s) -> np.ndarray:
    """Return TDB − TT at the geocentre, s, at t_s seconds of TT after the TT Julian date
    ``tt0_jd`` = (whole, fraction), same shape: ERFA's Fairhead & Bretagnon (1990) series
    (``erfa.dtdb`` without a site), by cubic Lagrange interpolation in day tables of nodes
    :data:`DTDB_STEP_s` apart, computed once per day (the series costs ~3.5 μs a time and a
    light-time solution asks for it ~100 times per sample; error < 5e-16 s, tested)."""
    x = np.asarray(t_s, dtype=float) / DTDB_STEP_s
    if x.size == 0:
        return np.zeros(x.shape)
    n = np.floor(x).astype(np.int64)
    first, last = (int(n.min()) - 1) // _DTDB_PER_DAY, (int(n.max()) + 2) // _DTDB_PER_DAY
    nodes = np.concatenate([_dtdb_day(*tt0_jd, d) for d in range(first, last + 1)])
    i = n - first * _DTDB_PER_DAY
    s = x - n
    return (-s * (s - 1.0) * (s - 2.0) / 6.0 * nodes[i - 1]
            + (s + 1.0) * (s - 1.0) * (s - 2.0) / 2.0 * nodes[i]
            - (s + 1.0) * s * (s - 2.0) / 2.0 * nodes[i + 1]
            + (s + 1.0) * s * (s - 1.0) / 6.0 * nodes[i + 2])


def topocentric_tdb_minus_tt_s(tt_jd: tuple, ut_fraction, site: tuple[float, float, float]
                               ) -> np.ndarray:
    """Return the topocentric terms of TDB − TT at a site, s (add them to the geocentric
    :func:`geocentric_tdb_minus_tt_s`): Moyer (1981) and Murray (1983), as ERFA's ``dtdb``
    evaluates them, with its fundamental arguments (Simon et al. 1994).

    The terms are linear in u and v; erfa.dtdb with the site minus erfa.dtdb without it
    equals them to 1e-19 s (tested).

    Parameters
    ----------
    tt_jd : (whole, fraction) TT Julian dates, arrays broadcasting together, days.
    ut_fraction : UT (UT1, or UTC within its 0.9 s) as a fraction of a day: the local solar
        time's argument.
    site : (east longitude rad, distance from the spin axis u km, from the equator v km).
    """
    elong, u, v = site
    w = ((np.asarray(tt_jd[0], float) - _J2000_JD) + tt_jd[1]) / _DAYS_PER_MILLENNIUM / 3600.0
    tsol = np.mod(ut_fraction, 1.0) * 2.0 * math.pi + elong
    elsun = np.mod(280.46645683 + 1296027711.03429 * w, 360.0) * _DEG  # Sun mean longitude
    emsun = np.mod(357.52910918 + 1295965810.481 * w, 360.0) * _DEG  # Sun mean anomaly
    d = np.mod(297.85019547 + 16029616012.090 * w, 360.0) * _DEG  # Moon's elongation
    elj = np.mod(34.35151874 + 109306899.89453 * w, 360.0) * _DEG  # Jupiter mean longitude
    els = np.mod(50.07744430 + 44046398.47038 * w, 360.0) * _DEG  # Saturn mean longitude
    return (0.00029e-10 * u * np.sin(tsol + elsun - els)
            + 0.00100e-10 * u * np.sin(tsol - 2.0 * emsun)
            + 0.00133e-10 * u * np.sin(tsol - d)
            + 0.00133e-10 * u * np.sin(tsol + elsun - elj)
            - 0.00229e-10 * u * np.sin(tsol + 2.0 * elsun + emsun)
            - 0.02200e-10 * v * np.cos(elsun + emsun)
            + 0.05312e-10 * u * np.sin(tsol - emsun)
            - 0.13677e-10 * u * np.sin(tsol + 2.0 * elsun)
            - 1.31840e-10 * v * np.cos(elsun)
            + 3.17679e-10 * u * np.sin(tsol))


@dataclass(frozen=True, slots=True)
class TimeScales:
    """The time scales of one scenario: its UTC epoch, the leap seconds and the EOP table."""

    epoch: Epoch
    eop: EopTable
    leaps: LeapSeconds

    @classmethod
    def of(cls, epoch: Epoch, eop: EopTable, source: str = "epoch") -> TimeScales:
        """Build for ``epoch`` (UTC); raises InputError for a date before 1972."""
        leaps = leap_seconds()
        leaps.at_utc(epoch.jd - MJD_OFFSET, source)
        return cls(epoch, eop, leaps)

    @property
    def tai_minus_utc_epoch_s(self) -> float:
        """ΔAT at the epoch, s."""
        return float(self.leaps.at_utc(self.epoch.jd - MJD_OFFSET))

    def _offset(self, t_s, extra_s) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t_s, dtype=float)
        fraction = self.epoch.jd_fraction + (t + extra_s) / SECONDS_PER_DAY
        return np.full(t.shape, self.epoch.jd_whole), fraction

    def tai(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """TAI Julian date at scenario times t_s, (whole, fraction) days."""
        return self._offset(t_s, self.tai_minus_utc_epoch_s)

    def tt(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """TT Julian date at scenario times t_s, (whole, fraction) days."""
        return self._offset(t_s, self.tai_minus_utc_epoch_s + TT_MINUS_TAI_s)

    def tdb(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """TDB Julian date at scenario times t_s (geocentric), (whole, fraction) days."""
        whole, fraction = self.tt(t_s)
        return whole, fraction + self.tdb_minus_tt_s(t_s) / SECONDS_PER_DAY

    def tdb_minus_tt_s(self, t_s) -> np.ndarray:
        """TDB − TT at the geocentre, s, at scenario times t_s
        (:func:`geocentric_tdb_minus_tt_s`)."""
        whole, fraction = self.tt(0.0)
        return geocentric_tdb_minus_tt_s((float(whole), float(fraction)), t_s)

    def utc_mjd(self, t_s) -> np.ndarray:
        """UTC as a modified Julian date at scenario times t_s (for table look-ups), days.

        During a leap second (23:59:60) this reads as the first second of the next day.
        """
        whole, fraction = self.tai(t_s)
        mjd_tai = (whole - MJD_OFFSET) + fraction
        return mjd_tai - self.leaps.at_tai(mjd_tai) / SECONDS_PER_DAY

    def ut1_minus_tai_s(self, t_s, source: str = "epoch") -> np.ndarray:
        """UT1 − TAI, s, at scenario times t_s (continuous across leap seconds)."""
        mjd_utc = self.utc_mjd(t_s)
        eop = self.eop.at(mjd_utc, source)
        return eop.ut1_minus_utc_s - self.leaps.at_utc(mjd_utc, source)

    def ut1(self, t_s, source: str = "epoch") -> tuple[np.ndarray, np.ndarray]:
        """UT1 Julian date at scenario times t_s, (whole, fraction) days."""
        whole, fraction = self.tai(t_s)
        return whole, fraction + self.ut1_minus_tai_s(t_s, source) / SECONDS_PER_DAY

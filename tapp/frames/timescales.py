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

from dataclasses import dataclass

import erfa
import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.frames.eop import MJD_OFFSET, EopTable, LeapSeconds, leap_seconds
from tapp.frames.time import Epoch

#: TT − TAI, s (IAU 1991 Resolution A4).
TT_MINUS_TAI_s = 32.184
#: Largest spacing of the nodes between which TDB − TT is interpolated linearly, s: the
#: series' fast terms leave an error of 3e-12 s (1e-10 s at 3600 s), measured over 60-day
#: spans from 1968 to 2050 (tests/tapp/frames/test_timescales.py).
DTDB_NODE_s = 600.0


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


def _tdb_minus_tt_s(whole: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """TDB − TT at the geocentre, s: ERFA's Fairhead & Bretagnon series."""
    return erfa.dtdb(whole, fraction, 0.0, 0.0, 0.0, 0.0)


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
        """TDB − TT at the geocentre, s, at scenario times t_s.

        Many times at once (more than there are nodes :data:`DTDB_NODE_s` apart over their
        span) take it interpolated linearly between such nodes: the series costs about 7 μs
        a time, and SEARCH's scans evaluated it at every grid point (80 % of a trajectory's
        time).
        """
        t = np.asarray(t_s, dtype=float)
        if t.size > 2 and np.isfinite(span_s := float(np.ptp(t))):
            count = max(int(np.ceil(span_s / DTDB_NODE_s)) + 1, 2)
            if count < t.size:
                nodes = float(t.min()) + span_s * np.linspace(0.0, 1.0, count)
                return np.interp(t.ravel(), nodes, _tdb_minus_tt_s(*self.tt(nodes))).reshape(
                    t.shape)
        return _tdb_minus_tt_s(*self.tt(t))

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

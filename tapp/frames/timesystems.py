"""Dates of trajectory files in their own time system, as scenario time, and SPICE's ET.

A trajectory file (a CCSDS OEM, a SPICE SPK) dates its states in a time system of its own
(the OEM's ``TIME_SYSTEM``; an SPK in ET, TDB seconds past J2000). Scenario time t is SI
seconds from the scenario's UTC epoch, running with TAI (:mod:`tapp.frames.timescales`). A
date ``D`` in system X becomes

.. math::
    t = \\big(TAI(D) - TAI(epoch)\\big)\\,86400\\ \\mathrm{s/d},

with, per X (IAU 1991 Resolution A4 and 2006 Resolution B3; IERS Conventions 2010 ch. 10):

- UTC: TAI = UTC + ΔAT(UTC), ΔAT from the IERS leap-second table (a date inside a leap
  second, 23:59:60, is refused by the calendar parser);
- TAI; TT = TAI + 32.184 s; GPS = TAI − 19 s (the GPS epoch 1980-01-06 UTC);
- TDB: TT = TDB − (TDB − TT)(TT), ERFA ``dtdb`` at the geocentre (≤ 1.7 ms; evaluated at
  the TDB date, which differs from TT's by 1e-8 of the term: 2e-11 s);
- TCG, TCB: ERFA ``tcgtt`` and ``tcbtdb`` (the IAU's linear relations L_G, L_B).

UT1 and the mission-elapsed or spacecraft clocks (MET, MRT, SCLK) are not read: they are
not uniform or need a mission's own origin. ET = TDB seconds past J2000 (JD 2451545.0 TDB):
one double holds it to 1.2e-7 s near 2026, 0.9 mm at 7.5 km/s, which bounds what an SPK
round trip can keep.
"""

from __future__ import annotations

import erfa
import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError
from tapp.frames.eop import MJD_OFFSET, EopTable
from tapp.frames.iers import leap_seconds
from tapp.frames.time import JD_J2000, Epoch
from tapp.frames.timescales import TimeScales, TT_MINUS_TAI_s

#: GPS time − TAI, s (the GPS epoch: TAI − UTC was 19 s on 1980-01-06).
GPS_MINUS_TAI_s = -19.0
#: The time systems a trajectory file may date its states in (CCSDS SANA names).
TIME_SYSTEMS = ("UTC", "TAI", "TT", "GPS", "TDB", "TCG", "TCB")
#: Offset of each TAI-uniform system from TAI, s (UTC's, the leap seconds, is per date).
_MINUS_TAI_s = {"TAI": 0.0, "TT": TT_MINUS_TAI_s, "GPS": GPS_MINUS_TAI_s}


def _epoch_tai_offset_s(epoch: Epoch, source: str) -> float:
    """ΔAT at the scenario epoch, s."""
    return float(leap_seconds().at_utc(epoch.jd - MJD_OFFSET, source))


def _tt_from(system: str, whole: np.ndarray, fraction: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """TT Julian dates (whole, fraction) of dates in TDB, TCG or TCB."""
    if system == "TCG":
        return erfa.tcgtt(whole, fraction)
    if system == "TCB":
        whole, fraction = erfa.tcbtdb(whole, fraction)
    dtdb_s = erfa.dtdb(whole, fraction, 0.0, 0.0, 0.0, 0.0)
    return whole, fraction - dtdb_s / SECONDS_PER_DAY


def scenario_seconds(jd_whole, jd_fraction, system: str, epoch: Epoch,
                     source: str = "trajectory", field: str = "TIME_SYSTEM") -> np.ndarray:
    """Return scenario time t (s from ``epoch``, TAI-uniform) of dates in ``system``.

    Parameters
    ----------
    jd_whole, jd_fraction : array_like, shape (N,)
        The dates as Julian dates *in ``system``*, split in two parts (days): the calendar
        date of a file's epoch read as if it were UTC (:func:`tapp.frames.time.calendar_to_jd`).
    system : str
        One of :data:`TIME_SYSTEMS`.
    epoch : Epoch
        The scenario epoch (UTC).
    source, field : where the time system was named (for the error).

    Returns
    -------
    (N,) s.

    Raises
    ------
    InputError
        An unknown system, or a UTC date before 1972 (no leap-second UTC).
    """
    if system not in TIME_SYSTEMS:
        raise InputError(source, field, f"a time system tapp reads ({', '.join(TIME_SYSTEMS)})",
                         system)
    whole = np.asarray(jd_whole, dtype=float)
    fraction = np.asarray(jd_fraction, dtype=float)
    offset_s = -_epoch_tai_offset_s(epoch, source)  # + (TAI - X) of the dates, below
    if system == "UTC":
        offset_s = offset_s + leap_seconds().at_utc(whole - MJD_OFFSET + fraction, source)
    elif system in _MINUS_TAI_s:
        offset_s = offset_s - _MINUS_TAI_s[system]
    else:
        whole, fraction = _tt_from(system, whole, fraction)
        offset_s = offset_s - TT_MINUS_TAI_s
    days = (whole - epoch.jd_whole) + (fraction - epoch.jd_fraction)
    return days * SECONDS_PER_DAY + offset_s


def et_split(t_s, epoch: Epoch) -> tuple[np.ndarray, np.ndarray]:
    """Return SPICE ET at scenario times t_s (N,) as the nearest doubles and what they leave
    out: (et, remainder) s, et + remainder the ET of t_s to 1e-10 s.

    ET near 2026 is 8.3e8 s, a double's spacing there 1.2e-7 s (0.9 mm at 7.5 km/s): the
    remainder lets a state be moved to the instant its rounded ET names (:func:`to_et`).
    """
    whole, fraction = _scales(epoch).tdb(np.asarray(t_s, dtype=float))
    days_s = (whole - JD_J2000) * SECONDS_PER_DAY  # whole seconds: exact
    part_s = fraction * SECONDS_PER_DAY
    et = days_s + part_s
    return et, part_s - (et - days_s)  # et - days_s is exact (Sterbenz)


def et_from_scenario(t_s, epoch: Epoch) -> np.ndarray:
    """Return SPICE ET (TDB seconds past J2000, geocentric TDB) at scenario times t_s (N,),
    rounded to doubles (:func:`et_split`)."""
    return et_split(t_s, epoch)[0]


def _scales(epoch: Epoch) -> TimeScales:
    return TimeScales.of(epoch, EopTable.zero())


def _et_rate(t_s: np.ndarray, epoch: Epoch) -> np.ndarray:
    """dET/dt at scenario times (N,): 1 + d(TDB − TT)/dt, by central differences over
    ±:data:`_RATE_STEP_s` (the periodic term's rate is at most 3.3e-10)."""
    dtdb = _scales(epoch).tdb_minus_tt_s
    return 1.0 + (dtdb(t_s + _RATE_STEP_s) - dtdb(t_s - _RATE_STEP_s)) / (2.0 * _RATE_STEP_s)


#: Step of the differences of TDB − TT for its rate, s.
_RATE_STEP_s = 60.0


def _moved(t: np.ndarray, x: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """States (N, 6) at times t (N,) moved by dt (N,), a fraction of a microsecond: r + dt v,
    v + dt a, a the derivative of v along the states (second-order differences; none with
    fewer than 3 states), to first order in dt (the next term, a dt²/2, is 1e-17 km)."""
    accel = (np.gradient(x[:, 3:], t, axis=0, edge_order=2) if t.size >= 3
             else np.zeros_like(x[:, 3:]))
    return np.concatenate([x[:, :3] + dt[:, None] * x[:, 3:],
                           x[:, 3:] + dt[:, None] * accel], axis=1)


def to_et(t_s, states, epoch: Epoch) -> tuple[np.ndarray, np.ndarray]:
    """Return states (N, 6) at scenario times t_s (N,) as an SPK holds them: (et, states at et)
    with et the rounded ET of t_s (:func:`et_split`), each state moved to the instant et names
    and its velocity per TDB second (dt/dET differs from 1 by up to 3.3e-10: 2.5 µm/s at
    7.5 km/s, which a Hermite interpolation through 30 s spacing turns into 0.04 mm).

    t_s must increase (the derivative of v along the states moves them).
    """
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(states, dtype=float)
    et, remainder = et_split(t, epoch)
    moved = _moved(t, x, -remainder)
    moved[:, 3:] /= _et_rate(t, epoch)[:, None]
    return et, moved


def from_et(t_s, states, epoch: Epoch) -> np.ndarray:
    """Return states (N, 6) that an SPK gives at the rounded ET of scenario times t_s (N,,
    increasing) as states at t_s, velocities per scenario second: the inverse of
    :func:`to_et`."""
    t = np.asarray(t_s, dtype=float)
    x = np.array(states, dtype=float)
    x[:, 3:] *= _et_rate(t, epoch)[:, None]
    return _moved(t, x, et_split(t, epoch)[1])

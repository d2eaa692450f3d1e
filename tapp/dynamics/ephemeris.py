"""Positions of the Sun, Moon and planets from JPL DE421, and time scales for reading it.

DE421 (Folkner, Williams & Boggs 2009, IPN Progress Report 42-178) ships inside the
``skyfield-data`` package and is read with ``jplephem``: nothing is downloaded at run time.
Its axes are the ICRF, which the iau2006 Earth orientation takes as the GCRS axes, and the
gmst model as EME2000 (they differ by ~20 mas, far below what matters for third-body
accelerations). Its time argument is TDB: with the iau2006 model it is TDB proper
(:class:`tapp.frames.timescales.TimeScales`); with gmst, as in the approximate-STM study,
TDB ≈ TT = UTC + ΔAT + 32.184 s (the periodic TDB−TT term, under 2 ms, neglected).

For the compiled propagator the positions relative to the integration centre are fitted by
piecewise Chebyshev series (:func:`chebyshev_table`), evaluated inside the C driver.
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Callable
from functools import cache, lru_cache, partial
from pathlib import Path

import numpy as np
from jplephem.spk import SPK

from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError
from tapp.frames.chebyshev import ChebyshevTable, fit_chebyshev, segment_starts
from tapp.frames.eop import MJD_OFFSET, EopTable
from tapp.frames.iers import leap_seconds
from tapp.frames.time import Epoch
from tapp.frames.timescales import TimeScales, TT_MINUS_TAI_s

# NAIF paths from the solar-system barycentre (0) in DE421: lists of (center, target).
_PATHS = {
    "sun": ((0, 10),),
    "mercury": ((0, 1), (1, 199)),
    "venus": ((0, 2), (2, 299)),
    "earth": ((0, 3), (3, 399)),
    "moon": ((0, 3), (3, 301)),
    "mars": ((0, 4), (4, 499)),
    "jupiter": ((0, 5),),
    "saturn": ((0, 6),),
    "uranus": ((0, 7),),
    "neptune": ((0, 8),),
}


#: Bodies whose positions DE421 gives here (NAIF paths below).
BODIES = tuple(_PATHS)


def tai_minus_utc_s(jd_utc: float, source: str = "epoch") -> float:
    """Return TAI − UTC (s) at a UTC Julian date, from the IERS leap-second table.

    ``source`` names where the date came from in the error (an option such as ``--epoch``);
    dates before 1972 are refused (:meth:`tapp.frames.eop.LeapSeconds.at_utc`).
    """
    return float(leap_seconds().at_utc(jd_utc - MJD_OFFSET, source))


def utc_to_tdb_jd(jd_utc: float, source: str = "epoch") -> float:
    """Return the TDB Julian date of a UTC Julian date (TDB ≈ TT, see module docstring)."""
    return jd_utc + (tai_minus_utc_s(jd_utc, source) + TT_MINUS_TAI_s) / SECONDS_PER_DAY


def tdb_reader(epoch_jd_utc: float | None, scales: TimeScales | None = None
               ) -> Callable[[np.ndarray], tuple]:
    """Return ``tdb(t_s) -> (whole, fraction)``, the TDB Julian date of scenario times t_s
    (s from the epoch), as every reader of the ephemeris takes it: ``scales``' TDB proper
    (iau2006), else TT of the UTC epoch (gmst: module docstring)."""
    if scales is not None:
        return scales.tdb
    return partial(_tt_dates, utc_to_tdb_jd(epoch_jd_utc))  # picklable (Dask workers)


def _tt_dates(jd_tdb: float, t_s: np.ndarray) -> tuple[float, np.ndarray]:
    return jd_tdb, np.asarray(t_s, dtype=float) / SECONDS_PER_DAY


def de421_path() -> Path:
    """Path of de421.bsp inside skyfield-data (found without importing the package,
    whose import warns about its Earth-orientation file's age)."""
    spec = importlib.util.find_spec("skyfield_data")
    if spec is None or not spec.submodule_search_locations:
        raise InputError("ephemeris", "skyfield-data", "the skyfield-data package installed")
    return Path(next(iter(spec.submodule_search_locations))) / "data" / "de421.bsp"


@cache
def _kernel() -> SPK:
    return SPK.open(str(de421_path()))


def coverage_jd_tdb() -> tuple[float, float]:
    """Return the first and last TDB Julian dates every segment of DE421 covers, days."""
    segments = _kernel().segments
    return (max(seg.start_jd for seg in segments), min(seg.end_jd for seg in segments))


def _iso_tdb(jd_tdb: float) -> str:
    whole = math.floor(jd_tdb - 0.5) + 0.5 if math.isfinite(jd_tdb) else jd_tdb
    if not math.isfinite(whole):
        return str(jd_tdb)
    return Epoch(whole, jd_tdb - whole).iso(0) + " TDB"


def check_coverage(jd_tdb: float | np.ndarray, jd_tdb2: float | np.ndarray = 0.0,
                   source: str = "DE421 ephemeris", field: str = "epoch") -> None:
    """Raise InputError unless every TDB date ``jd_tdb + jd_tdb2`` lies within DE421.

    The message names the first date outside and DE421's coverage; ``source`` and ``field``
    say where the date came from (an option such as ``--epoch``, or a scenario file field).
    """
    jd = np.asarray(jd_tdb, dtype=float) + np.asarray(jd_tdb2, dtype=float)
    if jd.size == 0:
        return
    first, last = coverage_jd_tdb()
    outside = ~((jd >= first) & (jd <= last))
    if np.any(outside):
        bad = float(jd.ravel()[np.argmax(outside.ravel())])
        raise InputError(source, field, f"a date within DE421's coverage {_iso_tdb(first)} .. "
                         f"{_iso_tdb(last)}", _iso_tdb(bad))


def _barycentric_km(body: str, jd: np.ndarray, jd2: np.ndarray) -> np.ndarray:
    kernel = _kernel()
    total = np.zeros((3, jd.size))
    for center, target in _PATHS[body]:
        total += kernel[center, target].compute(jd, jd2)
    return total.T


def barycentric_state(body: str, jd_tdb: float | np.ndarray,
                      jd_tdb2: float | np.ndarray = 0.0) -> np.ndarray:
    """Return the state (N, 6) [km, km/s] of ``body`` relative to the solar-system barycentre.

    The TDB date is split as in :func:`position_km`; the velocity is jplephem's derivative of
    the Chebyshev series (km/day, converted). For the barycentric light time
    (:mod:`tapp.measurements.relativity`).
    """
    jd, jd2 = np.broadcast_arrays(np.atleast_1d(np.asarray(jd_tdb, dtype=float)),
                                  np.atleast_1d(np.asarray(jd_tdb2, dtype=float)))
    check_coverage(jd, jd2)
    kernel = _kernel()
    total = np.zeros((6, jd.size))
    for center, target in _PATHS[body]:
        position, velocity = kernel[center, target].compute_and_differentiate(jd, jd2)
        total[:3] += position
        total[3:] += velocity / SECONDS_PER_DAY
    return total.T


def relative_state(body: str, origin: str, jd_tdb: float | np.ndarray,
                   jd_tdb2: float | np.ndarray = 0.0) -> np.ndarray:
    """Return the state (N, 6) [km, km/s] of ``body`` relative to ``origin`` (ICRF axes):
    the difference of their barycentric states (:func:`barycentric_state`), zeros when they
    are the same body. The translation of a change of integration centre
    (:mod:`tapp.dynamics.centres`), or from the body an injection is given about to the centre."""
    if body == origin:
        jd = np.broadcast_arrays(np.atleast_1d(np.asarray(jd_tdb, dtype=float)),
                                 np.atleast_1d(np.asarray(jd_tdb2, dtype=float)))[0]
        return np.zeros((jd.size, 6))
    return barycentric_state(body, jd_tdb, jd_tdb2) - barycentric_state(origin, jd_tdb, jd_tdb2)


def position_km(body: str, center: str, jd_tdb: float | np.ndarray,
                jd_tdb2: float | np.ndarray = 0.0) -> np.ndarray:
    """Return the position (N, 3), km, of ``body`` relative to ``center``.

    The TDB date is ``jd_tdb + jd_tdb2`` (days), split so that a whole date plus a small
    offset keeps sub-microsecond resolution (one float JD resolves only ~40 us, i.e. a metre
    of the Earth's heliocentric motion).
    """
    jd, jd2 = np.broadcast_arrays(np.atleast_1d(np.asarray(jd_tdb, dtype=float)),
                                  np.atleast_1d(np.asarray(jd_tdb2, dtype=float)))
    check_coverage(jd, jd2)
    if body == "moon" and center == "earth":  # avoid the barycentric round trip
        kernel = _kernel()
        return (kernel[3, 301].compute(jd, jd2) - kernel[3, 399].compute(jd, jd2)).T
    return _barycentric_km(body, jd, jd2) - _barycentric_km(center, jd, jd2)


def chebyshev_table(bodies: tuple[str, ...], center: str, epoch_jd_utc: float, t_start_s: float,
                    t_end_s: float, segment_s: float = 43200.0, n_coef: int = 14,
                    scales: TimeScales | None = None, origin_s: float | None = None
                    ) -> ChebyshevTable:
    """Fit piecewise Chebyshev series to body positions relative to ``center`` (km).

    Covers [min(t_start, t_end), max(...)] seconds from the UTC epoch, in segments of
    ``segment_s`` with ``n_coef`` coefficients per coordinate (:func:`fit_chebyshev`). With
    ``scales`` the ephemeris is read at TDB(t) of those scales; without, at TT (see the
    module docstring). ``origin_s`` puts the segments on a grid (see :func:`fit_chebyshev`).
    With the defaults (12 h, 14 coefficients) the fit reproduces DE421 to
    well under a metre for the Moon (checked in the tests).
    """
    if not bodies:
        return ChebyshevTable.empty()
    if scales is not None and origin_s is not None:
        starts = segment_starts(t_start_s, t_end_s, segment_s, origin_s)
        coeffs = np.concatenate([_tdb_segment(bodies, center, scales.epoch, float(start),
                                              segment_s, n_coef) for start in starts], axis=1)
        return ChebyshevTable(np.ascontiguousarray(coeffs), float(starts[0]), segment_s)
    return fit_chebyshev(_positions(bodies, center, tdb_reader(epoch_jd_utc, scales)),
                         t_start_s, t_end_s, segment_s,
                         n_coef, origin_s)


def _positions(bodies: tuple[str, ...], center: str, tdb) -> Callable[[np.ndarray], np.ndarray]:
    """fn(t) -> (n_bodies, M, 3) km of the bodies at TDB ``tdb(t)``."""

    def positions(t: np.ndarray) -> np.ndarray:
        jd, jd2 = tdb(t)
        return np.stack([position_km(body, center, jd, jd2) for body in bodies])

    return positions


@lru_cache(maxsize=8192)
def _tdb_segment(bodies: tuple[str, ...], center: str, epoch: Epoch, start_s: float,
                 segment_s: float, n_coef: int) -> np.ndarray:
    """One segment's coefficients (n_bodies, 1, 3, n_coef) at TDB of ``epoch``'s scales
    (cached: segments on a common grid are shared by every propagation of a run)."""
    tdb = TimeScales.of(epoch, EopTable.zero()).tdb
    return fit_chebyshev(_positions(bodies, center, tdb), start_s, start_s + segment_s,
                         segment_s, n_coef).coeffs

"""Rotation poles of the Moon, Mars and Venus in the ICRF (EME2000 axes), about which their J2
acts (:data:`tapp.constants.J2_CENTRE`).

IAU WGCCRE 2015 rotation models (Archinal et al. 2018, Celest. Mech. Dyn. Astron. 130:22,
Table 2 for Mars, Table 3 for the Moon; Venus unchanged since the 2009 report), with
T in Julian centuries and d in days of TDB from J2000 (JD 2451545.0 TDB):

.. math::
    \\alpha_0 = a_0 + a_1 T + \\sum_j A_j \\sin(\\phi_j + \\dot\\phi_j T),\\quad
    \\delta_0 = d_0 + d_1 T + \\sum_j D_j \\cos(\\psi_j + \\dot\\psi_j T),\\quad
    \\hat k = (\\cos\\delta_0\\cos\\alpha_0, \\cos\\delta_0\\sin\\alpha_0, \\sin\\delta_0).

- Mars (Kuchynka et al. 2014): a_0 = 317.269202°, a_1 = −0.10927547°/cy, d_0 = 54.432516°,
  d_1 = −0.05827105°/cy, and every periodic term. Leaving out the long-period ones (0.419° in
  α and 1.591° in δ, period 71 000 years) would move the pole by 1.5°; the four others are
  below 2.4e-4°.
- Moon (mean Earth/polar axis frame): a_0 = 269.9949°, a_1 = 0.0031°/cy, d_0 = 66.5392°,
  d_1 = 0.0130°/cy and all the periodic terms in E1 ... E13 (E1, the 18.6-year node, moves α
  by up to 3.88° and δ by 1.54°; the monthly E3, E4, E6 terms by up to 0.07°). The IAU series
  is an approximation of the DE librations (tens of arcsec), and the GRAIL fields are given
  in the principal-axis frame, whose pole lies ~80 arcsec (0.02°) from the mean-Earth one:
  a J2 pole error of that size, not yet validated against a DE-libration frame.
- Venus: α0 = 272.76°, δ0 = 67.16°, constant.

The pole moves with t: the propagator fits :func:`pole_table` beside the ephemeris and the
compiled right-hand side reads k(t) from it (:mod:`tapp.dynamics.equations`); nothing is held
constant over the arc.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tapp.frames.chebyshev import ChebyshevTable, fit_chebyshev

_J2000_JD = 2451545.0
_DAYS_PER_CENTURY = 36525.0
#: Segments and degree of the pole series (those of the ephemeris, so the tables stack).
SEGMENT_s = 43200.0
N_COEF = 14


def _moon_argument(e0_deg: float, rate_deg_day: float) -> tuple[float, float]:
    """An IAU lunar argument E_k = e0 + rate d as (phase °, rate °/century)."""
    return e0_deg, rate_deg_day * _DAYS_PER_CENTURY


# Lunar arguments E1 ... E13 (Archinal et al. 2018, Table 3), d in days.
_E = {k: _moon_argument(*v) for k, v in {
    1: (125.045, -0.0529921), 2: (250.089, -0.1059842), 3: (260.008, 13.0120009),
    4: (176.625, 13.3407154), 6: (311.589, 26.4057084), 7: (134.963, 13.0649930),
    10: (15.134, -0.1589763), 13: (25.053, 12.9590088)}.items()}

#: Body -> (a0 °, a1 °/cy, α terms [(A °, φ °, φ' °/cy)], d0 °, d1 °/cy, δ terms).
POLE_MODELS = {
    "mars": (317.269202, -0.10927547,
             ((0.000068, 198.991226, 19139.4819985), (0.000238, 226.292679, 38280.8511281),
              (0.000052, 249.663391, 57420.7251593), (0.000009, 266.183510, 76560.6367950),
              (0.419057, 79.398797, 0.5042615)),
             54.432516, -0.05827105,
             ((0.000051, 122.433576, 19139.9407476), (0.000141, 43.058401, 38280.8753272),
              (0.000031, 57.663379, 57420.7517205), (0.000005, 79.476401, 76560.6495004),
              (1.591274, 166.325722, 0.5042615))),
    "moon": (269.9949, 0.0031,
             tuple((a, *_E[k]) for a, k in ((-3.8787, 1), (-0.1204, 2), (0.0700, 3),
                                            (-0.0172, 4), (0.0072, 6), (-0.0052, 10),
                                            (0.0043, 13))),
             66.5392, 0.0130,
             tuple((a, *_E[k]) for a, k in ((1.5419, 1), (0.0239, 2), (-0.0278, 3),
                                            (0.0068, 4), (-0.0029, 6), (0.0009, 7),
                                            (0.0008, 10), (-0.0009, 13)))),
    "venus": (272.76, 0.0, (), 67.16, 0.0, ()),
}


def pole_ra_dec_deg(body: str, jd_tdb, jd_tdb2=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Return the IAU pole's right ascension and declination (°, ICRF), each (N,), at TDB
    Julian dates ``jd_tdb + jd_tdb2`` (module docstring)."""
    a0, a1, a_terms, d0, d1, d_terms = POLE_MODELS[body]
    jd = np.atleast_1d(np.asarray(jd_tdb, dtype=float))
    t = ((jd - _J2000_JD) + np.asarray(jd_tdb2, dtype=float)) / _DAYS_PER_CENTURY
    alpha = a0 + a1 * t + sum(a * np.sin(np.radians(p + r * t)) for a, p, r in a_terms)
    delta = d0 + d1 * t + sum(d * np.cos(np.radians(p + r * t)) for d, p, r in d_terms)
    return np.broadcast_to(alpha, t.shape), np.broadcast_to(delta, t.shape)


def pole_unit(body: str, jd_tdb, jd_tdb2=0.0) -> np.ndarray:
    """Return the unit rotation pole k (N, 3) of ``body`` in ICRF axes at TDB ``jd_tdb +
    jd_tdb2`` (Julian dates)."""
    alpha, delta = (np.radians(x) for x in pole_ra_dec_deg(body, jd_tdb, jd_tdb2))
    return np.stack([np.cos(delta) * np.cos(alpha), np.cos(delta) * np.sin(alpha),
                     np.sin(delta)], axis=-1)


#: Bodies whose equator has a pole here (:func:`equator_pole`): the Earth and the IAU models.
EQUATOR_POLE_BODIES = ("earth", *POLE_MODELS)


def equator_pole(body: str, jd_tdb, jd_tdb2=0.0) -> np.ndarray:
    """Return the pole (N, 3) of ``body``'s equator in ICRF (EME2000) axes at TDB ``jd_tdb +
    jd_tdb2`` (Julian dates): :func:`pole_unit` for the bodies of :data:`POLE_MODELS`, and for
    the Earth the pole of its mean equator of J2000, the EME2000 z axis (0, 0, 1) at every
    time (the B-plane's "earth_equator"; precession and nutation are not applied here).
    ``body`` must be one of :data:`EQUATOR_POLE_BODIES` (callers check it with its field)."""
    if body == "earth":
        t = np.atleast_1d(np.asarray(jd_tdb, dtype=float)) + np.asarray(jd_tdb2, dtype=float)
        return np.broadcast_to(np.array([0.0, 0.0, 1.0]), t.shape + (3,))
    return pole_unit(body, jd_tdb, jd_tdb2)


def pole_table(body: str, tdb: Callable[[np.ndarray], tuple], t_start_s: float,
               t_end_s: float, origin_s: float | None = None) -> ChebyshevTable:
    """Fit the pole k(t) of ``body`` over [t_start, t_end] s from the epoch: one 3-vector
    series in 12 h segments of 14 coefficients (those of the ephemeris, on the same grid for
    the same ``origin_s``). ``tdb(t)`` returns the TDB Julian date of t (s) as a pair (whole,
    fraction). The fastest term, the Moon's E6 (13.6 days), is fitted to ~1e-16."""
    def fn(t: np.ndarray) -> np.ndarray:
        return pole_unit(body, *tdb(t))[None]

    return fit_chebyshev(fn, t_start_s, t_end_s, SEGMENT_s, N_COEF, origin_s)


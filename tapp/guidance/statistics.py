"""Statistics of a guidance study, from the samples and from the linear covariance.

Both give one :class:`Outcome` so that a report can set them side by side:

- ΔV magnitude of each manoeuvre and of their sum: mean, σ, 50/90/99 % (km/s). Samples: the
  sample mean, σ (ddof = 1) and NumPy's linearly interpolated percentiles. Linear covariance:
  |Δv| of a Gaussian Δv of covariance P (:mod:`tapp.guidance.magnitude`), exact for the first
  manoeuvre and the Gaussian approximation for later ones; the total's mean is the sum of the
  means (exact whatever the correlations); its σ and percentiles need the joint law of the
  magnitudes and are not given.
- The final miss: mean and covariance; the B-plane dispersion ellipse of (B·T, B·R) (1σ
  semi-axes √λ of the 2 x 2 covariance, orientation of the major axis from T toward R, deg,
  in (−90, 90]); the flight-time σ.
- The fraction outside the corridor (:class:`Corridor`): samples counted; linear covariance
  P(qᵀ q > 1) for the B-plane ellipse (Imhof), 2Φ(−limit/σ) for the flight time, and no
  value for "either" when both limits are given (no closed form).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tapp.guidance.linear import LinearCovariance
from tapp.guidance.magnitude import eigenvalues, norm_distribution, quadratic_cdf
from tapp.guidance.model import Problem
from tapp.guidance.montecarlo import Samples

#: Percentiles of the ΔV magnitudes, %.
PERCENTS = (50.0, 90.0, 99.0)
#: Miss components of the B-plane, (T axis, R axis).
BPLANE = ("b_dot_t_km", "b_dot_r_km")
#: Miss components taken as the flight time (the first one the tape has).
FLIGHT_TIME = ("flight_time_s", "ltof_s")


@dataclass(frozen=True, slots=True)
class Corridor:
    """The accepted final miss about the aim point.

    Attributes
    ----------
    semi_axes_km : (a, b) semi-axes of the B-plane ellipse, km (a = b: a circle).
    angle_rad : direction of the a axis from T toward R, rad.
    flight_time_s : largest accepted |Δt_f|, s, or None for no limit.
    """

    semi_axes_km: tuple[float, float]
    angle_rad: float = 0.0
    flight_time_s: float | None = None


@dataclass(frozen=True, slots=True)
class Magnitude:
    """Distribution of a ΔV magnitude, km/s (None: not available from this method).

    Attributes
    ----------
    mean_km_s, sigma_km_s : mean and standard deviation.
    percentiles_km_s : (p, value) pairs, p in percent.
    """

    mean_km_s: float
    sigma_km_s: float | None
    percentiles_km_s: tuple[tuple[float, float], ...] | None


@dataclass(frozen=True, slots=True, eq=False)
class ManoeuvreStats:
    """One manoeuvre: recycle number, time, Δv mean (3,) and covariance (3, 3) in km/s and
    km²/s² (the tape's inertial frame), and its magnitude."""

    number: int
    t_s: float
    dv_mean_km_s: np.ndarray
    dv_cov: np.ndarray
    magnitude: Magnitude


@dataclass(frozen=True, slots=True)
class Ellipse:
    """1σ B-plane dispersion ellipse: semi-axes, km; major-axis angle from T toward R, deg."""

    semi_major_km: float
    semi_minor_km: float
    angle_deg: float


@dataclass(frozen=True, slots=True)
class Outside:
    """Fraction of the outcomes outside the corridor (None: not available or no limit)."""

    bplane: float | None
    flight_time: float | None
    either: float | None


@dataclass(frozen=True, slots=True, eq=False)
class Outcome:
    """The statistics of one method ("Monte Carlo" or "linear covariance").

    Attributes
    ----------
    method : which method.
    manoeuvres : per manoeuvre, in time order.
    total : the sum of the manoeuvres' ΔV magnitudes.
    miss_mean : (n_m,) mean final miss, miss units.
    miss_cov : (n_m, n_m) its covariance.
    ellipse : the B-plane ellipse (None: the tape has no B·T, B·R).
    flight_time_sigma_s : σ of the flight time (None: the tape has none).
    outside : corridor fractions (None: no corridor).
    """

    method: str
    manoeuvres: tuple[ManoeuvreStats, ...]
    total: Magnitude
    miss_mean: np.ndarray
    miss_cov: np.ndarray
    ellipse: Ellipse | None
    flight_time_sigma_s: float | None
    outside: Outside | None


def bplane_rows(miss_name: tuple[str, ...]) -> list[int] | None:
    """Positions of (B·T, B·R) in the miss vector, or None."""
    return [miss_name.index(n) for n in BPLANE] if set(BPLANE) <= set(miss_name) else None


def flight_time_row(miss_name: tuple[str, ...]) -> int | None:
    """Position of the flight time in the miss vector, or None."""
    return next((miss_name.index(n) for n in FLIGHT_TIME if n in miss_name), None)


def ellipse(cov: np.ndarray) -> Ellipse:
    """The 1σ ellipse of a 2 x 2 (T, R) covariance (module docstring)."""
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    angle = math.degrees(math.atan2(v[1, 1], v[0, 1]))
    if angle <= -90.0:
        angle += 180.0
    elif angle > 90.0:
        angle -= 180.0
    return Ellipse(math.sqrt(max(w[1], 0.0)), math.sqrt(max(w[0], 0.0)), angle)


def _corridor_frame(corridor: Corridor) -> np.ndarray:
    """W (2, 2): (T, R) -> (u/a, v/b), outside when |W x| > 1."""
    c, s = math.cos(corridor.angle_rad), math.sin(corridor.angle_rad)
    a, b = corridor.semi_axes_km
    return np.array([[c / a, s / a], [-s / b, c / b]])


def outside_masks(miss_name: tuple[str, ...], miss: np.ndarray, corridor: Corridor
                  ) -> tuple[np.ndarray, np.ndarray | None]:
    """Which samples of the final miss (n, n_m) fall outside the corridor: (n,) booleans
    for the B-plane ellipse, and for the flight-time limit (None: no limit)."""
    q = np.einsum("ij,sj->si", _corridor_frame(corridor), miss[:, bplane_rows(miss_name)])
    out_b = np.einsum("si,si->s", q, q) > 1.0
    if corridor.flight_time_s is None:
        return out_b, None
    return out_b, np.abs(miss[:, flight_time_row(miss_name)]) > corridor.flight_time_s


def _miss_stats(miss_name: tuple[str, ...], cov: np.ndarray
                ) -> tuple[Ellipse | None, float | None]:
    bp, ft = bplane_rows(miss_name), flight_time_row(miss_name)
    shape = None if bp is None else ellipse(cov[np.ix_(bp, bp)])
    return shape, None if ft is None else math.sqrt(max(cov[ft, ft], 0.0))


def sample_outcome(problem: Problem, samples: Samples, corridor: Corridor | None) -> Outcome:
    """Statistics of the Monte Carlo samples (module docstring)."""
    dv = samples.dv_km_s
    mags = samples.dv_magnitude_km_s

    def magnitude(x: np.ndarray) -> Magnitude:
        pct = np.percentile(x, PERCENTS)
        return Magnitude(float(np.mean(x)), float(np.std(x, ddof=1)),
                         tuple((p, float(v)) for p, v in zip(PERCENTS, pct, strict=True)))

    mans = tuple(ManoeuvreStats(s.number, s.t_s, dv[:, i].mean(axis=0),
                                np.cov(dv[:, i], rowvar=False), magnitude(mags[:, i]))
                 for i, s in enumerate(problem.manoeuvres))
    miss = samples.miss
    cov = np.atleast_2d(np.cov(miss, rowvar=False))
    shape, sigma_t = _miss_stats(problem.miss_name, cov)
    outside = None
    if corridor is not None:
        out_b, out_t = outside_masks(problem.miss_name, miss, corridor)
        outside = Outside(float(np.mean(out_b)), None if out_t is None else float(np.mean(out_t)),
                          float(np.mean(out_b if out_t is None else out_b | out_t)))
    return Outcome("Monte Carlo", mans, magnitude(mags.sum(axis=1)), miss.mean(axis=0), cov,
                   shape, sigma_t, outside)


def linear_outcome(problem: Problem, lin: LinearCovariance, corridor: Corridor | None
                   ) -> Outcome:
    """Statistics from the linear covariance (module docstring)."""
    mans = []
    for s, P in zip(problem.manoeuvres, lin.dv_cov, strict=True):
        dist = norm_distribution(P, PERCENTS)
        mans.append(ManoeuvreStats(s.number, s.t_s, np.zeros(3), P,
                                   Magnitude(dist.mean, dist.sigma, dist.percentiles)))
    total = Magnitude(sum(m.magnitude.mean_km_s for m in mans), None, None)
    cov = lin.miss_cov
    shape, sigma_t = _miss_stats(problem.miss_name, cov)
    outside = None
    if corridor is not None:
        bp = bplane_rows(problem.miss_name)
        W = _corridor_frame(corridor)
        out_b = 1.0 - quadratic_cdf(1.0, eigenvalues(W @ cov[np.ix_(bp, bp)] @ W.T))
        out_t = None
        if corridor.flight_time_s is not None:
            out_t = 0.0 if sigma_t == 0 else math.erfc(
                corridor.flight_time_s / (sigma_t * math.sqrt(2.0)))
        outside = Outside(out_b, out_t, out_b if out_t is None else None)
    return Outcome("linear covariance", tuple(mans), total, np.zeros(cov.shape[0]), cov,
                   shape, sigma_t, outside)


__all__ = ["BPLANE", "FLIGHT_TIME", "PERCENTS", "Corridor", "Ellipse", "Magnitude",
           "ManoeuvreStats", "Outcome", "Outside", "bplane_rows", "ellipse",
           "flight_time_row", "linear_outcome", "outside_masks", "sample_outcome"]

"""Which linear-covariance statistics the Monte Carlo of the same run contradicts.

The linear covariance (:mod:`tapp.guidance.linear`) gives some statistics exactly and
approximates the others:

- exact (:data:`EXACT`): the means (zero) and covariances of each Δv and of the final miss,
  and what follows from them alone, the σ of each miss component, the B-plane ellipse and
  the flight-time σ. The samples go through the same linear maps, so a Monte Carlo can
  differ from these by its sampling error only: they are not set against a run
  (``tests/tapp/guidance/test_monte_carlo.py`` sets them against 50,000 samples), and the
  linear value, free of sampling error, is the one to use. (A z test of them would not
  hold its false-alarm rate anyway: on the deep-space study the square of the final
  flight-time miss has a skewness of 49, and the z-scores of these second moments, in 500
  runs of 10,000 samples, fell beyond |z| = 4 ten times as often as the normal law says.)
- approximate: the |Δv| mean, σ and percentiles of each manoeuvre take Δv as Gaussian, true
  of the first manoeuvre only (the execution errors scale with |Δv|, so every later Δv is a
  scale mixture of Gaussians, with heavier tails than the Gaussian of its covariance); the
  total's mean is the sum of the means; the corridor fractions take the final miss as
  Gaussian (it is a scale mixture too). Each of these is set against the samples of the run
  and marked ``contradicted`` when they contradict it beyond their sampling error: the
  Monte Carlo's value, with its sampling error, is then the one to use.

Sampling errors and tests (N samples; two-sided):

- a mean (of |Δv| per manoeuvre, of their sum): z = (x̄ − μ)/(s/√N), s the sample σ;
- a σ (of |Δv| per manoeuvre) through its variance: the sample variance m₂ against σ², with
  the standard error √((m₄ − m₂²)/N), m₄ the sample fourth central moment; the σ's own
  standard error, shown, is that over 2√m₂;
- a percentile r_p: the number of samples ≤ r_p is Binomial(N, p) when r_p is the
  p-quantile of a continuous law, so the order statistics x_(l), x_(u) with
  l = F⁻¹(α/2) and u = F⁻¹(1 − α/2) + 1 (F the Binomial(N, p) CDF) bracket the true
  percentile with probability at least 1 − α, whatever the law; the linear r_p is
  contradicted outside [x_(l), x_(u)];
- a fraction outside the corridor: the count k outside is Binomial(N, q); the linear q is
  contradicted outside the exact (Clopper-Pearson) interval of k at confidence 1 − α.

The level: a run tests K statistics (5 per manoeuvre, the total's mean and one or two
corridor fractions: K = 18 for three manoeuvres and a corridor with a flight-time limit),
each at α = :data:`FAMILY_FALSE_ALARM` / K (Bonferroni), so that the probability that a run
marks any correct statistic is at most :data:`FAMILY_FALSE_ALARM` = 1e-3, whatever the
dependence between the statistics (|z| > 4.03 for K = 18). The percentile and fraction
tests are exact at any N. The z tests rest on the central limit theorem and are made only
with at least :data:`MIN_MOMENT_SAMPLES` samples; their null case is a Gaussian Δv, whose
|Δv| has light tails: there (the deep-space study with fixed execution errors only), the
z-scores of 1,000 runs of 10,000 samples fell beyond |z| = 2.5, 3, 3.5 and 4 at the rates
1.4e-2, 3.3e-3, 2.9e-4 and 0 (normal: 1.2e-2, 2.7e-3, 4.7e-4 and 6.3e-5), and no run marked
any statistic.

What the run cannot resolve is not marked: a z test with fewer than
:data:`MIN_MOMENT_SAMPLES` samples or no spread in them; a percentile interval is open at an
end with no order statistic (l < 1 or u > N) and says nothing beyond it (with both ends
open the percentile is not tested); the Clopper-Pearson interval of a count of 0 reaches
1 − (α/2)^(1/N) ≈ ln(2/α)/N (≈ 10/N), so a linear fraction expecting fewer than one sample
outside the corridor is never contradicted by a run that sees none.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import stats

from tapp.guidance.montecarlo import Samples
from tapp.guidance.statistics import Corridor, Outcome, outside_masks

#: Largest probability that a run marks any correct linear statistic (Bonferroni).
FAMILY_FALSE_ALARM = 1e-3
#: Fewest samples for a z test (the |Δv| means and σ's). Measured on Gaussian Δv's (the
#: deep-space study with fixed execution errors only): with 1,000 samples, 3.6e-4 of the
#: z-scores of 2,000 runs lay beyond |z| = 4 (normal: 6.3e-5) and a z test marked 5 runs
#: (Bonferroni allows 2); with 10,000, 1,000 runs gave the normal rates (module docstring)
#: and none was marked.
MIN_MOMENT_SAMPLES = 10_000
#: The outcome fields the linear covariance gives exactly, not set against a run.
EXACT = ("manoeuvres[].dv_mean_km_s", "manoeuvres[].dv_cov_km2_s2", "miss_mean", "miss_cov",
         "bplane_ellipse", "flight_time_sigma_s")

#: The place of a statistic in the linear outcome: names and indices, as in the JSON report
#: (``("manoeuvres", 1, "magnitude", "percentiles_km_s", "99")``).
Key = tuple[str | int, ...]


@dataclass(frozen=True, slots=True)
class Check:
    """One linear statistic against the Monte Carlo (module docstring).

    Attributes
    ----------
    key : its place in the linear outcome.
    label : what it is, for a reader.
    unit : the unit of ``linear``, ``monte_carlo``, ``sampling_error`` and ``interval``
        ("" for a fraction).
    test : "z", "order statistics" or "Clopper-Pearson".
    linear : the linear value.
    monte_carlo : the Monte Carlo's value of the same statistic.
    sampling_error : standard error of ``monte_carlo`` (z tests), else None.
    z : the z-score of the test (z tests), else None.
    interval : (low, high) of the Monte Carlo at confidence 1 − α (order statistics,
        Clopper-Pearson; None at an open end), else None.
    resolved : whether the run can test the statistic.
    contradicted : the run contradicts the linear value.
    """

    key: Key
    label: str
    unit: str
    test: str
    linear: float
    monte_carlo: float
    sampling_error: float | None
    z: float | None
    interval: tuple[float | None, float | None] | None
    resolved: bool
    contradicted: bool


@dataclass(frozen=True, slots=True)
class Level:
    """The level of each test of a run: α, the critical |z|, and the samples."""

    alpha: float
    z_limit: float
    n: int


@dataclass(frozen=True, slots=True, eq=False)
class Agreement:
    """The linear statistics of a study against its Monte Carlo (module docstring).

    Attributes
    ----------
    family_false_alarm : the bound on the probability of marking any correct statistic.
    level : each test's α and critical |z|, and the samples N.
    checks : one per linear statistic, in the order of the report.
    """

    family_false_alarm: float
    level: Level
    checks: tuple[Check, ...]

    def check(self, key: Key) -> Check | None:
        """The check of the statistic at ``key``, or None (no such linear statistic)."""
        return next((c for c in self.checks if c.key == key), None)

    @property
    def contradicted(self) -> tuple[Check, ...]:
        """The checks whose linear value the Monte Carlo contradicts."""
        return tuple(c for c in self.checks if c.contradicted)

    @property
    def unresolved(self) -> tuple[Check, ...]:
        """The checks the run cannot test."""
        return tuple(c for c in self.checks if not c.resolved)


#: A check waiting for its level (the level depends on how many there are).
Pending = Callable[[Level], Check]


def order_interval(x: np.ndarray, p: float, alpha: float) -> tuple[float | None, float | None]:
    """Return (x_(l), x_(u)), the order statistics of the samples ``x`` that bracket their
    law's p-quantile (0 < p < 1) with probability >= 1 − α; None at an end with no order
    statistic (module docstring).

    >>> order_interval(np.arange(1.0, 101.0), 0.5, 0.05)  # the median of 100: ranks 40, 61
    (40.0, 61.0)
    """
    n = x.size
    low = int(stats.binom.ppf(alpha / 2, n, p))
    high = int(stats.binom.ppf(1 - alpha / 2, n, p)) + 1
    ranks = [r - 1 for r in (low, high) if 1 <= r <= n]
    if not ranks:
        return None, None
    part = np.partition(x, ranks)
    return (float(part[low - 1]) if low >= 1 else None,
            float(part[high - 1]) if high <= n else None)


def clopper_pearson(k: int, n: int, alpha: float) -> tuple[float, float]:
    """Return the exact two-sided interval of a binomial fraction, k of n, at confidence
    1 − α (Clopper and Pearson, Biometrika 26 (1934) 404-413).

    >>> [round(v, 4) for v in clopper_pearson(0, 100, 0.05)]  # 1 − 0.025^(1/100)
    [0.0, 0.0362]
    """
    low = 0.0 if k == 0 else float(stats.beta.ppf(alpha / 2, k, n - k + 1))
    high = 1.0 if k == n else float(stats.beta.isf(alpha / 2, k + 1, n - k))
    return low, high


def _z_check(key: Key, label: str, unit: str, linear: float, monte_carlo: float,
             sampling_error: float, z: float, spread: float, level: Level) -> Check:
    """A z test: resolved with enough samples and a spread in them (module docstring)."""
    resolved = level.n >= MIN_MOMENT_SAMPLES and spread > 0
    return Check(key, label, unit, "z", linear, monte_carlo, sampling_error,
                 z if resolved else None, None, resolved,
                 resolved and abs(z) > level.z_limit)


def _mean(key: Key, label: str, unit: str, x: np.ndarray, linear: float) -> Pending:
    """The linear mean of x (n,) against the sample mean."""

    def run(level: Level) -> Check:
        mean = float(np.mean(x))
        se = float(np.std(x, ddof=1)) / math.sqrt(x.size)
        return _z_check(key, label, unit, linear, mean, se,
                        (mean - linear) / se if se > 0 else 0.0, se, level)

    return run


def _sigma(key: Key, label: str, unit: str, x: np.ndarray, linear: float) -> Pending:
    """The linear σ of x (n,) against the sample σ, through the variance."""

    def run(level: Level) -> Check:
        d = x - np.mean(x)
        m2 = float(np.mean(d * d))
        se_m2 = math.sqrt(max(float(np.mean(d ** 4)) - m2 * m2, 0.0) / x.size)
        s = math.sqrt(m2)
        return _z_check(key, label, unit, linear, s, se_m2 / (2 * s) if s > 0 else 0.0,
                        (m2 - linear * linear) / se_m2 if se_m2 > 0 else 0.0, se_m2, level)

    return run


def _percentile(key: Key, label: str, unit: str, x: np.ndarray, p: float, linear: float,
                monte_carlo: float) -> Pending:
    """The linear p-quantile of x (n,) against the order-statistic interval."""

    def run(level: Level) -> Check:
        low, high = order_interval(x, p, level.alpha)
        contradicted = (low is not None and linear < low) or (high is not None
                                                              and linear > high)
        return Check(key, label, unit, "order statistics", linear, monte_carlo, None, None,
                     (low, high), low is not None or high is not None, contradicted)

    return run


def _fraction(key: Key, label: str, outside: np.ndarray, linear: float) -> Pending:
    """The linear fraction of samples for which ``outside`` (n,) holds, against the
    Clopper-Pearson interval of their count."""

    def run(level: Level) -> Check:
        k = int(np.count_nonzero(outside))
        low, high = clopper_pearson(k, outside.size, level.alpha)
        return Check(key, label, "", "Clopper-Pearson", linear, k / outside.size, None, None,
                     (low, high), True, not low <= linear <= high)

    return run


def _manoeuvres(samples: Samples, mc: Outcome, linear: Outcome) -> list[Pending]:
    """The |Δv| mean, σ and percentiles of each manoeuvre and the total's mean."""
    mags = samples.dv_magnitude_km_s
    out: list[Pending] = []
    for i, (m, lin) in enumerate(zip(mc.manoeuvres, linear.manoeuvres, strict=True)):
        where = f"recycle {m.number}"
        key = ("manoeuvres", i, "magnitude")
        out.append(_mean((*key, "mean_km_s"), f"{where}: |Δv| mean", "km/s", mags[:, i],
                         lin.magnitude.mean_km_s))
        out.append(_sigma((*key, "sigma_km_s"), f"{where}: |Δv| σ", "km/s", mags[:, i],
                          lin.magnitude.sigma_km_s))
        out += [_percentile((*key, "percentiles_km_s", f"{p:g}"), f"{where}: |Δv| {p:g} %",
                            "km/s", mags[:, i], p / 100.0, r, mc_r)
                for (p, r), (_, mc_r) in zip(lin.magnitude.percentiles_km_s,
                                             m.magnitude.percentiles_km_s, strict=True)]
    out.append(_mean(("total", "mean_km_s"), "total |Δv| mean", "km/s", mags.sum(axis=1),
                     linear.total.mean_km_s))
    return out


def _corridor(miss_name: tuple[str, ...], samples: Samples, corridor: Corridor | None,
              linear: Outcome) -> list[Pending]:
    """The fractions outside the B-plane corridor and the flight-time limit."""
    if corridor is None:
        return []
    out_b, out_t = outside_masks(miss_name, samples.miss, corridor)
    out = [_fraction(("outside_corridor", "bplane"), "outside the B-plane corridor", out_b,
                     linear.outside.bplane)]
    if out_t is not None:
        out.append(_fraction(("outside_corridor", "flight_time"),
                             "outside the flight-time limit", out_t,
                             linear.outside.flight_time))
    return out


def compare(miss_name: tuple[str, ...], samples: Samples, corridor: Corridor | None,
            mc: Outcome, linear: Outcome, family_false_alarm: float = FAMILY_FALSE_ALARM
            ) -> Agreement:
    """Set the approximate linear statistics of a study against its Monte Carlo (module
    docstring).

    Parameters
    ----------
    miss_name : the final miss components.
    samples : the Monte Carlo samples.
    corridor : the corridor, or None.
    mc, linear : the statistics of the samples and of the linear covariance
        (:mod:`tapp.guidance.statistics`).
    family_false_alarm : the bound on the probability of marking a correct statistic.
    """
    pending = [*_manoeuvres(samples, mc, linear),
               *_corridor(miss_name, samples, corridor, linear)]
    alpha = family_false_alarm / len(pending)
    level = Level(alpha, float(stats.norm.isf(alpha / 2)), samples.n)
    return Agreement(family_false_alarm, level, tuple(run(level) for run in pending))


__all__ = ["EXACT", "FAMILY_FALSE_ALARM", "MIN_MOMENT_SAMPLES", "Agreement", "Check", "Key",
           "Level", "clopper_pearson", "compare", "order_interval"]

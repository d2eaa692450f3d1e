"""The linear statistics against the Monte Carlo of the same run (tapp.guidance.agreement).

Statistical levels. A study marks a correct linear statistic with probability at most 1e-3
(the module's Bonferroni family over the run's statistics); the three studies below that
expect no mark (the first manoeuvre of the deep-space study, whose Δv is Gaussian, and the
two Gaussian studies) false-alarm with probability at most 1e-3 each, 3e-3 in all. The seeds
are fixed, so each outcome is reproducible. The marks they expect are far beyond the sampling
error: at 100,000 samples the later manoeuvres' 99 % |Δv| lies 28 % and 40 % below the lower
end of its order-statistic interval, and the linear fraction outside the corridor is 1/60 of
the Clopper-Pearson interval's lower end.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import stats

from iter.execute import Execution
from tapp.guidance.agreement import MIN_MOMENT_SAMPLES, clopper_pearson, compare, order_interval
from tapp.guidance.guidefile import GuideFile, bind
from tapp.guidance.linear import linear_covariance
from tapp.guidance.statistics import BPLANE, ellipse
from tapp.guidance.study import guidance_study
from tapp.io.schema import validate
from tapp.io.tomlfile import read_toml
from tests.tapp.guidance.helpers import SCENARIOS, deep_space_t32

N = 100_000
SERIAL = Execution(serial=True)
SHIPPED = SCENARIOS / "tapp2_deep_space.toml"
P99 = ("percentiles_km_s", "99")


def _study(doc: dict, samples: int = N, seed: int = 1):
    guide = validate(GuideFile, doc, "guide.toml")
    return guidance_study(deep_space_t32(), guide, samples=samples, seed=seed,
                          execution=SERIAL)


@pytest.fixture(scope="module")
def shipped():
    """The shipped guidance file on the test tape."""
    return _study(read_toml(SHIPPED))


def test_the_deep_space_study_marks_the_later_tails_and_the_corridor(shipped):
    a = shipped.agreement
    assert a.level.n == N and not a.unresolved
    for i in (1, 2):  # the linear covariance understates the tail of |Δv|
        c = a.check(("manoeuvres", i, "magnitude", *P99))
        assert c.contradicted and c.linear < c.interval[0], c
    c = a.check(("outside_corridor", "bplane"))
    assert c.contradicted and c.linear < c.interval[0], c
    first = [c for c in a.checks if c.key[:2] == ("manoeuvres", 0)]
    assert len(first) == 5 and not any(c.contradicted for c in first), first
    # no sample beyond 30 s, and the linear fraction expects far fewer than one: the run
    # cannot resolve it, and it is not marked
    t = a.check(("outside_corridor", "flight_time"))
    assert t.monte_carlo == 0 and t.linear * N < 1 and not t.contradicted


def _gaussian_doc(execution: dict) -> dict:
    """The shipped study with Gaussian Δv's (``execution`` without proportional or pointing
    errors) and a corridor that about 5 % of the samples leave (2 σ_major, 2.5 σ_t)."""
    doc = read_toml(SHIPPED)
    doc["execution"] = execution
    del doc["corridor"]
    problem = bind(validate(GuideFile, doc, "guide.toml"), deep_space_t32(), "g").problem
    cov = linear_covariance(problem).miss_cov
    bp = [problem.miss_name.index(n) for n in BPLANE]
    ft = problem.miss_name.index("flight_time_s")
    doc["corridor"] = {"radius_km": 2.0 * ellipse(cov[np.ix_(bp, bp)]).semi_major_km,
                       "flight_time_s": 2.5 * float(np.sqrt(cov[ft, ft]))}
    return doc


@pytest.fixture(scope="module", params=[{}, {"sigma_fixed_mm_s": 1.0}],
            ids=["no execution errors", "fixed execution errors"])
def gaussian(request):
    return _study(_gaussian_doc(request.param), seed=7)


def test_a_gaussian_model_marks_nothing(gaussian):
    a = gaussian.agreement
    assert len(a.checks) == 18 and not a.unresolved
    assert not a.contradicted, a.contradicted
    # the corridor checks had something to test: hundreds of samples outside
    for name in ("bplane", "flight_time"):
        assert a.check(("outside_corridor", name)).monte_carlo * N > 500


def _scaled(outcome, mean: float, p99: float, outside: float):
    """The linear outcome with every |Δv| mean times ``mean``, every 99 % |Δv| times ``p99``
    and the B-plane fraction outside the corridor times ``outside``."""
    mans = tuple(dataclasses.replace(m, magnitude=dataclasses.replace(
        m.magnitude, mean_km_s=m.magnitude.mean_km_s * mean,
        percentiles_km_s=tuple((p, v * p99 if p == 99 else v)
                               for p, v in m.magnitude.percentiles_km_s)))
        for m in outcome.manoeuvres)
    return dataclasses.replace(outcome, manoeuvres=mans, outside=dataclasses.replace(
        outcome.outside, bplane=outcome.outside.bplane * outside))


def test_the_gaussian_checks_see_small_errors(gaussian):
    """The same samples against linear |Δv| means 2 % off, 99 % |Δv| 5 % off and a fraction
    outside the corridor 15 % off: every one is marked, so the no-mark above is not for want
    of resolution (at 100,000 samples the 99 % intervals reach 2 % above the value, the
    fraction's 6 %, and a 2 % error in a mean is z > 8)."""
    r = gaussian
    a = compare(r.miss_name, r.samples, r.corridor, r.monte_carlo,
                _scaled(r.linear, 1.02, 1.05, 1.15))
    marked = {c.key for c in a.contradicted}
    assert marked == {*(("manoeuvres", i, "magnitude", *name) for i in range(3)
                        for name in (("mean_km_s",), P99)), ("outside_corridor", "bplane")}


def test_a_small_run_does_not_test_what_it_cannot_resolve(shipped):
    """Below MIN_MOMENT_SAMPLES no z test is made: the later means and σ's, contradicted at
    100,000 samples, are then not tested (and not marked) rather than passed."""
    r = _study(read_toml(SHIPPED), samples=MIN_MOMENT_SAMPLES - 1000)
    z_tests = [c for c in r.agreement.checks if c.test == "z"]
    assert len(z_tests) == 7
    assert all(not c.resolved and c.z is None and not c.contradicted for c in z_tests)
    assert shipped.agreement.check(("manoeuvres", 1, "magnitude", "mean_km_s")).contradicted


@pytest.mark.parametrize(("k", "n"), [(0, 50), (1, 50), (25, 50), (50, 50), (36, 100_000)])
def test_clopper_pearson_is_the_exact_binomial_interval(k, n):
    alpha = 5.6e-5
    want = stats.binomtest(k, n).proportion_ci(1 - alpha, method="exact")
    np.testing.assert_allclose(clopper_pearson(k, n, alpha), (want.low, want.high),
                               rtol=1e-7, atol=1e-15)  # SciPy: root finding, ~1e-8


def test_a_count_of_zero_contradicts_only_a_fraction_that_expects_many():
    """With none of N outside, the upper end is 1 − (α/2)^(1/N) ≈ 10.5/N at α = 5.6e-5: a
    linear fraction expecting 1 sample is not contradicted, one expecting 11 is."""
    n, alpha = 100_000, 5.6e-5
    low, high = clopper_pearson(0, n, alpha)
    assert low == 0.0 and high == pytest.approx(1 - (alpha / 2) ** (1 / n), rel=1e-9)
    assert 1 / n < high < 11 / n


def test_the_order_interval_brackets_the_quantile_at_its_confidence():
    """20,000 sets of 200 Exp(1) samples: the interval of the 90 % misses the true quantile
    at the exact binomial rate P(B < l) + P(B >= u) (<= α by construction); the count of
    misses within 4.5 σ of it (false alarm 7e-6)."""
    n, p, alpha, runs = 200, 0.9, 0.05, 20_000
    rng = np.random.default_rng(11)
    true = -np.log(1 - p)
    misses = 0
    for x in rng.exponential(size=(runs, n)):
        low, high = order_interval(x, p, alpha)
        misses += not low <= true <= high
    b = stats.binom(n, p)
    lo_rank, hi_rank = int(b.ppf(alpha / 2)), int(b.ppf(1 - alpha / 2)) + 1
    rate = b.cdf(lo_rank - 1) + b.sf(hi_rank - 1)
    assert rate <= alpha
    assert abs(misses - runs * rate) < 4.5 * np.sqrt(runs * rate * (1 - rate)), (misses, rate)


def test_an_order_interval_without_order_statistics_is_open():
    """Ten samples cannot bracket their median at confidence 1 − 1e-3 (P(B = 0) = 1/1024 >
    α/2): both ends open; 200 samples bound the 99 % from below only."""
    assert order_interval(np.arange(10.0), 0.5, 1e-3) == (None, None)
    low, high = order_interval(np.arange(200.0), 0.99, 5.6e-5)
    assert low is not None and high is None

"""The Monte Carlo drawn in the space of the outcomes (tapp.guidance.montecarlo) against the
model drawn in the whole state, written here on its own: d₀, every step's tracking noise and
the execution errors drawn per sample, the state stepped through every map.

Both on the test tape (tests.tapp.guidance.helpers: n_o = 24, three recycles), with the
shipped guidance file and either navigation after a manoeuvre.

Deterministic: the maps F, C of :func:`~tapp.guidance.montecarlo.outcome_maps` against the
whole-state model's own linear response, A = ∂y/∂g (g the normals of d₀ and of every Σ_k) and
C = ∂y/∂ε, computed here by stepping unit inputs through the model: F Fᵀ = A Aᵀ and the C's
agree; and the second moments F Fᵀ + C diag(E[ε_jε_jᵀ]) Cᵀ are those of the linear covariance.

Statistical (:data:`N` samples of each sampler, independent streams): the two laws must agree,
so every statistic below must agree to the two runs' sampling error. Per navigation, K = 29
statistics: the mean and the 50/90/99 % of |Δv| of each manoeuvre, of the total |Δv| and of
each |miss component|, and the fraction outside the corridor. Each is tested at
α = :data:`FAMILY_FALSE_ALARM` / K (Bonferroni): a mean by the two-sample z-score
(x̄₁ − x̄₂)/√(s₁²/N + s₂²/N) (central limit theorem, N = 200,000); a percentile by the two
samples' order-statistic intervals (:func:`tapp.guidance.agreement.order_interval`), each at
confidence 1 − α/2, which overlap whenever both hold the true percentile, so they are disjoint
with probability at most α whatever the law; a fraction by the two counts' Clopper-Pearson
intervals the same way. A correct reduction is then flagged with probability at most 1e-3 per
navigation (2e-3 in all); the seeds are fixed, so each outcome is reproducible (measured: no
statistic flagged, largest |z| 2.1 with the 21-normal sampler (1.6 with the 33-normal one it
replaced, and 1.0 between the two); against the whole-state sampler TAPP II had before the
reduction, commit d1ec057, the same on this tape and on the shipped 69-parameter one, largest
|z| 2.2). The same test flags a whole-state model whose proportional execution error is 5 %
larger (σ_p = 0.021 instead of 0.02):
:func:`test_the_comparison_sees_a_five_percent_execution_error`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy import stats

from iter.execute import Execution
from tapp.guidance.agreement import clopper_pearson, order_interval
from tapp.guidance.execution import NORMALS_PER_MANOEUVRE, error_second_moment, sample_errors
from tapp.guidance.guidefile import GuideFile, bind
from tapp.guidance.linear import linear_covariance
from tapp.guidance.model import Problem
from tapp.guidance.montecarlo import outcome_maps
from tapp.guidance.shards import run_shards
from tapp.guidance.statistics import PERCENTS, Corridor, outside_masks
from tapp.io.schema import validate
from tapp.io.tomlfile import read_toml
from tests.tapp.guidance.helpers import SCENARIOS, deep_space_t32

N = 200_000
#: Largest probability that the comparison flags a correct reduction, per navigation.
FAMILY_FALSE_ALARM = 1e-3
#: F Fᵀ against A Aᵀ, each entry over √(A Aᵀ_ii A Aᵀ_jj): the Gaussian part of Δv₂ and Δv₃ is
#: what the nulling leaves, 1e-4 of Δv₁'s, so both round terms 1e4 times larger, in a
#: different order (measured 1.9e-12 and 6.6e-12, at Cov(Δv₁, Δv₂)).
FACTOR_TOL = 1e-10
#: C against the whole-state response to unit execution errors, over each row's largest
#: entry; rows without one (Δv₁) exactly zero in both (measured 0: the same products).
ERROR_MAP_TOL = 1e-12
#: The second moments against the linear covariance, each entry over √(P_ii P_jj): two
#: square-root propagations of the same maps (measured 1.2e-13, Cov(Δv₃) with the tape's
#: navigation; 4.0e-14 the miss).
MOMENT_TOL = 1e-10
SERIAL = Execution(serial=True)

ErrorsOf = Callable[[int, np.ndarray], np.ndarray]


def _problem(navigation: str, sigma_proportional: float | None = None
             ) -> tuple[Problem, Corridor]:
    """The shipped guidance file on the test tape (three manoeuvres, three targets, the
    corridor) with the navigation given; its problem and corridor."""
    doc = read_toml(SCENARIOS / "tapp2_deep_space.toml")
    doc["navigation"]["after_manoeuvre"] = navigation
    if sigma_proportional is not None:
        doc["execution"]["sigma_proportional"] = sigma_proportional
    study = bind(validate(GuideFile, doc, "guide.toml"), deep_space_t32(), "guide.toml")
    return study.problem, study.corridor


@pytest.fixture(scope="module", params=["tape", "inflate"])
def navigation(request) -> str:
    return request.param


def n_gauss(problem: Problem) -> int:
    """Normals of the whole-state model's Gaussian part: d₀ and each step's Σ_k."""
    return problem.n_o + sum(s.sigma_factor.shape[1] for s in problem.steps)


def whole_state(problem: Problem, g: np.ndarray, errors_of: ErrorsOf) -> np.ndarray:
    """Outcomes y = [Δv₁; …; Δv_M; m] (n, n_y) of the model of tapp.guidance, stepped in the
    whole state [d; e] for n samples of the normals g (n, :func:`n_gauss`), the execution error
    of manoeuvre j being ``errors_of(j, Δv_j)`` (n, 3)."""
    n_o, vel = problem.n_o, list(problem.velocity)
    d = g[:, :n_o] @ problem.lambda0_factor.T
    e = -d
    used = n_o
    dvs = []
    for step in problem.steps:
        width = step.sigma_factor.shape[1]
        d = d @ step.transition.T
        e = e @ step.LT.T + g[:, used:used + width] @ step.sigma_factor.T
        used += width
        if step.correction is None:
            continue
        dv = -(d + e) @ (step.correction.gain @ step.correction.B_target).T
        eps = errors_of(len(dvs), dv)
        d[:, vel] += dv + eps
        e[:, vel] -= eps
        dvs.append(dv)
    return np.hstack([*dvs, d @ problem.B_final.T])


def whole_state_samples(problem: Problem, n: int, seed: int, chunk: int = 20_000
                        ) -> tuple[np.ndarray, np.ndarray]:
    """n samples of the whole-state model: (Δv (n, M, 3), miss (n, n_m))."""
    rng = np.random.default_rng(seed)
    n_man = len(problem.manoeuvres)
    parts = []
    for lo in range(0, n, chunk):
        rows = min(chunk, n - lo)
        g = rng.standard_normal((rows, n_gauss(problem)))
        nu = rng.standard_normal((rows, n_man, NORMALS_PER_MANOEUVRE))
        parts.append(whole_state(problem, g, lambda j, dv, nu=nu: sample_errors(
            dv, nu[:, j], problem.errors)))
    y = np.vstack(parts)
    return y[:, :3 * n_man].reshape(n, n_man, 3), y[:, 3 * n_man:]


def _scaled(x: np.ndarray, ref: np.ndarray) -> float:
    """max |x − ref| over √(ref_ii ref_jj)."""
    s = np.sqrt(np.diag(ref))
    return float(np.max(np.abs(x - ref) / np.outer(s, s)))


def test_the_maps_are_the_whole_state_models_linear_response(navigation):
    problem, _ = _problem(navigation)
    maps = outcome_maps(problem)
    n_man = len(problem.manoeuvres)
    A = whole_state(problem, np.eye(n_gauss(problem)), lambda j, dv: np.zeros_like(dv)).T
    unit = np.eye(3 * n_man)
    C = whole_state(problem, np.zeros((3 * n_man, n_gauss(problem))),
                    lambda j, dv: unit[:, 3 * j:3 * j + 3]).T
    F = maps.gauss_factor
    assert np.array_equal(F, np.tril(F))
    assert _scaled(F @ F.T, A @ A.T) < FACTOR_TOL
    top = np.abs(C).max(axis=1, keepdims=True)
    assert np.max(np.abs(maps.error_map - C) / np.where(top > 0, top, 1.0)) < ERROR_MAP_TOL
    for j in range(n_man):  # ε_j acts on what follows manoeuvre j only
        assert not np.any(maps.error_map[:3 * (j + 1), 3 * j:3 * j + 3])


def test_the_maps_give_the_linear_covariance(navigation):
    """Cov(y) = F Fᵀ + Σ_j C_j E[ε_jε_jᵀ] C_jᵀ (tapp.guidance.montecarlo), E[ε_jε_jᵀ] from
    the linear covariance's Cov(Δv_j)."""
    problem, _ = _problem(navigation)
    maps, lin = outcome_maps(problem), linear_covariance(problem)
    cov = maps.gauss_factor @ maps.gauss_factor.T
    for j, P in enumerate(lin.dv_cov):
        Cj = maps.error_map[:, 3 * j:3 * j + 3]
        cov += Cj @ error_second_moment(P, problem.errors) @ Cj.T
    for j, P in enumerate(lin.dv_cov):
        assert _scaled(cov[3 * j:3 * j + 3, 3 * j:3 * j + 3], P) < MOMENT_TOL
    n = 3 * len(lin.dv_cov)
    assert _scaled(cov[n:, n:], lin.miss_cov) < MOMENT_TOL


def _statistics(dv: np.ndarray, miss: np.ndarray, names: tuple[str, ...]
                ) -> dict[str, np.ndarray]:
    """The per-sample magnitudes compared: |Δv| of each manoeuvre, their sum, |miss| of each
    component."""
    mags = np.linalg.norm(dv, axis=2)
    out = {f"|dv{j + 1}|": mags[:, j] for j in range(mags.shape[1])}
    out["total |dv|"] = mags.sum(axis=1)
    out.update({f"|{name}|": np.abs(miss[:, i]) for i, name in enumerate(names)})
    return out


def _outside(problem: Problem, corridor: Corridor, miss: np.ndarray) -> np.ndarray:
    """Which samples of the miss fall outside the corridor, either term."""
    out_b, out_t = outside_masks(problem.miss_name, miss, corridor)
    return out_b if out_t is None else out_b | out_t


def _disjoint(a: tuple, b: tuple) -> bool:
    """Two intervals (None: open at that end) that do not meet."""
    return ((a[1] is not None and b[0] is not None and a[1] < b[0])
            or (b[1] is not None and a[0] is not None and b[1] < a[0]))


def flagged(problem: Problem, corridor: Corridor, one: tuple[np.ndarray, np.ndarray],
            two: tuple[np.ndarray, np.ndarray]) -> dict[str, float]:
    """The statistics on which two runs (Δv, miss) of N samples disagree beyond their
    sampling error (module docstring): {name: |z|, or 1 for disjoint intervals}."""
    x1, x2 = _statistics(*one, problem.miss_name), _statistics(*two, problem.miss_name)
    k = len(x1) * (1 + len(PERCENTS)) + 1
    alpha = FAMILY_FALSE_ALARM / k
    z_limit = stats.norm.isf(alpha / 2)
    out: dict[str, float] = {}
    for name in x1:
        a, b = x1[name], x2[name]
        z = (a.mean() - b.mean()) / np.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)
        if abs(z) > z_limit:
            out[f"{name} mean"] = abs(z)
        for p in PERCENTS:
            if _disjoint(order_interval(a, p / 100, alpha / 2),
                         order_interval(b, p / 100, alpha / 2)):
                out[f"{name} {p:g} %"] = 1.0
    c1 = int(np.count_nonzero(_outside(problem, corridor, one[1])))
    c2 = int(np.count_nonzero(_outside(problem, corridor, two[1])))
    if _disjoint(clopper_pearson(c1, N, alpha / 2), clopper_pearson(c2, N, alpha / 2)):
        out["outside the corridor"] = 1.0
    return out


@pytest.fixture(scope="module")
def reduced(navigation):
    problem, _ = _problem(navigation)
    s = run_shards(problem, 2027, N, SERIAL).samples
    return s.dv_km_s, s.miss


def test_the_reduced_and_whole_state_samplers_agree(navigation, reduced):
    problem, corridor = _problem(navigation)
    whole = whole_state_samples(problem, N, 31)
    assert flagged(problem, corridor, reduced, whole) == {}


def test_the_comparison_sees_a_five_percent_execution_error(navigation, reduced):
    """The whole-state model with σ_p 5 % too large against the reduced samples: the later
    corrections' |Δv| means move by |z| = 11-18 (measured); the first, which no execution
    error reaches, not at all."""
    problem, corridor = _problem(navigation, sigma_proportional=0.021)
    bad = flagged(problem, corridor, reduced, whole_state_samples(problem, N, 31))
    assert {"|dv2| mean", "|dv3| mean"} <= set(bad), bad
    assert not any(name.startswith("|dv1|") for name in bad)

"""Batch weighted least-squares differential correction (Gauss-Newton) with the (J_N, J_M)
choice of the approximate-STM study.

Each iteration k propagates the reference trajectory from the current epoch estimate x_k
with the state model (J_N) and the STM with the variational model (J_M), then solves the
normal equations (Tapley, Schutz & Born, *Statistical Orbit Determination*, 2004, eq. 4.3.25)

.. math::
    \\Big(\\bar P^{-1} + \\sum_i H_i^T W H_i\\Big)\\,\\delta x
        = \\bar P^{-1}(\\bar x - x_k) + \\sum_i H_i^T W y_i,\\qquad
    H_i = \\tilde H_i\\,\\Phi_M(t_i, t_0),\\ y_i = z_i - h(x_N(t_i)),

by Cholesky, x_{k+1} = x_k + δx. Without an a priori the first term is absent (the study's
"infinite a priori covariance").

Before the first correction the normal matrix is diagnosed: when its condition number, once
scaled to a unit diagonal, exceeds ``max_condition`` the data do not determine the state,
and :class:`IllConditionedError` reports the condition number and the undetermined state
directions (the eigenvectors of the scaled matrix whose eigenvalues are below
λ_max / ``max_condition``) instead of iterating on into nonsense.

Outcomes (:class:`DCOutcome`), after the brief's RMS = sqrt(Σ y_i² w_i / m) (here
w_i = 1/σ_i², so RMS ≈ 1 at the noise level), with the thresholds of :class:`DCSettings`:

- the RMS has **settled** at iteration k when |RMS_{k-1} - RMS_k| / RMS_k < ``rms_rel_tol``
  (it stopped changing appreciably) and the correction just computed would not change it
  appreciably either, δx_kᵀ N δx_k / (2 m RMS_k²) < ``rms_rel_tol`` (for Gauss-Newton
  δxᵀNδx is the predicted decrease of the weighted sum of squares m RMS²): two equal RMS
  values in a row while the RMS oscillates on its way down are not a convergence;
- **converged** when the RMS settles at RMS_k <= ``rms_fit_limit`` and within the noise
  model's bound (below), or when RMS_k < ``rms_floor`` (a noise-free fit is exact to
  rounding);
- **converged, residuals inconsistent with the noise model** when the RMS settles within
  ``rms_fit_limit`` but above :func:`rms_bound`, the RMS a correct model exceeds with
  probability 1 − :data:`NOISE_MODEL_PROBABILITY` (0.1 %): the iteration converged, but the
  data are not explained by the model and their noise (a wrong Earth orientation, force
  model, station or σ), so the estimate may be far from the orbit;
- **stalled** when the RMS settles above ``rms_fit_limit`` (the data are not fitted to their
  noise level: the iteration found a point that is not the orbit);
- **diverged** when RMS_k > ``divergence_ratio`` × min_{j<k} RMS_j (the RMS grows), when the
  reference trajectory cannot be propagated (it hit the Earth or blew up), or when the
  iteration limit K is reached with the RMS not falling (it fails to settle);
- **converging** when the iteration limit K is reached while the RMS is still falling
  geometrically: the observed contraction factor q < 1 (below) and the largest RMS of the
  last w iterations is below the largest of the iterations before them (an envelope, so that
  an RMS oscillating on its way down counts as falling). The result gives q and the
  iterations still needed to reach ``rms_fit_limit`` if the fall goes on,
  ceil(log(rms_fit_limit / RMS_K) / log q) (0 when RMS_K is within the limit already).

The noise-model test. With Gaussian measurement errors of the stated σ and a state and
measurement model that are right, the weighted sum of squares of the m residuals at the
least-squares estimate of n parameters is χ² with ν = m − n degrees of freedom (the
standard result of linear least squares, e.g. Seber & Lee, *Linear Regression Analysis*,
2nd ed., 2003, ch. 3; the DC's last linearisation makes it so to first order), so

.. math::
    \\mathrm{RMS}^2 = \\frac{1}{m}\\sum_i w_i y_i^2 \\sim \\frac{\\chi^2_\\nu}{m},\\qquad
    \\mathrm{RMS}_{\\max} = \\sqrt{F^{-1}_{\\chi^2_\\nu}(0.999) / m}

(SciPy's ``chi2.ppf``). n = 6 (the epoch state); with an a priori, whose six
pseudo-measurements balance the six parameters, ν = m, a bound on the data's part of the
sum. With ν = 0 the fit interpolates the data and the bound is 0. The test is applied only
where the RMS settled within the fit limit: a stalled DC, settled above it, has its verdict
already (the data are not fitted; the default ``rms_fit_limit`` 3 is above every bound: the
largest, at m = 12, is 1.37), and a diverged or still converging one has no estimate to
judge; the bound is reported with every outcome. A fit whose STM is truncated (J_M ≠ J_N)
settles where H̃ᵀWy = 0, not at the least-squares estimate (HᵀWy = 0): its RMS is at or above
the minimum, and the test judges the estimate it returns.

The observed contraction factor q is measured on the corrections, not on the RMS: near the
solution the DC with a truncated STM is the fixed-point iteration e_{k+1} = M e_k,
M = I - (H̃ᵀWH̃)⁻¹H̃ᵀWH (:mod:`tapp.od.rate`), so the corrections obey δx_{k+1} = M δx_k
exactly, whatever the noise (the noise only moves the fixed point). q is exp of the
least-squares slope of log |δx_k|_N over the last w = min(K - 1, max(``trend_window``, K // 2))
iterations, with |δx|_N = sqrt(δxᵀ N δx) the correction's size in the metric of the normal
matrix N (scale-free; for a complex pair of eigenvalues a long window averages the
oscillation out).
In the linear regime q estimates the spectral radius ρ of M; far from the solution, or once
the corrections reach the rounding level of a converged fit, it is only a summary of the
iterations' pace.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import scipy.linalg
from scipy.stats import chi2

from tapp.dynamics import PropagationError, Propagator
from tapp.errors import InputError, SingularMatrixError, TooFewMeasurementsError
from tapp.frames.orientation import EarthOrientation
from tapp.measurements.observations import Observations, predict, residuals

#: Names of the state components, in order (km, km/s).
STATE_NAMES = ("x", "y", "z", "vx", "vy", "vz")
#: Most iterations a DC may be asked for (each propagates the whole arc with its STM).
MAX_ITERATIONS = 10_000
#: Probability with which the weighted residual RMS of a correct model stays within
#: :func:`rms_bound` (the issue's 99.9 %: one correct fit in a thousand is called inconsistent).
NOISE_MODEL_PROBABILITY = 0.999
#: Parameters a DC estimates from the data alone: the epoch state.
N_STATE = 6


class DCOutcome(StrEnum):
    """The five outcomes of a differential correction (module docstring for the rules)."""

    CONVERGED = "converged"
    INCONSISTENT = "converged, residuals inconsistent with the noise model"
    CONVERGING = "converging"
    STALLED = "stalled"
    DIVERGED = "diverged"


@dataclass(frozen=True, slots=True)
class DCSettings:
    """Iteration control of the differential correction (module docstring for the rules).

    ``max_iterations`` in 2 .. :data:`MAX_ITERATIONS` (two RMS values are needed to tell a
    falling RMS from a rising one); the contraction factor is measured over the last
    max(``trend_window``, K // 2) iterations (K - 1 at most); ``max_condition`` bounds the
    condition number of the scaled normal matrix at the start.
    """

    max_iterations: int = 15
    rms_rel_tol: float = 1e-3
    divergence_ratio: float = 10.0
    rms_floor: float = 1e-6
    rms_fit_limit: float = 3.0
    trend_window: int = 10
    max_condition: float = 1e10

    def __post_init__(self) -> None:
        if not 2 <= self.max_iterations <= MAX_ITERATIONS:
            raise InputError("dc", "max_iterations", f"an integer in 2 .. {MAX_ITERATIONS:,} "
                             "(two RMS values tell a falling RMS from a rising one)",
                             self.max_iterations)
        if not self.rms_rel_tol > 0:
            raise InputError("dc", "rms_rel_tol", "a number > 0", self.rms_rel_tol)
        if not self.divergence_ratio > 1:
            raise InputError("dc", "divergence_ratio", "a number > 1", self.divergence_ratio)
        if self.trend_window < 2:
            raise InputError("dc", "trend_window", "an integer >= 2", self.trend_window)
        if not self.max_condition > 1:
            raise InputError("dc", "max_condition", "a number > 1", self.max_condition)


class IllConditionedError(SingularMatrixError):
    """The normal matrix at the start of a DC is too ill-conditioned for the data to
    determine the state.

    Attributes
    ----------
    condition : condition number of the normal matrix scaled to a unit diagonal (inf when
        it is singular).
    limit : the ``max_condition`` it exceeds.
    directions : (n, 6) undetermined state directions, unit vectors in the scaled state
        (each component divided by 1/sqrt(N_ii)), weakest first.
    eigenvalues : (n,) their eigenvalues relative to the largest.
    n_measurements : scalar measurements in the arc.
    """

    def __init__(self, condition: float, limit: float, directions: np.ndarray,
                 eigenvalues: np.ndarray, n_measurements: int):
        self.condition = condition
        self.limit = limit
        self.directions = directions
        self.eigenvalues = eigenvalues
        self.n_measurements = n_measurements
        dirs = "; ".join(describe_direction(d) for d in directions)
        super().__init__(f"normal matrix ill-conditioned before the first correction: "
                         f"condition number {condition:.3g} > {limit:.3g} with "
                         f"{n_measurements} measurements; the data do not determine "
                         f"{len(directions)} state direction(s): {dirs}")


def rms_bound(n_residuals: int, n_parameters: int = N_STATE,
              probability: float = NOISE_MODEL_PROBABILITY) -> float:
    """Return the weighted residual RMS (dimensionless, w = 1/σ²) that a fit of a correct
    model to ``n_residuals`` scalar measurements, estimating ``n_parameters``, exceeds with
    probability 1 − ``probability``: sqrt(χ²_ν⁻¹(probability) / m), ν = m − n (module
    docstring); 0 when ν = 0.

    >>> round(rms_bound(1180), 4)   # the README's TDM: 590 range and range-rate pairs
    1.0614
    >>> rms_bound(6)
    0.0

    Raises
    ------
    InputError
        Fewer residuals than parameters (ν < 0).
    """
    dof = n_residuals - n_parameters
    if dof < 0:
        raise InputError("dc", "residuals", f"at least {n_parameters} (one per estimated "
                         "parameter)", n_residuals)
    if dof == 0:
        return 0.0
    return float(np.sqrt(chi2.ppf(probability, dof) / n_residuals))


def describe_direction(v: np.ndarray, smallest: float = 0.1) -> str:
    """Return a state direction as text, e.g. ``-0.70 z + 0.71 vz`` (components >= 0.1)."""
    order = np.argsort(-np.abs(v))
    if v[order[0]] < 0:  # a direction's sign is arbitrary: lead with a positive term
        v = -v
    terms = [(v[i], STATE_NAMES[i]) for i in order if abs(v[i]) >= smallest]
    text = " ".join(f"{'-' if c < 0 else '+'} {abs(c):.2f} {n}" for c, n in terms)
    return text.removeprefix("+ ")


@dataclass(frozen=True, slots=True)
class DCIteration:
    """One iteration: the estimate it started from, its residual RMS and its correction.

    ``x0`` (6,) km, km/s; ``rms`` weighted RMS (dimensionless); ``correction`` δx (6,);
    ``covariance`` (6, 6) the formal covariance (normal matrix inverse) at this iteration;
    ``step`` |δx|_N = sqrt(δxᵀ N δx), the correction's size in the normal matrix's metric.
    """

    index: int
    x0: np.ndarray
    rms: float
    correction: np.ndarray
    covariance: np.ndarray
    step: float = math.nan


@dataclass(frozen=True, slots=True)
class DCResult:
    """Outcome of a differential correction.

    ``status`` is a :class:`DCOutcome` value; ``reason`` says which rule fired; ``x0`` is the
    final estimate (the start of the last iteration, whose RMS is the last one reported);
    ``covariance`` its formal covariance; ``contraction_factor`` the observed factor q
    (module docstring; NaN with fewer than two iterations); ``projected_iterations`` the
    iterations still needed to reach the fit limit (status "converging" only, else None);
    ``rms_bound`` the noise model's bound on the RMS (:func:`rms_bound`, for every outcome).
    """

    status: str
    reason: str
    iterations: tuple[DCIteration, ...]
    x0: np.ndarray
    covariance: np.ndarray
    n_measurements: int
    contraction_factor: float = math.nan
    projected_iterations: int | None = None
    rms_bound: float = math.nan

    @property
    def converged(self) -> bool:
        """True for the outcome "converged" only: the RMS settled within the noise model."""
        return self.status == DCOutcome.CONVERGED

    @property
    def settled(self) -> bool:
        """True when the iteration converged, the residuals consistent with the noise model
        or not ("converged" or "converged, residuals inconsistent with the noise model")."""
        return self.status in (DCOutcome.CONVERGED, DCOutcome.INCONSISTENT)

    @property
    def iteration_converges(self) -> bool:
        """True when the iteration converged (:attr:`settled`) or was still converging at its
        limit: what the predicted rate ρ < 1 foretells (:mod:`tapp.od.rate`)."""
        return self.settled or self.status == DCOutcome.CONVERGING

    @property
    def converged_at(self) -> int | None:
        """Iteration at which the iteration converged (its RMS settled; :attr:`settled`),
        or None."""
        return len(self.iterations) if self.settled else None

    @property
    def rms(self) -> np.ndarray:
        """RMS per iteration (K,)."""
        return np.array([it.rms for it in self.iterations])

    @property
    def steps(self) -> np.ndarray:
        """Correction sizes |δx_k|_N per iteration (K,)."""
        return np.array([it.step for it in self.iterations])


def rms_tail_probability(rms: float, n_residuals: int, n_parameters: int = N_STATE) -> float:
    """Return the probability that a fit of a correct model to ``n_residuals`` scalar
    measurements, estimating ``n_parameters``, ends with a weighted residual RMS above
    ``rms``: the χ²_ν survival function at m·RMS², ν = m − n (module docstring). The inverse
    of :func:`rms_bound`: a fit fails the noise-model test when this falls below
    1 − :data:`NOISE_MODEL_PROBABILITY`.

    >>> round(rms_tail_probability(rms_bound(1180), 1180), 9)
    0.001
    >>> round(rms_tail_probability(1.0, 1180), 2)   # the RMS a correct model expects
    0.45

    Raises
    ------
    InputError
        As :func:`rms_bound`, or with ν = 0 (the fit interpolates: no test).
    """
    dof = n_residuals - n_parameters
    if dof <= 0:
        raise InputError("dc", "residuals", f"more than {n_parameters} (one per estimated "
                         "parameter)", n_residuals)
    return float(chi2.sf(n_residuals * rms**2, dof))


@dataclass(frozen=True, slots=True)
class Linearisation:
    """The DC's linearisation about an epoch estimate x0: the reference trajectory, its STM,
    and every measurement's residual and partials (module docstring's equation).

    Shapes: M observation rows of k kinds (``obs.kinds``, their units: km, km/s, rad).

    Attributes
    ----------
    t_s : (M,) s from the epoch.
    states : (M, 6) km, km/s: the state model's trajectory x_N(t_i) from x0.
    stm : (M, 6, 6) Φ_M(t_i, t0), the variational model's STM along it.
    residuals : (M, k) prefit residuals y_i = z_i − h(x_N(t_i)).
    state_partials : (M, k, 6) H̃_i = ∂h/∂x at t_i.
    partials : (M, k, 6) H_i = H̃_i Φ_M(t_i, t0), the partials with respect to x0.
    """

    t_s: np.ndarray
    states: np.ndarray
    stm: np.ndarray
    residuals: np.ndarray
    state_partials: np.ndarray
    partials: np.ndarray


def linearise(obs: Observations, prop: Propagator, x0: np.ndarray,
              orientation: EarthOrientation) -> Linearisation:
    """Propagate ``prop``'s (J_N, J_M) pair from x0 (6,) at t = 0 over ``obs``'s times and
    return the residuals and epoch-mapped partials of every measurement (one DC iteration's
    linearisation).

    Raises
    ------
    PropagationError
        The reference trajectory cannot be propagated.
    """
    traj = prop.propagate(x0, obs.t_s, orientation=orientation)
    h, h_tilde = predict(obs, traj.states, orientation)
    # H_i = H~_i Φ(t_i, t0)
    big_h = np.einsum("mkj,mjl->mkl", h_tilde, traj.stm)
    return Linearisation(traj.t_s, traj.states, traj.stm, residuals(obs, h), h_tilde, big_h)


def scaled_condition(normal: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Return (condition number, eigenvalues ascending, eigenvectors as columns) of the
    symmetric matrix ``normal`` (6, 6) scaled to a unit diagonal, D^-1/2 N D^-1/2.

    The scaling removes the units (km against km/s) from the condition number; a zero on
    the diagonal (a component no measurement depends on) gives an infinite condition number.
    """
    d = np.sqrt(np.diag(normal))
    if not np.all(d > 0) or not np.all(np.isfinite(normal)):
        eye = np.eye(normal.shape[0])
        bad = np.flatnonzero(~(d > 0))
        values = np.ones(normal.shape[0])
        values[bad] = 0.0
        return math.inf, values, eye
    scaled = normal / np.outer(d, d)
    values, vectors = np.linalg.eigh(0.5 * (scaled + scaled.T))
    cond = values[-1] / values[0] if values[0] > 0 else math.inf
    return float(cond), values, vectors


def _diagnose(normal: np.ndarray, settings: DCSettings, n_measurements: int) -> None:
    """Raise IllConditionedError if the scaled normal matrix is too ill-conditioned."""
    cond, values, vectors = scaled_condition(normal)
    if cond <= settings.max_condition:
        return
    weak = values < values[-1] / settings.max_condition
    raise IllConditionedError(cond, settings.max_condition, vectors[:, weak].T,
                              values[weak] / values[-1], n_measurements)


def contraction_factor(steps: np.ndarray, window: int) -> float:
    """Return q = exp(slope) of the least-squares line through log steps[-w-1:], w =
    min(window, len(steps) - 1); NaN with fewer than two positive steps."""
    tail = np.asarray(steps, dtype=float)[-(window + 1):]
    tail = tail[np.isfinite(tail) & (tail > 0)]
    if tail.size < 2:
        return math.nan
    slope = np.polyfit(np.arange(tail.size), np.log(tail), 1)[0]
    return float(np.exp(slope))


def trend_window(n_iterations: int, settings: DCSettings) -> int:
    """Return w, the iterations over which the contraction factor is measured (>= 1)."""
    return max(1, min(n_iterations - 1, max(settings.trend_window, n_iterations // 2)))


def _at_limit(history: list[DCIteration], settings: DCSettings
              ) -> tuple[str, str, float, int | None]:
    """Outcome when the iteration limit is reached: converging or diverged."""
    k = len(history)
    w = trend_window(k, settings)
    q = contraction_factor(np.array([it.step for it in history]), w)
    rms = np.array([it.rms for it in history])
    rms_now = rms[-1]
    # the largest RMS of the last w iterations against the largest before them
    envelope_now, envelope_then = rms[-w:].max(), rms[:-w].max()
    if q < 1 and envelope_now < envelope_then:
        limit = settings.rms_fit_limit
        more = 0 if rms_now <= limit else math.ceil(math.log(limit / rms_now) / math.log(q))
        return (DCOutcome.CONVERGING,
                f"iteration limit {k} reached while converging: over the last {w} "
                f"iterations the RMS fell to {rms_now:.4g} (largest {envelope_now:.4g}, "
                f"{envelope_then:.4g} before) and the corrections shrank by {q:.3g} per "
                f"iteration; {more} more iteration(s) to reach the fit limit {limit:g} "
                "at that pace", q, more)
    trend = (f"the corrections did not shrink (factor {q:.3g} per iteration)" if not q < 1
             else f"the RMS did not fall (largest {envelope_now:.4g} over the last {w} "
             f"iterations, {envelope_then:.4g} before)")
    return (DCOutcome.DIVERGED, f"no convergence in {k} iterations: {trend}; RMS "
            f"{rms_now:.4g}", q, None)


def differential_correction(obs: Observations, prop: Propagator, x_start: np.ndarray, *,
                            orientation: EarthOrientation, settings: DCSettings = DCSettings(),
                            apriori: tuple[np.ndarray, np.ndarray] | None = None) -> DCResult:
    """Run the DC from ``x_start`` (6,) at t = 0 on ``obs`` with ``prop``'s (J_N, J_M) pair.

    ``orientation`` places the stations and orients the field (the model of ``prop``'s force
    models); ``apriori`` = (x̄ (6,), P̄ (6, 6)) adds an a priori estimate and covariance.

    Raises
    ------
    TooFewMeasurementsError
        Fewer than 6 scalar measurements.
    IllConditionedError
        The normal matrix of the first iteration is ill-conditioned (module docstring).
    """
    if obs.count < N_STATE:
        raise TooFewMeasurementsError(N_STATE, obs.count)
    # with an a priori its six pseudo-measurements balance the six parameters (docstring)
    n_estimated = 0 if apriori is not None else N_STATE
    bound = rms_bound(obs.count, n_estimated)
    w = np.tile(1.0 / obs.sigma**2, obs.t_s.size)
    x = np.asarray(x_start, dtype=float).copy()
    info_prior = np.zeros((6, 6))
    if apriori is not None:
        info_prior = scipy.linalg.inv(apriori[1])  # 6x6 SPD, well conditioned by construction
    history: list[DCIteration] = []
    status, reason, q, more = DCOutcome.DIVERGED, "", math.nan, None
    for k in range(1, settings.max_iterations + 1):
        try:
            lin = linearise(obs, prop, x, orientation)
        except PropagationError as exc:
            reason = f"reference trajectory failed at iteration {k}: {exc}"
            break
        y, big_h = lin.residuals.reshape(-1), lin.partials.reshape(-1, 6)
        rms = float(np.sqrt(np.sum(w * y**2) / y.size))
        if not np.isfinite(rms):
            reason = f"non-finite residuals at iteration {k}"
            break
        # normal equations: (P̄⁻¹ + HᵀWH) δx = P̄⁻¹(x̄ - x) + HᵀWy
        normal = info_prior + big_h.T @ (w[:, None] * big_h)
        if k == 1:
            _diagnose(normal, settings, obs.count)
        rhs = big_h.T @ (w * y)
        if apriori is not None:
            rhs = rhs + info_prior @ (apriori[0] - x)
        try:
            chol = scipy.linalg.cho_factor(normal)
        except np.linalg.LinAlgError:
            reason = f"singular normal matrix at iteration {k}"
            break
        dx = scipy.linalg.cho_solve(chol, rhs)
        cov = scipy.linalg.cho_solve(chol, np.eye(6))
        # |δx|_N = sqrt(δxᵀ N δx)
        step = float(np.sqrt(max(dx @ normal @ dx, 0.0)))
        history.append(DCIteration(k, x.copy(), rms, dx, cov, step))
        rms_prev = [it.rms for it in history[:-1]]
        if rms < settings.rms_floor:
            status, reason = DCOutcome.CONVERGED, f"RMS below {settings.rms_floor:g} at " \
                f"iteration {k}"
            break
        # settled: the RMS did not change, and the correction would not change it
        if rms_prev and abs(rms_prev[-1] - rms) / rms < settings.rms_rel_tol and \
                step**2 / (2 * y.size * rms**2) < settings.rms_rel_tol:
            settled = rms <= settings.rms_fit_limit
            status = DCOutcome.CONVERGED if settled else DCOutcome.STALLED
            reason = (f"RMS settled (changed by less than {settings.rms_rel_tol:g}, "
                      f"relative) at iteration {k}" + ("" if settled else
                                          f", settling at {rms:.4g} > {settings.rms_fit_limit:g}"))
            if settled and rms > bound:
                status = DCOutcome.INCONSISTENT
                reason += (f", at RMS {rms:.4g} > {bound:.4g}, the "
                           f"{100 * NOISE_MODEL_PROBABILITY:g} % χ² bound of {y.size} "
                           f"residuals and {n_estimated} estimated parameters")
            break
        if rms_prev and rms > settings.divergence_ratio * min(rms_prev):
            reason = (f"RMS grew to {rms:.4g}, more than {settings.divergence_ratio:g} x its "
                      f"minimum {min(rms_prev):.4g}, at iteration {k}")
            break
        x = x + dx
    else:
        status, reason, q, more = _at_limit(history, settings)
    if math.isnan(q) and len(history) >= 2:
        q = contraction_factor(np.array([it.step for it in history]),
                               trend_window(len(history), settings))
    last = history[-1] if history else DCIteration(0, x, np.nan, np.zeros(6),
                                                   np.full((6, 6), np.nan))
    return DCResult(str(status), reason, tuple(history), last.x0, last.covariance, obs.count,
                    q, more, bound)

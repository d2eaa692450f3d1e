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

Convergence, after the brief's RMS = sqrt(Σ y_i² w_i / m) (here w_i = 1/σ_i², so RMS ≈ 1 at
the noise level), made explicit and configurable in :class:`DCSettings`:

- converged at iteration k when |RMS_{k-1} - RMS_k| / RMS_k < ``rms_rel_tol`` (the RMS
  stopped decreasing appreciably, and did not grow appreciably either), or when RMS_k <
  ``rms_floor`` (a noise-free fit is exact to rounding);
- stalled (converged by the rule above but to a wrong orbit) when the settled RMS exceeds
  ``rms_fit_limit`` (the data are not fitted to their noise level);
- diverged when RMS_k > ``divergence_ratio`` × min_{j<k} RMS_j (the RMS grows), when the
  reference trajectory cannot be propagated (it hit the Earth or blew up), or when
  ``max_iterations`` pass without convergence (the RMS fails to settle).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from tapp.dynamics import PropagationError, Propagator
from tapp.errors import InputError, TooFewMeasurementsError
from tapp.od.observations import Observations, predict, residuals


@dataclass(frozen=True, slots=True)
class DCSettings:
    """Iteration control of the differential correction (module docstring for the rules)."""

    max_iterations: int = 15
    rms_rel_tol: float = 1e-3
    divergence_ratio: float = 10.0
    rms_floor: float = 1e-6
    rms_fit_limit: float = 3.0

    def __post_init__(self) -> None:
        if self.max_iterations < 1:
            raise InputError("dc", "max_iterations", "an integer >= 1", self.max_iterations)
        if not self.rms_rel_tol > 0:
            raise InputError("dc", "rms_rel_tol", "a number > 0", self.rms_rel_tol)
        if not self.divergence_ratio > 1:
            raise InputError("dc", "divergence_ratio", "a number > 1", self.divergence_ratio)


@dataclass(frozen=True, slots=True)
class DCIteration:
    """One iteration: the estimate it started from, its residual RMS and its correction.

    ``x0`` (6,) km, km/s; ``rms`` weighted RMS (dimensionless); ``correction`` δx (6,);
    ``covariance`` (6, 6) the formal covariance (normal matrix inverse) at this iteration.
    """

    index: int
    x0: np.ndarray
    rms: float
    correction: np.ndarray
    covariance: np.ndarray


@dataclass(frozen=True, slots=True)
class DCResult:
    """Outcome of a differential correction.

    ``status`` is "converged", "stalled" or "diverged"; ``reason`` says which rule fired;
    ``x0`` is the final estimate (the start of the last iteration, whose RMS is the last
    one reported); ``covariance`` its formal covariance.
    """

    status: str
    reason: str
    iterations: tuple[DCIteration, ...]
    x0: np.ndarray
    covariance: np.ndarray
    n_measurements: int

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    @property
    def rms(self) -> np.ndarray:
        """RMS per iteration (K,)."""
        return np.array([it.rms for it in self.iterations])


def _linearise(obs: Observations, prop: Propagator, x0: np.ndarray, theta0_rad: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Return prefit residuals y (M k,) and epoch-mapped partials H (M k, 6)."""
    traj = prop.propagate(x0, obs.t_s, theta0_rad=theta0_rad)
    h, h_tilde = predict(obs, traj.states, theta0_rad)
    y = residuals(obs, h)
    # H_i = H~_i Φ(t_i, t0)
    big_h = np.einsum("mkj,mjl->mkl", h_tilde, traj.stm)
    return y.reshape(-1), big_h.reshape(-1, 6)


def differential_correction(obs: Observations, prop: Propagator, x_start: np.ndarray, *,
                            theta0_rad: float = 0.0, settings: DCSettings = DCSettings(),
                            apriori: tuple[np.ndarray, np.ndarray] | None = None) -> DCResult:
    """Run the DC from ``x_start`` (6,) at t = 0 on ``obs`` with ``prop``'s (J_N, J_M) pair.

    ``apriori`` = (x̄ (6,), P̄ (6, 6)) adds an a priori estimate and covariance.

    Raises
    ------
    TooFewMeasurementsError
        Fewer than 6 scalar measurements.
    """
    if obs.count < 6:
        raise TooFewMeasurementsError(6, obs.count)
    w = np.tile(1.0 / obs.sigma**2, obs.t_s.size)
    x = np.asarray(x_start, dtype=float).copy()
    info_prior = np.zeros((6, 6))
    if apriori is not None:
        info_prior = scipy.linalg.inv(apriori[1])  # 6x6 SPD, well conditioned by construction
    history: list[DCIteration] = []
    status, reason = "diverged", f"no convergence in {settings.max_iterations} iterations"
    for k in range(1, settings.max_iterations + 1):
        try:
            y, big_h = _linearise(obs, prop, x, theta0_rad)
        except PropagationError as exc:
            reason = f"reference trajectory failed at iteration {k}: {exc}"
            break
        rms = float(np.sqrt(np.sum(w * y**2) / y.size))
        if not np.isfinite(rms):
            reason = f"non-finite residuals at iteration {k}"
            break
        # normal equations: (P̄⁻¹ + HᵀWH) δx = P̄⁻¹(x̄ - x) + HᵀWy
        normal = info_prior + big_h.T @ (w[:, None] * big_h)
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
        history.append(DCIteration(k, x.copy(), rms, dx, cov))
        rms_prev = [it.rms for it in history[:-1]]
        if rms < settings.rms_floor:
            status, reason = "converged", f"RMS below {settings.rms_floor:g} at iteration {k}"
            break
        if rms_prev and abs(rms_prev[-1] - rms) / rms < settings.rms_rel_tol:
            status = "converged" if rms <= settings.rms_fit_limit else "stalled"
            reason = (f"RMS changed by less than {settings.rms_rel_tol:g} (relative) at "
                      f"iteration {k}" + ("" if status == "converged" else
                                          f", settling at {rms:.4g} > {settings.rms_fit_limit:g}"))
            break
        if rms_prev and rms > settings.divergence_ratio * min(rms_prev):
            reason = (f"RMS grew to {rms:.4g}, more than {settings.divergence_ratio:g} x its "
                      f"minimum {min(rms_prev):.4g}, at iteration {k}")
            break
        x = x + dx
    last = history[-1] if history else DCIteration(0, x, np.nan, np.zeros(6), np.full((6, 6),
                                                                                     np.nan))
    return DCResult(status, reason, tuple(history), last.x0, last.covariance, obs.count)

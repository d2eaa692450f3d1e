"""The predicted convergence rate of a DC with a truncated STM: the spectral radius ρ.

Near the solution x* the differential correction of :mod:`tapp.od.batch` with the
variational model J_M (partials H̃ = H̃_i Φ_M) and observations from the state model J_N
(true partials H = H̃_i Φ_N) is the fixed-point iteration

.. math::
    e_{k+1} = M\\,e_k,\\qquad
    M = I - (\\tilde H^T W \\tilde H)^{-1}\\,\\tilde H^T W H,

e_k = x_k - x̂ (x̂ the fixed point, x* moved by the noise): with y_k ≈ ν - H e_k the
correction is δx_k = (H̃ᵀWH̃)⁻¹H̃ᵀW y_k. Its spectral radius ρ = max |λ_i(M)| is the predicted
contraction factor per iteration: ρ < 1 converges (linearly, as ρ^k), ρ > 1 diverges, and a
complex pair of eigenvalues makes the error (and the RMS) oscillate while it shrinks or
grows. With the full STM (M = N) H̃ = H and M = 0: Gauss-Newton's linear rate vanishes
(its convergence is then quadratic up to the small residual-curvature terms ρ ignores).

ρ is computed here at the true state from the same observation times, stations and weights
as the DC, so it is a prediction made before iterating; the DC's observed factor
(:func:`tapp.od.batch.contraction_factor`) is the check. Both matrices are formed in the
scaled variables of H̃ᵀWH̃ (unit diagonal), which leaves the eigenvalues of M unchanged (a
similarity transform) and keeps the solve well conditioned. Dennis & Schnabel, *Numerical
Methods for Unconstrained Optimization and Nonlinear Equations*, 1996, §10.2 (local
convergence of Gauss-Newton with an approximate Jacobian).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from tapp.dynamics import ForceModel, Propagator
from tapp.errors import TooFewMeasurementsError
from tapp.frames.orientation import EarthOrientation
from tapp.measurements.observations import Observations, predict


@dataclass(frozen=True, slots=True)
class PredictedRate:
    """ρ and the eigenvalues of the DC's iteration matrix M at the true state.

    ``rho`` spectral radius max |λ_i|; ``eigenvalues`` (6,) complex, largest modulus first;
    ``matrix`` M (6, 6) in the state's units (km, km/s).
    """

    rho: float
    eigenvalues: np.ndarray
    matrix: np.ndarray

    @property
    def oscillating(self) -> bool:
        """True when the dominant eigenvalue is one of a complex pair (the error rotates)."""
        lead = self.eigenvalues[0]
        return bool(abs(lead.imag) > 1e-9 * max(abs(lead), 1e-300))


def epoch_partials(obs: Observations, prop: Propagator, x0: np.ndarray,
                   orientation: EarthOrientation) -> np.ndarray:
    """Return H (M k, 6) = ∂h/∂x(t_i) Φ(t_i, t0) along ``prop``'s trajectory from x0 (6,)."""
    traj = prop.propagate(x0, obs.t_s, orientation=orientation)
    _, h_tilde = predict(obs, traj.states, orientation)
    return np.einsum("mkj,mjl->mkl", h_tilde, traj.stm).reshape(-1, 6)


def iteration_matrix(h_true: np.ndarray, h_approx: np.ndarray, weights: np.ndarray
                     ) -> np.ndarray:
    """Return M = I - (H̃ᵀWH̃)⁻¹ H̃ᵀWH (6, 6) for H, H̃ (m, 6) and diagonal weights W (m,)."""
    normal = h_approx.T @ (weights[:, None] * h_approx)
    cross = h_approx.T @ (weights[:, None] * h_true)
    d = np.sqrt(np.diag(normal))
    # D⁻¹ (D⁻¹ N D⁻¹)⁻¹ D⁻¹ B = N⁻¹ B
    chol = scipy.linalg.cho_factor(normal / np.outer(d, d))
    return np.eye(6) - scipy.linalg.cho_solve(chol, cross / d[:, None]) / d[:, None]


def rate_from_matrix(m: np.ndarray) -> PredictedRate:
    """Return the :class:`PredictedRate` of an iteration matrix M (6, 6)."""
    values = np.linalg.eigvals(m)
    values = values[np.argsort(-np.abs(values), kind="stable")]
    return PredictedRate(float(np.abs(values[0])), values, m)


def predicted_rate(obs: Observations, state_model: ForceModel, variational_model: ForceModel,
                   x_true: np.ndarray, orientation: EarthOrientation) -> PredictedRate:
    """Return ρ of the (J_N, J_M) DC on ``obs`` at the true epoch state x_true (6,), the
    stations placed and the field oriented by ``orientation``.

    H uses the STM of ``state_model`` (J_N, the model of the data), H̃ that of
    ``variational_model`` (J_M); both along the trajectory of ``state_model`` from x_true.

    Raises
    ------
    TooFewMeasurementsError
        Fewer than 6 scalar measurements.
    numpy.linalg.LinAlgError
        H̃ᵀWH̃ is singular (the data do not determine the state; the DC diagnoses it).
    """
    if obs.count < 6:
        raise TooFewMeasurementsError(6, obs.count)
    weights = np.tile(1.0 / obs.sigma**2, obs.t_s.size)
    h_true = epoch_partials(obs, Propagator(state_model), x_true, orientation)
    h_approx = epoch_partials(obs, Propagator(state_model, variational_model), x_true,
                              orientation)
    return rate_from_matrix(iteration_matrix(h_true, h_approx, weights))

"""Piecewise-constant stochastic accelerations correlated as a first-order Gauss-Markov process.

The arc [t_0, t_K] is cut at boundaries t_0 < t_1 < ... < t_K into K intervals; in interval k
(t_k <= t < t_{k+1}) each component c of the acceleration (frame "ric" or "inertial",
:mod:`tapp.dynamics.empirical`) is a constant a_{k,c} (km/s², nominal 0). The components are
independent; along the intervals each is a stationary first-order Gauss-Markov sequence of
standard deviation σ and time constant τ, sampled at the intervals' mid-times
t̄_k = (t_k + t_{k+1}) / 2:

.. math::
    a_{k+1} = \\rho_k a_k + w_k,\\quad \\rho_k = e^{-(\\bar t_{k+1} - \\bar t_k)/\\tau},\\quad
    w_k \\sim N(0, \\sigma^2 (1 - \\rho_k^2)),\\qquad
    P_{jk} = E[a_j a_k] = \\sigma^2 e^{-|\\bar t_j - \\bar t_k|/\\tau}.

The recursion (the discrete process, as the stochastic batches of JPL's ODP and Bierman's
*Factorization Methods*, 1977, §VI.4) and the closed form agree exactly when ρ_k is taken over
the distance of the mid-times, since the ρ's multiply along the chain. Mid-times, not starts,
because a batch value stands for its whole interval: with unequal intervals the distance of
the mid-times is the one symmetric in the two intervals. τ → ∞ tends to one constant
acceleration over the arc, τ → 0 to independent batches.

Parameters are ordered interval-major, components within an interval: ``acc_R_001``,
``acc_I_001``, ``acc_C_001``, ``acc_R_002``, ... (1-based interval numbers, at least three
digits), so that P = P_time ⊗ I_c.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from tapp.dynamics.empirical import COMPONENTS, PARAMETERS

#: The frames of the acceleration components (:mod:`tapp.dynamics.empirical`).
FRAMES = tuple(COMPONENTS)
#: The parameter kind of stochastic accelerations on the T13 tape.
KIND = "stochastic"
#: Their unit on the tape.
UNIT = "km/s^2"


def gauss_markov_covariance(t_s: np.ndarray, sigma: float, tau_s: float) -> np.ndarray:
    """Return P_jk = σ² exp(−|t_j − t_k| / τ), (K, K), in σ's unit squared: the covariance
    of a first-order Gauss-Markov (exponentially correlated) process sampled at ``t_s``.

    Parameters
    ----------
    t_s : (K,) sample times, s (the intervals' mid-times).
    sigma : steady-state standard deviation (any unit).
    tau_s : time constant τ > 0, s.
    """
    t = np.asarray(t_s, dtype=float)
    return sigma**2 * np.exp(-np.abs(t[:, None] - t[None, :]) / tau_s)


@dataclass(frozen=True, slots=True)
class StochasticAccelerations:
    """Piecewise-constant accelerations correlated as a Gauss-Markov process (module doc).

    Attributes
    ----------
    frame : "ric" or "inertial".
    components : labels of the components modelled, in frame order (a subset of
        ``tapp.dynamics.empirical.COMPONENTS[frame]``).
    boundaries_s : (K + 1,) interval boundaries t_0 < ... < t_K, s from the epoch.
    sigma_km_s2 : steady-state σ of each component, km/s².
    tau_s : Gauss-Markov time constant, s.
    """

    frame: str
    components: tuple[str, ...]
    boundaries_s: tuple[float, ...]
    sigma_km_s2: float
    tau_s: float

    @property
    def n_intervals(self) -> int:
        """K, the number of intervals."""
        return len(self.boundaries_s) - 1

    @property
    def mid_s(self) -> np.ndarray:
        """The intervals' mid-times t̄_k, (K,) s."""
        b = np.asarray(self.boundaries_s, dtype=float)
        return 0.5 * (b[:-1] + b[1:])

    @property
    def model_parameters(self) -> tuple[str, ...]:
        """The empirical-acceleration model parameters of the components (``acc_R``, ...)."""
        table = dict(zip(COMPONENTS[self.frame], PARAMETERS[self.frame], strict=True))
        return tuple(table[c] for c in self.components)

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names, interval-major: ``acc_R_001``, ``acc_I_001``, ..."""
        width = max(3, len(str(self.n_intervals)))
        return tuple(f"acc_{c}_{k:0{width}d}" for k in range(1, self.n_intervals + 1)
                     for c in self.components)

    def covariance(self) -> np.ndarray:
        """The a priori covariance P (n, n), (km/s²)², n = K × components: the Gauss-Markov
        covariance of the mid-times for each component, none between components."""
        time = gauss_markov_covariance(self.mid_s, self.sigma_km_s2, self.tau_s)
        return np.kron(time, np.eye(len(self.components)))

    def information(self) -> np.ndarray:
        """P⁻¹ (n, n), 1/(km/s²)², by Cholesky (P is positive definite for finite τ > 0 and
        distinct mid-times)."""
        p = self.covariance()
        return cho_solve(cho_factor(p), np.eye(p.shape[0]))

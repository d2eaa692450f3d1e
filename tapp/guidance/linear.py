"""Linear covariance analysis of the guidance model: the samples' second moments, exactly.

The model of :mod:`tapp.guidance` is linear in z = [d; e] (2 n_o) except for the execution
errors, which are zero-mean given Δv and so uncorrelated with z. Every mean is zero, and the
covariance Z of z goes through the same maps as the samples:

.. math::

    Z_0 &= \\begin{bmatrix}\\bar\\Lambda^0 & -\\bar\\Lambda^0 \\\\
                           -\\bar\\Lambda^0 & \\bar\\Lambda^0\\end{bmatrix} \\\\
    Z &\\leftarrow M Z M^T + \\begin{bmatrix}0 & 0\\\\ 0 & \\Sigma_k\\end{bmatrix},
        \\quad M = \\begin{bmatrix}T_k & 0\\\\ 0 & L_k T_k\\end{bmatrix}
        && \\text{(recycle)}\\\\
    P &= K Z K^T, \\quad K = -G B_t \\,[I \\;\\; I]
        && \\text{(Cov}(\\Delta v))\\\\
    Z &\\leftarrow A Z A^T + N\\,E[\\varepsilon\\varepsilon^T]\\,N^T,
        \\quad A = I + \\begin{bmatrix}S\\\\0\\end{bmatrix} K,
        \\quad N = \\begin{bmatrix}S\\\\-S\\end{bmatrix}  && \\text{(manoeuvre)}

with S (n_o x 3) the columns of the identity at the velocity rows and E[εεᵀ] from
:func:`tapp.guidance.execution.error_second_moment` (exact for the multiplicative errors).
The final miss covariance is B_final Z_dd B_finalᵀ. The first manoeuvre's Δv is Gaussian;
later ones are not exactly (earlier execution errors scale with |Δv|), though their
covariances here are exact.

Numerics: Z is carried as a factor W (Z = W Wᵀ, a square-root covariance): each map acts on
W, a covariance that is added appends its factor's columns (Σ_k's from the tape, E[εεᵀ]'s
from :func:`tapp.estimation.factors.psd_factor`), and the columns are compressed back to
2 n_o by a Householder QR of Wᵀ. Every covariance formed from W (Cov(Δv), the final miss) is
a Gram matrix, positive semi-definite by construction, and the rounding of its entries is
relative to its own size rather than to the terms of a product M Z Mᵀ, whose cancellation
(the estimator L_k removes all but 1e-3 to 1e-6 of the a priori error) it would amplify.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.estimation.factors import gram, psd_factor, triangularize
from tapp.guidance.execution import error_second_moment
from tapp.guidance.model import Correction, Problem, Step


@dataclass(frozen=True, slots=True, eq=False)
class LinearCovariance:
    """Second moments of the guidance outcomes (module docstring).

    Attributes
    ----------
    dv_cov : (n_man, 3, 3) Cov(Δv) of each manoeuvre, km²/s².
    miss_cov : (n_m, n_m) covariance of the final miss, (miss unit)².
    W : (2 n_o, 2 n_o) factor of the covariance of [d; e] after the last manoeuvre, in its
        x^k: Z = W Wᵀ.
    """

    dv_cov: np.ndarray
    miss_cov: np.ndarray
    W: np.ndarray

    @property
    def Z(self) -> np.ndarray:
        """Cov([d; e]) = W Wᵀ (2 n_o, 2 n_o)."""
        return gram(self.W.T)


def _compress(W: np.ndarray) -> np.ndarray:
    """A factor of W Wᵀ with 2 n_o columns (Householder QR of Wᵀ)."""
    return triangularize(W.T).T


def _velocity_columns(problem: Problem) -> np.ndarray:
    """S (n_o, 3): the columns of the identity at the velocity rows."""
    S = np.zeros((problem.n_o, 3))
    S[list(problem.velocity), [0, 1, 2]] = 1.0
    return S


def initial(problem: Problem) -> np.ndarray:
    """W₀ (2 n_o, n_o) with W₀W₀ᵀ = Z₀: d₀ ~ N(0, Λ̄⁰), e₀ = −d₀."""
    f = problem.lambda0_factor
    return np.vstack([f, -f])


def recycle(W: np.ndarray, step: Step) -> np.ndarray:
    """W after the recycle ``step``: a factor of M Z Mᵀ + diag(0, Σ_k) (module docstring)."""
    n = step.transition.shape[0]
    noise = np.zeros((2 * n, step.sigma_factor.shape[1]))
    noise[n:] = step.sigma_factor
    mapped = np.vstack([step.transition @ W[:n], step.LT @ W[n:]])
    return _compress(np.hstack([mapped, noise]))


def manoeuvre(W: np.ndarray, correction: Correction, problem: Problem
              ) -> tuple[np.ndarray, np.ndarray]:
    """W after a manoeuvre and P = Cov(Δv) (3, 3) (module docstring)."""
    S = _velocity_columns(problem)
    gb = -correction.gain @ correction.B_target
    KW = gb @ (W[:problem.n_o] + W[problem.n_o:])              # K W, K = −G B_t [I I]
    P = gram(KW.T)
    AW = W + np.vstack([S @ KW, np.zeros_like(S @ KW)])
    H = psd_factor(error_second_moment(P, problem.errors)).T  # H Hᵀ = E[εεᵀ]
    return _compress(np.hstack([AW, np.vstack([S @ H, -S @ H])])), P


def linear_covariance(problem: Problem) -> LinearCovariance:
    """Propagate a factor of Cov([d; e]) through the recycles and manoeuvres (module
    docstring)."""
    W = initial(problem)
    dv_cov = []
    for step in problem.steps:
        W = recycle(W, step)
        if step.correction is not None:
            W, P = manoeuvre(W, step.correction, problem)
            dv_cov.append(P)
    n = problem.n_o
    return LinearCovariance(np.array(dv_cov), gram(W[:n].T, problem.B_final), W)


__all__ = ["LinearCovariance", "initial", "linear_covariance", "manoeuvre", "recycle"]

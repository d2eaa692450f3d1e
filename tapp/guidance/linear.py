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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.guidance.execution import error_second_moment
from tapp.guidance.model import Correction, Problem, Step


@dataclass(frozen=True, slots=True, eq=False)
class LinearCovariance:
    """Second moments of the guidance outcomes (module docstring).

    Attributes
    ----------
    dv_cov : (n_man, 3, 3) Cov(Δv) of each manoeuvre, km²/s².
    miss_cov : (n_m, n_m) covariance of the final miss, (miss unit)².
    Z : (2 n_o, 2 n_o) covariance of [d; e] after the last manoeuvre, in its x^k.
    """

    dv_cov: np.ndarray
    miss_cov: np.ndarray
    Z: np.ndarray


def _sym(m: np.ndarray) -> np.ndarray:
    return 0.5 * (m + m.T)


def initial(problem: Problem) -> np.ndarray:
    """Z₀ (2 n_o, 2 n_o): d₀ ~ N(0, Λ̄⁰), e₀ = −d₀."""
    lam = problem.Lambda0
    return np.block([[lam, -lam], [-lam, lam]])


def recycle(Z: np.ndarray, step: Step) -> np.ndarray:
    """Z after the recycle ``step``: M Z Mᵀ + diag(0, Σ_k) (module docstring)."""
    n = step.transition.shape[0]
    zeros = np.zeros((n, n))
    M = np.block([[step.transition, zeros], [zeros, step.LT]])
    Z = _sym(M @ Z @ M.T)
    Z[n:, n:] += step.Sigma
    return Z


def manoeuvre(Z: np.ndarray, correction: Correction, problem: Problem
              ) -> tuple[np.ndarray, np.ndarray]:
    """Z after a manoeuvre and P = Cov(Δv) (3, 3) (module docstring)."""
    n = problem.n_o
    S = np.zeros((n, 3))
    S[list(problem.velocity), [0, 1, 2]] = 1.0
    gb = -correction.gain @ correction.B_target
    K = np.hstack([gb, gb])
    P = _sym(K @ Z @ K.T)
    A = np.eye(2 * n) + np.vstack([S @ K, np.zeros((n, 2 * n))])
    N = np.vstack([S, -S])
    return _sym(A @ Z @ A.T + N @ error_second_moment(P, problem.errors) @ N.T), P


def linear_covariance(problem: Problem) -> LinearCovariance:
    """Propagate Cov([d; e]) through the recycles and manoeuvres (module docstring)."""
    Z = initial(problem)
    dv_cov = []
    for step in problem.steps:
        Z = recycle(Z, step)
        if step.correction is not None:
            Z, P = manoeuvre(Z, step.correction, problem)
            dv_cov.append(P)
    n, B = problem.n_o, problem.B_final
    return LinearCovariance(np.array(dv_cov), _sym(B @ Z[:n, :n] @ B.T), Z)


__all__ = ["LinearCovariance", "initial", "linear_covariance", "manoeuvre", "recycle"]

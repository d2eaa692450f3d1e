"""A navigation that knows its manoeuvres: the fit-world a priori after a manoeuvre gains the
execution-error covariance, and the regression is re-run from the tape's normal matrices.

The tape's L_k and Σ_k (:mod:`tapp.guidance`, step 2) belong to an estimator whose a priori at
t_k is its previous estimate as TAPP III formed it: it has never heard of a manoeuvre. After
one, the estimate error holds the execution error ε (metres per second), thousands of times
the velocity σ that a priori claims (fractions of a mm/s after a day of DSN tracking), so L_k
hardly corrects it and bends the data fit around it (into GM, station biases, position): on
the deep-space tape a second correction then leaves a worse miss than the first alone.

With ``after_manoeuvre = "inflate"`` the navigation adds the manoeuvre's execution-error
covariance E[εεᵀ] (:func:`tapp.guidance.execution.error_second_moment`, over the Δv
covariance the linear analysis predicts: the same for every sample, so the maps stay linear)
to the velocity rows of its a posteriori covariance Λ' before mapping it to the next recycle,
and forms L_k, Λ'_k and Σ_k again for that recycle and every later one from the tape's J_k and
J̃_k (seed TAPP III §2.5 with an a priori covariance, in x^k):

.. math::

    C &= T_k\\,(\\Lambda'_{k-1} + S\\,E[\\varepsilon\\varepsilon^T]\\,S^T)\\,T_k^T,
        \\qquad C_{11} = R_1 C R_1^T = U U^T \\\\
    {}^1\\Lambda^{11} &= (C_{11}^{-1} + E_1^T J E_1)^{-1}
        = U\\,(I + U^T E_1^T J E_1 U)^{-1}\\,U^T \\\\
    \\Lambda'_k &= E_1\\,{}^1\\Lambda^{11} E_1^T, \\quad L_k = I - \\Lambda'_k J_k, \\quad
    \\Sigma_k = \\Lambda'_k \\tilde J_k \\Lambda'_k = (\\Lambda'_k F)(\\Lambda'_k F)^T

with E₁ = ∂x/∂x^{f1} and R₁ = ∂x^{f1}/∂x from the tape's fit-system chain (``systems/fit``,
partition f1), U and F (F Fᵀ = J̃_k) positive semi-definite factors. The middle form needs no
inverse of the (ill-conditioned) a priori and factors a matrix whose eigenvalues are >= 1;
Σ_k is formed from factors, positive semi-definite by construction. Without a manoeuvre the
same equations give back the tape's L_k, Λ'_k and Σ_k (TAPP III forms them in information
form from the mapped normal matrix): checked in the tests.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import linalg

from tapp.guidance.execution import error_second_moment
from tapp.guidance.linear import initial, manoeuvre, recycle
from tapp.guidance.model import Problem, psd_factor
from tapp.tape.t32 import T32


@dataclass(frozen=True, slots=True, eq=False)
class FitWorld:
    """The fit world of a tape, per recycle in x^k.

    Attributes
    ----------
    E1 : (n_o, n_f1) ∂x/∂x^{f1}, the fit-world constraint matrix.
    R1 : (n_f1, n_o) ∂x^{f1}/∂x, the rows f1 of the fit-system chain.
    J, Jt : per recycle, (n_o, n_o) AᵀWA and AᵀWMWA of its interval.
    Lambda_fit : per recycle, (n_o, n_o) the tape's Λ'.
    """

    E1: np.ndarray
    R1: np.ndarray
    J: tuple[np.ndarray, ...]
    Jt: tuple[np.ndarray, ...]
    Lambda_fit: tuple[np.ndarray, ...]


@dataclass(frozen=True, slots=True, eq=False)
class Refit:
    """The regression of one recycle (module docstring): L_k, Λ'_k and F_Σ with
    F_Σ F_Σᵀ = Σ_k."""

    L: np.ndarray
    Lambda_fit: np.ndarray
    sigma_factor: np.ndarray


def fit_world(t32: T32) -> FitWorld:
    """The fit world of a tape (its fit chain, partition f1 and recycle matrices)."""
    chain = t32.systems["fit"]
    f1 = t32.partition("f1")
    E1 = linalg.solve(chain, np.eye(chain.shape[0]))[:, f1.tail:f1.head]
    rc = t32.recycles
    return FitWorld(E1, chain[f1.tail:f1.head], tuple(r.J for r in rc),
                    tuple(r.Jt for r in rc), tuple(r.Lambda_fit for r in rc))


def refit(C: np.ndarray, fit: FitWorld, J: np.ndarray, Jt: np.ndarray) -> Refit:
    """The fit-world regression of an interval with a priori covariance ``C`` (module
    docstring); C, J, Jt (n_o, n_o) in the same representation."""
    U = psd_factor(fit.R1 @ C @ fit.R1.T)
    UtJU = U.T @ (fit.E1.T @ J @ fit.E1) @ U
    M = np.eye(U.shape[1]) + 0.5 * (UtJU + UtJU.T)
    lam11 = U @ linalg.cho_solve(linalg.cho_factor(M), U.T)
    lam = fit.E1 @ (0.5 * (lam11 + lam11.T)) @ fit.E1.T
    return Refit(np.eye(J.shape[0]) - lam @ J, lam, lam @ psd_factor(Jt))


def inflate_after_manoeuvres(problem: Problem, fit: FitWorld) -> Problem:
    """The problem with L_k, Σ_k re-formed at every recycle after the first manoeuvre, the a
    priori after a manoeuvre holding its execution-error covariance (module docstring)."""
    S = np.zeros((problem.n_o, 3))
    S[list(problem.velocity), [0, 1, 2]] = 1.0
    Z = initial(problem)
    steps = []
    prior = None  # the navigation's covariance after the previous recycle, once re-formed
    for i, step in enumerate(problem.steps):
        lam = fit.Lambda_fit[i]
        if prior is not None:
            T = step.transition
            r = refit(T @ prior @ T.T, fit, fit.J[i], fit.Jt[i])
            F = r.sigma_factor
            step = dataclasses.replace(step, LT=r.L @ T, Sigma=F @ F.T, sigma_factor=F)
            lam = r.Lambda_fit
        Z = recycle(Z, step)
        if step.correction is not None:
            Z, P = manoeuvre(Z, step.correction, problem)
            prior = lam + S @ error_second_moment(P, problem.errors) @ S.T
        elif prior is not None:
            prior = lam
        steps.append(step)
    return dataclasses.replace(problem, steps=tuple(steps))


__all__ = ["FitWorld", "Refit", "fit_world", "inflate_after_manoeuvres", "refit"]

"""A navigation that knows its manoeuvres: after a manoeuvre, the fit world's a priori gains
the execution-error covariance, and the regression is re-run on the tape's data factors.

The tape's L_k and Σ_k (:mod:`tapp.guidance`, step 2) belong to an estimator whose a priori at
t_k is its previous estimate as TAPP III formed it: it has never heard of a manoeuvre. After
one, the estimate error holds the execution error ε (metres per second), thousands of times
the velocity σ that a priori claims (fractions of a mm/s after a day of DSN tracking), so L_k
hardly corrects it and bends the data fit around it (into GM, station biases, position): on
the deep-space tape a second correction then leaves a worse miss than the first alone.

With ``after_manoeuvre = "inflate"`` the navigation adds the manoeuvre's execution-error
covariance E[εεᵀ] (:func:`tapp.guidance.execution.error_second_moment`, over the Δv
covariance the linear analysis predicts: the same for every sample, so the maps stay linear)
to its a posteriori covariance in the velocity directions, maps it to the next recycle, and
forms L_k, Σ_k again there and at every later recycle with TAPP III's own regression
(:func:`tapp.estimation.regression`) on the tape's square-root information R_J, R̃ of the
interval (T32 version 2 carries them).

Everything stays in square-root information form (Bierman, *Factorization Methods for
Discrete Sequential Estimation*, 1977, ch. VI). The navigation carries the factor R of its
extended a posteriori normal matrix S' (the tape's at the first manoeuvre). Adding the
covariance H Hᵀ = E[εεᵀ] on the velocity, x ← x + S_v H w with w ~ N(0, I), is the process
noise step of the square-root information filter:

.. math::

    Q^T \\begin{bmatrix} I & 0 \\\\ -R\\,S_v H & R \\end{bmatrix}
    = \\begin{bmatrix} * & * \\\\ 0 & R^+ \\end{bmatrix},

R⁺ the information factor of x after the noise (w integrated out), with no inverse of the
(ill-conditioned) a priori and no subtraction. Mapping to the next recycle's representation
is R ← R T_k⁻¹ = R (T_k*)ᵀ with the tape's adjoint transition T_k* (TAPP III's: the orbit
link's exact inverse, rounded). Without a manoeuvre these steps give back the tape's L_k and
Σ_k (the same regression on the same factors): checked in the tests.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from tapp.estimation.factors import psd_factor, triangularize
from tapp.estimation.regression import FitSystem, regression
from tapp.guidance.execution import error_second_moment
from tapp.guidance.linear import initial, manoeuvre, recycle
from tapp.guidance.model import Problem
from tapp.io.tape.t32 import T32


def fit_system(t32: T32) -> FitSystem:
    """The fit world of a tape: D = its fit-system chain ∂x^f/∂x, E = D⁻¹, n_1 = |f1|."""
    chain = t32.systems["fit"]
    f1 = t32.partition("f1")
    return FitSystem(chain, np.linalg.solve(chain, np.eye(chain.shape[0])), f1.head - f1.tail)


def add_velocity_noise(R: np.ndarray, velocity: tuple[int, ...], H: np.ndarray) -> np.ndarray:
    """Return R⁺ (n_o, n_o), the information factor after x ← x + S_v H w (module docstring).

    Parameters
    ----------
    R : (m, n_o) information factor of x.
    velocity : positions of the velocity in x (the columns S_v).
    H : (3, r) factor of the added velocity covariance, H Hᵀ.
    """
    n_o, r = R.shape[1], H.shape[1]
    array = np.zeros((r + R.shape[0], r + n_o))
    array[:r, :r] = np.eye(r)
    array[r:, :r] = -R[:, list(velocity)] @ H
    array[r:, r:] = R
    return triangularize(array)[r:, r:]


def inflate_after_manoeuvres(problem: Problem, t32: T32) -> Problem:
    """The problem with L_k, Σ_k re-formed at every recycle after the first manoeuvre, the a
    priori after a manoeuvre holding its execution-error covariance (module docstring)."""
    fit = fit_system(t32)
    W = initial(problem)
    steps = []
    info = None  # the navigation's information factor after the previous recycle, once re-formed
    for step, rc in zip(problem.steps, t32.recycles, strict=False):
        S1 = rc.S_fit_factor
        if info is not None:
            reg = regression(fit, info @ rc.transition_adjoint.T, rc.J_factor, Rt=rc.Jt_factor)
            step = dataclasses.replace(step, LT=reg.L @ step.transition,
                                       sigma_factor=reg.K_sigma.T)
            S1 = reg.R_S1
        W = recycle(W, step)
        if step.correction is not None:
            W, P = manoeuvre(W, step.correction, problem)
            H = psd_factor(error_second_moment(P, problem.errors)).T
            info = add_velocity_noise(S1, problem.velocity, H)
        elif info is not None:
            info = S1
        steps.append(step)
    return dataclasses.replace(problem, steps=tuple(steps))


__all__ = ["add_velocity_noise", "fit_system", "inflate_after_manoeuvres"]

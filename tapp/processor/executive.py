"""The Executive Program of TAPP III (seed §4.2.2, Figure C-2): one entity from one command.

Z = (μ₁, τ₁, ρ₁ | [σ₀] | μ₂, τ₂, ρ₂) = X₁ [σ₀] X₂ᵀ with X = (μ, τ, ρ| the partials
accumulator; for σ₀ = I, Z = X₁ X₂ᵀ. Every other matrix option is held as a factor K with
[σ₀] = KᵀK (:mod:`tapp.estimation`), so Z = (K X₁ᵀ)ᵀ (K X₂ᵀ): a covariance or normal matrix
on one set of rows is a Gram matrix, positive semi-definite by construction. The factors come
from a callable so that the expensive ones are formed only when asked for.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tapp.estimation.factors import accurate_map, gram
from tapp.processor.commands import Command
from tapp.processor.representations import Accumulator


@dataclass(frozen=True, slots=True, eq=False)
class Budget:
    """Error budget of a real-world covariance entity: each source's variance per row.

    ``variances`` (n_sources, n_rows) add up to ``total`` (n_rows,), the entity's diagonal;
    a negative entry is the share of correlations between sources.
    """

    sources: tuple[str, ...]
    variances: np.ndarray
    total: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class Entity:
    """One evaluated output entity: its command, labels and matrix (rows x cols).

    ``digits`` (covariances only) estimates how many significant digits the matrix holds,
    on the scale √(Z_ii Z_jj) (:func:`tapp.estimation.factors.digits_held`). ``ric`` (a
    covariance of an orbit set, when the deck asks for RIC axes) is the same entity with its
    orbit rows and columns rotated to the radial / in-track / cross-track axes of the nominal
    state at the set's time (:mod:`tapp.frames.ric`), budget included.
    """

    omega: int
    command: Command
    rows: tuple[str, ...]
    cols: tuple[str, ...]
    matrix: np.ndarray
    budget: Budget | None = None
    digits: float | None = None
    ric: Entity | None = None


def evaluate(omega: int, cmd: Command, acc: Accumulator, factor: Callable[[str], np.ndarray],
             miss_names: tuple[str, ...]) -> Entity:
    """Return the entity of ``cmd`` (seed §4.2.2).

    Parameters
    ----------
    omega : entity number (1-based).
    cmd : the command.
    acc : the partials accumulator in the current state.
    factor : returns a factor K (m, n_o), KᵀK the matrix option of a code of
        :data:`tapp.processor.commands.MATRICES` (not called for I).
    miss_names : names of the miss parameters (labels of isolated miss sets).
    """
    x1 = acc.partials(cmd.rows.mu, cmd.rows.tau, cmd.rows.rho)
    if cmd.sigma == "I":
        z = x1 @ acc.partials(cmd.cols.mu, cmd.cols.tau, cmd.cols.rho).T
    elif cmd.rows == cmd.cols:
        z = gram(factor(cmd.sigma), x1)
    else:
        z = gram(factor(cmd.sigma), x1, acc.partials(cmd.cols.mu, cmd.cols.tau, cmd.cols.rho))
    return Entity(omega, cmd, tuple(acc.labels(cmd.rows.tau, cmd.rows.rho, miss_names)),
                  tuple(acc.labels(cmd.cols.tau, cmd.cols.rho, miss_names)), z)


def transform(cmd: Command, acc: Accumulator, k: np.ndarray,
              mapper: Callable[..., np.ndarray] = accurate_map) -> np.ndarray:
    """Return K X₂ᵀ for an update command (UPC): X₂ = (μ, τ, ρ| of its columns, K a factor
    (then the command's matrix X₂ KᵀK X₂ᵀ has the factor K X₂ᵀ and is never formed) or, for
    σ₀ = I, the stored partials of its rows.

    ``mapper(K, X, X_lo)`` forms the product: by default in twice the working precision
    (:func:`tapp.estimation.factors.accurate_map`): the transformation to a new epoch is
    ill-conditioned after a swing-by (cond 1e13), and a plain product's rounding moved the
    covariances after the deep-space tape's periapsis epoch by 1e-9 to 1e-8 of their scale.
    """
    side = cmd.cols
    return mapper(k, acc.partials(side.mu, side.tau, side.rho),
                  acc.remainder(side.mu, side.tau, side.rho))

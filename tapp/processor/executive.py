"""The Executive Program of TAPP III (seed §4.2.2, Figure C-2): one entity from one command.

Z = (μ₁, τ₁, ρ₁ | [σ₀] | μ₂, τ₂, ρ₂) = X₁ [σ₀] X₂ᵀ with X = (μ, τ, ρ| the partials
accumulator; for σ₀ = I, Z = X₁ X₂ᵀ. The matrix options come from a callable so that the
expensive ones (Λ' needs the fit normal matrix inverted) are formed only when asked for.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tapp.processor.commands import Command
from tapp.processor.regression import symmetric
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
    """One evaluated output entity: its command, labels and matrix (rows x cols)."""

    omega: int
    command: Command
    rows: tuple[str, ...]
    cols: tuple[str, ...]
    matrix: np.ndarray
    budget: Budget | None = None


def evaluate(omega: int, cmd: Command, acc: Accumulator, matrix: Callable[[str], np.ndarray],
             miss_names: tuple[str, ...]) -> Entity:
    """Return the entity of ``cmd`` (seed §4.2.2).

    Parameters
    ----------
    omega : entity number (1-based).
    cmd : the command.
    acc : the partials accumulator in the current state.
    matrix : returns the (n_o, n_o) matrix option of a code of
        :data:`tapp.processor.commands.MATRICES` (not called for I).
    miss_names : names of the miss parameters (labels of isolated miss sets).
    """
    x1 = acc.partials(cmd.rows.mu, cmd.rows.tau, cmd.rows.rho)
    x2 = acc.partials(cmd.cols.mu, cmd.cols.tau, cmd.cols.rho)
    if cmd.sigma == "I":
        z = x1 @ x2.T
    else:
        z = x1 @ matrix(cmd.sigma) @ x2.T
        if cmd.rows == cmd.cols:
            z = symmetric(z)
    return Entity(omega, cmd, tuple(acc.labels(cmd.rows.tau, cmd.rows.rho, miss_names)),
                  tuple(acc.labels(cmd.cols.tau, cmd.cols.rho, miss_names)), z)

"""The linear guidance problem of a T32 tape: per recycle, the maps the samples go through.

:func:`build_problem` takes from the tape, for every recycle up to the last manoeuvre, the
transition T_k = ∂x^k/∂x^{k_prev}, the estimator's L_k and a factor of Σ_k = Λ'J̃Λ' (all in
x^k; the T32 tape carries Σ_k and Λ̄⁰ as factors, so they are positive semi-definite as read),
and at the manoeuvre recycles the targeted rows B_t of B_k = ∂m/∂x^k with the guidance gain

.. math::

    G = B_v^T (B_v B_v^T)^{-1}, \\qquad B_v = \\partial m_t / \\partial v^k,

the minimum-norm velocity change that nulls the targeted miss (the exact inverse when three
components are targeted). G is formed from the SVD of B_v with its rows scaled to unit norm
(miss components in km and s), which also measures its rank: a B_v whose scaled reciprocal
condition number is below :data:`MIN_RCOND` is refused. The model these maps drive is in
:mod:`tapp.guidance`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.errors import InputError
from tapp.guidance.execution import ExecutionErrors
from tapp.io.tape.t32 import T32

#: Units of a Cartesian orbit (x, y, z, vx, vy, vz), the only orbit TAPP II can correct.
CARTESIAN_UNITS = ("km", "km", "km", "km/s", "km/s", "km/s")
#: Smallest reciprocal condition number of the row-scaled ∂m_t/∂v accepted: below it the
#: targeted components are not independently controllable by a velocity change.
MIN_RCOND = 1e-10


@dataclass(frozen=True, slots=True, eq=False)
class Correction:
    """What a manoeuvre recycle needs besides the estimator maps.

    Attributes
    ----------
    B_target : (n_t, n_o) targeted rows of B_k = ∂m/∂x^k, (miss unit)/u_b.
    gain : (3, n_t) G, km/s per (miss unit): Δv = −G B_t x̂.
    """

    B_target: np.ndarray
    gain: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class Step:
    """One recycle of the tape, in the order of the tape.

    Attributes
    ----------
    number : recycle number i'.
    t_s : t_k, s from the tape epoch.
    transition : (n_o, n_o) T_k = ∂x^k/∂x^{k_prev}.
    LT : (n_o, n_o) L_k T_k, with L_k = ∂(a posteriori error)/∂(a priori error) in x^k.
    sigma_factor : (n_o, m) F with F Fᵀ = Σ_k = Λ'J̃Λ', u_a u_b: the covariance of the
        interval's tracking noise in the estimate, which the samples are drawn from.
    correction : the manoeuvre at this recycle, None for an estimate update only.
    """

    number: int
    t_s: float
    transition: np.ndarray
    LT: np.ndarray
    sigma_factor: np.ndarray
    correction: Correction | None

    @property
    def Sigma(self) -> np.ndarray:
        """Σ_k = F Fᵀ (n_o, n_o), u_a u_b."""
        return self.sigma_factor @ self.sigma_factor.T


@dataclass(frozen=True, slots=True, eq=False)
class Problem:
    """Everything a Monte Carlo sample or the linear covariance needs (module docstring).

    Attributes
    ----------
    velocity : positions of vx, vy, vz in x^k.
    lambda0_factor : (n_o, n_o) F with F Fᵀ = Λ̄⁰, the real-world a priori covariance at
        injection, in x^0.
    steps : the recycles up to the last manoeuvre (later ones change no outcome).
    B_final : (n_m, n_o) B of the last manoeuvre's recycle: the final miss is B_final d.
    miss_name, miss_unit : the n_m miss components.
    targets : positions of the targeted components in the miss vector.
    errors : the execution errors.
    """

    velocity: tuple[int, int, int]
    lambda0_factor: np.ndarray
    steps: tuple[Step, ...]
    B_final: np.ndarray
    miss_name: tuple[str, ...]
    miss_unit: tuple[str, ...]
    targets: tuple[int, ...]
    errors: ExecutionErrors

    @property
    def n_o(self) -> int:
        """Number of parameters."""
        return self.lambda0_factor.shape[0]

    @property
    def Lambda0(self) -> np.ndarray:
        """Λ̄⁰ = F Fᵀ (n_o, n_o), u_a u_b."""
        return self.lambda0_factor @ self.lambda0_factor.T

    @property
    def manoeuvres(self) -> tuple[Step, ...]:
        """The manoeuvre recycles, in time order."""
        return tuple(s for s in self.steps if s.correction is not None)


def _velocity(t32: T32, source: str) -> tuple[int, int, int]:
    par = t32.parameters
    units = tuple(par.unit[:t32.n_p])
    kinds = set(par.kind[:t32.n_p])
    if t32.n_p != 6 or units != CARTESIAN_UNITS or kinds != {"orbit"}:
        raise InputError(source, "parameters/unit", "a Cartesian orbit: six orbit parameters "
                         "x, y, z (km), vx, vy, vz (km/s), whose velocity a manoeuvre changes",
                         ", ".join(f"{n} ({u})" for n, u in zip(par.name[:t32.n_p], units,
                                                                 strict=True)))
    return 3, 4, 5


def _gain(B_target: np.ndarray, velocity: tuple[int, ...], number: int,
          target_names: tuple[str, ...], source: str) -> np.ndarray:
    """G (3, n_t) from the SVD of the row-scaled B_v; refuse a rank-deficient B_v."""
    bv = B_target[:, list(velocity)]
    scale = np.sqrt(np.einsum("ij,ij->i", bv, bv))
    if np.all(scale > 0):
        u, s, vt = np.linalg.svd(bv / scale[:, None], full_matrices=False)
        rcond = float(s[-1] / s[0])
    else:
        rcond = 0.0
    if rcond < MIN_RCOND:
        raise InputError(source, "targets.miss", f"miss components that the velocity at "
                         f"recycle {number} controls independently (∂m/∂v of rank "
                         f"{len(target_names)}, reciprocal condition >= {MIN_RCOND:g})",
                         f"{', '.join(target_names)}: reciprocal condition {rcond:.3g}")
    # pinv of B_v = D B̂: B̂⁺ D⁻¹ = V S⁻¹ Uᵀ D⁻¹
    return (vt.T / s) @ (u.T / scale[None, :])


def build_problem(t32: T32, targets: tuple[str, ...], manoeuvres: tuple[int, ...],
                  errors: ExecutionErrors, *, tape_source: str = "T32",
                  guide_source: str = "guidance") -> Problem:
    """Return the guidance problem of a tape (module docstring).

    Parameters
    ----------
    t32 : the tape.
    targets : names of the 2 or 3 targeted miss components (``t32.miss_name``).
    manoeuvres : recycle numbers i' of the manoeuvres (at least one).
    errors : the execution errors.
    tape_source, guide_source : the files named in errors.

    Raises
    ------
    InputError
        Orbit parameters that are not Cartesian position and velocity (naming the tape);
        a target that is not a miss component of the tape, a manoeuvre at a recycle the
        tape does not have, or targets the velocity cannot control (naming the guidance);
        a tape without recycles.
    """
    velocity = _velocity(t32, tape_source)
    miss = t32.miss_name
    rows = []
    for i, name in enumerate(targets):
        if name not in miss:
            raise InputError(guide_source, f"targets.miss[{i}]",
                             f"a miss component of the tape ({', '.join(miss)})", name)
        rows.append(miss.index(name))
    if not 2 <= len(rows) <= 3:
        raise InputError(guide_source, "targets.miss", "2 or 3 targeted miss components",
                         list(targets))
    numbers = [r.number for r in t32.recycles]
    if not numbers:
        raise InputError(tape_source, "recycles/number", "at least one recycle (the TAPP III "
                         "deck's recycle times are the manoeuvre times)", 0)
    for i, n in enumerate(manoeuvres):
        if n not in numbers:
            raise InputError(guide_source, f"manoeuvres.recycles[{i}]",
                             f"a recycle number of the tape (1..{len(numbers)})", n)
    if not manoeuvres:
        raise InputError(guide_source, "manoeuvres.recycles", "at least one manoeuvre", [])
    last = max(manoeuvres)
    steps = []
    for rc in t32.recycles[:numbers.index(last) + 1]:
        correction = None
        if rc.number in manoeuvres:
            bt = rc.B[rows]
            correction = Correction(bt, _gain(bt, velocity, rc.number, targets, guide_source))
        steps.append(Step(rc.number, rc.t_s, rc.transition, rc.L @ rc.transition,
                          rc.Sigma_factor.T, correction))
    return Problem(velocity, t32.Lambda0_real_factor.T, tuple(steps),
                   t32.recycles[numbers.index(last)].B, miss, t32.miss_unit, tuple(rows),
                   errors)


__all__ = ["CARTESIAN_UNITS", "MIN_RCOND", "Correction", "Problem", "Step", "build_problem"]

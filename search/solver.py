"""SEARCH: n-by-n Newton-Raphson targeting of any callable (seed TM 33-203, sections II-V).

The seed's SEARCH finds the initial conditions x of "a trajectory (or any computation) whose
end conditions are known". It runs a *nominal* case at x, then n *perturbed* cases
x + delta_j e_j, differences them into the matrix of partials A, inverts A with DINV, and runs
*applied* cases x + A^-1 (y_T - y), reusing the same A for ITER applied cases. After NPR sets
of partials without convergence it takes the *diverged* exit; a singular A takes the *singular*
exit; convergence (|y_k - y_Tk| <= eps_k for every k) takes the *converged* exit.

Names follow the seed's Table 1 where a reader may want to audit the port:

==============  ===============================  ==========================================
seed (Table 1)  here                             meaning
==============  ===============================  ==========================================
IV1..IV6        ``x0`` / ``x``                   independent variables
DV1..DV6        ``y``                            dependent variables, y = f(x)
DELI1..         ``increments``                   delta_j, perturbation forming the partials
EPSD1..         ``tolerances``                   eps_k, permissible error of y_k
CVRG1..         ``targets``                      y_T, the target values
ITER            ``iterations_per_partials``      applied cases per set of partials (3)
NPR             ``partial_sets``                 sets of partials before diverged exit (3)
AP, PRTLS       ``partials``                     analytic partials (first A, row-wise)
ORDER           ``len(x0)``                      n, of the "n by n search"
CONST, MASSI    ``mass=(m, k)``                  m' = m - k Delta (auxiliary calculation)
CH1..CH6        ``target_increments``            theta_i: y_Ti = y_0i + theta_i if != 0
PAR             ``partials_only``                first A only, then the converged exit
STATE           ``Case.kind/index/partial_set``  type of the case about to be run
FLAG            ``SearchResult.flag``            1 converged, 2 diverged, 3 singular
==============  ===============================  ==========================================

Choices where the seed is silent (each is documented again where it is implemented):

* The first nominal case is tested for convergence (unless ``partials_only``): if it already
  meets every tolerance, the converged exit is taken with no perturbed or applied case.
* A set of partials after the first takes the last applied case as its nominal (it has just
  been run at the current x); no extra nominal case is run, so ``n_nominal`` is always 1.
* Partials are differenced with the seed's formula a_ij = (y_ip - y_in) / (x_jp - x_jn), the
  denominator being the difference actually realised in floating point.

Opt-in improvements beyond the seed: Broyden's rank-one update of A after every applied case
(``broyden=True``) and step halving when an applied case increases the miss
(``step_halving=True``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from search.dinv import DEFAULT_PIVOT_RTOL, dinv
from search.errors import SearchInputError, SingularMatrixError

Status = Literal["converged", "diverged", "singular"]
CaseKind = Literal["nominal", "perturbed", "applied"]
PartialsSource = Literal["differenced", "analytic", "broyden"]

#: The seed's FLAG cell (Table 3): "1 for 1st non-standard return, etc." The three
#: non-standard exits are, in order, converged, diverged and singular (section III).
EXIT_FLAG: dict[str, int] = {"converged": 1, "diverged": 2, "singular": 3}

#: With ``step_halving=True``, how many times a step is halved (trials at 1/2, ..., 1/32 of
#: the full step) before the set of partials is abandoned as no longer giving descent.
MAX_STEP_HALVINGS = 5


@dataclass(frozen=True, slots=True)
class Case:
    """One run of the driven function f: the seed's STATE plus what went in and came out.

    Attributes
    ----------
    number : int
        1-based position of the case in the order the cases were run.
    kind : {"nominal", "perturbed", "applied"}
        Type of the case (STATE sign: + nominal or applied, - perturbed).
    partial_set : int
        1-based number of the set of partials in use or being computed (STATE decrement).
    index : int
        1-based ordinal of the perturbed or applied case within its set (STATE address): the
        perturbed variable j, or the iteration number of the applied case. 0 for the nominal.
    halving : int
        For applied cases with ``step_halving=True``: how many times the step was halved
        (0 = full step). 0 otherwise.
    x : numpy.ndarray, shape (n,)
        Independent variables the case was run with (read-only).
    y : numpy.ndarray, shape (n,)
        Dependent variables it returned (read-only).
    mass : float or None
        m' = m - k Delta passed to f with this case; None when ``mass`` was not given.
    """

    number: int
    kind: CaseKind
    partial_set: int
    index: int
    halving: int
    x: np.ndarray
    y: np.ndarray
    mass: float | None


@dataclass(frozen=True, slots=True)
class Step:
    r"""One Newton-Raphson step, taken just before the applied case it produced.

    Attributes
    ----------
    case : int
        ``Case.number`` of the applied case run with this step.
    index : int
        Iteration number within the set of partials (as ``Case.index``).
    halving : int
        Number of halvings applied to the full step (0 = full step A^-1 (y_T - y)).
    step : numpy.ndarray, shape (n,)
        Delta x, the change to the previous set of initial values (seed: "I.V. INCREMENTS
        (DELTAS)"): :math:`\Delta x = 2^{-h} A^{-1} (y_T - y)`.
    total_step : numpy.ndarray, shape (n,)
        x - x0, the difference between the new initial values and those of the first nominal
        case (seed: "TOTAL INCREMENTS").
    """

    case: int
    index: int
    halving: int
    step: np.ndarray
    total_step: np.ndarray


@dataclass(frozen=True, slots=True)
class PartialSet:
    """One matrix of partials A as used by SEARCH, with its inverse and the steps it gave.

    A new record starts with every set of partials and, with ``broyden=True``, with every
    rank-one update of A inside a set.

    Attributes
    ----------
    number : int
        1-based number of the set of partials (STATE decrement).
    update : int
        0 for the matrix as computed or given; k for the k-th Broyden update within the set.
    source : {"differenced", "analytic", "broyden"}
        Forward differences of perturbed cases, caller-supplied partials, or a Broyden update.
    after_case : int
        Number of cases run when this matrix was formed (for chronological reports).
    x_nominal, y_nominal : numpy.ndarray, shape (n,)
        The point the matrix was formed at (for a Broyden update: the point it was updated to).
    partials : numpy.ndarray, shape (n, n)
        A, a_ij = dy_i/dx_j.
    inverse : numpy.ndarray or None, shape (n, n)
        A^-1 from DINV; None when A was singular (singular exit).
    determinant : float
        det A from DINV (0.0 when DINV found A singular before finishing).
    steps : tuple of Step
        The steps computed with this matrix, in order.
    """

    number: int
    update: int
    source: PartialsSource
    after_case: int
    x_nominal: np.ndarray
    y_nominal: np.ndarray
    partials: np.ndarray
    inverse: np.ndarray | None
    determinant: float
    steps: tuple[Step, ...]


@dataclass(frozen=True, slots=True)
class History:
    """Every case run and every matrix of partials used, in the order they happened."""

    cases: tuple[Case, ...]
    partial_sets: tuple[PartialSet, ...]


@dataclass(frozen=True, slots=True)
class SearchInputs:
    """The validated inputs of a search (seed Table 1), kept with the result for reports.

    Arrays have shape (n,). ``analytic_partials`` is ``"none"``, ``"first set"`` (a matrix was
    given) or ``"every set"`` (a callable x -> A was given). ``mass`` is (m, k) or None.
    """

    x0: np.ndarray
    targets: np.ndarray
    target_increments: np.ndarray
    tolerances: np.ndarray
    increments: np.ndarray
    iterations_per_partials: int
    partial_sets: int
    partials_only: bool
    analytic_partials: Literal["none", "first set", "every set"]
    mass: tuple[float, float] | None
    broyden: bool
    step_halving: bool
    pivot_rtol: float


@dataclass(frozen=True, slots=True)
class SearchResult:
    """Outcome of :func:`solve`.

    Attributes
    ----------
    status : {"converged", "diverged", "singular"}
        Which of the seed's three non-standard exits was taken.
    x : numpy.ndarray, shape (n,)
        Final independent variables: the converged case; the point where A was singular; or,
        when diverged, the current point (the last applied case, or with ``step_halving`` the
        best one). For ``partials_only``: x0.
    y : numpy.ndarray, shape (n,)
        f at ``x``.
    targets : numpy.ndarray, shape (n,)
        y_T actually used (after the theta modifications).
    miss : numpy.ndarray, shape (n,)
        y - y_T.
    mass : float or None
        m' of the final case; None when ``mass`` was not given.
    n_nominal, n_perturbed, n_applied : int
        Number of cases of each kind that were run.
    inputs : SearchInputs
        The validated inputs.
    history : History
        Every case and every matrix of partials.
    """

    status: Status
    x: np.ndarray
    y: np.ndarray
    targets: np.ndarray
    miss: np.ndarray
    mass: float | None
    n_nominal: int
    n_perturbed: int
    n_applied: int
    inputs: SearchInputs
    history: History

    @property
    def flag(self) -> int:
        """The seed's FLAG: 1 converged, 2 diverged, 3 singular exit."""
        return EXIT_FLAG[self.status]

    @property
    def converged(self) -> bool:
        """True when the converged exit was taken."""
        return self.status == "converged"

    @property
    def n_cases(self) -> int:
        """Total number of cases run."""
        return self.n_nominal + self.n_perturbed + self.n_applied


def _frozen(a: np.ndarray) -> np.ndarray:
    out = np.array(a, dtype=np.float64, copy=True)
    out.setflags(write=False)
    return out


def _vector(name: str, value: ArrayLike, n: int | None) -> np.ndarray:
    """Return ``value`` as a finite float64 vector of length n (any length if n is None)."""
    v = np.asarray(value, dtype=np.float64)
    if v.ndim != 1 or v.size == 0:
        raise SearchInputError(name, "a non-empty 1-D sequence of numbers", f"shape {v.shape}")
    if n is not None and v.size != n:
        raise SearchInputError(
            name, f"length {n}, the length of x0 (SEARCH is n by n)", f"length {v.size}"
        )
    if not np.all(np.isfinite(v)):
        raise SearchInputError(name, "finite numbers", v.tolist())
    return v


def _count(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise SearchInputError(name, "an integer >= 1", repr(value))
    return int(value)


def _validate(
    x0,
    targets,
    tolerances,
    increments,
    iterations_per_partials,
    partial_sets,
    target_increments,
    partials,
    partials_only,
    mass,
    broyden,
    step_halving,
    pivot_rtol,
) -> SearchInputs:
    x0_v = _vector("x0", x0, None)
    n = x0_v.size
    targets_v = _vector("targets", targets, n)
    tolerances_v = _vector("tolerances", tolerances, n)
    if np.any(tolerances_v <= 0.0):
        raise SearchInputError("tolerances", "every tolerance > 0", tolerances_v.tolist())
    increments_v = _vector("increments", increments, n)
    if np.any(increments_v == 0.0):
        raise SearchInputError(
            "increments",
            "every increment non-zero (it divides the partials)",
            increments_v.tolist(),
        )
    theta = (
        np.zeros(n)
        if target_increments is None
        else _vector("target_increments", target_increments, n)
    )
    if partials is None:
        analytic: Literal["none", "first set", "every set"] = "none"
    elif callable(partials):
        analytic = "every set"
    else:
        _matrix("partials", partials, n)
        analytic = "first set"
    if mass is None:
        mass_t = None
    else:
        m_k = np.asarray(mass, dtype=np.float64)
        if m_k.shape != (2,) or not np.all(np.isfinite(m_k)):
            raise SearchInputError("mass", "a pair of finite numbers (m, k)", repr(mass))
        mass_t = (float(m_k[0]), float(m_k[1]))
    if not (np.isfinite(pivot_rtol) and pivot_rtol >= 0.0):
        raise SearchInputError("pivot_rtol", "a finite number >= 0", pivot_rtol)
    return SearchInputs(
        x0=_frozen(x0_v),
        targets=_frozen(targets_v),
        target_increments=_frozen(theta),
        tolerances=_frozen(tolerances_v),
        increments=_frozen(increments_v),
        iterations_per_partials=_count("iterations_per_partials", iterations_per_partials),
        partial_sets=_count("partial_sets", partial_sets),
        partials_only=bool(partials_only),
        analytic_partials=analytic,
        mass=mass_t,
        broyden=bool(broyden),
        step_halving=bool(step_halving),
        pivot_rtol=float(pivot_rtol),
    )


def _matrix(name: str, value: ArrayLike, n: int, where: str = "") -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != (n, n):
        raise SearchInputError(name, f"shape ({n}, {n}){where}", f"shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise SearchInputError(name, f"finite partials{where}", a.tolist())
    return a


@dataclass(slots=True)
class _OpenSet:
    """A matrix of partials whose steps are still being collected (private, mutable)."""

    number: int
    update: int
    source: PartialsSource
    after_case: int
    x_nominal: np.ndarray
    y_nominal: np.ndarray
    partials: np.ndarray
    inverse: np.ndarray | None = None
    determinant: float = 0.0
    steps: list[Step] = field(default_factory=list)

    def freeze(self) -> PartialSet:
        return PartialSet(
            number=self.number,
            update=self.update,
            source=self.source,
            after_case=self.after_case,
            x_nominal=_frozen(self.x_nominal),
            y_nominal=_frozen(self.y_nominal),
            partials=_frozen(self.partials),
            inverse=None if self.inverse is None else _frozen(self.inverse),
            determinant=self.determinant,
            steps=tuple(self.steps),
        )


class _Runner:
    """Runs cases of f, applies the auxiliary mass calculation, and records the history."""

    def __init__(self, f: Callable[..., ArrayLike], inputs: SearchInputs):
        self.f = f
        self.inputs = inputs
        self.n = inputs.x0.size
        self.cases: list[Case] = []
        self.sets: list[PartialSet] = []
        self.counts = {"nominal": 0, "perturbed": 0, "applied": 0}

    def mass_for(self, x: np.ndarray) -> float | None:
        """m' = m - k Delta, with Delta = |x - x0| (Euclidean) for the case about to be run."""
        if self.inputs.mass is None:
            return None
        m, k = self.inputs.mass
        return m - k * float(np.linalg.norm(x - self.inputs.x0))

    def run(self, kind: CaseKind, partial_set: int, index: int, halving: int, x: np.ndarray):
        mass = self.mass_for(x)
        x_case = _frozen(x)
        out = self.f(x_case) if mass is None else self.f(x_case, mass)
        y = np.asarray(out, dtype=np.float64)
        where = f"{kind} case {index} of partial set {partial_set} at x={x_case.tolist()}"
        if y.shape != (self.n,):
            raise SearchInputError(
                "f", f"an output of shape ({self.n},) for the {where}", f"shape {y.shape}"
            )
        if not np.all(np.isfinite(y)):
            raise SearchInputError("f", f"finite outputs for the {where}", f"y={y.tolist()}")
        self.counts[kind] += 1
        case = Case(
            number=len(self.cases) + 1,
            kind=kind,
            partial_set=partial_set,
            index=index,
            halving=halving,
            x=x_case,
            y=_frozen(y),
            mass=mass,
        )
        self.cases.append(case)
        return case


def solve(
    f: Callable[..., ArrayLike],
    x0: ArrayLike,
    targets: ArrayLike,
    *,
    tolerances: ArrayLike,
    increments: ArrayLike,
    iterations_per_partials: int = 3,
    partial_sets: int = 3,
    target_increments: ArrayLike | None = None,
    partials: ArrayLike | Callable[[np.ndarray], ArrayLike] | None = None,
    partials_only: bool = False,
    mass: tuple[float, float] | None = None,
    broyden: bool = False,
    step_halving: bool = False,
    pivot_rtol: float = DEFAULT_PIVOT_RTOL,
) -> SearchResult:
    r"""Find x with |f(x)_k - y_Tk| <= eps_k for every k by SEARCH's Newton-Raphson iteration.

    Each set of partials s = 1..``partial_sets`` is formed at the current point (x_n, y_n):

    .. math::

        a_{ij} \approx \frac{y_{ip} - y_{in}}{x_{jp} - x_{jn}}, \qquad
        x_p = x_n + \delta_j e_j, \quad j = 1..n

    and is then used for up to ``iterations_per_partials`` applied cases

    .. math::

        \Delta x = A^{-1} (y_T - y), \qquad x \leftarrow x + \Delta x

    with A^-1 from :func:`search.dinv.dinv`. Convergence is
    :math:`|y_k - y_{Tk}| \le \epsilon_k,\ k = 1..n` (seed section II).

    Parameters
    ----------
    f : callable
        ``f(x) -> y``, x and y float64 arrays of shape (n,) in the caller's units. When
        ``mass`` is given, ``f(x, m_prime) -> y`` instead, m' being the auxiliary mass of the
        case (see ``mass``). Its own exceptions propagate unchanged.
    x0 : array_like, shape (n,)
        Initial independent variables (IV1..IVn), first nominal case.
    targets : array_like, shape (n,)
        Target values y_T (CVRG1..); entries with a non-zero ``target_increments`` are
        replaced.
    tolerances : array_like, shape (n,)
        Permissible error eps_k > 0 of each dependent variable (EPSD1..), units of y_k.
    increments : array_like, shape (n,)
        Perturbation delta_j != 0 of each independent variable used to difference the partials
        (DELI1..), units of x_j.
    iterations_per_partials : int, optional
        Applied cases per set of partials (ITER; seed's standard value 3).
    partial_sets : int, optional
        Sets of partials before the diverged exit (NPR; seed's standard value 3).
    target_increments : array_like, shape (n,), optional
        theta_i (CH1..): where theta_i != 0, :math:`y_{Ti} = y_{0i} + \theta_i` with y_0 from the
        first nominal case.
    partials : array_like of shape (n, n), or callable, optional
        Analytic partials (AP = 1, PRTLS). A matrix is used as the first A instead of
        perturbing; later sets are differenced. A callable ``x -> A`` is used for every set,
        and no perturbed case is ever run.
    partials_only : bool, optional
        PAR != 0: run the first nominal case, form (and invert) the first A, then take the
        converged exit at x0 without any applied case.
    mass : (float, float), optional
        (m, k) of the auxiliary calculation :math:`m' = m - k\Delta`,
        :math:`\Delta = |x - x_0|` (Euclidean norm, units of x) for each case about to be run,
        x0 being the first nominal case. m' is passed to f and recorded with every case.
    broyden : bool, optional
        Improvement beyond the seed: after each accepted applied case inside a set, update A by
        Broyden's rank-one formula
        :math:`A \leftarrow A + (\Delta y - A\Delta x)\Delta x^T / (\Delta x^T \Delta x)`
        (Broyden 1965, Math. Comp. 19, 577) and re-invert it with DINV.
    step_halving : bool, optional
        Improvement beyond the seed: when an applied case increases the miss
        :math:`\|(y - y_T)/\epsilon\|_2` (tolerance-scaled), retry with half the step, up to
        ``MAX_STEP_HALVINGS`` times; if none decreases it, return to the best point and form a
        new set of partials there.
    pivot_rtol : float, optional
        Relative pivot threshold below which DINV declares A singular (singular exit).

    Returns
    -------
    SearchResult
        ``status`` in {"converged", "diverged", "singular"}, final ``x``, ``y``, counts of
        nominal/perturbed/applied cases, and the full ``history``.

    Raises
    ------
    SearchInputError
        For inputs of the wrong length (x0, targets, tolerances, increments and
        target_increments must all have length n), a zero increment, a tolerance <= 0,
        non-finite inputs, bad counts, partials of the wrong shape, or an output of f that is
        not finite or not of shape (n,) (the message names the case: kind, index, set and x).

    Notes
    -----
    Source: N. S. Newhall, "A Users' Guide for SEARCH and ITER", JPL TM 33-203 (1965),
    sections II (theory), III (Table 1, inputs and exits) and V-A (SRCH). Where the seed is
    silent the choices are listed in the module docstring.
    """
    inputs = _validate(
        x0,
        targets,
        tolerances,
        increments,
        iterations_per_partials,
        partial_sets,
        target_increments,
        partials,
        partials_only,
        mass,
        broyden,
        step_halving,
        pivot_rtol,
    )
    runner = _Runner(f, inputs)
    n = inputs.x0.size

    nominal = runner.run("nominal", 1, 0, 0, inputs.x0.copy())
    theta = inputs.target_increments
    # Seed section II: "If a non-zero number theta_i is input, SEARCH sets y_Ti = y_0i + theta_i".
    y_T = np.where(theta != 0.0, nominal.y + theta, inputs.targets)
    tol = inputs.tolerances

    def converged(y: np.ndarray) -> bool:
        return bool(np.all(np.abs(y - y_T) <= tol))

    def scaled_miss(y: np.ndarray) -> float:
        return float(np.linalg.norm((y - y_T) / tol))

    def finish(status: Status, case: Case) -> SearchResult:
        return SearchResult(
            status=status,
            x=case.x,
            y=case.y,
            targets=_frozen(y_T),
            miss=_frozen(case.y - y_T),
            mass=case.mass,
            n_nominal=runner.counts["nominal"],
            n_perturbed=runner.counts["perturbed"],
            n_applied=runner.counts["applied"],
            inputs=inputs,
            history=History(cases=tuple(runner.cases), partial_sets=tuple(runner.sets)),
        )

    def invert(open_set: _OpenSet) -> bool:
        """DINV on the set's A; records inverse and det; False if A is singular."""
        try:
            d = dinv(open_set.partials, pivot_rtol=inputs.pivot_rtol)
        except SingularMatrixError:
            runner.sets.append(open_set.freeze())
            return False
        open_set.inverse = d.inverse
        open_set.determinant = d.determinant
        return True

    if not inputs.partials_only and converged(nominal.y):
        return finish("converged", nominal)

    current = nominal  # the nominal of the next set of partials
    for s in range(1, inputs.partial_sets + 1):
        # --- Form the matrix of partials A at the current point.
        if inputs.analytic_partials == "every set":
            A = _matrix("partials", partials(current.x), n, f" from partials(x) at x={current.x}")
            source: PartialsSource = "analytic"
        elif inputs.analytic_partials == "first set" and s == 1:
            A = _matrix("partials", partials, n)
            source = "analytic"
        else:
            A = np.empty((n, n))
            for j in range(n):
                x_p = current.x.copy()
                x_p[j] += inputs.increments[j]
                perturbed = runner.run("perturbed", s, j + 1, 0, x_p)
                # a_ij = (y_ip - y_in) / (x_jp - x_jn), with the difference actually realised.
                A[:, j] = (perturbed.y - current.y) / (perturbed.x[j] - current.x[j])
            source = "differenced"
        open_set = _OpenSet(s, 0, source, len(runner.cases), current.x, current.y, A.copy())
        if not invert(open_set):
            return finish("singular", current)
        if inputs.partials_only:
            runner.sets.append(open_set.freeze())
            return finish("converged", current)

        # --- Applied cases with this A (and its Broyden updates).
        for it in range(1, inputs.iterations_per_partials + 1):
            full_step = open_set.inverse @ (y_T - current.y)
            accepted = None
            for h in range(MAX_STEP_HALVINGS + 1 if inputs.step_halving else 1):
                dx = full_step * 0.5**h
                x_new = current.x + dx
                applied_number = len(runner.cases) + 1
                open_set.steps.append(
                    Step(applied_number, it, h, _frozen(dx), _frozen(x_new - inputs.x0))
                )
                trial = runner.run("applied", s, it, h, x_new)
                if converged(trial.y):
                    runner.sets.append(open_set.freeze())
                    return finish("converged", trial)
                if not inputs.step_halving or scaled_miss(trial.y) < scaled_miss(current.y):
                    accepted = trial
                    break
            if accepted is None:
                # Step halving found no decrease: keep the best point, form fresh partials.
                break
            if inputs.broyden and it < inputs.iterations_per_partials:
                dx_taken = accepted.x - current.x
                dy_taken = accepted.y - current.y
                A = open_set.partials
                A_new = A + np.outer(dy_taken - A @ dx_taken, dx_taken) / (dx_taken @ dx_taken)
                runner.sets.append(open_set.freeze())
                after = len(runner.cases)
                update = open_set.update + 1
                open_set = _OpenSet(s, update, "broyden", after, accepted.x, accepted.y, A_new)
                if not invert(open_set):
                    return finish("singular", accepted)
            current = accepted
        runner.sets.append(open_set.freeze())
    return finish("diverged", current)

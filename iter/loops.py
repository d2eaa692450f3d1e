"""ITER loops and the cases they generate (seed section VI, "ITER").

A loop varies ``n`` named parameters over ``sets`` cases (the seed's N and SETS); it is the
seed's m x n matrix :math:`[a_{ij}]` with m = ``sets``, one row per case:

* **type 1**: all m x n values are given, row-wise, in ``vary`` (the seed's VARY).
* **type 2**: only the first row is given in ``vary``, with n increments ``delta`` (the seed's
  DELTA); row k follows from the previous one,

  .. math:: a_{kj} = a_{k-1,j} + \\delta_j, \\quad j = 1, 2, \\dots, n,

  which is computed here in closed form as :math:`a_{kj} = a_{1j} + (k - 1)\\,\\delta_j`:
  equal in exact arithmetic, and free of the rounding that k successive additions would pile up.

Loops nest to any depth, outermost first: the inner loop restarts for each case of the outer
one (the seed's RESET), so cases come out outer-major, like nested DO loops. The seed's CASE 2
(30 days x 5 azimuths = 150 runs) gives day 1 with its five azimuths, then day 2 with its five,
and so on.

Case numbers here start at 0 (the seed counts from 1).
"""

from __future__ import annotations

import itertools
import keyword
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import SweepInputError

#: ``source`` of the errors raised while building a loop in code; the sweep-file reader
#: re-raises them with the file name and the loop's position.
LOOP_SOURCE = "loop"
#: Most cases a sweep may have (each case is a row held in memory and in the results file);
#: checked before any case is generated.
MAX_CASES = 1_000_000


def _as_numbers(field: str, values: Sequence[object]) -> tuple[float, ...]:
    """Return ``values`` as finite floats, or raise naming ``field``."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence):
        raise SweepInputError(LOOP_SOURCE, field, "a list of numbers", values)
    out = []
    for j, value in enumerate(values):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise SweepInputError(LOOP_SOURCE, f"{field}[{j}]", "a number", value)
        if not math.isfinite(value):
            raise SweepInputError(LOOP_SOURCE, f"{field}[{j}]", "a finite number", value)
        out.append(float(value))
    return tuple(out)


@dataclass(frozen=True, slots=True)
class Loop:
    """One ITER loop: ``sets`` cases of ``n = len(names)`` varied parameters.

    Parameters
    ----------
    type : int
        1 (every row given in ``vary``) or 2 (first row in ``vary``, increments in ``delta``).
    names : tuple of str
        The n varied parameters, in column order; Python identifiers carrying their unit
        (``azimuth_deg``). Bodies receive them as keyword arguments.
    sets : int
        Number of cases m (the seed's SETS), at least 1.
    vary : tuple of float
        Type 1: the m x n matrix row-wise, length m*n. Type 2: the first row, length n.
    delta : tuple of float or None
        Type 2 only: the n increments added from one case to the next.

    Raises
    ------
    SweepInputError
        With ``source="loop"`` and the field at fault; the sweep-file reader puts the file
        name and the loop's position in its place.
    """

    type: int
    names: tuple[str, ...]
    sets: int
    vary: tuple[float, ...]
    delta: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if isinstance(self.type, bool) or self.type not in (1, 2):
            raise SweepInputError(LOOP_SOURCE, "type", "1 (table) or 2 (start + delta)",
                                  self.type)
        if isinstance(self.names, str) or not isinstance(self.names, Sequence):
            raise SweepInputError(LOOP_SOURCE, "names", "a list of parameter names",
                                  self.names)
        if len(self.names) == 0:
            raise SweepInputError(LOOP_SOURCE, "names", "at least one parameter name", [])
        for j, name in enumerate(self.names):
            if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
                raise SweepInputError(LOOP_SOURCE, f"names[{j}]",
                                      "a Python identifier such as azimuth_deg", name)
        if len(set(self.names)) != len(self.names):
            raise SweepInputError(LOOP_SOURCE, "names", "distinct names", list(self.names))
        if isinstance(self.sets, bool) or not isinstance(self.sets, int) or self.sets < 1:
            raise SweepInputError(LOOP_SOURCE, "sets", "a whole number of cases >= 1",
                                  self.sets)
        if self.sets > MAX_CASES:
            raise SweepInputError(LOOP_SOURCE, "sets", f"at most {MAX_CASES:,} cases",
                                  self.sets)
        n = len(self.names)
        vary = _as_numbers("vary", self.vary)
        if self.type == 1:
            if self.delta is not None:
                raise SweepInputError(LOOP_SOURCE, "delta",
                                      "no delta for type 1 (only type 2 takes increments)",
                                      self.delta)
            if len(vary) != self.sets * n:
                raise SweepInputError(
                    LOOP_SOURCE, "vary",
                    f"sets x n = {self.sets} x {n} = {self.sets * n} values, row-wise",
                    f"{len(vary)} values")
            delta = None
        else:
            if len(vary) != n:
                raise SweepInputError(LOOP_SOURCE, "vary",
                                      f"the first row only: n = {n} values for type 2",
                                      f"{len(vary)} values")
            if self.delta is None:
                raise SweepInputError(LOOP_SOURCE, "delta",
                                      f"n = {n} increments for type 2", "nothing")
            delta = _as_numbers("delta", self.delta)
            if len(delta) != n:
                raise SweepInputError(LOOP_SOURCE, "delta", f"n = {n} increments",
                                      f"{len(delta)} values")
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "vary", vary)
        object.__setattr__(self, "delta", delta)

    @property
    def n(self) -> int:
        """Number of parameters varied per case (the seed's N)."""
        return len(self.names)

    def table(self) -> np.ndarray:
        """Return the (sets, n) matrix :math:`[a_{ij}]` of this loop's values, float64."""
        if self.type == 1:
            return np.asarray(self.vary, dtype=np.float64).reshape(self.sets, self.n)
        k = np.arange(self.sets, dtype=np.float64)[:, np.newaxis]
        return np.asarray(self.vary) + k * np.asarray(self.delta)


@dataclass(frozen=True, slots=True)
class Case:
    """One run of the body: its number in the sweep and the values of every varied parameter.

    Parameters
    ----------
    index : int
        Position in the outer-major case order, from 0.
    names : tuple of str
        Every varied parameter, outermost loop first.
    values : tuple of float
        Their values for this case, same order as ``names``.
    """

    index: int
    names: tuple[str, ...]
    values: tuple[float, ...]

    def kwargs(self) -> dict[str, float]:
        """Return the varied values as keyword arguments for the body."""
        return dict(zip(self.names, self.values, strict=True))


def varied_names(loops: Sequence[Loop]) -> tuple[str, ...]:
    """Return every varied name, outermost loop first; raise if a name is used twice.

    Raises
    ------
    SweepInputError
        Field ``loop[i].names`` when loop i reuses a name of an outer loop.
    """
    names: list[str] = []
    for i, loop in enumerate(loops):
        for name in loop.names:
            if name in names:
                raise SweepInputError(LOOP_SOURCE, f"loop[{i}].names",
                                      "names not already varied by an outer loop", name)
            names.append(name)
    return tuple(names)


def case_count(loops: Sequence[Loop]) -> int:
    """Return the number of cases of the nest: the product of every loop's ``sets``."""
    return math.prod(loop.sets for loop in loops)


def check_case_count(loops: Sequence[Loop], source: str = LOOP_SOURCE) -> int:
    """Return the number of cases of the nest if at most :data:`MAX_CASES`, else raise.

    Raises
    ------
    SweepInputError
        Field ``loop``: the message gives the number of cases the loops would make.
    """
    n = case_count(loops)
    if n > MAX_CASES:
        sets = " x ".join(str(loop.sets) for loop in loops)
        raise SweepInputError(source, "loop", f"at most {MAX_CASES:,} cases in all (lower "
                              "the sets of a loop)", f"{sets} = {n:,} cases")
    return n


def generate_cases(loops: Sequence[Loop]) -> tuple[Case, ...]:
    """Return every case of nested ITER loops, outer-major (the seed's nesting order).

    Parameters
    ----------
    loops : sequence of Loop
        Outermost first; at least one.

    Returns
    -------
    tuple of Case
        ``case_count(loops)`` cases; case ``index`` holds, for each loop, row
        ``k_level`` of its table, where the innermost ``k`` varies fastest.

    Raises
    ------
    SweepInputError
        No loops, or a name varied by two loops.

    Examples
    --------
    >>> days = Loop(type=2, names=("day",), sets=2, vary=(5730.0,), delta=(1.0,))
    >>> azimuths = Loop(type=1, names=("azimuth_deg",), sets=2, vary=(96.0, 99.0))
    >>> [c.values for c in generate_cases([days, azimuths])]
    [(5730.0, 96.0), (5730.0, 99.0), (5731.0, 96.0), (5731.0, 99.0)]
    """
    if len(loops) == 0:
        raise SweepInputError(LOOP_SOURCE, "loop", "at least one loop", [])
    names = varied_names(loops)
    check_case_count(loops)
    tables = [loop.table() for loop in loops]
    cases = []
    for index, rows in enumerate(itertools.product(*(range(loop.sets) for loop in loops))):
        values = tuple(float(v) for table, k in zip(tables, rows, strict=True)
                       for v in table[k])
        cases.append(Case(index=index, names=names, values=values))
    return tuple(cases)

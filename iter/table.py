"""The outcome of each case and the results table they make up (pure data, no I/O).

Table columns, in order: ``case`` (the case index), every varied value (outermost loop
first), every output (in order of first appearance by case index), ``status``, ``error`` and
``elapsed_s`` (wall time of the body for that case).

Status codes (``CaseStatus``):

====  ========  ==========================================================
code  name      meaning
====  ========  ==========================================================
0     ok        the body returned its outputs
1     failed    the body raised, the program exited non-zero or timed out,
                or the outputs were not a mapping of named scalars
====  ========  ==========================================================

An output column holds floats (NaN where missing) when every value in it is a number or null,
and text ("" where missing) otherwise.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

#: Column names the table itself uses; neither varied names nor outputs may take them.
RESERVED_COLUMNS = ("case", "status", "error", "elapsed_s")

OutputValue = float | str


class CaseStatus(enum.IntEnum):
    """Status code of one case; see the module docstring for the table."""

    OK = 0
    FAILED = 1


@dataclass(frozen=True, slots=True)
class CaseResult:
    """What one case gave: its values, its outputs or its error.

    Parameters
    ----------
    index : int
        Case index in the sweep's outer-major order.
    values : tuple of float
        The varied values, in the sweep's name order.
    outputs : mapping of str to float or str
        Named scalar outputs; empty for a failed case.
    status : CaseStatus
        OK or FAILED.
    error : str
        ``"ExceptionType: message"`` for a failed case, ``""`` otherwise.
    elapsed_s : float
        Wall time spent in the body, s. Not compared by ``==``, so two runs of the same
        sweep give equal rows.
    """

    index: int
    values: tuple[float, ...]
    outputs: Mapping[str, OutputValue]
    status: CaseStatus
    error: str = ""
    elapsed_s: float = field(default=math.nan, compare=False)


def output_is_numeric(rows: tuple[CaseResult, ...], name: str) -> bool:
    """Return True when every value of output ``name`` in ``rows`` is a float."""
    return all(isinstance(row.outputs[name], float) for row in rows if name in row.outputs)


@dataclass(frozen=True, slots=True)
class ResultTable:
    """Every case's result, sorted by case index, with the column names.

    Parameters
    ----------
    names : tuple of str
        The varied names, outermost loop first.
    rows : tuple of CaseResult
        Sorted by ``index``; each index at most once.
    """

    names: tuple[str, ...]
    rows: tuple[CaseResult, ...]

    def __post_init__(self) -> None:
        indices = [row.index for row in self.rows]
        if indices != sorted(set(indices)):
            raise ValueError("ResultTable rows must be sorted by case index, each index once")

    @classmethod
    def from_results(cls, names: tuple[str, ...],
                     results: Mapping[int, CaseResult]) -> ResultTable:
        """Return the table of ``results`` (keyed by case index) sorted by case index."""
        return cls(names=names, rows=tuple(results[k] for k in sorted(results)))

    @property
    def output_names(self) -> tuple[str, ...]:
        """Every output name, in order of first appearance by case index."""
        seen: dict[str, None] = {}
        for row in self.rows:
            seen.update(dict.fromkeys(row.outputs))
        return tuple(seen)

    @property
    def n_succeeded(self) -> int:
        """Number of cases with status OK."""
        return sum(row.status is CaseStatus.OK for row in self.rows)

    @property
    def n_failed(self) -> int:
        """Number of cases with status FAILED."""
        return sum(row.status is CaseStatus.FAILED for row in self.rows)

    def column(self, name: str) -> np.ndarray:
        """Return one column, shape (len(rows),).

        ``case`` and ``status`` are int64, varied values and ``elapsed_s`` float64, outputs
        float64 (NaN where missing) or str (``""`` where missing), ``error`` str.

        Raises
        ------
        KeyError
            ``name`` is not a column of this table.
        """
        if name == "case":
            return np.array([row.index for row in self.rows], dtype=np.int64)
        if name == "status":
            return np.array([int(row.status) for row in self.rows], dtype=np.int64)
        if name == "error":
            return np.array([row.error for row in self.rows], dtype=object)
        if name == "elapsed_s":
            return np.array([row.elapsed_s for row in self.rows], dtype=np.float64)
        if name in self.names:
            j = self.names.index(name)
            return np.array([row.values[j] for row in self.rows], dtype=np.float64)
        if name in self.output_names:
            if output_is_numeric(self.rows, name):
                return np.array([row.outputs.get(name, math.nan) for row in self.rows],
                                dtype=np.float64)
            return np.array([_as_text(row.outputs.get(name, "")) for row in self.rows],
                            dtype=object)
        raise KeyError(f"no column {name!r}; columns are {self.columns}")

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column name, in table order."""
        return ("case", *self.names, *self.output_names, "status", "error", "elapsed_s")


def _as_text(value: OutputValue) -> str:
    return value if isinstance(value, str) else repr(value)

"""A sweep: nested ITER loops plus the body run for each case."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass

from .body import Body
from .errors import SweepInputError
from .loops import Case, Loop, case_count, check_case_count, generate_cases, varied_names
from .table import RESERVED_COLUMNS


@dataclass(frozen=True, slots=True)
class Sweep:
    """Nested loops (outermost first) and a body; validated on construction.

    Parameters
    ----------
    loops : tuple of Loop
        Outermost first; at least one.
    body : CallableBody or ProgramBody
        Run once per case.
    source : str
        Where the sweep came from (the sweep file path); used in error messages.
    document : mapping or None
        The sweep file contents as parsed, stored in the results as JSON; None for a sweep
        built in code, which then stores :meth:`definition` instead.

    Raises
    ------
    SweepInputError
        No loop, a name varied twice, a varied name that is also a constant or a file, a
        file that is also a constant, a name taken by a table column (``case``, ``status``,
        ``error``, ``elapsed_s``), or more than :data:`iter.loops.MAX_CASES` cases.
    """

    loops: tuple[Loop, ...]
    body: Body
    source: str = "<sweep>"
    document: Mapping[str, object] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "loops", tuple(self.loops))
        if not self.loops:
            raise SweepInputError(self.source, "loop", "at least one [[loop]] table", [])
        try:
            varied_names(self.loops)
        except SweepInputError as exc:
            raise SweepInputError(self.source, exc.field, exc.expected, exc.got) from None
        for name in self.body.files:
            if name in self.body.constants:
                raise SweepInputError(self.source, f"body.files.{name}",
                                      "a name that is not also in body.constants", name)
        for i, loop in enumerate(self.loops):
            for name in loop.names:
                if name in self.body.constants or name in self.body.files:
                    raise SweepInputError(self.source, f"loop[{i}].names", "names that are "
                                          "not also body.constants or body.files", name)
                if name in RESERVED_COLUMNS:
                    raise SweepInputError(self.source, f"loop[{i}].names",
                                          f"a name other than {list(RESERVED_COLUMNS)}", name)
        check_case_count(self.loops, self.source)

    @property
    def names(self) -> tuple[str, ...]:
        """Every varied name, outermost loop first (the table's input columns)."""
        return varied_names(self.loops)

    @property
    def n_cases(self) -> int:
        """Number of cases: the product of every loop's ``sets``."""
        return case_count(self.loops)

    def cases(self) -> tuple[Case, ...]:
        """Return every case, outer-major (see :func:`iter.loops.generate_cases`)."""
        return generate_cases(self.loops)

    def check_case(self, case: Case) -> None:
        """Raise if ``case`` cannot run: the body's reference, its files, and (a callable)
        the arguments and the function's own input check (:meth:`CallableBody.check_case`).

        Called on the first case to run, before any runs: an input error there, in a file the
        body reads or in the sweep file, would be hit by every case.
        """
        fields = {name: f"loop[{i}].names" for i, loop in enumerate(self.loops)
                  for name in loop.names}
        self.body.check_case(case, self.source, fields)

    def definition(self) -> dict[str, object]:
        """Return the sweep as a canonical sweep-file document (defaults filled in)."""
        loops = []
        for loop in self.loops:
            table: dict[str, object] = {"type": loop.type, "names": list(loop.names),
                                        "sets": loop.sets, "vary": list(loop.vary)}
            if loop.delta is not None:
                table["delta"] = list(loop.delta)
            loops.append(table)
        return {"body": self.body.definition(), "loop": loops}

    def definition_json(self) -> str:
        """Return :meth:`definition` as canonical JSON; equal JSON means the same cases."""
        return json.dumps(self.definition(), sort_keys=True, default=str)

    def contents_json(self) -> str:
        """Return the sweep file contents as JSON (the definition for a sweep built in code)."""
        document = self.definition() if self.document is None else self.document
        return json.dumps(document, sort_keys=True, default=str)

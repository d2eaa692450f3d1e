"""Read a sweep file (TOML) into a :class:`~iter.sweep.Sweep`.

Format
------
::

    [sweep]                      # optional, free text kept with the results
    description = "Five launch azimuths on each of 30 days (seed VI, CASE 2)"
    # title = "..."

    [body]                       # exactly one of `callable` or `program`
    callable = "tapp.targeting.launch_azimuth:launch_azimuth_case"   # "module:function"
    # program = ["tapp", "propagate"]                # argv of a command-line program
    # json = true          # program only: append --json - (default true)
    # dashes = false       # program only: --azimuth-deg instead of --azimuth_deg (default false)
    # timeout_s = 600.0    # wall-time limit per case, s: program default 3600; a callable
    #                      # with a limit runs each case in a child process (default: none)

    [body.constants]             # optional: passed unchanged to every case
    latitude_deg = 28.5

    [body.files]                 # optional: paths the body reads, passed like constants,
    stations = "stations.toml"   # relative to THIS FILE's folder; each must exist

    [[loop]]                     # one table per loop, OUTERMOST FIRST
    type = 2                     # the seed's TYPE: 1 = table, 2 = start + increments (default 1)
    names = ["launch_day"]       # the varied parameters, n = len(names); units in the names
    sets = 30                    # the seed's SETS: number of cases m of this loop
    vary = [5730.0]              # type 1: m*n values row-wise; type 2: the first row (n values)
    delta = [1.0]                # type 2 only: n increments (the seed's DELTA)
    # n = 1                      # optional, the seed's N: checked against len(names)

    [[loop]]
    type = 1
    names = ["azimuth_deg"]
    sets = 5
    vary = [96.0, 99.0, 102.0, 105.0, 108.0]

Inner loops restart for every case of the outer loop, so the cases come out outer-major:
``30 x 5 = 150`` cases, the five azimuths of the first day first. A varied value reaches a
callable body as a keyword argument (a float) and a program as ``--name value``.

Paths
-----
A path in a sweep file is taken from the sweep file's folder, as every input file of the
project takes the paths inside it from its own folder, so a sweep runs the same from any
working directory. Each entry of ``[body.files]`` reaches the body as an absolute path (a
keyword argument of a callable, ``--name PATH`` for a program) and must exist;
``body.program[0]``, when it is a path (``"./run.sh"``, ``"bin/body"``) rather than the name
of a program on PATH, is taken from the sweep file's folder too. Absolute paths are kept.
Constants are passed unchanged, so a path a body takes belongs in ``[body.files]``, never in
``[body.constants]``. A document parsed without a file (:func:`parse_sweep`) takes its paths
from ``base_dir``, the current directory by default.

Checks before anything runs
---------------------------
Reading the file checks its fields, that the callable imports (or the program is found) and
that every file exists. Running it (:func:`iter.run.run_sweep`) then checks the first case's
inputs before any case runs or anything is written: a callable must take every constant,
file and varied name as a keyword argument and be given every argument it needs, and its own
input check (:func:`iter.body.input_check`), if it offers one, must pass. An input error
there would be the error of every case; errors a case meets later are recorded in its row.

The file is validated against one declared schema, :class:`SweepFile` (``iter.schema``):
unknown keys and tables are errors (a typo must not silently fall back to a default), and
booleans are not numbers nor numbers strings. Errors name the file and the field, e.g.
``loop[1].vary``, where ``loop[0]`` is the first ``[[loop]]`` table.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

from pydantic import Field, model_validator

from .body import Body, CallableBody, ProgramBody, names_a_path
from .errors import SweepInputError
from .inputfile import read_toml
from .loops import Loop
from .schema import Invalid, Schema, validate
from .sweep import Sweep

_Positive = Annotated[float, Field(gt=0)]
_Scalar = str | int | float | bool


class SweepMeta(Schema):
    """``[sweep]``: free text kept with the results."""

    title: str = Field("", description="A title.")
    description: str = Field("", description="What the sweep is.")


class BodyTable(Schema):
    """``[body]``: what runs for each case: exactly one of ``callable`` or ``program``."""

    callable: str | None = Field(None, description="A Python function \"module:function\", "
                                 "called with the constants, files and varied values as "
                                 "keyword arguments; it returns a table of named outputs.")
    program: Annotated[list[Annotated[str, Field(min_length=1)]], Field(min_length=1)] | None \
        = Field(None, description="The argv of a program, run with --name value for each "
                "constant, file and varied value; its stdout is one JSON object of outputs.")
    json_option: bool | None = Field(None, alias="json", description="Program only: append "
                                     "--json - (the outputs on standard output); default true.")
    dashes: bool | None = Field(None, description="Program only: --azimuth-deg instead of "
                                "--azimuth_deg; default false.")
    timeout_s: _Positive | None = Field(None, description="Wall-time limit of a case (a "
                                        "callable with one runs in a child process); default: "
                                        "3600 s for a program, none for a callable.")
    constants: dict[str, Any] = Field({}, description="Arguments passed unchanged to every "
                                      "case, by name.")
    files: dict[str, Annotated[str, Field(min_length=1)]] = Field(
        {}, description="Paths the body reads, by argument name, relative to this file's "
        "folder; each must exist.")

    @model_validator(mode="after")
    def _one_kind(self) -> BodyTable:
        for table in ("constants", "files"):
            for name in getattr(self, table):
                if not name.isidentifier():
                    raise Invalid("a Python identifier as the name", name, f"{table}.{name}")
        if (self.callable is None) == (self.program is None):
            raise Invalid("exactly one of callable or program",
                          "both" if self.callable is not None else "neither")
        if self.callable is not None:
            for key, attr in _PROGRAM_ONLY_KEYS.items():
                if getattr(self, attr) is not None:
                    raise Invalid("no such key for a callable body (program only)",
                                  getattr(self, attr), key)
        else:
            for name, value in self.constants.items():
                if not isinstance(value, _Scalar):
                    raise Invalid("a string, number or boolean for a program body", value,
                                  f"constants.{name}")
        return self


class LoopTable(Schema):
    """``[[loop]]``: one loop, outermost first (the seed's TYPE, N, SETS, VARY, DELTA); inner
    loops restart for every case of the outer ones."""

    type: int = Field(1, description="1: every value given in vary; 2: a start and "
                      "increments.", json_schema_extra={"enum": [1, 2]})
    names: list[str] = Field(description="The varied arguments; units in the names.")
    n: int | None = Field(None, description="The seed's N, checked against len(names).")
    sets: int = Field(description="Cases of this loop.", json_schema_extra={"minimum": 1})
    vary: list[float] = Field(description="Type 1: sets x len(names) values, row by row; type "
                              "2: the first row.")
    delta: list[float] | None = Field(None, description="Type 2: the increment of each name.")


class SweepFile(Schema):
    """Schema of a sweep file (module docstring)."""

    sweep: SweepMeta = Field(SweepMeta(), description="Free text.")
    body: BodyTable = Field(description="What runs for each case.")
    loop: Annotated[list[LoopTable], Field(min_length=1)] = Field(
        description="The loops, outermost first.")


#: Keys of a program body only, and their attributes.
_PROGRAM_ONLY_KEYS = {"json": "json_option", "dashes": "dashes"}


def load_sweep(path: str | Path, *, check_body: bool = True) -> Sweep:
    """Return the sweep described by the TOML file at ``path``.

    Parameters
    ----------
    path : str or Path
        The sweep file.
    check_body : bool
        Import the callable (or look up the program) now, so a bad name fails before any
        case runs.

    Raises
    ------
    SweepInputError
        The file is missing or not TOML, or a field is missing or invalid; the message
        names the file and the field.
    """
    source = str(path)
    document = read_toml(path, "sweep file")
    return parse_sweep(document, source=source, check_body=check_body,
                       base_dir=Path(path).parent)


def parse_sweep(document: Mapping[str, object], *, source: str = "<sweep>",
                check_body: bool = True, base_dir: str | Path = ".") -> Sweep:
    """Return the sweep described by a parsed sweep-file ``document`` (see module docstring).

    The document is validated against :class:`SweepFile` (``iter.schema``: unknown keys are
    errors, booleans are not numbers, ...), then the loops and the body are built, with the
    paths of the body taken from ``base_dir`` (the sweep file's folder; see "Paths").

    Raises
    ------
    SweepInputError
        A field is missing or invalid; ``source`` names the file in the message.
    """
    doc = validate(SweepFile, document, source)
    body = _body(doc.body, Path(base_dir))
    loops = tuple(_loop(source, i, table) for i, table in enumerate(doc.loop))
    sweep = Sweep(loops=loops, body=body, source=source, document=dict(document))
    if check_body:
        body.check(source)
    return sweep


def _from_folder(base_dir: Path, path: str) -> str:
    """Return ``path`` as an absolute path, taken from ``base_dir`` when it is relative."""
    return os.path.abspath(base_dir / path)


def _body(table: BodyTable, base_dir: Path) -> Body:
    constants = dict(table.constants)
    files = {name: _from_folder(base_dir, path) for name, path in table.files.items()}
    if table.callable is not None:
        return CallableBody(target=table.callable, constants=constants,
                            timeout_s=table.timeout_s, files=files)
    program, *args = table.program
    if names_a_path(program):
        program = _from_folder(base_dir, program)
    return ProgramBody(argv=(program, *args), constants=constants,
                       json_option=True if table.json_option is None else table.json_option,
                       dashes=bool(table.dashes), timeout_s=table.timeout_s, files=files)


def _loop(source: str, i: int, table: LoopTable) -> Loop:
    where = f"loop[{i}]"
    try:
        loop = Loop(type=table.type, names=tuple(table.names), sets=table.sets,
                    vary=tuple(table.vary),
                    delta=None if table.delta is None else tuple(table.delta))
    except SweepInputError as exc:
        raise SweepInputError(source, f"{where}.{exc.field}", exc.expected, exc.got) from None
    if table.n is not None and table.n != loop.n:
        raise SweepInputError(source, f"{where}.n", f"len(names) = {loop.n}", table.n)
    return loop

"""Read a sweep file (TOML) into a :class:`~iter.sweep.Sweep`.

Format
------
::

    [sweep]                      # optional, free text kept with the results
    description = "Five launch azimuths on each of 30 days (seed VI, CASE 2)"

    [body]                       # exactly one of `callable` or `program`
    callable = "iter.examples:launch_azimuth_case"   # "module:function"
    # program = ["tapp", "propagate"]                # argv of a command-line program
    # json = true          # program only: append --json (default true)
    # dashes = false       # program only: --azimuth-deg instead of --azimuth_deg (default false)
    # timeout_s = 600.0    # wall-time limit per case, s: program default 3600; a callable
    #                      # with a limit runs each case in a child process (default: none)

    [body.constants]             # optional: passed unchanged to every case
    latitude_deg = 28.5

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

Unknown keys are errors (a typo must not silently fall back to a default). Errors name the
file and the field, e.g. ``loop[1].vary``, where ``loop[0]`` is the first ``[[loop]]`` table.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path

from .body import Body, CallableBody, ProgramBody
from .errors import SweepInputError
from .loops import Loop
from .sweep import Sweep

_TOP_KEYS = frozenset({"sweep", "body", "loop"})
_BODY_KEYS = frozenset({"callable", "program", "json", "dashes", "timeout_s", "constants"})
_PROGRAM_ONLY_KEYS = ("json", "dashes")
_LOOP_KEYS = frozenset({"type", "names", "n", "sets", "vary", "delta"})


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
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise SweepInputError(source, "file", "a readable sweep file (TOML)",
                              exc.strerror) from None
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SweepInputError(source, "file", "valid TOML", str(exc)) from None
    return parse_sweep(document, source=source, check_body=check_body)


def parse_sweep(document: Mapping[str, object], *, source: str = "<sweep>",
                check_body: bool = True) -> Sweep:
    """Return the sweep described by a parsed sweep-file ``document`` (see module docstring).

    Raises
    ------
    SweepInputError
        A field is missing or invalid; ``source`` names the file in the message.
    """
    _no_unknown_keys(source, "", document, _TOP_KEYS)
    if "sweep" in document and not isinstance(document["sweep"], Mapping):
        raise SweepInputError(source, "sweep", "a table of free-text metadata",
                              document["sweep"])
    body = _parse_body(source, document.get("body"))
    loop_tables = document.get("loop")
    if not isinstance(loop_tables, list) or not loop_tables:
        raise SweepInputError(source, "loop", "at least one [[loop]] table", loop_tables)
    loops = tuple(_parse_loop(source, i, table) for i, table in enumerate(loop_tables))
    sweep = Sweep(loops=loops, body=body, source=source, document=dict(document))
    if check_body:
        body.check(source)
    return sweep


def _no_unknown_keys(source: str, prefix: str, table: Mapping[str, object],
                     allowed: frozenset[str]) -> None:
    for key in table:
        if key not in allowed:
            raise SweepInputError(source, f"{prefix}{key}",
                                  f"one of the keys {sorted(allowed)}", "an unknown key")


def _parse_body(source: str, table: object) -> Body:
    if not isinstance(table, Mapping):
        raise SweepInputError(source, "body",
                              'a [body] table with callable = "module:function" or '
                              "program = [argv...]", table)
    _no_unknown_keys(source, "body.", table, _BODY_KEYS)
    constants = table.get("constants", {})
    if not isinstance(constants, Mapping):
        raise SweepInputError(source, "body.constants", "a table of name = value", constants)
    for name in constants:
        if not name.isidentifier():
            raise SweepInputError(source, f"body.constants.{name}",
                                  "a Python identifier as the name", name)
    has_callable, has_program = "callable" in table, "program" in table
    if has_callable == has_program:
        raise SweepInputError(source, "body", "exactly one of callable or program",
                              "both" if has_callable else "neither")
    if has_callable:
        for key in _PROGRAM_ONLY_KEYS:
            if key in table:
                raise SweepInputError(source, f"body.{key}",
                                      "no such key for a callable body (program only)",
                                      table[key])
        target = table["callable"]
        if not isinstance(target, str):
            raise SweepInputError(source, "body.callable", '"module:function"', target)
        return CallableBody(target=target, constants=dict(constants),
                            timeout_s=_timeout_s(source, table))
    return _parse_program(source, table, dict(constants))


def _parse_program(source: str, table: Mapping[str, object],
                   constants: dict[str, object]) -> ProgramBody:
    argv = table["program"]
    if (not isinstance(argv, list) or not argv
            or not all(isinstance(a, str) and a for a in argv)):
        raise SweepInputError(source, "body.program",
                              'a non-empty list of strings, e.g. ["tapp", "propagate"]', argv)
    for name, value in constants.items():
        if not isinstance(value, str | int | float | bool):
            raise SweepInputError(source, f"body.constants.{name}",
                                  "a string, number or boolean for a program body", value)
    flags = {}
    for key in ("json", "dashes"):
        value = table.get(key, key == "json")
        if not isinstance(value, bool):
            raise SweepInputError(source, f"body.{key}", "true or false", value)
        flags[key] = value
    return ProgramBody(argv=tuple(argv), constants=constants, json_option=flags["json"],
                       dashes=flags["dashes"], timeout_s=_timeout_s(source, table))


def _timeout_s(source: str, table: Mapping[str, object]) -> float | None:
    timeout_s = table.get("timeout_s")
    if timeout_s is not None and (isinstance(timeout_s, bool)
                                  or not isinstance(timeout_s, int | float)
                                  or not 0 < timeout_s < float("inf")):
        raise SweepInputError(source, "body.timeout_s", "a positive, finite number of seconds",
                              timeout_s)
    return None if timeout_s is None else float(timeout_s)


def _parse_loop(source: str, i: int, table: object) -> Loop:
    where = f"loop[{i}]"
    if not isinstance(table, Mapping):
        raise SweepInputError(source, where, "a [[loop]] table", table)
    _no_unknown_keys(source, f"{where}.", table, _LOOP_KEYS)
    for key in ("names", "sets", "vary"):
        if key not in table:
            raise SweepInputError(source, f"{where}.{key}", f"a {key} key", "nothing")
    try:
        loop = Loop(type=table.get("type", 1), names=table["names"], sets=table["sets"],
                    vary=table["vary"], delta=table.get("delta"))
    except SweepInputError as exc:
        raise SweepInputError(source, f"{where}.{exc.field}", exc.expected, exc.got) from None
    if "n" in table and table["n"] != loop.n:
        raise SweepInputError(source, f"{where}.n", f"len(names) = {loop.n}", table["n"])
    return loop

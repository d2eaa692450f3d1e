"""Bodies: what ITER runs for each case (the seed's "program iterated over").

Two kinds, both picklable so Dask can ship them to workers:

* :class:`CallableBody`: a Python function named ``"module:function"``, called with the
  varied values and the constants as keyword arguments; it returns a mapping of named
  outputs.
* :class:`ProgramBody`: a command-line program (a ``tapp`` subcommand or any executable),
  run once per case with each constant and varied value passed as ``--name value``, and
  ``--json -`` appended (unless turned off: "write the JSON to standard output", as every
  ``tapp`` command takes it); its stdout must be one JSON object, which is taken as the
  outputs.

Both take ``files``: named paths passed like constants, each as an absolute path (the sweep
file reader takes relative ones from the sweep file's folder); each must exist.

Before a sweep runs, :meth:`CallableBody.check_case` checks the first case's inputs: the
function resolves, every file exists, every argument is one the function takes and none it
needs is missing, and, if the function offers one (:func:`input_check`), its own input check
passes. An error there would be an error of every case, so the sweep stops before it starts.

Outputs are flattened into named scalars: a nested mapping ``{"b": {"t_km": 1.0}}`` gives
``b.t_km``, a list ``{"r_km": [1, 2, 3]}`` gives ``r_km[0]``, ``r_km[1]``, ``r_km[2]``. Numbers
become floats, ``null`` becomes NaN, text stays text; anything else fails the case.

:func:`run_case` turns whatever the body does into a :class:`~iter.table.CaseResult`: a body
that raises, a program that exits non-zero or times out, or outputs that are not named scalars
give a FAILED row carrying the message, and the sweep goes on.

Hangs: every program body runs under a wall-time limit, ``timeout_s`` or
:data:`DEFAULT_PROGRAM_TIMEOUT_S`. A callable body runs in-process unless it has a
``timeout_s``; then each case runs in a child process (``python -m iter._child``) that is
killed, with everything it started, when the limit is reached. A case that times out is a
FAILED row with its elapsed time.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import json
import math
import os
import pickle
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np

from .errors import IterError, SweepInputError
from .loops import Case
from .table import RESERVED_COLUMNS, CaseResult, CaseStatus, OutputValue

#: Attribute under which a body function carries its input check (:func:`input_check`).
INPUT_CHECK_ATTRIBUTE = "iter_input_check"

F = TypeVar("F", bound=Callable[..., object])

#: Characters of a failing program's stderr kept in the error message (its tail).
STDERR_TAIL_CHARS = 400
#: Appended to a program body's command line: its outputs as JSON on standard output.
JSON_TO_STDOUT = ("--json", "-")
#: Wall-time limit of a program body's case when the sweep file gives none, s (one hour).
DEFAULT_PROGRAM_TIMEOUT_S = 3600.0


class CaseFailure(IterError):
    """A body ran but its case failed: non-zero exit, timeout, or unusable outputs."""


class CaseTimeout(CaseFailure):
    """A case ran longer than its body's ``timeout_s`` and was stopped."""


class ChildFailure(CaseFailure):
    """A callable body raised in its child process; keeps the exception's type name."""

    def __init__(self, type_name: str, message: str):
        self.type_name = type_name
        super().__init__(message)


def run_bounded(command: Sequence[str], stdin: bytes, timeout_s: float,
                what: str) -> subprocess.CompletedProcess[bytes]:
    """Run ``command`` with ``stdin``; kill it and its children after ``timeout_s`` seconds.

    The command runs in a session of its own, so that a timeout kills whatever it started
    too (a program that runs another one would otherwise keep the pipes open), and with a
    temporary folder of its own (``TMPDIR``), removed once it is done, so that a command
    killed at its timeout leaves no temporaries either.

    Raises
    ------
    CaseTimeout
        The command ran longer than ``timeout_s``.
    """
    with (tempfile.TemporaryDirectory(prefix="iter-case-", ignore_cleanup_errors=True) as scratch,
          subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, start_new_session=True,
                           env={**os.environ, "TMPDIR": scratch}) as proc):
        finished = False
        try:
            stdout, stderr = proc.communicate(stdin, timeout=timeout_s)
            finished = True
        except subprocess.TimeoutExpired:
            kill_session(proc)
            proc.communicate()
            raise CaseTimeout(f"{what} timed out after {timeout_s:g} s") from None
        finally:
            if not finished:  # a timeout, Ctrl-C or a worker shutdown: leave nothing running
                kill_session(proc)
    return subprocess.CompletedProcess(command, proc.returncode, stdout, stderr)


def kill_session(proc: subprocess.Popen[bytes]) -> None:
    """SIGKILL ``proc``, started with ``start_new_session``, and every process of its group
    (what it started)."""
    if hasattr(os, "killpg"):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    else:  # pragma: no cover - Windows
        proc.kill()


def _tail(stderr: bytes) -> str:
    return stderr.decode("utf-8", "replace").strip()[-STDERR_TAIL_CHARS:] or "(no stderr)"


def resolve_callable(target: str, source: str = "body") -> Callable[..., object]:
    """Return the function named by ``"module:function"`` (``function`` may be dotted).

    Raises
    ------
    SweepInputError
        Field ``body.callable``: not of the form ``module:function``, the module cannot be
        imported, or it has no such callable attribute.
    """
    module_name, sep, attr_path = target.partition(":")
    if not sep or not module_name or not attr_path:
        raise SweepInputError(source, "body.callable", '"module:function"', target)
    try:
        obj: object = importlib.import_module(module_name)
    except ImportError as exc:
        raise SweepInputError(source, "body.callable",
                              f"an importable module ({exc})", target) from None
    for part in attr_path.split("."):
        if not hasattr(obj, part):
            raise SweepInputError(source, "body.callable",
                                  f"a function {attr_path!r} in module {module_name!r}",
                                  target)
        obj = getattr(obj, part)
    if not callable(obj):
        raise SweepInputError(source, "body.callable", "a callable",
                              f"{target} is a {type(obj).__name__}")
    return obj


@functools.lru_cache(maxsize=16)
def _cached_callable(target: str) -> Callable[..., object]:
    return resolve_callable(target)


def input_check(check: Callable[..., object]) -> Callable[[F], F]:
    """Return a decorator that gives a body function ``check`` as its input check.

    ``check`` takes the body's keyword arguments (constants, files and varied values) and
    raises on input it refuses, naming the file and the field where it can (``iter``'s
    :class:`~iter.errors.SweepInputError`, or the caller's own input-error type: whatever it
    raises stops the sweep unchanged). It must be cheap: read and validate the inputs, never
    compute. It runs once, on the first case to run, before any case runs or anything is
    written; the body should call it too, so that a case run alone is checked the same way.

    >>> def check(x_km):
    ...     if x_km < 0:
    ...         raise SweepInputError("sweep.toml", "x_km", "a length >= 0", x_km)
    >>> @input_check(check)
    ... def body(x_km):
    ...     check(x_km)
    ...     return {"y_km": 2.0 * x_km}
    >>> getattr(body, INPUT_CHECK_ATTRIBUTE) is check
    True
    """
    def attach(function: F) -> F:
        setattr(function, INPUT_CHECK_ATTRIBUTE, check)
        return function

    return attach


def _check_files(files: Mapping[str, str], source: str) -> None:
    """Raise SweepInputError (field ``body.files.NAME``) for a file that does not exist."""
    for name, path in files.items():
        if not Path(path).exists():
            raise SweepInputError(source, f"body.files.{name}", "an existing file (a relative "
                                  "path is taken from the sweep file's folder)", path)


def _check_arguments(function: Callable[..., object], target: str,
                     arguments: Mapping[str, object], fields: Mapping[str, str],
                     source: str) -> None:
    """Raise SweepInputError unless ``function`` can be called with ``arguments`` by keyword.

    ``fields`` names, for each argument, the sweep-file field that gives it.
    """
    try:
        parameters = inspect.signature(function).parameters.values()
    except ValueError:  # a compiled function that declares no signature: nothing to check
        return
    keywords = [p.name for p in parameters if p.kind in (p.POSITIONAL_OR_KEYWORD,
                                                         p.KEYWORD_ONLY)]
    if not any(p.kind is p.VAR_KEYWORD for p in parameters):
        for name, value in arguments.items():
            if name not in keywords:
                raise SweepInputError(source, fields[name], f"an argument of {target} "
                                      f"({', '.join(keywords) or 'it takes none'})", value)
    for p in parameters:
        if (p.default is p.empty and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
                and (p.name not in arguments or p.kind is p.POSITIONAL_ONLY)):
            raise SweepInputError(source, "body.constants", f"a value for the argument "
                                  f"{p.name!r} of {target} (a constant, a file or a varied "
                                  "name)")


def names_a_path(name: str) -> bool:
    """Return True when program ``name`` has a directory part (a path, not a name on PATH)."""
    return os.sep in name or (os.altsep is not None and os.altsep in name)


def find_executable(name: str) -> str | None:
    """Return the path of program ``name``, or None when it cannot be found.

    A name with a directory part is taken as it is. A bare name is looked up on ``PATH``,
    then next to the running Python interpreter, so ``tapp`` is found in an unactivated
    virtual environment.
    """
    if names_a_path(name):
        return name if os.access(name, os.X_OK) else None
    return shutil.which(name) or shutil.which(name, path=str(Path(sys.executable).parent))


def flatten_outputs(raw: object) -> dict[str, OutputValue]:
    """Return the body's outputs as named scalars (floats or text).

    Raises
    ------
    CaseFailure
        ``raw`` is not a mapping with string keys, a name contains ``/``, or a value is
        not a number, bool, null, text, list or mapping.
    """
    if not isinstance(raw, Mapping):
        raise CaseFailure(f"outputs must be a mapping of name to value, got "
                          f"{type(raw).__name__}")
    flat: dict[str, OutputValue] = {}
    _flatten_into(flat, "", raw)
    return flat


def _flatten_into(flat: dict[str, OutputValue], name: str, value: object) -> None:
    if isinstance(value, np.ndarray | np.generic):
        value = value.tolist()
    if isinstance(value, Mapping):
        for key, item in value.items():
            if not isinstance(key, str) or not key or "/" in key:
                raise CaseFailure(f"output name {key!r} under {name or 'the outputs'!r}: "
                                  "expected a non-empty string without '/'")
            _flatten_into(flat, f"{name}.{key}" if name else key, item)
    elif isinstance(value, list | tuple):
        for j, item in enumerate(value):
            _flatten_into(flat, f"{name}[{j}]", item)
    elif isinstance(value, bool | int | float):
        flat[name] = float(value)
    elif value is None:
        flat[name] = math.nan
    elif isinstance(value, str):
        flat[name] = value
    else:
        raise CaseFailure(f"output {name!r} is a {type(value).__name__}; expected a number, "
                          "text, null, or a list or mapping of those")


@dataclass(frozen=True, slots=True)
class CallableBody:
    """A Python function run in-process for each case.

    Parameters
    ----------
    target : str
        ``"module:function"``; the module must be importable where the case runs (on every
        Dask worker).
    constants : mapping of str to object
        Keyword arguments passed unchanged to every case.
    timeout_s : float or None
        Wall-time limit per case, s. None (the default) runs each case in this process, with
        no limit; a number runs each case in a child process, killed at the limit (the
        constants and outputs must then be picklable, and each case pays for starting a
        Python process).
    files : mapping of str to str
        Paths passed to every case as keyword arguments, like constants; absolute (a
        relative path is taken from the current directory of the process running the case).
    """

    target: str
    constants: Mapping[str, object] = field(default_factory=dict)
    timeout_s: float | None = None
    files: Mapping[str, str] = field(default_factory=dict)

    def check(self, source: str) -> None:
        """Raise SweepInputError (field ``body.callable`` or ``body.files.NAME``) unless the
        target resolves and every file exists."""
        resolve_callable(self.target, source)
        _check_files(self.files, source)

    def check_case(self, case: Case, source: str, fields: Mapping[str, str]) -> None:
        """Raise unless ``case`` can run: :meth:`check`, the arguments against the function's
        signature, then the function's own input check if it offers one (:func:`input_check`).

        ``fields`` names the sweep-file field of each varied name (``loop[1].names``).

        Raises
        ------
        SweepInputError
            Naming ``source`` and the field: the target, a missing file, an argument the
            function does not take or one it needs and is not given.
        Exception
            Whatever the function's input check raises, unchanged.
        """
        self.check(source)
        function = resolve_callable(self.target, source)
        arguments = _arguments(self, case)
        _check_arguments(function, self.target, arguments, {**_fields(self), **fields},
                         source)
        check = getattr(function, INPUT_CHECK_ATTRIBUTE, None)
        if check is not None:
            check(**arguments)

    def definition(self) -> dict[str, object]:
        """Return the body as the ``[body]`` table of a sweep file."""
        table: dict[str, object] = {"callable": self.target, "constants": dict(self.constants)}
        if self.timeout_s is not None:
            table["timeout_s"] = self.timeout_s
        if self.files:
            table["files"] = dict(self.files)
        return table

    def __call__(self, case: Case) -> object:
        """Run the function for ``case``; return what it returns (outputs, unchecked).

        Raises
        ------
        CaseTimeout
            The case ran longer than ``timeout_s`` (its child process was killed).
        ChildFailure
            The function raised in its child process (``timeout_s`` set).
        """
        kwargs = _arguments(self, case)
        if self.timeout_s is None:
            return _cached_callable(self.target)(**kwargs)
        payload = pickle.dumps(([p for p in sys.path if p], self.target, kwargs))
        proc = run_bounded([sys.executable, "-m", "iter._child"], payload, self.timeout_s,
                           self.target)
        try:
            answer = pickle.loads(proc.stdout)
        except (pickle.UnpicklingError, EOFError, ValueError):
            raise CaseFailure(f"{self.target}: its process exited with status "
                              f"{proc.returncode}: {_tail(proc.stderr)}") from None
        if answer[0] == "error":
            raise ChildFailure(answer[1], answer[2])
        return answer[1]


@dataclass(frozen=True, slots=True)
class ProgramBody:
    """A command-line program run once per case; its ``--json -`` stdout is the outputs.

    Parameters
    ----------
    argv : tuple of str
        The program and its fixed arguments, e.g. ``("tapp", "propagate")`` or
        ``("python", "body.py")``. The program is run in the current working directory.
    constants : mapping of str to str, int, float or bool
        Passed to every case as ``--name value``; ``true`` as a bare ``--name`` flag, and
        ``false`` not at all.
    json_option : bool
        Append ``--json -`` to the command line (the ``json`` key of the sweep file).
    dashes : bool
        Spell options with dashes, ``--azimuth-deg`` for ``azimuth_deg``, as typer/click
        programs (``tapp``) expect.
    timeout_s : float or None
        Wall-time limit per case, s; None for :data:`DEFAULT_PROGRAM_TIMEOUT_S`.
    files : mapping of str to str
        Paths passed to every case as ``--name path``, like constants; absolute (a relative
        path is taken from the current directory).
    """

    argv: tuple[str, ...]
    constants: Mapping[str, object] = field(default_factory=dict)
    json_option: bool = True
    dashes: bool = False
    timeout_s: float | None = None
    files: Mapping[str, str] = field(default_factory=dict)

    def check(self, source: str) -> None:
        """Raise SweepInputError (field ``body.program`` or ``body.files.NAME``) unless the
        program is found and every file exists."""
        if find_executable(self.argv[0]) is None:
            raise SweepInputError(source, "body.program",
                                  "a program on PATH, next to the Python interpreter, or a "
                                  "path to an executable", self.argv[0])
        _check_files(self.files, source)

    def check_case(self, case: Case, source: str, fields: Mapping[str, str]) -> None:
        """Raise SweepInputError unless the program is found and every file exists (a
        program offers no input check of its own: its arguments are its to check)."""
        self.check(source)

    def definition(self) -> dict[str, object]:
        """Return the body as the ``[body]`` table of a sweep file."""
        table: dict[str, object] = {"program": list(self.argv), "json": self.json_option,
                                    "dashes": self.dashes, "constants": dict(self.constants)}
        if self.timeout_s is not None:
            table["timeout_s"] = self.timeout_s
        if self.files:
            table["files"] = dict(self.files)
        return table

    def command(self, case: Case) -> list[str]:
        """Return the command line for ``case``."""
        executable = find_executable(self.argv[0]) or self.argv[0]
        args = [executable, *self.argv[1:]]
        for name, value in _arguments(self, case).items():
            option = "--" + (name.replace("_", "-") if self.dashes else name)
            if value is True:
                args.append(option)
            elif value is not False:
                args += [option, repr(value) if isinstance(value, float) else str(value)]
        if self.json_option:
            args += JSON_TO_STDOUT
        return args

    def __call__(self, case: Case) -> Mapping[str, object]:
        """Run the program for ``case``; return its stdout parsed as one JSON object.

        Raises
        ------
        CaseFailure
            Non-zero exit (with the tail of stderr), timeout, or stdout not one JSON object.
        """
        timeout_s = DEFAULT_PROGRAM_TIMEOUT_S if self.timeout_s is None else self.timeout_s
        proc = run_bounded(self.command(case), b"", timeout_s, self.argv[0])
        if proc.returncode != 0:
            raise CaseFailure(f"{self.argv[0]} exited with status {proc.returncode}: "
                              f"{_tail(proc.stderr)}")
        stdout = proc.stdout.decode("utf-8", "replace")
        try:
            outputs = json.loads(stdout)
        except json.JSONDecodeError as exc:
            raise CaseFailure(f"{self.argv[0]} stdout is not one JSON object: {exc} "
                              f"(stdout starts {stdout[:80]!r})") from None
        if not isinstance(outputs, dict):
            raise CaseFailure(f"{self.argv[0]} printed JSON {type(outputs).__name__}, "
                              "expected one object")
        return outputs


Body = CallableBody | ProgramBody


def _arguments(body: Body, case: Case) -> dict[str, object]:
    """Return the arguments of ``case``: the constants, the files, then the varied values."""
    return {**body.constants, **body.files, **case.kwargs()}


def _fields(body: Body) -> dict[str, str]:
    """Return the sweep-file field of each constant and file of ``body``."""
    return {**{name: f"body.constants.{name}" for name in body.constants},
            **{name: f"body.files.{name}" for name in body.files}}


#: Prefix given to an output whose name is a varied name or a reserved column.
CLASH_PREFIX = "output."


def rename_clashes(outputs: dict[str, object], names: Sequence[str]) -> dict[str, object]:
    """Return ``outputs`` with names that clash with a varied name or a reserved column
    (``case``, ``status``, ``error``, ``elapsed_s``) prefixed by ``output.``: a program's own
    ``status`` field is kept as ``output.status`` beside the sweep's status column."""
    taken = {*names, *RESERVED_COLUMNS}
    return {(CLASH_PREFIX + k if k in taken else k): v for k, v in outputs.items()}


def run_case(body: Body, case: Case) -> CaseResult:
    """Run ``body`` for ``case`` and return its row; a failure becomes a FAILED row.

    Any exception from the body is caught here on purpose: a failing case is data (recorded
    with ``"ExceptionType: message"``), and the other cases must still run.
    """
    start_s = time.perf_counter()
    try:
        outputs = rename_clashes(flatten_outputs(body(case)), case.names)
    except Exception as exc:  # noqa: BLE001 - recorded in the row; see docstring
        name = exc.type_name if isinstance(exc, ChildFailure) else type(exc).__name__
        return CaseResult(index=case.index, values=case.values, outputs={},
                          status=CaseStatus.FAILED, error=f"{name}: {exc}",
                          elapsed_s=time.perf_counter() - start_s)
    return CaseResult(index=case.index, values=case.values, outputs=outputs,
                      status=CaseStatus.OK, elapsed_s=time.perf_counter() - start_s)


def run_chunk(body: Body, cases: Sequence[Case]) -> list[CaseResult]:
    """Run ``body`` for each case of a chunk in turn (the unit of work sent to a worker)."""
    return [run_case(body, case) for case in cases]

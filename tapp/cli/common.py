"""Shared pieces of the CLI: the app object, the exit-code contract, error handling, JSON.

Exit codes (every command keeps this contract)
-----------------------------------------------
0
    Success.
2
    Bad input of any kind, and nothing is written: an option (unparseable, out
    of range, a size beyond the limits below), an input file (missing, not TOML, a field
    missing, misspelt, of the wrong type or out of range, a truncated or corrupt tape or
    ITER results file, a checksum that does not match), an output path that is an input or
    another output (symbolic links and relative paths resolved) or cannot be written, an
    epoch outside the ephemeris' coverage, a scenario whose B-plane miss has no encounter
    (``tapp simulate``, ``tapp pipeline``: the message names the closest approach;
    :mod:`tapp.tracking.encounter`). ``tapp iter`` also refuses, before any case runs,
    input that every case would meet: checked on the first case, a file the body reads
    missing (``body.files``) or invalid (the body's own input check, which names that file
    and its field), a body that cannot be imported or found, an argument the body does not
    take or one it needs and is not given. The message is one line on stderr,
    ``error: SOURCE: FIELD: expected WHAT (got VALUE)``, where SOURCE is the option as typed
    (``--process-noise``, ``-o/--output``) when an option is at fault, and the file when a
    file is, with the field (``noise.fit.sigma_range_m``, ``records/info``). Input files
    are regular files: a FIFO, a device (a symbolic link to ``/dev/zero``), a socket or a
    directory is refused before it is read (:mod:`iter.inputfile`); a user's EOP table is
    checked field by field (:mod:`tapp.frames.iers`, naming the line); matrices of decks and
    tapes are checked symmetric and positive semi-definite on each entry's own scale, and
    numbers that would overflow downstream are refused where they are read (deck σ's within
    1e-30..1e30, tape numbers within 1e60); ``tapp guide`` refuses a tape whose linear
    covariance overflows or has a Δv σ at the speed of light.
3, 4, 5, 6, 7
    A numerical outcome, with its output still printed and written: ``tapp dc`` diverged
    (3), found the normal matrix too ill-conditioned to iterate (4; the condition number and
    the undetermined state directions are printed), stalled above the fit limit (5),
    reached its iteration limit while still converging (6), or converged with residuals
    inconsistent with the noise model (7: the weighted residual RMS settled above its
    99.9 % χ² bound for the number of residuals and estimated parameters; the RMS and the
    bound are printed, and the estimate is not to be used as an orbit)
    (:mod:`tapp.cli.od_cmd`); ``tapp search`` diverged (3) or met a singular matrix (4)
    (``--write-scenario`` is then not written: a scenario that misses its aim point is no
    answer). ``tapp simulate`` of a scenario with a ``[targeting]`` table whose SEARCH
    diverged (3) or met a singular matrix (4): one line on stderr, and no tape (there is no
    injection to simulate).
1
    Anything else: a computation that could not be completed (``tapp search``, or the
    ``[targeting]`` of ``tapp simulate``: a trajectory that misses the target's sphere of
    influence, or a conic first guess that cannot be formed; ``tapp dc``, ``tapp ekf``: too
    few measurements in the data (an arc too short for them, where a longer one would do, is
    bad input: 2, naming ``--arc``); ``tapp iter``: every case of the sweep failed, the message
    giving the first case's error, after the summary is printed and the results file, which
    records every failure, is written), or an internal failure (a bug; out of memory). Also
    one line on stderr.
130
    Interrupted (Ctrl-C).

Warnings (the run goes on: an old tape without checksums, a station that yields no
observation) are one line each on stderr, ``warning: SOURCE: FIELD: what`` like the errors
(:func:`echo_warning`, :func:`one_line_warnings`); a command's own (not a library's) come
last, once its outputs are written, so that a failed run's one line is its error.

Limits checked before allocating: output grids of at most ``tapp.io.options.MAX_GRID_SAMPLES``
samples (``--arc`` or ``--span`` with ``--step``), ITER sweeps of at most
``iter.loops.MAX_CASES`` cases (the product of the loops' ``sets``), TAPP II Monte Carlos of
``tapp.guidance.study.MIN_SAMPLES`` to ``MAX_SAMPLES`` samples, SEARCH scans of at most
``tapp.targeting.program.MAX_SCAN_STEPS`` steps, local Dask clusters of at most
``iter.execute.MAX_WORKERS_PER_CORE`` workers per core (no limit with ``--scheduler``), TOML
files of at most ``iter.inputfile.MAX_TOML_BYTES`` (4 MiB), TDM and CSV observation files of
``tapp.io.obsfile.MAX_TEXT_BYTES`` (64 MiB), EOP tables of ``tapp.io.eop_file.MAX_EOP_BYTES``
(16 MiB), TAPP III decks of at most ``tapp.processor.deck.MAX_COMMANDS`` commands a list and
runs of at most ``MAX_ENTITIES`` output entities and ``MAX_ENTITY_NUMBERS`` numbers in them;
each message gives the size that would be needed and the option or field to change.

Conventions of every command: ``--json PATH`` writes the command's results as one JSON
object to PATH, with the other outputs (all or none), and ``--json -`` prints it on
standard output in place of the report (the old flag form, ``--json`` with no value or
followed by another option, is refused naming ``--json -``); a duration is a number and its
unit, ``24h``, ``90m``, ``3600s``, ``2d`` (a bare number is refused); help text is plain text
(square brackets are not rich markup). Where the work runs (``iter``, ``guide``,
``pipeline``): ``--serial`` in this process, ``--workers N`` on a local Dask cluster of N
processes, ``--scheduler ADDRESS`` on a running cluster; with none of them, in this process
unless the work repays a local cluster's start (``guide``: from
``tapp.guidance.shards.DASK_MIN_SAMPLES`` samples; ``iter``: from
``iter.execute.DASK_MIN_WORK_S`` of serial work projected from its first cases). Commands
run on one BLAS thread, and so do a local cluster's workers (:func:`one_blas_thread`).

Epochs are checked against DE421's coverage (1899-07-29 .. 2053-10-09) before any
propagation. An ITER case that runs longer than its body's ``timeout_s`` (program bodies:
3600 s unless the sweep file says otherwise) is stopped and recorded as failed.

What is left on disk: nothing new when a command fails. Outputs are written to hidden
temporaries beside their targets and renamed over them only once all are complete and the
report is printed (:func:`delivering`, :class:`tapp.io.outputs.OutputSet`); on any failure,
standard output that cannot be written among them, the old outputs are left untouched.
A killed run leaves the old outputs or the new ones, each complete, and possibly hidden
``.NAME.*.tmp`` temporaries, which the next write of the same output removes. ``tapp iter``
checkpoints its results file (each time atomically) as cases complete, so that a killed or
interrupted sweep can be resumed; a sweep whose every case failed (exit 1) keeps its results
file and CSV, which record the failures.

Faults from outside the input: a full disk while writing an output is one line naming the
option and the path asked for, exit 1 (a path at fault, a read-only folder, is exit 2);
standard output full, closed or a broken pipe is ``error: standard output: not written
(REASON)``, exit 1; SIGINT and SIGTERM stop the run cleanly, ``error: interrupted (SIGINT)``
or ``error: terminated (SIGTERM)``, exit 130 or 143. No folder made for outputs that were not
written is left. Each run keeps its temporaries, and the Dask cluster's scratch space, in a
private folder ``tapp-run-*`` of the system's temporary folder, removed at its end; the next
run removes those of runs killed outright (SIGKILL).
"""

from __future__ import annotations

import fcntl
import io
import json
import math
import os
import re
import shutil
import signal
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer
from typer.core import TyperGroup

from iter.errors import ClusterError
from iter.execute import MAX_WORKERS_PER_CORE
from tapp.errors import DeprecatedSpelling, InputError, TapeError, TappError
from tapp.io.outputs import OutputSet

if TYPE_CHECKING:
    from rich.progress import Progress, ProgressColumn

# click's base exception, whether typer vendors click (typer >= 0.23) or uses the package.
_ClickException = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


#: What rich takes for a markup tag (as :func:`rich.markup.escape` finds them): ``[body]``,
#: ``[[loop]]``, ``[default: auto]``. Help text here is plain text, so each is escaped.
_RICH_TAG = re.compile(r"(\\*)(\[[a-z#/@][^[]*?])")


def _plain(text: str | None) -> str | None:
    """``text`` with every bracket rich would take for markup escaped (None stays None)."""
    return None if text is None else _RICH_TAG.sub(r"\1\1\\\2", text)


def _escape_help(command: Any) -> None:
    """Escape the help of ``command``, of its parameters and of its subcommands."""
    command.help = _plain(command.help)
    command.short_help = _plain(command.short_help)
    for param in command.params:
        if getattr(param, "help", None):
            param.help = _plain(param.help)
    for sub in getattr(command, "commands", {}).values():
        _escape_help(sub)


class Group(TyperGroup):
    """A group of commands whose ``--help``, when not given, is False: typer coerces an
    option's missing value (None) through pydantic, whose import (~50 ms) ``tapp CMD
    --help`` would otherwise wait for while the groups above CMD parse their options."""

    def get_help_option(self, ctx: Any) -> Any:
        option = super().get_help_option(ctx)
        if option is not None and option.default is None:
            option.default = False
        return option


class _OneLineErrors(Group):
    """The root group, the CLI's edge: a usage error (a bad or missing option) is one line,
    exit 2; a warning is one line (:func:`one_line_warnings`); help text is shown as written
    (no square bracket taken for rich markup); SIGINT
    and SIGTERM stop the run with one line (exit 130 and 143, :class:`Interrupted`); standard
    output that cannot be written is one line, exit 1; the run's temporaries live in a
    private folder removed at the end (:func:`run_folder`)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        _escape_help(self)

    def main(self, args: Sequence[str] | None = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True,
             **extra: Any) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        _hold_standard_output()
        try:
            with stopping_on_signals(), run_folder(), one_line_warnings():
                code = super().main(args, prog_name, complete_var, False, **extra)
                sys.stdout.flush()  # here, where a failure is one line, not at exit
        except InputError as exc:  # from an option's own check while the line is parsed
            echo_error(exc)
            code = EXIT_INPUT
        except _ClickException as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # `tapp` alone: the help
                exc.show()
                sys.exit(exc.exit_code)
            typer.echo(f"error: {_usage_message(exc)}", err=True)
            code = exc.exit_code
        except typer.Abort:
            typer.echo("error: aborted", err=True)
            code = EXIT_FAILURE
        except Interrupted as exc:
            typer.echo(f"error: {exc.what} ({exc})", err=True)
            code = exc.exit_code
        except StandardOutputError as exc:
            code = report_standard_output(exc)
        except OSError as exc:  # outside any command's run_guarded (an option's check)
            echo_error(exc)
            code = EXIT_FAILURE
        sys.exit(code if isinstance(code, int) else 0)


@contextmanager
def one_line_warnings() -> Iterator[None]:
    """Within: a Python warning the library gives (an old tape's: no checksums, normal
    matrices; an old results file's) is written as one ``warning: MESSAGE`` line on stderr,
    not as Python's lines with the source path, line number and code. Which warnings are
    shown, and where, is left to the filters (``-W``, ``PYTHONWARNINGS``) and to whoever
    records them (``warnings.catch_warnings(record=True)``): only their text changes, and an
    input's earlier spelling (:class:`~tapp.errors.DeprecatedSpelling`, a DeprecationWarning
    Python would hide) is shown unless ``-W`` says otherwise."""
    saved = warnings.formatwarning
    warnings.formatwarning = _one_line_warning
    try:
        with warnings.catch_warnings():
            if not sys.warnoptions:  # an input's earlier spelling is the user's to see
                warnings.simplefilter("default", DeprecatedSpelling)
            yield
    finally:
        warnings.formatwarning = saved


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, line: str | None = None) -> str:
    return _line("warning", str(message)) + "\n"


#: The signals that stop a run cleanly (:class:`Interrupted`).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: Prefix of the private temporary folder of each command-line run (:func:`run_folder`).
RUN_FOLDER_PREFIX = "tapp-run-"


class Interrupted(BaseException):
    """SIGINT (Ctrl-C) or SIGTERM asked the run to stop.

    Raised by the CLI's signal handlers (:func:`stopping_on_signals`) in place of a
    KeyboardInterrupt, which click turns into a silent exit and SIGTERM does not raise at
    all: it unwinds the stack like any exception, so every ``finally`` and context manager
    runs (temporaries removed, an ITER sweep checkpointed, a Dask cluster stopped), up to the
    root command, which prints one line and exits 128 + the signal's number.
    """

    def __init__(self, signum: int):
        self.signum = signum
        self.exit_code = 128 + signum
        self.what = "interrupted" if signum == signal.SIGINT else "terminated"
        super().__init__(signal.Signals(signum).name)


@contextmanager
def stopping_on_signals() -> Iterator[None]:
    """While the block runs, SIGINT and SIGTERM raise :class:`Interrupted` (once: while the
    run cleans up, further ones are ignored; SIGKILL still stops it, and the next run
    removes what it left).

    A signal that arrives while an extension module initialises is not seen as itself:
    the module's loader (pybind11's, SciPy's HiGHS) replaces the exception the handler
    raised with ``ImportError: initialization failed``. Any exception that leaves the block
    after a stop signal is therefore that signal's :class:`Interrupted`, the first one
    chained as its cause.
    """
    received: list[int] = []

    def stop(signum: int, frame: object) -> None:
        for sig in STOP_SIGNALS:  # a second Ctrl-C would cut the clean-up short
            signal.signal(sig, signal.SIG_IGN)
        received.append(signum)
        raise Interrupted(signum)

    saved = {sig: signal.signal(sig, stop) for sig in STOP_SIGNALS}
    try:
        yield
    except Exception as exc:
        if not received:
            raise
        raise Interrupted(received[0]) from exc
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)


class StandardOutputError(Exception):
    """Standard output could not be written: closed, full, or nothing reads it (a broken
    pipe); ``strerror`` says which.

    Not an OSError: typer turns an OSError of EPIPE into a silent exit 1 (``tapp --help |
    head -0``), rich a BrokenPipeError, and code that writes a file takes any OSError for
    that file's.
    """

    def __init__(self, exc: OSError):
        self.strerror = exc.strerror or type(exc).__name__
        super().__init__(self.strerror)


class _StandardOutput(io.FileIO):
    """File descriptor 1, whose failed writes raise :class:`StandardOutputError`."""

    def write(self, data: Any) -> int | None:
        try:
            return super().write(data)
        except OSError as exc:
            raise StandardOutputError(exc) from None


def _hold_standard_output() -> None:
    """Write standard output through :class:`_StandardOutput` (a test harness's own stream
    is left alone).

    Standard output closed at start (``>&-``) is held open on /dev/null for reading: writes
    then fail as on a closed stream (EBADF), and no file the run opens takes descriptor 1.
    """
    current = sys.stdout
    if current is not None and current is not sys.__stdout__:
        return
    if current is None:
        fd = os.open(os.devnull, os.O_RDONLY)
        if fd != 1:
            os.dup2(fd, 1)
            os.close(fd)
    else:
        current.flush()
    sys.stdout = io.TextIOWrapper(
        io.BufferedWriter(_StandardOutput(1, "w", closefd=False)),
        encoding=getattr(current, "encoding", None) or "utf-8",
        errors=getattr(current, "errors", None), line_buffering=bool(
            getattr(current, "line_buffering", False)))


def report_standard_output(exc: StandardOutputError) -> int:
    """Write the one line of standard output that cannot be written; return the exit code,
    1. Standard output then goes to /dev/null: what is still buffered is dropped at exit,
    where it would print "Exception ignored" lines."""
    typer.echo(f"error: standard output: not written ({exc.strerror})", err=True)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    return EXIT_FAILURE


@contextmanager
def run_folder() -> Iterator[Path]:
    """Give the run, and every process it starts, a private temporary folder; remove it when
    the block ends, however it ends.

    The folder ``tapp-run-<random>`` is made in the system's temporary folder and becomes
    :mod:`tempfile`'s and, through ``TMPDIR``, that of the processes the run starts: the
    Dask cluster's scratch space, ITER's case processes and what they make all go with it.
    It is locked (``flock``) while the run lives, and folders of earlier runs that are no
    longer locked (killed by SIGKILL) are removed on entering.
    """
    base = Path(tempfile.gettempdir())
    _remove_unlocked(base.glob(f"{RUN_FOLDER_PREFIX}*"))
    # Locked before it takes a name another run's clean-up looks for.
    new = Path(tempfile.mkdtemp(prefix=f".{RUN_FOLDER_PREFIX}"))
    lock = os.open(new, os.O_RDONLY)
    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    folder = new.rename(base / new.name[1:])
    saved = tempfile.tempdir, os.environ.get("TMPDIR")
    tempfile.tempdir = os.environ["TMPDIR"] = str(folder)
    try:
        yield folder
    finally:
        tempfile.tempdir = saved[0]
        if saved[1] is None:
            del os.environ["TMPDIR"]
        else:
            os.environ["TMPDIR"] = saved[1]
        shutil.rmtree(folder, ignore_errors=True)
        os.close(lock)


def _remove_unlocked(folders: Iterator[Path]) -> None:
    """Remove the run folders, this user's, that no live run holds locked."""
    for folder in folders:
        try:
            fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        except OSError:  # gone meanwhile, not a folder (a link to one), or not readable
            continue
        try:
            if os.fstat(fd).st_uid != os.getuid():  # another user's: never ours to remove
                continue
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            shutil.rmtree(folder, ignore_errors=True)
        except BlockingIOError:  # a live run holds it
            pass
        finally:
            os.close(fd)


def _usage_message(exc: Exception) -> str:
    """One line: the option as typed and what is wrong with it."""
    if getattr(exc, "option_name", None) == "--json":  # last on the line, as the old flag
        return str(_json_form_error("no value"))
    message = " ".join(exc.format_message().split())
    opts = getattr(getattr(exc, "param", None), "opts", None) or ()
    if opts and not any(opt in message for opt in opts):
        return f"{'/'.join(opts)}: {message}"
    return message


app = typer.Typer(
    name="tapp",
    cls=_OneLineErrors,
    help="Tracking accuracy prediction: trajectories, tracking, matrix processing, guidance, "
    "targeting and sweeps.",
    rich_markup_mode="rich",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

T = TypeVar("T")

#: Exit code for bad input: options, files, fields, corrupt tapes (click's usage errors too).
EXIT_INPUT = 2
#: Exit code for any other failure: a computation that could not be completed, or a bug.
EXIT_FAILURE = 1


def _version_callback(value: bool) -> None:
    if value:
        from tapp import __version__

        typer.echo(f"tapp {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version_callback, is_eager=True,
                     help="Print the version and exit."),
    ] = False,
) -> None:
    """Tracking accuracy prediction and orbit-determination analysis."""


def positive_option(name: str, value: float) -> float:
    """Return ``value`` if finite and > 0, else raise InputError naming the option."""
    if not (math.isfinite(value) and value > 0):
        raise InputError(name, "value", "a finite number > 0", value)
    return value


#: The ``--earth-orientation`` option of every command that reads a scenario (or builds one).
EarthOrientationOpt = Annotated[str | None, typer.Option(
    "--earth-orientation", help='Earth orientation model, overriding the file: "iau2006" (IAU '
    '2006/2000A with IERS EOP) or "gmst" (GMST + omega t, the approximate-STM study\'s).')]


def earth_orientation_option(value: str | None) -> str | None:
    """Return the ``--earth-orientation`` value (None: the file's), or raise InputError."""
    if value is None:
        return None
    from tapp.frames.orientation import check_model

    return check_model(value, "--earth-orientation", "value")


#: The Dask options of every command that runs on a cluster (iter, guide, pipeline). With
#: none of them the work runs in this process unless it repays starting a local cluster
#: (:attr:`iter.execute.Execution.automatic`).
SchedulerOpt = Annotated[str | None, typer.Option(
    "--scheduler", help="Address tcp://HOST:PORT of a running Dask scheduler [default: none: "
                        "this process, or a local cluster when the work repays its start].")]
WorkersOpt = Annotated[int | None, typer.Option(
    "--workers", help="Start a local cluster of this many worker processes, at most "
                      f"{MAX_WORKERS_PER_CORE} per core [default: one per core, when the work "
                      "repays it].")]
SerialOpt = Annotated[bool, typer.Option(
    "--serial", help="Run in this process whatever the size of the work, no Dask (the "
                     "results are the same).")]
ConnectTimeoutOpt = Annotated[float, typer.Option(
    "--connect-timeout-s", help="Wait for the scheduler, s.")]


def scheduler_error(exc, source: str = "--scheduler", field: str = "value") -> InputError:
    """The one-line InputError of a Dask scheduler that does not answer (``iter``'s
    SchedulerError)."""
    return InputError(source, field, f"a Dask scheduler answering within {exc.timeout_s:g} s "
                      f"({exc.reason})", exc.address)


def execution_options(scheduler: str | None, workers: int | None, timeout_s: float,
                      serial: bool = False):
    """Return the ``iter.Execution`` of ``--scheduler``/``--workers``/``--serial`` options, or
    raise InputError naming the option at fault (a Monte Carlo's shards run as ITER's cases)."""
    from iter import SweepInputError
    from iter.execute import Execution

    try:
        return Execution(serial=serial, scheduler=scheduler, workers=workers,
                         connect_timeout_s=timeout_s)
    except SweepInputError as exc:
        raise InputError(f"--{exc.field.replace('_', '-')}", "value", exc.expected,
                         exc.got) from None


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Within: one BLAS thread in this process (``threadpoolctl``), as in a local cluster's
    workers (:data:`iter.execute.WORKER_ENVIRON`). A command's matrices are small (n_o up
    to about 100, blocks of 1,000 samples): more threads cost more than they save, and on a
    loaded machine they made small solves up to 10x slower (``make bench``, section ``cli``).
    """
    import numpy  # noqa: F401  (loads BLAS: the limit applies to the libraries loaded)
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield


def run_guarded(fn: Callable[[], T]) -> T:
    """Run ``fn`` under the exit-code contract of the module docstring, on one BLAS thread
    (:func:`one_blas_thread`).

    Bad input (:class:`~tapp.errors.InputError`, :class:`~tapp.errors.TapeError`, a file
    that cannot be read) is one line on stderr and exit 2; any other
    :class:`~tapp.errors.TappError`, and running out of memory, one line and exit 1.
    """
    try:
        with one_blas_thread():
            return fn()
    except (InputError, TapeError) as exc:
        echo_error(exc)
        raise typer.Exit(EXIT_INPUT) from None
    except (TappError, ClusterError) as exc:
        echo_error(exc)
        raise typer.Exit(EXIT_FAILURE) from None
    except OSError as exc:
        if exc.filename is None:  # a device's or the system's, not a file's
            echo_error(exc)
            raise typer.Exit(EXIT_FAILURE) from None
        typer.echo(f"error: {exc.filename}: file: expected an accessible file "
                   f"(got {exc.strerror or type(exc).__name__!r})", err=True)
        raise typer.Exit(EXIT_INPUT) from None
    except MemoryError:
        typer.echo("error: out of memory (an input asks for more than this machine has)",
                   err=True)
        raise typer.Exit(EXIT_FAILURE) from None


def progress_bar(*columns: ProgressColumn | str, quiet: bool) -> Progress:
    """A transient rich progress bar on stderr, shown on a terminal only: elsewhere rich
    draws nothing but leaves an empty line, which would sit above a failure's one line."""
    from rich.console import Console
    from rich.progress import Progress

    console = Console(stderr=True)
    return Progress(*columns, console=console, disable=quiet or not console.is_terminal,
                    transient=True)


def echo_error(exc: BaseException) -> None:
    """Write ``error: MESSAGE`` on stderr, the message on one line."""
    typer.echo(_line("error", str(exc)), err=True)


def echo_warning(message: str) -> None:
    """Write ``warning: MESSAGE`` on stderr, the message on one line: something the run
    goes on with, which the user may not have meant (it is in the command's JSON too)."""
    typer.echo(_line("warning", message), err=True)


def _line(kind: str, message: str) -> str:
    """``KIND: MESSAGE``, the message's whitespace (line breaks too) made single spaces."""
    return f"{kind}: {' '.join(message.split())}"


def _to_jsonable(obj: object) -> object:
    if hasattr(obj, "tolist"):  # a NumPy array (nested lists) or scalar (a Python number)
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _dumps(obj: object) -> str:
    return json.dumps(obj, default=_to_jsonable)


def print_json(obj: object) -> None:
    """Write one JSON object on stdout (NumPy arrays and scalars converted)."""
    sys.stdout.write(_dumps(obj))
    sys.stdout.write("\n")


#: ``--json -``: the JSON on standard output, in place of the command's report.
STDOUT = "-"


def _json_form_error(got: str) -> InputError:
    return InputError("--json", "value", "a file path, or - for standard output (the flag "
                      "--json is now written --json -)", got)


def _json_value(value: str | None) -> str | None:
    """The ``--json`` value; an option in its place is the old flag form followed by the
    next option (``--json --orbit X``), refused before the option is taken for a path."""
    if value is not None and value != STDOUT and value.startswith("-"):
        raise _json_form_error(value)
    return value


#: The ``--json`` option of every command (one convention): a file, or ``-`` for stdout.
JsonOpt = Annotated[str | None, typer.Option(
    "--json", metavar="PATH", callback=_json_value,
    help="Also write the results as one JSON object to PATH ('-': on standard output, in "
         "place of the report).")]


def json_file(value: str | None) -> Path | None:
    """The file ``--json`` names (None: not given, or ``-``), for
    :func:`tapp.io.outputs.check_paths`."""
    return None if value is None or value == STDOUT else Path(value)


def add_json(outputs: OutputSet, value: str | None, content: object) -> None:
    """Add the file of ``--json``, if it names one, to a command's ``outputs``."""
    path = json_file(value)
    if path is not None:
        outputs.add("--json", path, lambda tmp: tmp.write_text(_dumps(content) + "\n",
                                                                "utf-8"))


@contextmanager
def delivering(value: str | None, content: object, outputs: OutputSet | None = None
               ) -> Iterator[bool]:
    """Deliver a command's results: ``content`` where ``--json`` asks (on standard output
    for ``-``, into its file, or nowhere when not given) and the command's other
    ``outputs``, all together with the report the block prints.

    Every file is written to its temporary first; then the JSON of ``--json -`` is printed,
    the block runs (it yields False when that JSON stands in place of the report) and
    standard output is flushed; only then are the files renamed into place. Standard output
    that cannot be written (full, closed, or a reader gone: ``| head -1``) thus leaves no
    new file, as any failure (:meth:`tapp.io.outputs.OutputSet.staged`).
    """
    outputs = OutputSet() if outputs is None else outputs
    add_json(outputs, value, content)
    with outputs.staged():
        if value == STDOUT:
            print_json(content)
        yield value != STDOUT
        sys.stdout.flush()

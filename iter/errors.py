"""The typed failures of ``iter``; every message names where the problem is and the numbers.

``iter`` knows nothing of ``tapp`` (an import-linter contract forbids it), so it has its own
small hierarchy. The ``tapp iter`` command maps :class:`SweepInputError`,
:class:`ResultFileError` and :class:`SchedulerError` onto ``tapp.errors.InputError`` (exit 2)
field for field, and the others onto ``tapp.errors.TappError``.

A failing *case* (the body raises, or the program exits non-zero) is not an exception at this
level: it is recorded in the results table with its message, and the sweep goes on. A sweep
whose every case failed has no answer: :meth:`iter.run.SweepResult.raise_if_all_failed`
raises :class:`AllCasesFailed` for it, once the failures are recorded.
"""

from __future__ import annotations


class IterError(Exception):
    """Base class of every error ``iter`` raises on purpose."""


class SweepInputError(IterError, ValueError):
    """Bad sweep input: names the source, the field, what was expected and what was given.

    Parameters
    ----------
    source : str
        Where the input came from: a sweep file path, a results file path, or ``"options"``
        for execution settings.
    field : str
        The offending field, e.g. ``"loop[1].vary"`` or ``"body.callable"``.
    expected : str
        What a valid value looks like.
    got : object, optional
        The value given; omitted from the message when None.
    """

    def __init__(self, source: str, field: str, expected: str, got: object = None):
        self.source = source
        self.field = field
        self.expected = expected
        self.got = got
        detail = "" if got is None else f" (got {got!r})"
        super().__init__(f"{source}: {field}: expected {expected}{detail}")


class SchedulerError(IterError):
    """No Dask scheduler answered at an address within the connect timeout.

    Parameters
    ----------
    address : str
        The scheduler address tried, ``tcp://HOST:PORT``.
    timeout_s : float
        The connect timeout that expired or was in force, in seconds.
    reason : str
        What went wrong (timed out, refused, not a Dask scheduler, ...).
    """

    def __init__(self, address: str, timeout_s: float, reason: str):
        self.address = address
        self.timeout_s = timeout_s
        self.reason = reason
        super().__init__(
            f"no Dask scheduler at {address} within {timeout_s:g} s: {reason}"
        )


class ClusterError(IterError):
    """A local Dask cluster did not start.

    Parameters
    ----------
    workers : int
        The workers asked for.
    returncode : int or None
        How its process ended.
    reason : str
        The last line of its log.
    """

    def __init__(self, workers: int, returncode: int | None, reason: str):
        self.workers = workers
        self.returncode = returncode
        self.reason = reason
        super().__init__(f"a local Dask cluster of {workers} workers did not start (its "
                         f"process exited with status {returncode}): {reason}")


class ResultFileError(IterError):
    """A results file cannot be read or written, or is not a valid results file.

    Parameters
    ----------
    path : str
        The results file (the requested path, never a temporary).
    field : str
        What is at fault: ``"file"``, an attribute or a dataset (``"status"``).
    expected : str
        What a valid file has there.
    got : object, optional
        What was found; omitted from the message when None.
    """

    def __init__(self, path: str, field: str, expected: str, got: object = None):
        self.path = path
        self.field = field
        self.expected = expected
        self.got = got
        detail = "" if got is None else f" (got {got!r})"
        super().__init__(f"{path}: {field}: expected {expected}{detail}")


class ResultWriteError(ResultFileError):
    """A results file (or its CSV copy) could not be written; ``error`` is the OSError, from
    which a caller tells a path at fault (a read-only folder) from a full disk."""

    def __init__(self, path: str, error: OSError):
        self.error = error
        super().__init__(path, "file", "a writable file", error.strerror or type(error).__name__)


class AllCasesFailed(IterError):
    """Every case of a sweep failed: the table holds failures only, no answer.

    Parameters
    ----------
    source : str
        The sweep (its file path).
    n_cases : int
        Cases in the sweep, every one failed.
    first_index : int
        The first failed case (the lowest case number).
    first_error : str
        Its error, ``"ExceptionType: message"``.
    output : str or None
        The results file that records every failure, if one was written.
    """

    def __init__(self, source: str, n_cases: int, first_index: int, first_error: str,
                 output: str | None = None):
        self.source = source
        self.n_cases = n_cases
        self.first_index = first_index
        self.first_error = first_error
        self.output = output
        where = "" if output is None else f" (every failure is recorded in {output})"
        super().__init__(f"{source}: every case failed ({n_cases} of {n_cases}); case "
                         f"{first_index}: {first_error}{where}")

"""The typed failures of tapp; every message states the numbers behind it.

``InputError`` is the one raised for bad user input: it names the source (a file or a CLI
option) and the field, and says what was expected, so the CLI can print one line and exit
non-zero.
"""

from __future__ import annotations


class TappError(Exception):
    """Base class of every error tapp raises on purpose."""


class InputError(TappError, ValueError):
    """Bad input: names where it came from, which field, and what was expected."""

    def __init__(self, source: str, field: str, expected: str, got: object = None):
        self.source = source
        self.field = field
        self.expected = expected
        self.got = got
        detail = "" if got is None else f" (got {got!r})"
        super().__init__(f"{source}: {field}: expected {expected}{detail}")


class DeprecatedSpelling(DeprecationWarning):
    """An input in an earlier spelling: it is read, and the warning names the spelling to
    write (parameter names: :mod:`tapp.dynamics.parameters`). The CLI shows it on stderr
    (Python hides a DeprecationWarning raised outside ``__main__`` by default)."""


class WriteError(TappError):
    """An output could not be written for a reason that is not the input's (a full disk, a
    device error): names the option as typed and the requested path, never a temporary."""

    def __init__(self, source: str, path: str, reason: str):
        self.source = source
        self.path = path
        self.reason = reason
        super().__init__(f"{source}: {path}: not written ({reason})")


class DivergenceError(TappError):
    """An iterative process did not converge; carries the iteration count."""

    def __init__(self, message: str, iterations: int):
        self.iterations = iterations
        super().__init__(f"{message} after {iterations} iterations")


class SingularMatrixError(TappError):
    """A matrix that must be inverted is singular to working precision."""


class TooFewMeasurementsError(TappError):
    """Fewer measurements than unknowns."""

    def __init__(self, need: int, got: int):
        self.need = need
        self.got = got
        super().__init__(f"too few measurements: need at least {need}, got {got}")


class NotHyperbolicError(TappError):
    """A B-plane was asked of a non-hyperbolic orbit."""


class TapeError(TappError):
    """A tape is unreadable, truncated or violates its schema; names file and dataset."""

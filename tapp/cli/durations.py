"""Durations on the command line: the earlier spellings of the options that take one.

A duration is a number and its unit, ``24h``, ``90m``, ``3600s``, ``2d``
(:mod:`tapp.io.options`). A number without a unit is refused where it was never accepted; the
earlier spellings of ``tapp propagate`` and ``tapp rsig`` (``--hours 24``, ``--step 60`` in
seconds) are still read, with a warning on stderr naming the new spelling once the command
has succeeded (:func:`warn_deprecated`: a refused command says one line, its error).
"""

from __future__ import annotations

import math
import sys

from tapp.errors import InputError
from tapp.io.options import DURATION_FORMS, parse_duration_s


def warn_deprecated(option: str, hours: float | None, step: str) -> None:
    """Print on stderr, for each earlier spelling a command was given (``--hours``, a bare
    ``--step`` number), the spelling to use; a command calls it once it has succeeded."""
    if hours is not None:
        print(f"warning: --hours {hours:g} is deprecated: write {option} {hours:g}h",
              file=sys.stderr)
    if _is_number(step):
        print(f"warning: --step {step} (seconds) is deprecated: write --step {step}s",
              file=sys.stderr)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def span_option(option: str, text: str | None, hours: float | None, default: str) -> float:
    """The span of ``option`` (a duration) in seconds, or of the deprecated ``--hours``.

    Raises
    ------
    InputError
        Both given, or either not a finite duration > 0.
    """
    if hours is None:
        return parse_duration_s(default if text is None else text, option)
    if text is not None:
        raise InputError(option, "value", f"{option} or the deprecated --hours, not both",
                         f"{option} {text} --hours {hours:g}")
    if not (math.isfinite(hours) and hours > 0):
        raise InputError("--hours", "value", "a finite number > 0", hours)
    return hours * 3600.0


def step_option(text: str) -> float:
    """``--step`` in seconds: a duration, or a bare number of seconds (deprecated)."""
    if not _is_number(text):
        return parse_duration_s(text, "--step")
    seconds = float(text)
    if not (math.isfinite(seconds) and seconds > 0):
        raise InputError("--step", "value", f"a duration > 0 with a unit: {DURATION_FORMS}",
                         text)
    return seconds

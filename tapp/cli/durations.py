"""Durations on the command line: one syntax for every option that takes one.

A duration is a number and its unit, ``24h``, ``90m``, ``3600s``, ``2d`` (``--arc``, ``--span``,
``--step``). A number without a unit is refused where it was never accepted (hours, minutes
and seconds are all in use, and the unit a reader assumes is not always the one meant); the
earlier spellings of ``tapp propagate`` and ``tapp rsig`` (``--hours 24``, ``--step 60`` in
seconds) are still read, with a warning on stderr naming the new spelling once the command
has succeeded (:func:`warn_deprecated`: a refused command says one line, its error).
"""

from __future__ import annotations

import math
import re
import sys

from tapp.errors import InputError

#: A duration: a positive number and its unit (s, m, h or d).
_DURATION = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([smhd])\s*$")
_UNIT_S = {"s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0}
#: The forms a duration is written in, as the error message shows them.
DURATION_FORMS = "24h, 90m, 3600s, 2d"


def parse_duration_s(text: str, option: str = "--arc") -> float:
    """Return a duration in seconds from a number and its unit: '24h', '90m', '3600s', '2d'.

    >>> parse_duration_s("1.5d")
    129600.0
    >>> parse_duration_s("24")
    Traceback (most recent call last):
    ...
    tapp.errors.InputError: --arc: value: expected a duration with a unit: 24h, 90m, 3600s, \
2d (got '24')
    """
    m = _DURATION.match(text)
    if m is None:
        raise InputError(option, "value", f"a duration with a unit: {DURATION_FORMS}", text)
    value = float(m.group(1)) * _UNIT_S[m.group(2)]
    if not (value > 0 and math.isfinite(value)):
        raise InputError(option, "value", f"a duration > 0 with a unit: {DURATION_FORMS}", text)
    return value


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

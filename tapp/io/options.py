"""Values of a run's options, checked where the library takes them: durations, output grids,
seeds and non-negative numbers.

A duration is a number and its unit, ``24h``, ``90m``, ``3600s``, ``2d`` (``--arc``,
``--span``, ``--step``; the front door's ``arc``, ``span``, ``step`` also take a number of
seconds). A number without a unit is refused where text is given (hours, minutes and seconds
are all in use, and the unit a reader assumes is not always the one meant). Errors name the
option as the command spells it, so that ``tapp dc`` and :func:`tapp.api.od.fit` say the same
line.
"""

from __future__ import annotations

import math
import re

from tapp.errors import InputError

#: A duration: a positive number and its unit (s, m, h or d).
_DURATION = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([smhd])\s*$")
_UNIT_S = {"s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0}
#: The forms a duration is written in, as the error message shows them.
DURATION_FORMS = "24h, 90m, 3600s, 2d"
#: Largest output grid (samples of a trajectory, with its STM) a run allocates.
MAX_GRID_SAMPLES = 1_000_000


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


def duration_s(value: str | float, option: str) -> float:
    """Return a duration in seconds: text as :func:`parse_duration_s` reads it, or a number
    of seconds (finite, > 0).

    >>> duration_s("90m", "--arc"), duration_s(5400, "--arc")
    (5400.0, 5400.0)
    """
    if isinstance(value, str):
        return parse_duration_s(value, option)
    if isinstance(value, bool) or not isinstance(value, int | float) or not (
            math.isfinite(value) and value > 0):
        raise InputError(option, "value", f"a duration > 0: seconds, or text with a unit: "
                         f"{DURATION_FORMS}", value)
    return float(value)


def grid_samples(span_s: float, step_s: float) -> float:
    """Return the number of samples of a grid 0, step, ..., span (float: may be inf)."""
    ratio = span_s / step_s
    return float(math.floor(ratio)) + 2.0 if math.isfinite(ratio) else math.inf


def check_grid_size(option: str, n: float, limit: int = MAX_GRID_SAMPLES,
                    what: str = "output samples") -> int:
    """Return ``n`` as an int if it is at most ``limit``, else raise InputError naming
    ``option`` with the size that would be needed.

    Call it before allocating anything of size ``n`` (``n`` may be inf or NaN, from huge
    or tiny option values).

    >>> check_grid_size("--step", 1441.0)
    1441
    >>> check_grid_size("--step", 8.6e13)
    Traceback (most recent call last):
    ...
    tapp.errors.InputError: --step: value: expected a value giving at most 1,000,000 \
output samples (got 'it would need 8.6e+13')
    """
    if not (math.isfinite(n) and n <= limit):
        raise InputError(option, "value", f"a value giving at most {limit:,} {what}",
                         f"it would need {n:.3g}")
    return int(n)


def check_seed(name: str, value: int | None) -> int | None:
    """Return a noise seed (None for the scenario's) if it is >= 0, else raise InputError."""
    if value is not None and value < 0:
        raise InputError(name, "value", "a whole number >= 0 (a seed for numpy's "
                         "SeedSequence)", value)
    return value


def check_nonnegative(name: str, value: float) -> float:
    """Return ``value`` if finite and >= 0, else raise InputError naming the option."""
    if not (math.isfinite(value) and value >= 0):
        raise InputError(name, "value", "a finite number >= 0", value)
    return value

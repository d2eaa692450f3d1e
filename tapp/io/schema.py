"""One declared schema per input-file type, and one error path for all of them.

Every TOML file tapp reads (tracking scenarios, the study file, the SEARCH scenario, ITER sweep
files, the TAPP III deck) is described by a subclass of :class:`Schema`, a pydantic v2 model
that is strict and closed:

- an unknown key or section is an error that names it and lists the allowed keys;
- booleans are not numbers, numbers are not strings, strings are not numbers (strict mode);
  an integer is accepted where a float is declared (``1`` for ``1.0``);
- floats must be finite; a field that may be infinite says so with :data:`AllowInf`
  (``x: Annotated[float, AllowInf]``; NaN stays an error);
- instances are frozen;
- a list whose items must not repeat says so with :data:`Unique`
  (``Annotated[list[str], Unique]``).

:func:`validate` turns the first validation error into one :class:`tapp.errors.InputError`
``(source, "dotted.field[2].path", expected, got)`` with a plain-English ``expected``
("a number", "one of 'J2' or 'J0'", "no such key (allowed: a, b, c)", "a finite number > 0"),
so the CLI prints one line, never a traceback. :func:`load` reads and validates a file.

Checks that are not about types (physics limits, cross-field rules) are validators on the
schema; they raise :class:`Invalid` with the plain-English expectation (and optionally a
sub-field and the offending value), which :func:`validate` reports the same way.

Field names are the TOML keys; a key that is not a Python identifier, or that clashes with a
pydantic attribute (``json``, ``copy``, ...), is declared ``x: T = Field(default, alias="key")``
(messages use the key). Validate one table of a larger file with ``prefix="table"``.

The schemas: :class:`tapp.tracking.scenario_file.ScenarioFile` (tracking scenarios),
:class:`tapp.od.study_schema.StudyFile` (the study file),
:class:`tapp.targeting.searchfile.SearchFile` (SEARCH scenarios),
:class:`iter.sweepfile.SweepFile` (ITER sweep files), and the tables they share:
:class:`tapp.io.orbits.OrbitTable`, :class:`tapp.io.stations_file.StationTable`.

The mechanism itself is :mod:`iter.schema` (``iter`` may not import ``tapp``, and its sweep
files are validated the same way, raising ``SweepInputError``); this module is its ``tapp``
face, raising :class:`tapp.errors.InputError`.

Example
-------
>>> class Study(Schema):
...     seed: int = 0
...     sigma_m: float = 1.0
>>> validate(Study, {"seed": 7}, "study.toml").seed
7
>>> validate(Study, {"sed": 1969}, "study.toml")
Traceback (most recent call last):
...
tapp.errors.InputError: study.toml: sed: expected no such key (allowed: seed, sigma_m) (got 1969)
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Literal, TypeVar

from pydantic import AfterValidator, Field, PlainValidator

from iter.schema import AllowInf, InfFloat, Invalid, Schema, Unique
from iter.schema import validate as _validate
from tapp.errors import InputError
from tapp.io.tomlfile import read_toml

__all__ = ["AllowInf", "EarthOrientationName", "EopSource", "InfFloat", "Invalid", "Schema",
           "Time", "Tolerance", "Unique", "UtcDate", "load", "validate"]

M = TypeVar("M", bound=Schema)


def validate(model: type[M], data: Mapping, source: str, *, prefix: str = "") -> M:
    """Return ``data`` validated as ``model``; the first problem as one InputError.

    Parameters
    ----------
    model : the file's schema (a :class:`Schema` subclass).
    data : parsed TOML (or any mapping).
    source : the file name (or option) named in the message.
    prefix : dotted path of ``data`` within its file, when validating one table of it.

    Raises
    ------
    InputError
        ``source: dotted.field[2].path: expected <plain English> (got <value>)`` for the first
        problem; unknown keys are reported before anything else.
    """
    return _validate(model, data, source, prefix=prefix, error=InputError)


def load(model: type[M], path: Path | str) -> M:
    """Read the TOML file at ``path`` and validate it as ``model`` (errors name the file)."""
    return validate(model, read_toml(path), str(Path(path)))


def _tolerance(value: float) -> float:
    # the range lives with the integrator (tapp.dynamics.propagate.TOLERANCE_RANGE); imported
    # here, not at module level, so reading a file does not load the compiled dynamics
    from tapp.dynamics.propagate import check_tolerance

    try:
        return check_tolerance(value)
    except InputError as exc:
        raise Invalid(exc.expected, value) from None


def _utc_date(value: object) -> object:
    if not isinstance(value, str | dt.datetime):
        raise Invalid("a UTC date (ISO 8601 string or TOML date-time)", value)
    return value


def _time_value(value: object) -> object:
    ok = (isinstance(value, int | float) and not isinstance(value, bool)
          and math.isfinite(value)) or isinstance(value, str | dt.date)
    if not ok:
        raise Invalid("a time: s from the epoch (a finite number) or a UTC date (ISO string "
                      "or TOML date)", value)
    return value


#: A time of a scenario: seconds from the epoch, or a UTC date (ISO string or TOML date),
#: converted by the file's reader once the epoch is known.
Time = Annotated[object, PlainValidator(_time_value,
                                        json_schema_input_type=float | dt.datetime),
                 Field(json_schema_extra={"unit": "s or UTC"})]


def _tolerance_range(json_schema: dict) -> None:
    from tapp.dynamics.propagate import TOLERANCE_RANGE

    json_schema["minimum"], json_schema["maximum"] = TOLERANCE_RANGE


#: An integrator tolerance, within the documented range (``check_tolerance``).
Tolerance = Annotated[float, AfterValidator(_tolerance),
                      Field(json_schema_extra=_tolerance_range)]
#: A UTC date: an ISO 8601 string or a TOML date-time (parsed by the file's reader).
UtcDate = Annotated[object, PlainValidator(_utc_date, json_schema_input_type=dt.datetime)]
#: The Earth orientation model of a scenario file (``earth_orientation``): see
#: :mod:`tapp.frames.orientation`. New scenarios default to "iau2006".
EarthOrientationName = Annotated[Literal["iau2006", "gmst"], Field(
    description="Earth orientation of stations and field: \"iau2006\" (IAU 2006/2000A with "
    "the IERS EOP) or \"gmst\" (GMST + ω t, no precession, nutation or polar motion: the "
    "approximate-STM study's).")]


def _eop_source(value: object) -> object:
    if not isinstance(value, str) or not value.strip():
        raise Invalid('"iers" (the shipped IERS table), "none" (UT1 = UTC, no polar motion) or '
                      "the path of an IERS finals2000A file", value)
    return value


#: Where the EOP come from (``eop``): "iers", "none" or a finals2000A file path (relative to
#: the scenario file); see :func:`tapp.io.eop_file.orientation_for`.
EopSource = Annotated[str, PlainValidator(_eop_source, json_schema_input_type=str), Field(
    description="Earth orientation parameters of iau2006: \"iers\" (the shipped IERS table), "
    "\"none\" (UT1 = UTC, no polar motion: a study beyond the predictions) or the path of a "
    "finals2000A file (relative to this file).")]


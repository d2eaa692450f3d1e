"""Strict, closed schemas for input files, and one error path naming file and field.

This is the mechanism behind :mod:`tapp.io.schema` (which raises ``tapp.errors.InputError``);
it lives here because ``iter`` may not import ``tapp`` and its sweep files are validated the
same way (raising :class:`~iter.errors.SweepInputError`). Read :mod:`tapp.io.schema` for the
rules; in short, a :class:`Schema` subclass is a pydantic v2 model that

- forbids unknown keys and sections (the error names the key and lists the allowed ones);
- is strict: booleans are not numbers, numbers are not strings, strings are not numbers;
  an integer is accepted where a float is declared;
- requires finite floats, unless the field is ``Annotated[float, AllowInf]`` (:data:`InfFloat`;
  infinities allowed, NaN still refused);
- is frozen; a tuple field accepts a TOML array (lists are declared ``list[...]``);
- refuses a key it has renamed (:attr:`Schema.renamed_keys`), naming the new key.

Checks beyond types raise :class:`Invalid` in validators; :func:`validate` reports them like
type errors.

Example
-------
>>> class Loop(Schema):
...     sets: int
>>> validate(Loop, {"sets": 3}, "sweep.toml").sets
3
>>> validate(Loop, {"sets": True}, "sweep.toml")
Traceback (most recent call last):
...
iter.errors.SweepInputError: sweep.toml: sets: expected an integer (got True)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from types import UnionType
from typing import Annotated, Any, ClassVar, TypeVar, Union, get_args, get_origin

import pydantic
from pydantic import AfterValidator, ConfigDict, model_validator
from pydantic.types import AllowInfNan
from pydantic_core import PydanticCustomError

from .errors import SweepInputError

__all__ = ["AllowInf", "InfFloat", "Invalid", "Schema", "Unique", "validate"]

M = TypeVar("M", bound="Schema")


def _not_nan(value: float) -> float:
    if math.isnan(value):
        raise Invalid("a number or inf (not nan)", value)
    return value


class _AllowInf:
    """Marker metadata: this float may be +inf or -inf (NaN stays an error)."""

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        return handler(Annotated[source, AllowInfNan(True), AfterValidator(_not_nan)])


#: Use as ``Annotated[float, AllowInf]`` for a float that may be infinite (never NaN).
AllowInf = _AllowInf()
#: A float that may be +-inf but not NaN.
InfFloat = Annotated[float, AllowInf]


def _unique(values: list) -> list:
    for i, value in enumerate(values):
        if value in values[:i]:
            raise Invalid(f"each item once ({value!r} is repeated)", values)
    return values


class Invalid(ValueError):
    """A failed check in a schema validator: what was expected, the value, and where.

    Parameters
    ----------
    expected : plain English, e.g. "a perigee radius >= 6378.137 km".
    got : the offending value (None: not shown).
    field : dotted sub-path below the validated model or field ("" for the model itself).
    """

    def __init__(self, expected: str, got: object = None, field: str = ""):
        self.expected = expected
        self.got = got
        self.field = field
        super().__init__(expected)


class _Unique:
    """Marker metadata: the list's items must not repeat (JSON Schema ``uniqueItems``)."""

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        return handler(Annotated[source, AfterValidator(_unique)])

    def __get_pydantic_json_schema__(self, core_schema: Any, handler: Any) -> Any:
        return {**handler(core_schema), "uniqueItems": True}


#: Use as ``Annotated[list[X], Unique]`` for a list whose items must not repeat.
Unique = _Unique()


class Schema(pydantic.BaseModel):
    """Base of every file schema: unknown keys forbidden, strict types, finite floats, frozen.

    Field names are the TOML keys; declare ``Field(alias="...")`` for a key that is not a
    Python identifier. Nested tables are nested ``Schema`` subclasses; ``[tables.NAME]`` are
    ``dict[str, Sub]``. Describe every key with ``Field(description=...)``: the reference
    pages are generated from the descriptions (:mod:`tapp.io.reference`).
    """

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False,
                              populate_by_name=False)

    #: Keys this table had under another name, and what replaces each: a file that still
    #: uses one is refused with the new key in the message (one vocabulary across files).
    renamed_keys: ClassVar[Mapping[str, str]] = {}

    @classmethod
    def __get_pydantic_json_schema__(cls, core_schema: Any, handler: Any) -> Any:
        """The JSON Schema of the table, with its renamed keys as ``renamedKeys``."""
        json_schema = super().__get_pydantic_json_schema__(core_schema, handler)
        if cls.renamed_keys:
            handler.resolve_ref_schema(json_schema)["renamedKeys"] = dict(cls.renamed_keys)
        return json_schema

    @model_validator(mode="before")
    @classmethod
    def _known_keys_only(cls, data: Any) -> Any:
        if isinstance(data, Mapping):
            allowed = [f.alias or name for name, f in cls.model_fields.items()]
            for key in data:
                if key in cls.renamed_keys and key not in allowed:
                    raise PydanticCustomError(
                        "renamed_key", "renamed", {"key": key, "new": cls.renamed_keys[key],
                                                   "value": data[key]})
                if key not in allowed:
                    raise PydanticCustomError(
                        "unknown_key", "no such key", {"key": key, "allowed": allowed,
                                                       "value": data[key]})
            tuples = [f.alias or name for name, f in cls.model_fields.items()
                      if _is_tuple(f.annotation)]
            if any(isinstance(data.get(key), list) for key in tuples):
                data = {k: tuple(v) if k in tuples and isinstance(v, list) else v
                        for k, v in data.items()}
        return data


def _is_tuple(annotation: Any) -> bool:
    """Whether a field is a tuple (or an optional one): a TOML array is accepted for it."""
    origin = get_origin(annotation)
    if origin is Annotated:
        return _is_tuple(get_args(annotation)[0])
    if origin in (Union, UnionType):
        return any(_is_tuple(a) for a in get_args(annotation))
    return origin is tuple or annotation is tuple


_EXPECTED = {
    "float_type": "a number",
    "float_parsing": "a number",
    "int_type": "an integer",
    "int_parsing": "an integer",
    "int_from_float": "an integer",
    "finite_number": "a finite number",
    "string_type": "text (a quoted string)",
    "bool_type": "true or false",
    "list_type": "a list",
    "tuple_type": "a list",
    "set_type": "a list",
    "dict_type": "a table",
    "model_type": "a table",
    "model_attributes_type": "a table",
    "datetime_type": "a date and time",
    "datetime_parsing": "a date and time",
    "date_type": "a date",
    "missing": "a value (the key is required)",
    "none_required": "nothing",
}
#: Errors about a key itself (unknown, renamed), reported before any other.
_KEY_ERRORS = ("unknown_key", "renamed_key")
_BOUNDS = {"greater_than": ("gt", ">"), "greater_than_equal": ("ge", ">="),
           "less_than": ("lt", "<"), "less_than_equal": ("le", "<=")}


def _expected(err: Mapping) -> str:
    """Plain-English expectation of one pydantic error."""
    kind = err["type"]
    ctx = err.get("ctx") or {}
    if kind in _BOUNDS:
        key, op = _BOUNDS[kind]
        return f"a finite number {op} {ctx[key]:g}" if isinstance(ctx[key], int | float) \
            else f"a value {op} {ctx[key]}"
    if kind in ("literal_error", "enum"):
        return f"one of {ctx['expected']}"
    if kind == "unknown_key":
        return f"no such key (allowed: {', '.join(ctx['allowed']) or 'none'})"
    if kind == "renamed_key":
        return f"{ctx['new']} in its place (the key was renamed)"
    if kind in ("too_short", "string_too_short"):
        return f"at least {ctx['min_length']} item{'s' * (ctx['min_length'] != 1)}"
    if kind in ("too_long", "string_too_long"):
        return f"at most {ctx['max_length']} item{'s' * (ctx['max_length'] != 1)}"
    if kind == "union_tag_invalid":
        return f"one of {ctx['expected_tags']}"
    if kind == "union_tag_not_found":
        return "a value (the key is required)"
    if kind in ("value_error", "assertion_error"):
        error = ctx.get("error")
        return error.expected if isinstance(error, Invalid) else str(error)
    return _EXPECTED.get(kind, err["msg"])


def _path(data: Any, loc: Sequence, keep_last: bool) -> tuple[list, Any]:
    """The locations of ``loc`` that exist in ``data`` (union tags dropped), and the node.

    ``keep_last`` keeps an absent last key (a missing required key).
    """
    path: list = []
    node = data
    for i, part in enumerate(loc):
        if isinstance(node, Mapping) and part in node:
            path.append(part)
            node = node[part]
        elif (isinstance(node, Sequence) and not isinstance(node, str)
              and isinstance(part, int) and -len(node) <= part < len(node)):
            path.append(part)
            node = node[part]
        elif keep_last and i == len(loc) - 1 and (
                isinstance(node, Mapping)
                or (isinstance(node, Sequence) and isinstance(part, int))):
            path.append(part)
            node = None
    return path, node


def _dotted(path: Sequence) -> str:
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


class _Shown:
    """A value as shown in a message: its repr, cut short when long (whole tables)."""

    def __init__(self, value: object):
        self.value = value

    def __repr__(self) -> str:
        text = repr(self.value)
        return text if len(text) <= 80 else text[:76] + " ..."


def _got(value: object) -> object:
    return _Shown(value) if isinstance(value, Mapping | list | tuple) else value


def _translate(exc: pydantic.ValidationError, data: Mapping, prefix: str
               ) -> tuple[str, str, object]:
    """The first error of ``exc`` as (dotted field, expected, got); unknown keys come first.

    Errors at the same place from the members of a union are joined with "or".
    """
    errors = exc.errors(include_url=False)
    errors.sort(key=lambda e: e["type"] not in _KEY_ERRORS)
    located = []
    for err in errors:
        path, node = _path(data, err["loc"], keep_last=err["type"] == "missing")
        ctx = err.get("ctx") or {}
        got: object = None if err["type"] == "missing" else node
        if err["type"] in _KEY_ERRORS:
            path.append(ctx["key"])
            got = ctx["value"]
        if err["type"] in ("union_tag_invalid", "union_tag_not_found"):
            path.append(str(ctx["discriminator"]).strip("'"))
            got = ctx.get("tag")
        error = ctx.get("error")
        if isinstance(error, Invalid):
            if error.field:
                path.extend(error.field.split("."))
            got = error.got if error.got is not None or error.field else node
        what = _expected(err)
        if err["type"] == "missing" and path and isinstance(path[-1], int):
            what = "an item here (the array is too short)"
        located.append((tuple(path), what, got))
    first = located[0][0]
    expected: list[str] = []
    for path, what, _ in located:
        if path == first and what not in expected:
            expected.append(what)
    field = _dotted(((prefix,) if prefix else ()) + first) or "(document)"
    return field, " or ".join(expected), _got(located[0][2])


def validate(model: type[M], data: Mapping, source: str, *, prefix: str = "",
             error: Callable[[str, str, str, object], Exception] = SweepInputError) -> M:
    """Return ``data`` validated as ``model``; the first problem as one ``error``.

    Parameters
    ----------
    model : the file's schema (a :class:`Schema` subclass).
    data : parsed TOML (or any mapping).
    source : the file name (or option) named in the message.
    prefix : dotted path of ``data`` within its file, when validating one table of it.
    error : the exception class raised, called as ``error(source, field, expected, got)``
        (``tapp.io.schema.validate`` passes ``tapp.errors.InputError``).

    Raises
    ------
    SweepInputError (or ``error``)
        ``source: dotted.field[2].path: expected <plain English> (got <value>)`` for the first
        problem; unknown and renamed keys are reported before anything else.
    """
    try:
        return model.model_validate(data)
    except pydantic.ValidationError as exc:
        raise error(source, *_translate(exc, data, prefix)) from None

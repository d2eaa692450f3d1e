"""The reference of every input file, generated from its schema: one source, no drift.

Each kind of input file is read by one declared schema (:mod:`tapp.io.schema`), whose fields
carry their descriptions, defaults and bounds. :func:`json_schema` gives the JSON Schema of a
kind (``tapp schema KIND``), in the file's own terms: TOML has no null, so an optional key
without a default is simply left out; each key's unit, from its name (``_km``, ``_s``, ...)
or declared, is the keyword ``unit``; keys the table had under another name are
``renamedKeys``. :func:`markdown` renders that JSON Schema as the page
``docs/reference/KIND.md``: every table, and for every key its type, unit, default, allowed
values and meaning; :func:`tapes_markdown` renders the tapes' layout tables as
``docs/reference/tapes.md``. The committed pages are checked against this rendering by the tests;
``python -m tapp.io.reference docs/reference`` writes them again after a schema changes.
"""

from __future__ import annotations

import importlib
import json
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic.json_schema import GenerateJsonSchema

from tapp.errors import InputError


@dataclass(frozen=True, slots=True)
class Kind:
    """A kind of input file: its schema (``module:Class``), a title and what it is for."""

    schema: str
    title: str
    summary: str


#: Every kind of input file, as ``tapp schema KIND`` names it.
KINDS: dict[str, Kind] = {
    "scenario": Kind(
        "tapp.tracking.scenario_file:ScenarioFile", "Tracking scenario (TAPP I)",
        "What `tapp simulate` (and a pipeline) flies and tracks: the injection, the force "
        "models, the parameters, the stations and their schedule, the fit-world and "
        "real-world noise, the T13 times and the miss parameters; optionally a SEARCH "
        "retargeting of the injection. Times are seconds from the epoch or UTC dates."),
    "deck": Kind(
        "tapp.processor.deck:Deck", "TAPP III deck",
        "How `tapp process` reads a T13 tape: print and recycle times, station flags, the "
        "common, fit and real systems (permutations, constraints, a priori), miss partitions "
        "and the print and recycle commands. Parameters are named as on the tape or given by "
        "their 1-based position; times are T13 indices (integers), seconds from the tape "
        "epoch or UTC dates, and must be T13 times."),
    "guidance": Kind(
        "tapp.guidance.guidefile:GuideFile", "TAPP II guidance file",
        "What `tapp guide` does with a T32 tape: the miss components the midcourse "
        "manoeuvres null, at which recycles, how the navigation treats them, their execution "
        "errors and the arrival corridor."),
    "pipeline": Kind(
        "tapp.pipeline.spec:PipelineFile", "Pipeline file",
        "TAPP I → TAPP III → TAPP II in one `tapp pipeline` run: the scenario, deck and "
        "guidance file, each a path (relative to this file) or an inline table, and the "
        "options of the steps."),
    "sweep": Kind(
        "iter.sweepfile:SweepFile", "ITER sweep file",
        "A `tapp iter` parameter sweep: the body run for each case (a Python callable or a "
        "program) and the loops that vary its arguments, outermost first."),
    "search": Kind(
        "tapp.targeting.searchfile:SearchFile", "SEARCH file",
        "A `tapp search` B-plane targeting: the injection whose velocity SEARCH moves, the "
        "force models, the target body's B-plane and SEARCH's targets, tolerances, "
        "increments and iteration control."),
    "study": Kind(
        "tapp.od.study_schema:StudyFile", "Approximate-STM study file",
        "The orbits, stations, simulated tracking and runs of the approximate-STM study "
        "(`tapp dc`, `tapp ekf`, `tapp rsig`, `--orbit NAME` and `make scenario`); the "
        "shipped `approx_stm.toml` is the default."),
}

#: Unit of a key from the end of its name, longest first.
_SUFFIX_UNITS = (("_km3_s2", "km³/s²"), ("_km_s2", "km/s²"), ("_m_s2", "m/s²"),
                 ("_km_s", "km/s"), ("_mm_s", "mm/s"), ("_km", "km"), ("_nrad", "nrad"),
                 ("_mrad", "mrad"), ("_rad", "rad"), ("_deg", "deg"), ("_days", "d"),
                 ("_ns", "ns"), ("_m", "m"), ("_s", "s"), ("_h", "h"))


def unit_of(key: str) -> str | None:
    """The unit a key's name carries (``sigma_range_rate_mm_s`` -> ``mm/s``), or None.

    >>> unit_of("sigma_range_rate_mm_s"), unit_of("GM_km3_s2"), unit_of("rtol")
    ('mm/s', 'km³/s²', None)
    """
    for suffix, unit in _SUFFIX_UNITS:
        if key.endswith(suffix):
            return unit
    return None


def check_kind(kind: str, source: str = "KIND") -> Kind:
    """Return the :class:`Kind` named ``kind``, or raise InputError listing the kinds."""
    if kind not in KINDS:
        raise InputError(source, "value", f"one of {', '.join(KINDS)}", kind)
    return KINDS[kind]


def schema_class(kind: str) -> Any:
    """The schema class of a kind (imported on demand: some pull in the dynamics)."""
    module, name = check_kind(kind).schema.split(":")
    return getattr(importlib.import_module(module), name)


class _TomlJsonSchema(GenerateJsonSchema):
    """JSON Schema in TOML's terms: no null, no default of None, no generated field titles."""

    def nullable_schema(self, schema: Any) -> Any:
        return self.generate_inner(schema["schema"])

    def default_schema(self, schema: Any) -> Any:
        json_schema = super().default_schema(schema)
        if json_schema.get("default", 0) is None:
            del json_schema["default"]
        return json_schema

    def field_title_should_be_set(self, schema: Any) -> bool:
        return False


def _objects(node: Any) -> Iterator[dict]:
    """Every JSON object in a JSON Schema document."""
    if isinstance(node, dict):
        yield node
        for value in node.values():
            yield from _objects(value)
    elif isinstance(node, list):
        for value in node:
            yield from _objects(value)


def _inner_unit(schema: dict) -> str | None:
    """The unit of a list's items or of a union's members (a list of times: "s or UTC")."""
    for inner in [schema.get("items"), *schema.get("anyOf", [])]:
        if isinstance(inner, dict):
            unit = inner.get("unit") or _inner_unit(inner)
            if unit:
                return unit
    return None


def json_schema(kind: str) -> dict:
    """The JSON Schema (2020-12) of a kind of input file, with units (module docstring)."""
    info = check_kind(kind)
    document = schema_class(kind).model_json_schema(by_alias=True,
                                                    schema_generator=_TomlJsonSchema)
    for node in _objects(document):
        for key, prop in node.get("properties", {}).items():
            unit = unit_of(key) or _inner_unit(prop)
            if unit is not None and "unit" not in prop and "$ref" not in prop:
                prop["unit"] = unit
    return {"$schema": "https://json-schema.org/draft/2020-12/schema",
            **document, "title": info.title, "description": info.summary}


# --- Markdown ----------------------------------------------------------------------------------


def _prose(text: str) -> str:
    """Docstring text as one Markdown line: rST roles and double backquotes made plain."""
    text = re.sub(r":(?:class|func|mod|data|meth|attr):`~?([^`]+)`", r"`\1`", text)
    return " ".join(text.replace("``", "`").split()).replace("|", "\\|")


def _number(value: float) -> str:
    return f"{value:,}" if isinstance(value, int) else f"{value:g}"


class _Page:
    """The Markdown page of one JSON Schema document."""

    def __init__(self, document: dict):
        self.defs = document.get("$defs", {})
        self.lines: list[str] = []
        self.rendered: dict[str, str] = {}  # def name -> the first section that showed it
        self.queue: list[tuple[str, dict, str]] = []  # tables still to show, outer first

    def resolve(self, schema: dict) -> dict:
        ref = schema.get("$ref")
        return self.defs[ref.split("/")[-1]] if ref else schema

    def type_of(self, schema: dict) -> str:
        if "$ref" in schema:
            return "table"
        if "anyOf" in schema:
            names = []
            for member in schema["anyOf"]:
                name = self.type_of(member)
                if name not in names:
                    names.append(name)
            return " or ".join(names)
        kind = schema.get("type")
        if "enum" in schema or "const" in schema:
            return "text" if kind in (None, "string") else kind
        if kind == "string":
            return "UTC date" if schema.get("format") == "date-time" else "text"
        if kind == "array":
            items = schema.get("items")
            if not isinstance(items, dict) or not items:
                return "list"
            return "list of tables" if "$ref" in items else f"list of {self.type_of(items)}"
        if kind == "object":
            values = schema.get("additionalProperties")
            if isinstance(values, dict) and "$ref" in values:
                return "tables by name"
            return f"table of {self.type_of(values)}" if isinstance(values, dict) and values \
                else "table"
        return {"number": "number", "integer": "integer", "boolean": "true or false",
                None: "any"}.get(kind, kind)

    def allowed(self, schema: dict) -> str:
        parts: list[str] = []
        if "allowed" in schema:
            parts.append(schema["allowed"])
        for member in schema.get("anyOf", []):
            text = self.allowed(member)
            if text and text not in parts:
                parts.append(text)
        if "enum" in schema:
            parts.append("one of " + ", ".join(f"`{json.dumps(v)}`" for v in schema["enum"]))
        if "const" in schema:
            parts.append(f"`{json.dumps(schema['const'])}`")
        bounds = [f"{op} {_number(schema[key])}" for key, op in (
            ("exclusiveMinimum", ">"), ("minimum", ">="), ("exclusiveMaximum", "<"),
            ("maximum", "<=")) if key in schema]
        if bounds:
            parts.append(", ".join(bounds))
        lo, hi = schema.get("minItems"), schema.get("maxItems")
        if lo is not None and lo == hi:
            parts.append(f"{lo} items")
        elif lo or hi is not None:
            count = hi if lo is None or (hi is not None and hi > 1) else lo
            parts.append(", ".join(([f"at least {lo}"] if lo else [])
                                   + ([f"at most {hi}"] if hi is not None else []))
                         + (" item" if count == 1 else " items"))
        if schema.get("uniqueItems"):
            parts.append("each once")
        for key in ("items", "additionalProperties"):
            inner = schema.get(key)
            if isinstance(inner, dict) and "$ref" not in inner and self.allowed(inner):
                parts.append(f"{'items' if key == 'items' else 'values'}: "
                             f"{self.allowed(inner)}")
        return "; ".join(parts)

    @staticmethod
    def default(schema: dict, required: bool) -> str:
        if required:
            return "required"
        if "default" not in schema:
            return "not set"
        value = schema["default"]
        if isinstance(value, dict):
            return "`{}`" if not value else "the table's defaults"
        if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
            return f"`{value:.1f}`"
        return f"`{json.dumps(value, ensure_ascii=False)}`"

    def subtable(self, schema: dict) -> tuple[str, dict] | None:
        """(form, table schema) of a key holding tables: ``[k]``, ``[k.NAME]``, ``[[k]]``."""
        members = schema.get("anyOf", [schema])
        for member in members:
            if "$ref" in member:
                return "table", self.resolve(member)
            values, items = member.get("additionalProperties"), member.get("items")
            if isinstance(values, dict) and "$ref" in values:
                return "named", self.resolve(values)
            if isinstance(items, dict) and "$ref" in items:
                return "array", self.resolve(items)
        return None

    def section(self, path: str, table: dict, heading: str) -> None:
        name = table.get("title", "")
        self.lines += [f"## {heading}", ""]
        if table.get("description"):
            text = re.sub(r"^`\[[^`]*\]`: ", "", _prose(table["description"]))
            self.lines += [text[:1].upper() + text[1:], ""]
        if name in self.rendered:
            self.lines += [f"The keys of `{self.rendered[name]}`.", ""]
            return
        self.rendered[name] = heading
        props = table.get("properties", {})
        required = set(table.get("required", []))
        if props:
            self.lines += ["| key | type | unit | default | allowed | meaning |",
                           "|---|---|---|---|---|---|"]
            for key, prop in props.items():
                meaning = _prose(prop.get("description", ""))
                self.lines.append(
                    f"| `{key}` | {self.type_of(prop)} | {prop.get('unit', '')} | "
                    f"{self.default(prop, key in required)} | {self.allowed(prop)} | "
                    f"{meaning} |")
            self.lines.append("")
        by_new: dict[str, list[str]] = {}
        for old, new in table.get("renamedKeys", {}).items():
            by_new.setdefault(new, []).append(f"`{old}`")
        if by_new:
            self.lines += ["Old spellings, refused with the new key named: " + "; ".join(
                f"{', '.join(olds)} → `{new}`" for new, olds in by_new.items()) + ".", ""]
        for key, prop in props.items():
            sub = self.subtable(prop)
            if sub is not None:
                form, inner = sub
                child = f"{path}.{key}" if path else key
                if form == "named":
                    child += ".NAME"
                self.queue.append((child, inner, f"[[{child}]]" if form == "array"
                                   else f"[{child}]"))


def markdown(kind: str) -> str:
    """The reference page of a kind of input file (``docs/reference/KIND.md``)."""
    document = json_schema(kind)
    page = _Page(document)
    page.lines += [f"# {document['title']}", "", document["description"], "",
                   f"The JSON Schema of this file is `tapp schema {kind}`; examples: "
                   f"`tapp examples DIR`. Generated from the schema by `python -m "
                   f"tapp.io.reference docs/reference`: do not edit.", ""]
    page.queue.append(("", {**document, "description": ""}, "Top level"))
    while page.queue:  # breadth first: every table before the tables inside it
        page.section(*page.queue.pop(0))
    appendix = getattr(schema_class(kind), "reference_appendix", "")  # a deck's commands
    text = "\n".join(page.lines).rstrip() + "\n"
    return text + f"\n{appendix.rstrip()}\n" if appendix else text


#: The page of the tapes' format, beside the input files' (:func:`tapes_markdown`).
TAPES_PAGE = "tapes.md"


def tapes_markdown() -> str:
    """The format reference of the T13 and T32 tapes (``docs/reference/tapes.md``), from the
    layout tables the tapes' writers and readers use (:mod:`tapp.io.tape.layout`)."""
    from tapp.io.tape import layout, t13, t32  # NumPy: only when the page is wanted

    return layout.markdown(t13.VERSION, t32.VERSION)


def write_reference(folder: Path) -> list[Path]:
    """Write ``KIND.md`` of every kind and :data:`TAPES_PAGE` into ``folder``; return the
    paths."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for kind in KINDS:
        path = folder / f"{kind}.md"
        path.write_text(markdown(kind), encoding="utf-8")
        written.append(path)
    path = folder / TAPES_PAGE
    path.write_text(tapes_markdown(), encoding="utf-8")
    return [*written, path]


if __name__ == "__main__":
    for written_path in write_reference(Path(sys.argv[1] if len(sys.argv) > 1 else
                                             "docs/reference")):
        print(written_path)

"""The reference of the input files: generated from the schemas, committed, never drifting.

``docs/reference/KIND.md`` must be exactly what :func:`tapp.io.reference.markdown` renders from
the schema (``python -m tapp.io.reference docs/reference`` writes them); every key carries a
description; the JSON Schema that ``tapp schema KIND`` prints accepts every shipped example of
its kind and refuses what the schema refuses.
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import jsonschema
import pytest

from tapp.errors import InputError
from tapp.examples import FILES
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.reference import (
    KINDS,
    TAPES_PAGE,
    _objects,
    json_schema,
    markdown,
    schema_class,
    tapes_markdown,
)
from tapp.io.schema import validate
from tapp.io.tomlfile import read_toml

REFERENCE = Path(__file__).resolve().parents[3] / "docs" / "reference"


@pytest.mark.parametrize("kind", KINDS)
def test_the_committed_reference_page_is_the_generated_one(kind: str) -> None:
    committed = (REFERENCE / f"{kind}.md").read_text(encoding="utf-8")
    assert committed == markdown(kind), (
        f"docs/reference/{kind}.md differs from its schema: run "
        "`.venv/bin/python -m tapp.io.reference docs/reference` and commit the result")


def test_the_committed_tapes_page_is_the_generated_one() -> None:
    committed = (REFERENCE / TAPES_PAGE).read_text(encoding="utf-8")
    assert committed == tapes_markdown(), (
        f"docs/reference/{TAPES_PAGE} differs from the layout tables: run "
        "`.venv/bin/python -m tapp.io.reference docs/reference` and commit the result")


def test_the_reference_folder_holds_one_page_per_kind_the_tapes_page_and_nothing_else() -> None:
    assert sorted(p.name for p in REFERENCE.iterdir()) == sorted(
        [*(f"{k}.md" for k in KINDS), TAPES_PAGE])


@pytest.mark.parametrize("kind", KINDS)
def test_every_key_and_table_is_described(kind: str) -> None:
    document = json_schema(kind)
    tables = [document, *document.get("$defs", {}).values()]
    assert all(table.get("description") for table in tables), kind
    undescribed = [f"{node.get('title')}.{key}" for node in _objects(document)
                   for key, prop in node.get("properties", {}).items()
                   if not prop.get("description")]
    assert undescribed == []


@pytest.mark.parametrize("kind", KINDS)
def test_the_json_schema_speaks_toml(kind: str) -> None:
    """No null (TOML has none: an optional key is left out) and a unit on every key whose
    name carries one."""
    text = json.dumps(json_schema(kind))
    assert '"null"' not in text and '"default": null' not in text
    for node in _objects(json_schema(kind)):
        for key, prop in node.get("properties", {}).items():
            if key.endswith(("_km", "_s", "_deg", "_m")) and "$ref" not in prop:
                assert prop.get("unit"), f"{kind}: {key}"


def _as_json(value: object) -> object:
    """A TOML document as JSON sees it (dates as ISO strings)."""
    if isinstance(value, dict):
        return {k: _as_json(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_as_json(v) for v in value]
    if isinstance(value, dt.date | dt.datetime | dt.time):
        return value.isoformat()
    return value


#: The shipped files a scenario reads (its [reference] trajectory and its pass schedule): no
#: schema of their own, they are read by tapp.io.trajectory_file and tapp.io.schedule_file.
READ_BY_A_SCENARIO = ("trajectory", "schedule")


@pytest.mark.parametrize("name", [n for n, kind in FILES.items() if kind in KINDS])
def test_every_shipped_example_passes_its_schema_and_its_json_schema(name: str) -> None:
    kind = FILES[name]
    document = read_toml(EXAMPLES / name)
    validate(schema_class(kind), document, name)
    jsonschema.validate(_as_json(document), json_schema(kind))


def test_the_examples_listed_are_the_examples_shipped() -> None:
    shipped = [str(p.relative_to(EXAMPLES)) for p in EXAMPLES.rglob("*")
               if p.is_file() and p.suffix not in (".py", ".pyc")]
    assert sorted(FILES) == sorted(shipped)
    assert set(FILES.values()) == {*KINDS, *READ_BY_A_SCENARIO}


@pytest.mark.parametrize(("name", "edit"), [
    ("deep_space.toml", lambda d: d["model"].update(gravity_model="J2")),   # unknown key
    ("deep_space.toml", lambda d: d["tracking"].update(data_interval_s=-60.0)),
    ("deep_space.toml", lambda d: d["injection"].update(r_km=[1.0, 2.0])),
    ("search_bplane.toml", lambda d: d["model"].update(stm_gravity="J2")),  # renamed key
    ("tapp2_deep_space.toml", lambda d: d["execution"].update(sigma_proportional=1.5)),
    ("iter_azimuth_type1.toml", lambda d: d.pop("body")),                    # required table
])
def test_the_json_schema_refuses_what_the_schema_refuses(name: str, edit) -> None:
    kind = FILES[name]
    document = read_toml(EXAMPLES / name)
    edit(document)
    with pytest.raises(InputError) as refused:
        validate(schema_class(kind), document, name)
    assert "expected" in str(refused.value)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(_as_json(document), json_schema(kind))

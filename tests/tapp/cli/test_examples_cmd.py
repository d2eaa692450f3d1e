"""``tapp examples DIR`` and ``tapp schema KIND``: a new user's first two commands."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app
from tapp.examples import FILES
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.reference import KINDS, json_schema, markdown

runner = CliRunner()


def test_examples_copies_every_shipped_file_and_lists_its_kind(tmp_path: Path) -> None:
    out = tmp_path / "start"
    result = runner.invoke(app, ["examples", str(out)])
    assert result.exit_code == 0, result.output
    copied = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert copied == sorted(FILES)
    for name, kind in FILES.items():
        assert (out / name).read_bytes() == (EXAMPLES / name).read_bytes()
        assert f"{kind}" in result.output and str(out / name) in result.output
    assert [p.name for p in tmp_path.iterdir()] == ["start"]  # no temporary left
    listed = runner.invoke(app, ["examples", str(tmp_path / "again"), "--json", "-"])
    assert json.loads(listed.stdout)["files"] == [
        {"kind": kind, "path": str(tmp_path / "again" / name)} for name, kind in FILES.items()]


def test_examples_never_writes_over_files(tmp_path: Path) -> None:
    (tmp_path / "mine.toml").write_text("title = 'mine'\n")
    result = runner.invoke(app, ["examples", str(tmp_path)])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: DIR: directory: expected a new or "
                                                   "empty directory"), result.output
    assert [p.name for p in tmp_path.iterdir()] == ["mine.toml"]


@pytest.mark.parametrize("kind", KINDS)
def test_schema_prints_the_json_schema_and_the_reference_page(kind: str) -> None:
    result = runner.invoke(app, ["schema", kind])
    assert result.exit_code == 0, result.output
    assert json.loads(result.output) == json_schema(kind)
    page = runner.invoke(app, ["schema", kind, "--markdown"])
    assert page.exit_code == 0 and page.output == markdown(kind)
    compact = runner.invoke(app, ["schema", kind, "--json", "-"])
    assert json.loads(compact.stdout) == json_schema(kind)


def test_schema_of_an_unknown_kind_is_one_line_listing_the_kinds() -> None:
    result = runner.invoke(app, ["schema", "guide"])
    assert result.exit_code == 2
    assert result.output.strip() == ("error: KIND: value: expected one of " + ", ".join(KINDS)
                                     + " (got 'guide')")

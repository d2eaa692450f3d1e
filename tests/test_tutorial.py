"""``docs/tutorial.md`` runs: every file it shows is written and every command it shows is run,
in order, in an empty folder; every figure it names is then there.

The tutorial's blocks: ```` ```toml title="NAME" ```` is a file the reader saves (written
here as shown), ```` ```console ```` holds commands after ``$ `` (``tapp ...`` run through the
typer app in this process, ``cd DIR``). Any other command fails the test: a reader could not
run what this test does not. Sample counts and arcs are the tutorial's own, small; about 20 s.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from typer.testing import CliRunner

import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app

TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"
_BLOCK = re.compile(r"^```(\w+)([^\n]*)\n(.*?)^```$", re.S | re.M)
_TITLE = re.compile(r'title="([^"]+)"')


def steps(text: str) -> list[tuple[str, str, str]]:
    """The tutorial's steps in order: ("file", name, content) or ("run", command, "")."""
    out = []
    for lang, info, body in _BLOCK.findall(text):
        if lang == "toml" and (title := _TITLE.search(info)):
            out.append(("file", title.group(1), body))
        elif lang == "console":
            out += [("run", line[2:], "") for line in body.splitlines() if line.startswith("$ ")]
    return out


def test_every_block_of_the_tutorial_is_a_step() -> None:
    """No TOML block without its file name, no console block without a command: nothing
    the reader is shown escapes the test."""
    text = TUTORIAL.read_text(encoding="utf-8")
    found = steps(text)
    assert sum(kind == "file" for kind, _, _ in found) == text.count("```toml")
    consoles = [body for lang, _, body in _BLOCK.findall(text) if lang == "console"]
    assert consoles and all(line.startswith("$ ") for body in consoles
                            for line in body.splitlines())
    assert found[0] == ("run", "tapp examples my_study", "")


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> Path:
    """Follow the tutorial in an empty folder; return the study folder it works in (my_study:
    its last section goes down into my_study/mission)."""
    folder = tmp_path_factory.mktemp("tutorial")
    runner = CliRunner()
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(folder)
        for kind, what, content in steps(TUTORIAL.read_text(encoding="utf-8")):
            if kind == "file":
                Path(what).write_text(content, encoding="utf-8")
                continue
            program, *args = shlex.split(what)
            if program == "cd":
                patch.chdir(args[0])
                continue
            assert program == "tapp", f"the tutorial runs only tapp and cd: {what}"
            result = runner.invoke(app, args)
            assert result.exit_code == 0, f"$ {what}\n{result.output}"
        return folder / "my_study"


def test_every_figure_the_tutorial_names_is_made(study: Path) -> None:
    figures = set(re.findall(r"[\w/.-]+\.png", TUTORIAL.read_text(encoding="utf-8")))
    assert len(figures) >= 9
    missing = sorted(f for f in figures if not (study / f).is_file())
    assert missing == []


def test_the_trade_study_has_a_row_per_case(study: Path) -> None:
    rows = (study / "trade.csv").read_text().splitlines()
    assert rows[0].startswith("case,network,data_interval_s,")
    assert [row.split(",")[-3] for row in rows[1:]] == ["ok"] * 4


def test_your_own_mission_flies_its_oem_fitted_on_each_arc(study: Path) -> None:
    """Section 6: the OEM TAPP I flew has a segment before DV1 and one after, and says what
    the fit found and the burn it flew."""
    text = (study / "mission" / "flown.oem").read_text()
    assert text.count("META_START") == 2
    assert "UTC, after DV1: dv fitted [3, " in text
    assert "COMMENT MANOEUVRE DV1 impulsive at 2026-03-11T06:00:00.000000 UTC: dv = [3, " in text

"""Every input file is opened as a regular file or refused (issue "Hardening, second round",
item 1): a FIFO blocked every reader forever in ``open()`` and a symbolic link to
``/dev/zero`` was read until memory ran out. For each reader kind, both are now one line on
stderr and exit 2, with nothing written, and the test cannot hang: it runs under a deadline
and an address-space cap (:mod:`tests.deadline`).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tapp.cli import app
from tapp.examples import FOLDER as EXAMPLES
from tests.deadline import guarded

SCENARIOS = EXAMPLES
runner = CliRunner()


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _zero(path: Path) -> None:
    path.symlink_to("/dev/zero")


BAD_KINDS = {"fifo": (_fifo, "a FIFO (named pipe)"), "dev-zero": (_zero, "a character device")}


def _dummy(folder: Path, name: str) -> Path:
    """A regular file the command would read after the bad one (never reached)."""
    path = folder / name
    path.write_text("not read\n")
    return path


def _leo_with(folder: Path, old: str, new: str) -> Path:
    """leo_equatorial.toml in ``folder`` with ``old`` replaced by ``new`` (once)."""
    path = folder / "leo.toml"
    path.write_text((SCENARIOS / "leo_equatorial.toml").read_text().replace(old, new, 1))
    return path


def _scenario_with_eop(folder: Path, bad: Path) -> Path:
    return _leo_with(folder, '\nepoch = ', f'\neop = "{bad.name}"\nepoch = ')


def _scenario_with_schedule(folder: Path, bad: Path) -> Path:
    return _leo_with(folder, "blackouts = []", f'blackouts = []\nschedule = "{bad.name}"')


def _pipeline_with_deck(folder: Path, bad: Path) -> Path:
    path = folder / "pipeline.toml"
    path.write_text(f'scenario = "{SCENARIOS / "deep_space.toml"}"\ndeck = "{bad}"\n'
                    f'guidance = "{SCENARIOS / "tapp2_deep_space.toml"}"\n'
                    "[guide]\nsamples = 1000\nseed = 1\n")
    return path


#: reader kind -> (bad file name, arguments of the command given the folder and that file)
READERS: dict[str, tuple[str, Callable[[Path, Path], list[str]]]] = {
    "scenario (TOML)": ("s.toml", lambda d, b: ["simulate", str(b), "-o", str(d / "o.h5")]),
    "deck (TOML)": ("deck.toml", lambda d, b: ["process", str(_dummy(d, "t.t13.h5")), str(b)]),
    "guidance file (TOML)": ("g.toml", lambda d, b: [
        "guide", str(_dummy(d, "t.t32.h5")), str(b), "--samples", "1000", "--seed", "1",
        "--serial"]),
    "pipeline file (TOML)": ("p.toml", lambda d, b: [
        "pipeline", str(b), "-o", str(d / "run"), "--serial"]),
    "the pipeline's deck (TOML)": ("deck.toml", lambda d, b: [
        "pipeline", str(_pipeline_with_deck(d, b)), "-o", str(d / "run"), "--serial"]),
    "sweep file (TOML)": ("w.toml", lambda d, b: ["iter", str(b), "--serial"]),
    "study file (TOML)": ("study.toml", lambda d, b: [
        "dc", "--orbit", "SATORB1", "--arc", "2h", "--scenario", str(b)]),
    "TDM observations": ("obs.tdm", lambda d, b: [
        "dc", "--orbit", "SATORB1", "--arc", "2h", "--obs", str(b)]),
    "CSV observations": ("obs.csv", lambda d, b: [
        "dc", "--orbit", "SATORB1", "--arc", "2h", "--obs", str(b)]),
    "HDF5 observations": ("obs.h5", lambda d, b: [
        "dc", "--orbit", "SATORB1", "--arc", "2h", "--obs", str(b)]),
    "EOP table": ("finals2000A.user", lambda d, b: [
        "simulate", str(_scenario_with_eop(d, b)), "-o", str(d / "o.h5")]),
    "pass schedule (CSV)": ("passes.csv", lambda d, b: [
        "simulate", str(_scenario_with_schedule(d, b)), "-o", str(d / "o.h5")]),
    "T13 tape": ("t.t13.h5", lambda d, b: [
        "process", str(b), str(SCENARIOS / "tapp3_leo_equatorial.toml")]),
    "T32 tape": ("t.t32.h5", lambda d, b: [
        "guide", str(b), str(SCENARIOS / "tapp2_deep_space.toml"), "--samples", "1000",
        "--seed", "1", "--serial"]),
    "tape info": ("t.t13.h5", lambda d, b: ["tape", "info", str(b)]),
}


@pytest.mark.parametrize("kind", BAD_KINDS)
@pytest.mark.parametrize("reader", READERS)
def test_a_fifo_or_a_device_is_refused_before_it_is_read(tmp_path: Path, reader: str,
                                                          kind: str) -> None:
    name, command = READERS[reader]
    make, described = BAD_KINDS[kind]
    bad = tmp_path / name
    make(bad)
    args = command(tmp_path, bad)
    before = sorted(p.name for p in tmp_path.iterdir())
    with guarded():
        res = runner.invoke(app, args)
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, (reader, res.exit_code, res.output, res.exception)
    assert len(lines) == 1 and "Traceback" not in res.output, lines
    assert lines[0].startswith(f"error: {bad}: file: expected a regular file ("), lines[0]
    assert lines[0].endswith(f"(got '{described}')"), lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_a_directory_given_as_a_deck_is_refused_naming_it(tmp_path: Path) -> None:
    deck = tmp_path / "deck.toml"
    deck.mkdir()
    res = runner.invoke(app, ["process", str(_dummy(tmp_path, "t.t13.h5")), str(deck)])
    assert res.exit_code == 2
    assert res.stderr.strip() == (f"error: {deck}: file: expected a regular file (TOML file) "
                                  "(got 'a directory')")


def test_a_toml_file_beyond_its_size_bound_is_refused_from_its_size(tmp_path: Path) -> None:
    from iter.inputfile import MAX_TOML_BYTES

    scenario = tmp_path / "big.toml"
    shutil.copy(SCENARIOS / "leo_equatorial.toml", scenario)
    with scenario.open("a") as stream:  # a valid file, padded with a comment past the bound
        stream.write("#" + "x" * MAX_TOML_BYTES + "\n")
    size = scenario.stat().st_size
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(tmp_path / "o.h5")])
    assert res.exit_code == 2
    assert res.stderr.strip() == (f"error: {scenario}: file: expected a TOML file of at most "
                                  f"{MAX_TOML_BYTES:,} bytes (got '{size:,} bytes')")
    assert not (tmp_path / "o.h5").exists()

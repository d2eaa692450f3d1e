"""``tapp simulate`` with a ``[reference]``: bad reference files are one line naming the file
and the field, exit 2 and nothing written; a poor fit is refused unless ``--force``."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
import tomli_w
from typer.testing import CliRunner

import tapp.cli.simulate_cmd  # noqa: F401  (registers the command)
from tapp.cli.common import app
from tests.tapp.tracking.helpers import leo_document

runner = CliRunner()


@pytest.fixture(scope="module")
def flown(tmp_path_factory) -> Path:
    """The LEO scenario's OEM and SPK (``tapp simulate --oem --spk``)."""
    d = tmp_path_factory.mktemp("flown")
    (d / "leo.toml").write_text(tomli_w.dumps(leo_document()))
    res = runner.invoke(app, ["simulate", str(d / "leo.toml"), "-o", str(d / "leo.t13.h5"),
                              "--oem", str(d / "leo.oem"), "--spk", str(d / "leo.bsp")])
    assert res.exit_code == 0, res.output
    return d


def _case(tmp_path: Path, flown: Path, reference: dict, edit: Callable[[str], str] | None = None,
          **tables) -> Path:
    """A scenario reading ``reference`` in ``tmp_path``, beside copies of the OEM and SPK (the
    OEM passed through ``edit``)."""
    shutil.copy(flown / "leo.bsp", tmp_path / "leo.bsp")
    text = (flown / "leo.oem").read_text()
    (tmp_path / "leo.oem").write_text(text if edit is None else edit(text))
    path = tmp_path / "ref.toml"
    path.write_text(tomli_w.dumps(leo_document(**{"injection": None, "reference": reference,
                                                  **tables})))
    return path


def _run(tmp_path: Path, scenario: Path, *extra: str):
    before = sorted(p.name for p in tmp_path.iterdir())
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(tmp_path / "out.t13.h5"),
                              "--oem", str(tmp_path / "out.oem"), "--spk",
                              str(tmp_path / "out.bsp"), *extra])
    return res, before


def _line(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def _truncated(text: str) -> str:
    """The OEM without its last hour (STOP_TIME moved to match)."""
    lines = text.splitlines()
    keep = [line for line in lines if not line.startswith("2026-01-01T02:")
            and not line.startswith("2026-01-01T03:")]
    return "\n".join(keep).replace("STOP_TIME = 2026-01-01T03:00:00.000000",
                                   "STOP_TIME = 2026-01-01T01:59:40.000000") + "\n"


def _swapped(text: str) -> str:
    """The OEM with its 4th and 5th states swapped."""
    lines = text.splitlines()
    first = lines.index("META_STOP") + 2
    lines[first + 3], lines[first + 4] = lines[first + 4], lines[first + 3]
    return "\n".join(lines) + "\n"


#: (reference table, OEM edit, file named: "scenario" or "oem", field, expected, got).
CASES = {
    "missing file": ({"file": "nowhere.oem"}, None, "scenario", "reference.file",
                     "an SPK or OEM file that exists", "nowhere.oem"),
    "SPK without the object": ({"file": "leo.bsp", "object": -5}, None, "scenario",
                               "reference.object", "a body whose data leo.bsp holds (-999)",
                               "-5"),
    "OEM short of the span": ({"file": "leo.oem"}, _truncated, "oem", "line 15: STOP_TIME",
                              "states up to the end of the scenario's span",
                              "2026-01-01T01:59:40.000 UTC"),
    "unknown frame": ({"file": "leo.oem"}, lambda t: _line(t, "REF_FRAME = GCRF",
                                                           "REF_FRAME = TOD"),
                      "oem", "line 12: REF_FRAME", "a frame tapp reads", "TOD"),
    "unknown centre": ({"file": "leo.oem"}, lambda t: _line(t, "CENTER_NAME = EARTH",
                                                            "CENTER_NAME = ALPHA CENTAURI"),
                       "oem", "line 11: CENTER_NAME", "EARTH, or a body whose state DE421 "
                       "gives", "ALPHA CENTAURI"),
    "unknown time system": ({"file": "leo.oem"}, lambda t: _line(t, "TIME_SYSTEM = UTC",
                                                                 "TIME_SYSTEM = UT1"),
                            "oem", "line 13: TIME_SYSTEM", "a time system tapp reads", "UT1"),
    "non-monotonic epoch": ({"file": "leo.oem"}, _swapped, "oem", "line 24: epoch",
                            "epochs strictly increasing within a segment",
                            "2026-01-01T00:01:00.000000"),
    "step_s with an OEM": ({"file": "leo.oem", "step_s": 30.0}, None, "scenario",
                           "reference.step_s", "no step_s for an OEM", "30.0"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_reference_is_one_line_exit_2_and_nothing_written(tmp_path: Path, flown: Path,
                                                              case: str) -> None:
    reference, edit, named, field, expected, got = CASES[case]
    scenario = _case(tmp_path, flown, reference, edit)
    res, before = _run(tmp_path, scenario)
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    file = scenario if named == "scenario" else tmp_path / "leo.oem"
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"error: {file}: {field}: expected {expected}"), lines[0]
    assert lines[0].endswith(f"{got}')") or lines[0].endswith(f"(got {got})"), lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before


@pytest.mark.parametrize(("tables", "field"), [
    ({"injection": leo_document()["injection"]}, "injection"),
    ({"targeting": {"targets": {"b_dot_r_km": 0.0, "b_dot_t_km": 5000.0}}}, "targeting"),
])
def test_the_reference_replaces_the_injection_and_refuses_targeting(
        tmp_path: Path, flown: Path, tables: dict, field: str) -> None:
    scenario = _case(tmp_path, flown, {"file": "leo.oem"}, **tables)
    res, before = _run(tmp_path, scenario)
    assert res.exit_code == 2
    assert res.stderr.startswith(f"error: {scenario}: {field}: expected ")
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_poor_fit_is_refused_unless_forced_and_then_said(tmp_path: Path, flown: Path) -> None:
    """Two-body against the J2 trajectory: kilometres off over 3 h."""
    scenario = _case(tmp_path, flown, {"file": "leo.oem"},
                     model={"gravity": "J0", "var_gravity": "J0"},
                     parameters={"dynamic": ["GM_km3_s2"]})
    res, before = _run(tmp_path, scenario)
    assert res.exit_code == 2
    (line,) = res.stderr.strip().splitlines()
    assert line.startswith(f"error: {scenario}: reference.max_fit_error_m: expected TAPP I's "
                           "force model within 100 m of the reference ")
    assert "--force accepts it) (got 'largest " in line
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    res, _ = _run(tmp_path, scenario, "--force", "--json", str(tmp_path / "out.json"))
    assert res.exit_code == 0, res.output
    info = json.loads((tmp_path / "out.json").read_text())
    (arc,) = info["reference"]["arcs"]
    assert info["reference"]["forced"] and arc["max_m"] > 1000.0
    (warning,) = res.stderr.strip().splitlines()
    assert warning == (f"warning: {scenario}: reference.max_fit_error_m: the fit to "
                       f"{tmp_path / 'leo.oem'} misses it by {arc['max_m']:.4g} m (RMS "
                       f"{arc['rms_m']:.4g} m), more than 100 m; flown as --force asked")
    assert "exceeded, accepted by --force" in (tmp_path / "out.oem").read_text()

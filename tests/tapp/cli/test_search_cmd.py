"""``tapp search`` end to end through the typer app, on scenarios/search_bplane.toml."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import tapp.cli.search_cmd  # noqa: F401  (registers the command until tapp.cli imports it)
from search import EXIT_FLAG
from tapp.cli.common import app
from tapp.cli.search_cmd import EXIT_CODE

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "search_bplane.toml"
runner = CliRunner()


def _edited(tmp_path: Path, old: str, new: str, name: str = "edited.toml") -> Path:
    text = SCENARIO.read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def test_exit_codes_follow_search_flags() -> None:
    assert EXIT_CODE == {"converged": 0, "diverged": 3, "singular": 4}
    assert set(EXIT_CODE) == set(EXIT_FLAG)


@pytest.mark.parametrize("extra", [[], ["--analytic-partials"]])
def test_json_on_the_scenario_converges(extra: list[str]) -> None:
    result = runner.invoke(app, ["search", str(SCENARIO), "--json", *extra])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["status"] == "converged" and out["flag"] == 1 and out["exit_code"] == 0
    y, targets, tol = (np.array(out[k]) for k in ("y", "targets", "tolerances"))
    assert np.all(np.abs(y - targets) <= tol)
    np.testing.assert_allclose(out["miss"], y - targets)
    np.testing.assert_array_equal(targets[:2], [-2000.0, 5300.0])
    cases = out["history"]["cases"]
    assert out["cases_run"] == len(cases) == out["trajectories"] == sum(out["cases"].values())
    assert cases[0]["kind"] == "nominal"
    assert targets[2] == cases[0]["y"][2] + 3600.0  # theta on the flight time
    assert cases[-1]["x"] == out["x"] and cases[-1]["y"] == out["y"]
    assert out["analytic_partials"] is bool(extra)
    sources = {ps["source"] for ps in out["history"]["partial_sets"]}
    assert sources == ({"analytic"} if extra else {"differenced"})
    assert out["cases"]["perturbed"] == (0 if extra else 3 * len(out["history"]["partial_sets"]))
    assert out["encounter"]["body"] == "moon" and out["encounter"]["periapsis_altitude_km"] > 0


def test_text_report_has_the_seed_blocks() -> None:
    result = runner.invoke(app, ["search", str(SCENARIO)])
    assert result.exit_code == 0, result.output
    for line in ("SEARCH PROGRAM PARAMETERS", "T. V. MODIFICATIONS", "THE MATRIX OF PARTIALS IS",
                 "THE INVERSE PARTIAL MATRIX IS", "I.V. INCREMENTS (DELTAS) ARE",
                 "TOTAL INCREMENTS ARE", "EXIT: CONVERGED", "ENCOUNTER WITH THE MOON"):
        assert line in result.stdout


def test_one_set_of_one_iteration_cannot_converge_exit_3(tmp_path: Path) -> None:
    path = _edited(tmp_path, "iterations_per_partials = 3", "iterations_per_partials = 1")
    path.write_text(path.read_text().replace("partial_sets = 3", "partial_sets = 1", 1))
    result = runner.invoke(app, ["search", str(path), "--json"])
    assert result.exit_code == 3, result.output
    out = json.loads(result.stdout)
    assert out["status"] == "diverged" and out["cases"] == {"nominal": 1, "perturbed": 3,
                                                             "applied": 1}
    assert np.any(np.abs(np.array(out["miss"])) > np.array(out["tolerances"]))


@pytest.mark.parametrize(("old", "new", "field"), [
    ("b_dot_t_km = 1.0", "b_dot_t_km = -1.0", "search.tolerances.b_dot_t_km"),
    ('gravity = "J2"', 'gravity = "J2x"', "model.gravity"),
    ('body = "moon"', 'body = "mars"', "target.body"),
    ("partial_sets = 3", "partial_sets = 0", "search.partial_sets"),
    ("vz_km_s = 1e-5", "vz_km_s = 0.0", "search.increments.vz_km_s"),
    ('epoch = "2026-03-10T12:00:00"', 'epoch = "tomorrow"', "epoch"),
    ("[injection]", "[injection]\nmass_kg = 1000.0", "injection.mass_kg"),
])
def test_bad_field_one_line_naming_file_and_field(tmp_path: Path, old: str, new: str,
                                                  field: str) -> None:
    path = _edited(tmp_path, old, new, "bad.toml")
    result = runner.invoke(app, ["search", str(path)])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}: {field}:"), lines


def test_missing_file_and_bad_toml(tmp_path: Path) -> None:
    missing = runner.invoke(app, ["search", str(tmp_path / "none.toml")])
    assert missing.exit_code == 2 and "none.toml: file:" in missing.stderr
    broken = tmp_path / "broken.toml"
    broken.write_text("epoch = \n")
    result = runner.invoke(app, ["search", str(broken)])
    assert result.exit_code == 2 and "broken.toml: TOML:" in result.stderr


def test_case_that_misses_the_moon_fails_with_one_line(tmp_path: Path) -> None:
    path = _edited(tmp_path, "max_flight_time_s = 691200.0", "max_flight_time_s = 172800.0")
    result = runner.invoke(app, ["search", str(path)])
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "search case 1 at v0" in lines[0]
    assert "sphere of influence" in lines[0]


def test_earth_orientation_option_overrides_the_file() -> None:
    """The J2 pole differs by 0.36 deg between the models: the targeted injection velocity
    moves (by about 0.5 m/s here), both converge; an unknown model is one line, exit 2."""
    runs = {}
    for model in ("iau2006", "gmst"):
        res = runner.invoke(app, ["search", str(SCENARIO), "--json", "--earth-orientation",
                                  model])
        assert res.exit_code == 0, res.output
        runs[model] = np.array(json.loads(res.stdout)["x"])
    assert 1e-5 < np.linalg.norm(runs["iau2006"] - runs["gmst"]) < 1e-2  # km/s
    res = runner.invoke(app, ["search", str(SCENARIO), "--earth-orientation", "iau1980"])
    assert res.exit_code == 2
    assert res.stderr.strip() == ('error: --earth-orientation: value: expected "iau2006" or '
                                  '"gmst" (got \'iau1980\')')

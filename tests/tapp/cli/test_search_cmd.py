"""``tapp search`` end to end through the typer app, on the example search_bplane.toml."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import tapp.cli.search_cmd  # noqa: F401  (registers the command until tapp.cli imports it)
import tapp.cli.simulate_cmd  # noqa: F401  (tapp simulate, for the written scenarios)
from search import EXIT_FLAG
from tapp.cli.common import app
from tapp.cli.search_cmd import exit_code
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.tape.t13_hdf5 import read_t13
from tapp.tracking.scenario_build import read_scenario
from tests.tapp.tracking.encounter_reference import (
    AIM,
    TARGETING,
    Reference,
    moved_deep_space,
)

SCENARIO = EXAMPLES / "search_bplane.toml"
runner = CliRunner()


def _edited(tmp_path: Path, old: str, new: str, name: str = "edited.toml") -> Path:
    text = SCENARIO.read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def test_exit_codes_follow_search_flags() -> None:
    assert {status: exit_code(status) for status in EXIT_FLAG} == {
        "converged": 0, "diverged": 3, "singular": 4}
    assert exit_code("missed") is None  # not one of SEARCH's exits: the caller's to map


@pytest.mark.parametrize("extra", [[], ["--analytic-partials"]])
def test_json_on_the_scenario_converges(extra: list[str]) -> None:
    result = runner.invoke(app, ["search", str(SCENARIO), "--json", "-", *extra])
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
    result = runner.invoke(app, ["search", str(path), "--json", "-"])
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
    ("[model]", '[model]\nmethod = "rkn12"\natmosphere = "exponential"\n'
     "area_to_mass_m2_kg = 0.01", "model.method"),  # was "propagator: method: ..."
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
        res = runner.invoke(app, ["search", str(SCENARIO), "--json", "-", "--earth-orientation",
                                  model])
        assert res.exit_code == 0, res.output
        runs[model] = np.array(json.loads(res.stdout)["x"])
    assert 1e-5 < np.linalg.norm(runs["iau2006"] - runs["gmst"]) < 1e-2  # km/s
    res = runner.invoke(app, ["search", str(SCENARIO), "--earth-orientation", "iau1980"])
    assert res.exit_code == 2
    assert res.stderr.strip() == ('error: --earth-orientation: value: expected "iau2006" or '
                                  '"gmst" (got \'iau1980\')')


# --- tracking scenarios with [targeting], and --write-scenario -------------------------------

DEEP = SCENARIO.parent / "deep_space.toml"
ONE_KM = 1.0


def _moved(tmp_path: Path, targeting: str | None = TARGETING) -> Path:
    path = tmp_path / "moved.toml"
    path.write_text(moved_deep_space(DEEP.read_text(), targeting=targeting))
    return path


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> tuple[Path, Path, dict]:
    """``tapp search moved.toml --json --write-scenario targeted.toml``: (input, written,
    JSON)."""
    folder = tmp_path_factory.mktemp("write")
    path, out = _moved(folder), folder / "targeted.toml"
    res = runner.invoke(app, ["search", str(path), "--json", "-", "--write-scenario", str(out)])
    assert res.exit_code == 0, res.output
    return path, out, json.loads(res.stdout)


def test_a_tracking_scenario_is_searched_on_its_targeting_table(written) -> None:
    _, _, out = written
    assert out["status"] == "converged" and out["first_guess"] == "conic"
    assert out["x_names"] == ["vx_km_s", "vy_km_s", "vz_km_s"]
    assert out["y_names"] == ["b_dot_r_km", "b_dot_t_km", "flight_time_s"]
    np.testing.assert_array_equal(out["targets"], list(AIM.values()))
    assert np.all(np.abs(np.array(out["miss"])) <= np.array(out["tolerances"]))
    assert out["v0_km_s"] == out["x"]


def test_written_scenario_has_the_targeted_injection_and_keeps_the_rest(written) -> None:
    """The [injection] table replaced exactly (the floats read back bit for bit), [targeting]
    gone, every other table and the comments as they were."""
    path, out_path, out = written
    text, before = out_path.read_text(), path.read_text()
    doc, original = tomllib.loads(text), tomllib.loads(before)
    assert doc["injection"] == {"r_km": original["injection"]["r_km"], "v_km_s": out["x"]}
    assert "targeting" not in doc and "# Targeted by tapp search from moved.toml" in text
    assert {k: v for k, v in doc.items() if k != "injection"} == {
        k: v for k, v in original.items() if k not in ("injection", "targeting")}
    kept = [line for line in before.splitlines() if line.startswith("#")]
    assert kept and all(line in text for line in kept)


def test_written_scenario_simulates_to_the_aim_point(written, tmp_path: Path) -> None:
    """``tapp simulate`` of the written scenario (no SEARCH any more): its tape's injection,
    flown by the reference trajectory, is within 1 km of the aim point."""
    _, out_path, out = written
    tape_path = tmp_path / "run.t13.h5"
    res = runner.invoke(app, ["simulate", str(out_path), "-o", str(tape_path), "--json", "-"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["targeting"] is None
    tape = read_t13(tape_path)
    np.testing.assert_array_equal(tape.parameters.nominal[3:6], out["x"])
    ref = Reference(read_scenario(out_path), tape.parameters.nominal[:6], tape.miss.t_s + 7200.0)
    _, b_r, b_t = ref.periapsis_b_plane(tape.miss.t_s)
    assert abs(b_r - AIM["b_dot_r_km"]) < ONE_KM and abs(b_t - AIM["b_dot_t_km"]) < ONE_KM


def test_write_scenario_refuses_its_input_and_writes_nothing_unconverged(tmp_path: Path) -> None:
    path = _moved(tmp_path)
    before = path.read_bytes()
    res = runner.invoke(app, ["search", str(path), "--write-scenario", str(path)])
    assert res.exit_code == 2 and path.read_bytes() == before
    assert res.stderr.startswith(f"error: --write-scenario: {path}: expected a file other than "
                                 "the input SCENARIO")
    diverging = tmp_path / "diverging.toml"
    diverging.write_text(before.decode().replace('first_guess = "conic"', 'first_guess = "conic"'
                                                 "\niterations_per_partials = 1\npartial_sets = 1"))
    res = runner.invoke(app, ["search", str(diverging), "--write-scenario",
                              str(tmp_path / "out.toml")])
    assert res.exit_code == 3
    assert "not written: SEARCH diverged" in res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["diverging.toml", "moved.toml"]


def test_write_scenario_keeps_the_file_s_earth_orientation(tmp_path: Path) -> None:
    path = _moved(tmp_path)
    res = runner.invoke(app, ["search", str(path), "--earth-orientation", "gmst",
                              "--write-scenario", str(tmp_path / "out.toml")])
    assert res.exit_code == 2
    assert res.stderr.startswith(f"error: --write-scenario: {tmp_path / 'out.toml'}: expected "
                                 "no --earth-orientation other than the file's")


def test_a_tracking_scenario_without_targeting_is_refused(tmp_path: Path) -> None:
    path = _moved(tmp_path, targeting=None)
    res = runner.invoke(app, ["search", str(path)])
    assert res.exit_code == 2
    assert res.stderr.strip() == (f"error: {path}: targeting: expected a [targeting] table (the "
                                  "aim point) in a tracking scenario given to tapp search")


def test_a_search_file_is_written_back_with_its_converged_first_guess(tmp_path: Path) -> None:
    """A SEARCH file keeps its [search] table: written back, its first guess is the solution,
    so searching it again converges on its first case."""
    out = tmp_path / "again.toml"
    res = runner.invoke(app, ["search", str(SCENARIO), "--json", "-", "--write-scenario", str(out)])
    assert res.exit_code == 0, res.output
    assert tomllib.loads(out.read_text())["injection"]["v_km_s"] == json.loads(res.stdout)["x"]
    again = runner.invoke(app, ["search", str(out), "--json", "-"])
    assert again.exit_code == 0, again.output
    assert json.loads(again.stdout)["cases"] == {"nominal": 1, "perturbed": 0, "applied": 0}

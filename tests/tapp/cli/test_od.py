"""``tapp dc``, ``tapp ekf``, ``tapp rsig`` and observation files, end to end."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tapp.cli import app
from tapp.od import setup
from tapp.od.obsfile import read_observations, write_observations
from tapp.stations_file import load_stations

runner = CliRunner()


def test_dc_json_reports_the_converged_fit() -> None:
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "12h", "--truth", "J2",
                              "--stm", "J2", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["converged"] is True and out["iterations"] <= 6
    assert out["rms"][0] > 100 and out["rms"][-1] == pytest.approx(1.0, abs=0.1)
    assert out["final_elements"]["a_km"] == pytest.approx(6550.524, abs=1e-3)
    assert out["position_error_km"] < 0.01


def test_dc_that_diverges_exits_3_with_its_json() -> None:
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "24h", "--stm", "J0",
                              "--json"])
    assert res.exit_code == 3
    assert json.loads(res.stdout)["converged"] is False


def test_ekf_and_rsig_json_shapes() -> None:
    res = runner.invoke(app, ["ekf", "--orbit", "SATORB1", "--arc", "3h", "--apriori", "2",
                              "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert len(out["passes"]) == len(out["max_abs_residual_per_pass"]) > 0
    assert set(out["max_abs_residual_per_pass"][0]) == {"range_m", "range_rate_mm_s"}
    res = runner.invoke(app, ["rsig", "--orbit", "SATORB1", "--truth", "J0", "--stm", "J0",
                              "--hours", "2", "--step", "600", "--json"])
    out = json.loads(res.stdout)
    assert len(out["t_s"]) == len(out["R"]) == 13
    assert out["R"][0] == pytest.approx(np.sqrt(3.0))  # Φ(t0) = I: three unit entries


@pytest.mark.parametrize(("args", "option"), [
    (["dc", "--orbit", "SATORB9"], "--orbit"),
    (["dc", "--orbit", "a=7000,e=0.1,i=0,raan=0,argp=0"], "--orbit"),
    (["dc", "--orbit", "SATORB1", "--arc", "0h"], "--arc"),
    (["dc", "--orbit", "SATORB1", "--arc", "-6h"], "--arc"),
    (["dc", "--orbit", "SATORB1", "--stm", "J2x"], "--stm"),
    (["ekf", "--orbit", "SATORB1", "--apriori", "7"], "--apriori"),
    (["ekf", "--orbit", "SATORB1", "--apriori", "sx=1,sy=1,sz=1,svx=0,svy=1,svz=1"],
     "--apriori"),
    (["rsig", "--orbit", "SATORB1", "--hours", "0"], "--hours"),
])
def test_bad_input_one_line_nonzero_exit(args: list[str], option: str) -> None:
    res = runner.invoke(app, args)
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {option}")


@pytest.fixture(scope="module")
def small_obs():
    x = setup.true_orbit("SATORB1")
    obs = setup.simulated_observations(x, "J2", setup.network_for(x, None))
    return obs.window(6 * 3600.0)


@pytest.mark.parametrize("suffix", [".h5", ".csv"])
def test_observation_file_round_trip(tmp_path: Path, small_obs, suffix: str) -> None:
    path = tmp_path / f"obs{suffix}"
    write_observations(path, small_obs)
    stations = load_stations(setup.load_study(), "approx_stm.toml")
    back = read_observations(path, stations, small_obs.sigma)
    np.testing.assert_array_equal(back.t_s, small_obs.t_s)
    np.testing.assert_array_equal(back.values, small_obs.values)
    names = [small_obs.stations[i].name for i in small_obs.station]
    assert [back.stations[i].name for i in back.station] == names


def test_dc_reads_an_observation_file(tmp_path: Path, small_obs) -> None:
    path = tmp_path / "obs.csv"
    write_observations(path, small_obs)
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "6h", "--obs", str(path),
                              "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["measurements"] == small_obs.count


@pytest.mark.parametrize(("text", "field"), [
    ("t_s,station,range_km\n0,QUITO,1000\n", "header"),  # range-rate column missing vs σ
    ("t_s,range_km,range_rate_km_s\n0,1,2\n", "header"),
    ("t_s,station,range_km,range_rate_km_s\n10,QUITO,1,0.1\n5,QUITO,1,0.1\n", "t_s"),
    ("t_s,station,range_km,range_rate_km_s\n10,NOWHERE,1,0.1\n", "station"),
    ("t_s,station,range_km,range_rate_km_s\n10,QUITO,x,0.1\n", "line 2"),
])
def test_bad_observation_file_names_file_and_field(tmp_path: Path, text: str,
                                                   field: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--obs", str(path)])
    assert res.exit_code == 2
    line = res.stderr.strip()
    assert str(path) in line and field in line

"""``tapp dc``, ``tapp ekf``, ``tapp rsig`` and observation files, end to end; the Earth
orientation switch (the study file's ``earth_orientation`` and ``eop``, ``--earth-orientation``)
and what the outputs record of it."""

from __future__ import annotations

import json
from datetime import datetime, timedelta
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from tapp.cli import app
from tapp.od import setup
from tapp.od.observations import MadeUnder
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
    out = json.loads(res.stdout)
    assert out["converged"] is False and out["status"] == "diverged" and out["exit_code"] == 3
    assert out["predicted_rate"] > 1 and len(out["eigenvalues"]) == 6
    assert out["eigenvalues"][0]["abs"] == pytest.approx(out["predicted_rate"])


def test_dc_stopped_while_converging_exits_6_with_factor_and_projection() -> None:
    """The issue's example: --max-iter 3 with the RMS falling from 3295 is not "diverged"."""
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "24h", "--max-iter", "3",
                              "--json"])
    assert res.exit_code == 6, res.output
    out = json.loads(res.stdout)
    assert out["status"] == "converging" and out["iterations"] == 3
    assert out["rms"][0] == pytest.approx(3295, rel=1e-3) and out["rms"][-1] < 3
    assert 0 < out["contraction_factor"] < 0.1 and out["projected_iterations"] == 0
    assert out["predicted_rate"] < 1e-9 and out["converged_at"] is None


def test_dc_text_output_shows_outcome_and_rates() -> None:
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "12h", "--stm", "J0",
                              "--max-iter", "20"])
    assert res.exit_code == 6, res.output
    assert "converging: iteration limit 20 reached while converging" in res.stdout
    assert "predicted rate ρ = 0.98" in res.stdout and "factor q = 0.97" in res.stdout


def test_dc_ill_conditioned_normal_matrix_exits_4_with_the_diagnosis() -> None:
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "10m", "--json"])
    assert res.exit_code == 4, res.output
    out = json.loads(res.stdout)
    assert out["status"] == "ill-conditioned" and out["condition_number"] > 1e10
    (direction,) = out["undetermined_directions"]
    assert abs(direction["z"]) > 0.6 and abs(direction["vz"]) > 0.6
    text = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "10m"])
    assert text.exit_code == 4 and "condition number" in text.stdout and "vz" in text.stdout


def test_an_arc_longer_than_the_data_names_arc_and_the_span() -> None:
    for command in ("dc", "ekf"):
        res = runner.invoke(app, [command, "--orbit", "SATORB1", "--arc", "1000d"])
        assert res.exit_code == 2
        line = res.stderr.strip()
        assert line.startswith("error: --arc: value: expected an arc no longer than the data "
                               "span") and "120 h" in line and "'1000d'" in line


def test_no_measurement_in_the_arc_fails_alike_for_dc_and_ekf() -> None:
    dc = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "2m"])
    ekf = runner.invoke(app, ["ekf", "--orbit", "SATORB1", "--arc", "2m"])
    assert dc.exit_code == ekf.exit_code == 1
    for res in (dc, ekf):
        assert res.stderr.strip().startswith("error: too few measurements: need at least")
        assert "got 0" in res.stderr


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


@pytest.mark.parametrize("suffix", [".h5", ".csv", ".tdm"])
def test_observation_file_round_trip(tmp_path: Path, small_obs, suffix: str) -> None:
    path = tmp_path / f"obs{suffix}"
    write_observations(path, small_obs, epoch=setup.epoch(), spacecraft="SATORB1")
    stations = load_stations(setup.load_study(), "approx_stm.toml")
    back = read_observations(path, stations, small_obs.sigma, epoch=setup.epoch())
    np.testing.assert_array_equal(back.t_s, small_obs.t_s)
    np.testing.assert_array_equal(back.values, small_obs.values)
    np.testing.assert_array_equal(back.sigma, small_obs.sigma)
    names = [small_obs.stations[i].name for i in small_obs.station]
    assert [back.stations[i].name for i in back.station] == names
    if suffix != ".csv":
        assert back.end_s == pytest.approx(small_obs.end_s)
    # the study file's model, gmst, which uses no EOP, in the mean frame of J2000
    assert back.made_under == small_obs.made_under == MadeUnder("gmst", "not used", "EME2000")


def test_dc_saves_and_reads_a_tdm(tmp_path: Path) -> None:
    path = tmp_path / "obs.tdm"
    first = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "6h", "--save-obs",
                                str(path), "--json"])
    assert first.exit_code == 0, first.output
    text = path.read_text()
    assert text.startswith("CCSDS_TDM_VERS = 2.0") and "PARTICIPANT_2 = SATORB1" in text
    assert "RANGE_UNITS = km" in text and "DOPPLER_INSTANTANEOUS = 2026-01-01T" in text
    again = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "6h", "--obs", str(path),
                                "--json"])
    assert again.exit_code == 0, again.output
    a, b = json.loads(first.stdout), json.loads(again.stdout)
    assert a["measurements"] == b["measurements"]
    np.testing.assert_array_equal(a["rms"], b["rms"])
    ekf = runner.invoke(app, ["ekf", "--orbit", "SATORB1", "--arc", "3h", "--obs", str(path),
                              "--json"])
    assert ekf.exit_code == 0, ekf.output


def test_a_published_tdm_is_refused_in_one_line_naming_keyword_and_block() -> None:
    example = Path(__file__).resolve().parents[2] / "data/ccsds-tdm/TDMExample8.txt"
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--obs", str(example)])
    assert res.exit_code == 2
    line = res.stderr.strip()
    assert "\n" not in line
    assert line.startswith(f"error: {example}: DOPPLER_INTEGRATED (segment 1 DATA, line 21)")


def test_simulate_writes_a_tdm_that_dc_fits_exactly(tmp_path: Path) -> None:
    """TAPP I's noise-free observations of SATORB1 in a 5x5 field, through a TDM, fitted by the
    DC with the same models and the same Earth orientation (iau2006): the epoch state comes
    back to within a millimetre."""
    scenario = Path(__file__).resolve().parents[3] / "scenarios" / "leo_equatorial.toml"
    tape, tdm = tmp_path / "run.t13.h5", tmp_path / "run.tdm"
    sim = runner.invoke(app, ["simulate", str(scenario), "-o", str(tape), "--tdm", str(tdm),
                              "--earth-orientation", "iau2006", "--json"])
    assert sim.exit_code == 0, sim.output
    assert json.loads(sim.stdout)["tdm"] == str(tdm)
    with h5py.File(tape) as f:
        assert "raw" not in f  # the raw rows fed the TDM; the tape is as without --raw
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--obs", str(tdm), "--arc", "24h",
                              "--truth", "5x5", "--stm", "5x5", "--earth-orientation", "iau2006",
                              "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["measurements"] == json.loads(sim.stdout)["observations"]
    assert out["position_error_km"] < 1e-6
    assert out["earth_orientation"]["model"] == "iau2006"


def test_dc_reads_an_observation_file(tmp_path: Path, small_obs) -> None:
    path = tmp_path / "obs.csv"
    write_observations(path, small_obs)
    # a CSV declares no data span: it ends with its last observation (at 5.58 h here)
    last = f"{small_obs.t_s[-1]:.0f}s"
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", last, "--obs", str(path),
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


# --- the Earth orientation switch ---------------------------------------------------------

STUDY = Path(__file__).resolve().parents[3] / "scenarios" / "approx_stm.toml"


def _study(tmp_path: Path, old: str, new: str) -> Path:
    text = STUDY.read_text()
    assert text.count(old) == 1
    path = tmp_path / "study.toml"
    path.write_text(text.replace(old, new))
    return path


def _refused(args: list[str], starts: str, tmp_path: Path) -> str:
    """Exit 2, one line on stderr starting with ``starts``, nothing written in tmp_path."""
    before = sorted(tmp_path.iterdir())
    res = runner.invoke(app, args)
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(starts), lines
    assert sorted(tmp_path.iterdir()) == before
    return lines[0]


def test_the_study_file_runs_gmst_and_the_outputs_say_so() -> None:
    """The shipped study file asks for gmst (the paper's model): the DC's JSON records the
    model, no EOP and no predictions; the text output names it."""
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "6h", "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["earth_orientation"] == {"model": "gmst", "eop": "",
                                                          "predicted_eop": False}
    text = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "6h"])
    assert text.exit_code == 0 and "Earth orientation: gmst" in text.stdout
    assert "), gmst: converged" in text.stdout


@pytest.mark.parametrize("command", [
    ["dc", "--arc", "12h"], ["ekf", "--arc", "3h"], ["rsig", "--hours", "2", "--step", "600"]])
def test_earth_orientation_option_overrides_the_file(command: list[str]) -> None:
    """--earth-orientation iau2006 on every OD command: the data (dc, ekf) are simulated and
    fitted under iau2006 and the JSON records the model and the EOP source; the DC still
    converges to the truth."""
    res = runner.invoke(app, [*command, "--orbit", "SATORB1", "--earth-orientation", "iau2006",
                              "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["earth_orientation"]["model"] == "iau2006"
    assert out["earth_orientation"]["eop"].startswith("finals2000A")
    assert out["earth_orientation"]["predicted_eop"] is False  # 2026-01-01 is measured
    if command[0] == "dc":
        assert out["converged"] and out["position_error_km"] < 0.01


def test_predicted_eop_are_reported(tmp_path: Path) -> None:
    """An epoch ten days past the last measured EOP (the table's predictions, still within
    it): the DC runs, and its outputs say that predicted EOP were used."""
    table = setup.orientation(model="iau2006").scales.eop
    when = datetime(1858, 11, 17) + timedelta(days=table.predicted_from_mjd + 10)  # MJD 0
    path = _study(tmp_path, 'epoch = "2026-01-01T00:00:00"',
                  f'epoch = "{when:%Y-%m-%dT00:00:00}"')
    args = ["dc", "--orbit", "SATORB1", "--arc", "6h", "--scenario", str(path),
            "--earth-orientation", "iau2006"]
    res = runner.invoke(app, [*args, "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["earth_orientation"]["predicted_eop"] is True
    text = runner.invoke(app, args)
    assert "predicted EOP used" in text.stdout


@pytest.mark.parametrize("command", [["dc"], ["ekf"], ["rsig"]])
def test_an_unknown_earth_orientation_option_is_one_line_naming_the_choices(
        tmp_path: Path, command: list[str]) -> None:
    line = _refused([*command, "--orbit", "SATORB1", "--earth-orientation", "itrf"],
                    "error: --earth-orientation", tmp_path)
    assert '"iau2006"' in line and '"gmst"' in line and "itrf" in line


def test_an_unknown_earth_orientation_in_the_file_is_refused(tmp_path: Path) -> None:
    path = _study(tmp_path, 'earth_orientation = "gmst"', 'earth_orientation = "gmst82"')
    line = _refused(["dc", "--orbit", "SATORB1", "--scenario", str(path), "--save-obs",
                     str(tmp_path / "obs.h5")], f"error: {path}: earth_orientation:", tmp_path)
    assert "gmst82" in line


def test_an_epoch_outside_the_eop_table_is_refused(tmp_path: Path) -> None:
    """2060 with eop = "iers": outside the IERS table (and its predictions). The file's gmst
    model needs no EOP; asking for iau2006, in the file or on the CLI, is refused in one line
    naming the file, the epoch and the way out (eop = "none")."""
    path = _study(tmp_path, 'epoch = "2026-01-01T00:00:00"', 'epoch = "2060-01-01T00:00:00"')
    gmst = runner.invoke(app, ["rsig", "--orbit", "SATORB1", "--scenario", str(path),
                               "--hours", "1"])
    assert gmst.exit_code == 0, gmst.output
    save = ["--save-obs", str(tmp_path / "obs.h5")]
    line = _refused(["dc", "--orbit", "SATORB1", "--scenario", str(path),
                     "--earth-orientation", "iau2006", *save], f"error: {path}: epoch:",
                    tmp_path)
    assert "2060-01-01" in line and 'eop = "none"' in line
    (tmp_path / "in_file").mkdir()
    in_file = _study(tmp_path / "in_file", 'earth_orientation = "gmst"',
                     'earth_orientation = "iau2006"')
    in_file.write_text(in_file.read_text().replace('epoch = "2026-01-01T00:00:00"',
                                                   'epoch = "2060-01-01T00:00:00"'))
    for command in (["dc", *save], ["ekf"], ["rsig"]):
        _refused([*command, "--orbit", "SATORB1", "--scenario", str(in_file)],
                 f"error: {in_file}: epoch:", tmp_path)
    # beyond the predictions, eop = "none" (UT1 = UTC, no polar motion) runs (a new file:
    # study files are read once per path)
    no_eop = tmp_path / "in_file" / "no_eop.toml"
    no_eop.write_text(in_file.read_text().replace('eop = "iers"', 'eop = "none"'))
    res = runner.invoke(app, ["rsig", "--orbit", "SATORB1", "--scenario", str(no_eop),
                              "--hours", "1", "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["earth_orientation"]["eop"].startswith("none")


def test_saved_observations_record_the_earth_orientation(tmp_path: Path) -> None:
    path = tmp_path / "obs.h5"
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "6h", "--save-obs",
                              str(path), "--earth-orientation", "iau2006", "--json"])
    assert res.exit_code == 0, res.output
    with h5py.File(path) as f:
        comments = [str(c) for c in f.attrs["comments"]]
    assert any("simulated with Earth orientation iau2006" in c for c in comments)

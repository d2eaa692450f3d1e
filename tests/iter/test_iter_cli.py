"""``tapp iter``: summary, results files, and one-line errors with exit code 2."""

from __future__ import annotations

import csv
import json
import socket
from pathlib import Path

import pytest
from typer.testing import CliRunner

import tapp.cli.iter_cmd  # noqa: F401  (registers the iter command on the app)
from iter import CaseStatus, read_hdf5
from tapp.cli.common import EXIT_FAILURE, EXIT_INPUT, app
from tapp.examples import FOLDER as EXAMPLES

SCENARIOS = EXAMPLES
runner = CliRunner()


def test_serial_run_writes_h5_and_csv_and_prints_the_summary(tmp_path):
    h5 = tmp_path / "days.h5"
    table = tmp_path / "days.csv"
    result = runner.invoke(app, ["iter", str(SCENARIOS / "iter_days_azimuths.toml"),
                                 "-o", str(h5), "--csv", str(table), "--serial"])
    assert result.exit_code == 0, result.output
    assert "succeeded" in result.stdout and "150" in result.stdout
    assert h5.exists()
    with table.open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 150
    assert (rows[77]["case"], rows[77]["launch_day"], rows[77]["azimuth_deg"],
            rows[77]["status"]) == ("77", "5745.0", "102.0", "ok")
    assert list(rows[0])[:3] == ["case", "launch_day", "azimuth_deg"]
    assert list(rows[0])[-3:] == ["status", "error", "elapsed_s"]


def test_json_summary_and_resume(tmp_path):
    args = ["iter", str(SCENARIOS / "iter_azimuth_type2.toml"), "-o", str(tmp_path / "a.h5"),
            "--serial", "--json", "-"]
    first = json.loads(runner.invoke(app, args).stdout)
    second = json.loads(runner.invoke(app, args).stdout)
    assert (first["n_cases"], first["n_succeeded"], first["n_failed"]) == (5, 5, 0)
    assert (first["n_resumed"], second["n_resumed"]) == (0, 5)


def _bad_sweep(tmp_path: Path, loop: str) -> Path:
    path = tmp_path / "bad.toml"
    path.write_text('[body]\ncallable = "tapp.targeting.launch_azimuth:launch_azimuth_case"\n'
                    f'[[loop]]\nnames = ["azimuth_deg"]\n{loop}\n')
    return path


@pytest.mark.parametrize(("loop", "message"), [
    ("type = 1\nsets = 5\nvary = [96.0, 99.0]",
     "loop[0].vary: expected sets x n = 5 x 1 = 5 values, row-wise (got '2 values')"),
    ("type = 7\nsets = 1\nvary = [96.0]", "loop[0].type: expected 1 (table) or 2"),
    ("type = 2\nsets = 5\nvary = [96.0]", "loop[0].delta: expected n = 1 increments"),
])
def test_bad_sweep_file_is_one_line_naming_file_and_field(tmp_path, loop, message):
    path = _bad_sweep(tmp_path, loop)
    result = runner.invoke(app, ["iter", str(path), "-o", str(tmp_path / "x.h5"), "--serial"])
    assert result.exit_code == EXIT_INPUT
    assert result.stderr.count("\n") == 1
    assert result.stderr.startswith(f"error: {path}: {message}")
    assert not (tmp_path / "x.h5").exists()


def test_unknown_body_module_is_bad_input(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[body]\ncallable = "no_such_module_xyz:f"\n'
                    '[[loop]]\nnames = ["azimuth_deg"]\nsets = 1\nvary = [96.0]\n')
    result = runner.invoke(app, ["iter", str(path), "--serial"])
    assert result.exit_code == EXIT_INPUT
    assert result.stderr.startswith(f"error: {path}: body.callable: expected an importable")


def test_unreachable_scheduler_is_one_line(tmp_path):
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    result = runner.invoke(app, ["iter", str(SCENARIOS / "iter_azimuth_type1.toml"),
                                 "-o", str(tmp_path / "x.h5"), "--scheduler", address,
                                 "--connect-timeout-s", "1"])
    assert result.exit_code == EXIT_INPUT
    assert result.stderr.startswith("error: command line: --scheduler: expected a Dask "
                                    "scheduler answering within 1 s (")
    assert result.stderr.endswith(f"(got '{address}')\n")
    assert result.stderr.count("\n") == 1


def test_conflicting_options_name_the_option(tmp_path):
    result = runner.invoke(app, ["iter", str(SCENARIOS / "iter_azimuth_type1.toml"),
                                 "--serial", "--workers", "2"])
    assert result.exit_code == EXIT_INPUT
    assert result.stderr.startswith("error: command line: --serial: expected no scheduler")


@pytest.fixture
def bodies(monkeypatch):
    """The helper module iter_bodies, importable by name for a sweep's callable."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parent))
    import iter_bodies

    return iter_bodies


def _altitude_sweep(tmp_path: Path, altitudes_km: list[float]) -> Path:
    """A sweep over altitudes; one below the Earth's centre fails (math domain error)."""
    path = tmp_path / "altitudes.toml"
    path.write_text('[body]\ncallable = "tapp.targeting.launch_azimuth:launch_azimuth_case"\n'
                    '[body.constants]\nlaunch_day = 0.0\nazimuth_deg = 90.0\n'
                    'latitude_deg = 28.5\neast_longitude_deg = 0.0\n'
                    f'[[loop]]\nnames = ["altitude_km"]\nsets = {len(altitudes_km)}\n'
                    f'vary = {altitudes_km}\n')
    return path


def test_a_sweep_whose_every_case_fails_exits_1_with_the_first_error(tmp_path):
    path = _altitude_sweep(tmp_path, [-7000.0, -8000.0])
    h5, table = tmp_path / "r.h5", tmp_path / "r.csv"
    result = runner.invoke(app, ["iter", str(path), "-o", str(h5), "--csv", str(table),
                                 "--serial", "--json", "-"])
    assert result.exit_code == EXIT_FAILURE
    assert result.stderr == (f"error: {path}: every case failed (2 of 2); case 0: "
                             f"ValueError: math domain error (every failure is recorded in "
                             f"{h5})\n")
    summary = json.loads(result.stdout)  # the summary is still printed
    assert (summary["n_succeeded"], summary["n_failed"]) == (0, 2)
    rows = read_hdf5(h5).table.rows  # and the failures recorded
    assert [row.status for row in rows] == [CaseStatus.FAILED] * 2
    assert table.read_text().count("math domain error") == 2


def test_a_sweep_with_one_case_that_succeeds_exits_0(tmp_path):
    path = _altitude_sweep(tmp_path, [-7000.0, 185.0])
    result = runner.invoke(app, ["iter", str(path), "-o", str(tmp_path / "r.h5"), "--serial"])
    assert result.exit_code == 0, result.output
    assert "case 0: ValueError: math domain error" in result.stdout


def _scaled_sweep(folder: Path, scale: str) -> Path:
    """A sweep file in ``folder`` whose body reads ``data/scale.txt`` (a relative path)."""
    (folder / "data").mkdir(parents=True)
    (folder / "data" / "scale.txt").write_text(scale)
    path = folder / "scaled.toml"
    path.write_text('[body]\ncallable = "iter_bodies:scaled_body"\n'
                    f'[body.constants]\ncalls_dir = "{folder / "data"}"\n'
                    '[body.files]\nscale_file = "data/scale.txt"\n'
                    '[[loop]]\ntype = 2\nnames = ["azimuth_deg"]\nsets = 3\nvary = [96.0]\n'
                    'delta = [3.0]\n')
    return path


def test_a_sweep_reads_its_files_from_its_folder_in_any_directory(tmp_path, monkeypatch,
                                                                  bodies):
    path = _scaled_sweep(tmp_path / "study", "2")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    result = runner.invoke(app, ["iter", "../study/scaled.toml", "-o", "r.h5", "--serial",
                                 "--json", "-"])
    assert result.exit_code == 0, result.output
    rows = read_hdf5(tmp_path / "elsewhere" / "r.h5").table.rows
    assert [row.outputs["scaled_deg"] for row in rows] == [192.0, 198.0, 204.0]
    assert path.exists()


def test_a_file_the_body_refuses_stops_the_sweep_before_any_case(tmp_path, bodies):
    path = _scaled_sweep(tmp_path, "fast")
    h5 = tmp_path / "r.h5"
    result = runner.invoke(app, ["iter", str(path), "-o", str(h5), "--serial"])
    assert result.exit_code == EXIT_INPUT
    assert result.stderr == (f"error: {tmp_path / 'data' / 'scale.txt'}: file: expected a "
                             "number (got 'fast')\n")
    assert bodies.calls(tmp_path / "data") == []
    assert not h5.exists()

"""``tapp guide`` (TAPP II) end to end: the printout, JSON, plots, and bad input."""

from __future__ import annotations

import json
import logging
import socket
from pathlib import Path

import pytest
from typer.testing import CliRunner

import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.io.tape.t32_hdf5 import write_t32
from tests.tapp.guidance.helpers import deep_space_t13, deep_space_t32

runner = CliRunner()

GUIDE = """title = "three midcourse corrections"
[tape]
iden = "DSN-LUNAR-2026-03-10"
[targets]
miss = ["b_dot_t_km", "b_dot_r_km", "flight_time_s"]
[manoeuvres]
recycles = [1, 2, 3]
[execution]
sigma_proportional = 0.02
sigma_pointing_mrad = 10.0
sigma_fixed_mm_s = 1.0
[corridor]
radius_km = 500.0
flight_time_s = 600.0
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tapp2")
    tape = write_t32(folder / "ds.t32.h5", deep_space_t32())
    guide = folder / "guide.toml"
    guide.write_text(GUIDE)
    return tape, guide


@pytest.fixture(scope="module")
def scheduler():
    """A running Dask cluster of two worker threads, reached over TCP (``--scheduler``)."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp://",
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster:
        yield cluster.scheduler_address


def test_guide_prints_markdown_and_writes_json_and_plots(files, scheduler, tmp_path: Path):
    tape, guide = files
    js, plots = tmp_path / "g.json", tmp_path / "plots"
    res = runner.invoke(app, ["guide", str(tape), str(guide), "--samples", "4000", "--seed",
                              "3", "--scheduler", scheduler, "--shard-size", "2000",
                              "--json", str(js), "--plots", str(plots)])
    assert res.exit_code == 0, res.stderr
    out = res.stdout
    assert out.startswith("# TAPP II guidance study: three midcourse corrections")
    assert "| 1 | 1.000 | Monte Carlo |" in out and "| 1 | 1.000 | linear covariance |" in out
    assert "## B-plane dispersion (1σ)" in out and "outside either" in out
    content = json.loads(js.read_text())
    assert content["samples"] == 4000 and content["seed"] == 3
    assert content["navigation"] == "tape" and content["targets"] == ["b_dot_t_km",
                                                                      "b_dot_r_km",
                                                                      "flight_time_s"]
    assert content["shard_samples"] == 2000 and content["where"].startswith("scheduler")
    mc, lin = content["monte_carlo"], content["linear"]
    assert [m["recycle"] for m in mc["manoeuvres"]] == [1, 2, 3]
    assert set(mc["manoeuvres"][0]["magnitude"]["percentiles_km_s"]) == {"50", "90", "99"}
    assert lin["total"]["sigma_km_s"] is None and lin["outside_corridor"]["either"] is None
    assert len(mc["miss_cov"]) == 3 and mc["bplane_ellipse"]["semi_major_km"] > 0
    assert content["left_out"] == {} and content["agreement"]["statistics"] == 18
    assert "## Linear covariance against the Monte Carlo" in out
    assert sorted(p.name for p in plots.iterdir()) == ["bplane_scatter.png",
                                                        "dv_histograms.png"]
    for png in plots.iterdir():
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_json_on_standard_output(files, scheduler):
    tape, guide = files
    res = runner.invoke(app, ["guide", str(tape), str(guide), "--samples", "1000", "--seed",
                              "3", "--scheduler", scheduler, "--json", "-"])
    assert res.exit_code == 0, res.stderr
    assert json.loads(res.stdout)["monte_carlo"]["manoeuvres"][2]["recycle"] == 3


def _closed_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _run_bad(tmp_path: Path, files, guide_text: str | None = None, options=(),
             tape: Path | None = None) -> tuple[int, str, list[str]]:
    t32, guide = files
    if guide_text is not None:
        guide = tmp_path / "bad.toml"
        guide.write_text(guide_text)
    tape = t32 if tape is None else tape
    before = sorted(p.name for p in tmp_path.iterdir())
    args = ["guide", str(tape), str(guide), "--samples", "1000", "--seed", "1", "--json",
            str(tmp_path / "g.json"), "--plots", str(tmp_path / "plots"), *options]
    res = runner.invoke(app, args)
    return res.exit_code, res.stderr, sorted(set(p.name for p in tmp_path.iterdir())
                                             - set(before))


def _refused(code: int, err: str, new: list[str], fragment: str) -> None:
    """Bad input: exit 2, one line on stderr holding ``fragment``, no file written."""
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and fragment in err, err
    assert new == []


@pytest.mark.parametrize(("edit", "fragment"), [
    (lambda t: t.replace("sigma_fixed_mm_s = 1.0", "sigma_fixed_mm_s = -1.0"),
     "bad.toml: execution.sigma_fixed_mm_s: expected a finite number >= 0"),
    (lambda t: t.replace("sigma_fixed_mm_s = 1.0", "sigma_fixed_mm_s = nan"),
     "execution.sigma_fixed_mm_s: expected a finite number"),
    (lambda t: t.replace("sigma_proportional = 0.02", "sigma_proportional = 1.0"),
     "execution.sigma_proportional: expected a finite number < 1"),
    (lambda t: t.replace("sigma_pointing_mrad = 10.0", "sigma_pointing_mrad = 500.0"),
     "execution.sigma_pointing_mrad: expected a finite number <= 200"),
    (lambda t: t.replace("sigma_pointing_mrad", "sigma_pointing_deg"),
     "execution.sigma_pointing_deg: expected no such key"),
    (lambda t: t.replace('"b_dot_r_km",', '"b_dot_q_km",'),
     "bad.toml: targets.miss[1]: expected a miss component of the tape"),
    (lambda t: t.replace(', "b_dot_r_km", "flight_time_s"]', "]"),
     "targets.miss: expected at least 2 items"),
    (lambda t: t.replace('"b_dot_r_km",', '"b_dot_t_km",'), "targets.miss: expected each item "
                                                            "once"),
    # a corridor term on a component the guidance does not target
    (lambda t: t.replace(', "flight_time_s"]', "]"),
     "bad.toml: corridor.flight_time_s: expected a corridor on targeted miss components only "
     "(targets.miss: b_dot_t_km, b_dot_r_km) (got 'flight_time_s not targeted')"),
    (lambda t: t.replace('"b_dot_t_km", ', ""),
     "bad.toml: corridor.radius_km: expected a corridor on targeted miss components only "
     "(targets.miss: b_dot_r_km, flight_time_s) (got 'b_dot_t_km not targeted')"),
    (lambda t: t.replace("recycles = [1, 2, 3]", "recycles = [1, 4]"),
     "manoeuvres.recycles[1]: expected a recycle number of the tape (1..3)"),
    (lambda t: t.replace("recycles = [1, 2, 3]", "recycles = []"),
     "manoeuvres.recycles: expected at least 1 item"),
    (lambda t: t.replace("radius_km = 500.0", "radius_km = 0.0"),
     "corridor.radius_km: expected a finite number > 0"),
    (lambda t: t.replace("radius_km = 500.0", "radius_km = 5.0\nsemi_axes_km = [5.0, 2.0]"),
     "corridor: expected either radius_km or semi_axes_km"),
    (lambda t: t.replace("flight_time_s = 600.0", "flight_time_s = -1.0"),
     "corridor.flight_time_s: expected a finite number > 0"),
    (lambda t: t.replace("DSN-LUNAR", "LEO"), "tape.iden: expected the tape's identification"),
    (lambda t: t.replace("[targets]", "[target]"), "target: expected no such key"),
    (lambda t: t.replace("[execution]", '[navigation]\nafter_manoeuvre = "kalman"\n[execution]'),
     "navigation.after_manoeuvre: expected one of 'tape' or 'inflate'"),
])
def test_bad_guidance_files_are_one_line_exit_2_and_write_nothing(tmp_path, files, edit,
                                                                   fragment):
    _refused(*_run_bad(tmp_path, files, edit(GUIDE)), fragment)


@pytest.mark.parametrize(("options", "fragment"), [
    (["--samples", "1"], "--samples: value: expected a whole number of samples 2..5,000,000"),
    (["--samples", "1000000000"], "--samples: value: expected a whole number of samples"),
    (["--seed", "-1"], "--seed: value: expected a whole number >= 0"),
    (["--shard-size", "1500"], "--shard-size: value: expected a whole multiple of 1,000"),
    (["--workers", "0"], "--workers: value: expected a whole number >= 1"),
    (["--workers", "1", "--scheduler", "tcp://127.0.0.1:8786"],
     "--workers: value: expected no worker count with a scheduler address"),
    (["--scheduler", "localhost:8786"], "--scheduler: value: expected an address"),
    (["--connect-timeout-s", "0"], "--connect-timeout-s: value: expected a positive time"),
    (["--samples", "many"], "--samples"),
])
def test_bad_options_are_one_line_exit_2_and_write_nothing(tmp_path, files, options, fragment):
    _refused(*_run_bad(tmp_path, files, options=options), fragment)


def test_a_scheduler_that_does_not_answer_is_bad_input(tmp_path, files):
    address = f"tcp://127.0.0.1:{_closed_port()}"
    _refused(*_run_bad(tmp_path, files, options=["--scheduler", address,
                                                 "--connect-timeout-s", "0.5"]),
             "--scheduler: value: expected a Dask scheduler answering")


def test_a_tape_that_is_not_a_t32_is_refused(tmp_path, files):
    t13 = write_t13(tmp_path / "ds.t13.h5", deep_space_t13())
    _refused(*_run_bad(tmp_path, files, tape=t13), "ds.t13.h5")


def test_an_output_that_is_an_input_is_refused_before_any_work(files):
    tape, guide = files
    before = guide.read_bytes()
    res = runner.invoke(app, ["guide", str(tape), str(guide), "--samples", "1000", "--seed",
                              "1", "--json", str(guide)])
    assert res.exit_code == 2 and "--json" in res.stderr and "GUIDE" in res.stderr
    assert guide.read_bytes() == before


def test_the_shipped_guidance_file_runs(files, scheduler):
    tape, _ = files
    shipped = EXAMPLES / "tapp2_deep_space.toml"
    res = runner.invoke(app, ["guide", str(tape), str(shipped), "--samples", "2000", "--seed",
                              "1", "--scheduler", scheduler, "--json", "-"])
    assert res.exit_code == 0, res.stderr
    content = json.loads(res.stdout)
    assert content["navigation"] == "inflate" and len(content["targets"]) == 3
    # the informed navigation's later corrections are small beside the first
    dv = [m["magnitude"]["mean_km_s"] for m in content["linear"]["manoeuvres"]]
    assert dv[2] < dv[1] < 0.1 * dv[0]

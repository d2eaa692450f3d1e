"""Issue 10's examples, one test per class: outputs never clobber inputs (1), all outputs or none
(2), no tracebacks or exhaustion (6), and one exit-code contract (8). Class 7 (hangs) is tested
in tests/iter/test_iter_execute.py; the fuzz and kill tests are tests/test_fuzz.py and
tests/test_kill.py."""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from iter.results import values_digest
from tapp.cli import app
from tapp.cli.common import EXIT_FAILURE, EXIT_INPUT, run_folder
from tapp.examples import FOLDER as EXAMPLES
from tests.faults import read_only_folder

ROOT = Path(__file__).resolve().parents[3]
SCENARIOS = EXAMPLES
LEO = SCENARIOS / "leo_equatorial.toml"
SWEEP = SCENARIOS / "iter_azimuth_type1.toml"
PIPELINE = SCENARIOS / "pipeline_deep_space.toml"
runner = CliRunner()


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _refused(args: list[str], *, code: int = EXIT_INPUT, says: str = "") -> str:
    """Run ``tapp ARGS``; assert exit ``code`` and one line on stderr; return that line."""
    res = runner.invoke(app, args)
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == code, (res.exit_code, res.output, res.exception)
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    assert "Traceback" not in res.output
    assert says in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "S.toml"
    shutil.copy(LEO, path)
    return path


@pytest.fixture
def sweep(tmp_path: Path) -> Path:
    path = tmp_path / "SWEEP.toml"
    shutil.copy(SWEEP, path)
    return path


# --- class 1: outputs never clobber inputs ---------------------------------------------------


@pytest.mark.parametrize("outputs", [
    ["-o", "{s}"],                               # tapp simulate S.toml -o S.toml
    ["-o", "{d}/run.t13.h5", "--oem", "{s}"],    # --oem equal to the scenario
    ["-o", "{d}/run.t13.h5", "--oem", "{d}/run.t13.h5"],  # --oem equal to -o
    ["-o", "{d}/link.toml"],                     # a symbolic link to the input
    ["-o", "{d}/sub/../S.toml"],                 # another spelling of the input
])
def test_simulate_never_overwrites_its_scenario_or_its_other_output(
        tmp_path: Path, scenario: Path, outputs: list[str]) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.toml").symlink_to(scenario)
    before = _digest(scenario)
    args = [a.format(s=scenario, d=tmp_path) for a in outputs]
    line = _refused(["simulate", str(scenario), *args], says="expected a file other than the")
    assert ("SCENARIO" in line) or ("-o/--output" in line and line.startswith("error: --oem"))
    assert _digest(scenario) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["S.toml", "link.toml", "sub"]


@pytest.mark.parametrize(("outputs", "says"), [
    (["--csv", "{w}"], "--csv: {w}: expected a file other than the input SWEEP_FILE"),
    (["-o", "{w}"], "-o/--output: {w}: expected a file other than the input SWEEP_FILE"),
    (["-o", "{d}/r.h5", "--csv", "{d}/r.h5"], "--csv: {d}/r.h5: expected a file other than "
     "the output -o/--output"),
])
def test_iter_never_overwrites_its_sweep_file_or_its_results(
        tmp_path: Path, sweep: Path, outputs: list[str], says: str) -> None:
    before = _digest(sweep)
    args = [a.format(w=sweep, d=tmp_path) for a in outputs]
    _refused(["iter", str(sweep), *args, "--serial"],
             says=says.format(w=sweep, d=tmp_path))
    assert _digest(sweep) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["SWEEP.toml"]


def test_dc_never_saves_observations_over_its_scenario(tmp_path: Path) -> None:
    study = tmp_path / "study.toml"
    shutil.copy(SCENARIOS / "approx_stm.toml", study)
    before = _digest(study)
    _refused(["dc", "--orbit", "SATORB1", "--scenario", str(study), "--save-obs", str(study)],
             says="--save-obs")
    assert _digest(study) == before


# --- class 2: all of a command's outputs, or none ---------------------------------------------


def test_a_failed_tape_write_leaves_the_old_oem_and_tape_and_no_temporary(
        tmp_path: Path, monkeypatch) -> None:
    tape, oem = tmp_path / "run.t13.h5", tmp_path / "run.oem"
    tape.write_text("old tape")
    oem.write_text("old oem")

    def no_space(path: Path) -> None:
        Path(path).write_bytes(b"half a tape")
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr("tapp.io.tape.t13_hdf5.t13_file_writer", lambda tape, source: no_space)
    line = _refused(["simulate", str(LEO), "-o", str(tape), "--oem", str(oem)],
                    code=EXIT_FAILURE)  # the disk's failure, not the input's
    assert line == f"error: -o/--output: {tape}: not written (No space left on device)"
    assert (tape.read_text(), oem.read_text()) == ("old tape", "old oem")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.oem", "run.t13.h5"]


def test_temporaries_left_by_a_killed_run_are_removed_by_the_next(tmp_path: Path) -> None:
    tape, oem = tmp_path / "run.t13.h5", tmp_path / "run.oem"
    for stale in (".run.t13.h5.0123456789abcdef.tmp", ".run.oem.a1b2c3d4.tmp",
                  "..run.t13.h5.0123456789abcdef.tmp.fedcba9876543210.tmp"):
        (tmp_path / stale).write_text("left by a kill")
    res = runner.invoke(app, ["simulate", str(LEO), "-o", str(tape), "--oem", str(oem)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.oem", "run.t13.h5"]


def test_the_run_folder_goes_with_the_run_and_a_killed_run_s_with_the_next(
        tmp_path: Path, monkeypatch) -> None:
    base = tmp_path / "tmp"
    base.mkdir()
    monkeypatch.setenv("TMPDIR", str(base))
    monkeypatch.setattr(tempfile, "tempdir", str(base))
    killed = base / "tapp-run-killed00"  # its run was killed: nothing holds its lock
    (killed / "dask-cluster-x" / "dask-scratch-space").mkdir(parents=True)
    live = base / "tapp-run-livelive"  # a run still going holds its lock
    live.mkdir()
    lock = os.open(live, os.O_RDONLY)
    fcntl.flock(lock, fcntl.LOCK_EX)
    try:
        with run_folder() as folder:
            assert folder.parent == base and folder.name.startswith("tapp-run-")
            assert tempfile.gettempdir() == os.environ["TMPDIR"] == str(folder)
            (folder / "scratch").mkdir()  # what the run makes there
            assert sorted(p.name for p in base.iterdir()) == sorted([folder.name, live.name])
        assert (os.environ["TMPDIR"], tempfile.gettempdir()) == (str(base), str(base))
        assert [p.name for p in base.iterdir()] == [live.name]
        assert runner.invoke(app, ["--version"]).exit_code == 0
        assert [p.name for p in base.iterdir()] == [live.name]
    finally:
        os.close(lock)
    assert runner.invoke(app, ["--version"]).exit_code == 0
    assert list(base.iterdir()) == []


def test_a_run_removes_no_folder_that_is_not_provably_a_killed_run_s(tmp_path: Path,
                                                                      monkeypatch) -> None:
    """Named like a run folder, but a symbolic link (to the user's data), or another
    user's (made so when the test runs as root): both kept, and what the link points to."""
    base = tmp_path / "tmp"
    data = tmp_path / "data"
    (data / "keep").mkdir(parents=True)
    base.mkdir()
    monkeypatch.setenv("TMPDIR", str(base))
    monkeypatch.setattr(tempfile, "tempdir", str(base))
    (base / "tapp-run-link0000").symlink_to(data)
    kept = ["tapp-run-link0000"]
    if os.geteuid() == 0:
        (base / "tapp-run-other000").mkdir()
        os.chown(base / "tapp-run-other000", 65534, 65534)
        kept.append("tapp-run-other000")
    assert runner.invoke(app, ["--version"]).exit_code == 0
    assert sorted(p.name for p in base.iterdir()) == kept
    assert [p.name for p in data.iterdir()] == ["keep"]


# --- class 6: tracebacks and exhaustion --------------------------------------------------------


@pytest.mark.parametrize(("args", "says"), [
    (["propagate", "--orbit", "SATORB1", "--arc", "1e300h"], "--arc/--step"),
    (["propagate", "--orbit", "SATORB1", "--step", "1e-9s"], "it would need 8.64e+13"),
    (["rsig", "--orbit", "SATORB1", "--span", "1e300h"], "at most 1,000,000 output samples"),
    (["propagate", "--orbit", "SATORB1", "--third-body", "moon", "--epoch", "2060-01-01",
      "--earth-orientation", "gmst"],
     "DE421's coverage 1899-07-29T00:00:00 TDB .. 2053-10-09T00:00:00 TDB"),
    # the default iau2006 model needs Earth orientation parameters at the epoch
    (["propagate", "--orbit", "SATORB1", "--epoch", "2060-01-01"],
     "error: --epoch: epoch: expected an epoch within the IERS EOP table"),
    (["propagate", "--orbit", "SATORB1", "--earth-orientation", "iau1980"],
     "error: --earth-orientation: value: expected \"iau2006\" or \"gmst\""),
    (["dc", "--orbit", "SATORB1", "--seed", "-1"], "error: --seed: value: expected a whole "),
    (["ekf", "--orbit", "SATORB1", "--seed", "-5"], "error: --seed:"),
    (["ekf", "--orbit", "SATORB1", "--process-noise", "-1"], "error: --process-noise:"),
    (["ekf", "--orbit", "SATORB1", "--process-noise", "nan"], "error: --process-noise:"),
    (["iter", str(SWEEP), "--workers", "1000000"], "--workers: expected at most"),
    (["propagate", "--orbit", "SATORB1", "--arc", "abc"], "--arc: value: expected a duration"),
    (["dc", "--orbit", "SATORB1", "--max-iter", "0"], "error: --max-iter:"),
    # the option at fault is named, not the file or the library's field
    (["dc", "--orbit", "SATORB1", "--stations", "NOWHERE"], "error: --stations: name:"),
    (["propagate", "--orbit", "SATORB1", "--third-body", "moon", "--epoch", "1960-01-01"],
     "error: --epoch: date:"),
    (["propagate", "--orbit", "SATORB1", "--third-body", "pluto"], "error: --third-body:"),
])
def test_huge_sizes_and_bad_options_are_one_line_before_any_work(args: list[str],
                                                                 says: str) -> None:
    _refused(args, says=says)


@pytest.mark.parametrize("args", [
    ["pipeline", str(PIPELINE), "-o", "{d}/out"],
    ["guide", "{d}/run.t32.h5", str(SCENARIOS / "tapp2_deep_space.toml"), "--samples", "10",
     "--seed", "1"],
    ["iter", str(SWEEP), "-o", "{d}/r.h5"],
])
def test_workers_0_is_a_bad_worker_count_before_a_conflict_with_serial(
        tmp_path: Path, args: list[str]) -> None:
    line = _refused([a.format(d=tmp_path) for a in args] + ["--workers", "0", "--serial"])
    assert "--workers" in line and "expected a whole number >= 1 (got 0)" in line, line
    assert list(tmp_path.iterdir()) == []


def test_a_pipeline_directory_inside_a_file_names_the_option_and_the_file(
        tmp_path: Path) -> None:
    scenario = tmp_path / "deep_space.toml"
    shutil.copy(SCENARIOS / "deep_space.toml", scenario)
    line = _refused(["pipeline", str(PIPELINE), "-o", str(scenario / "out")])
    assert line == (f"error: -o/--output: {scenario / 'out'}: expected a path inside a folder "
                    f"({scenario} is a file)")  # was "(got 'File exists')", naming the file


def test_a_pipeline_directory_that_is_a_symbolic_link_is_refused_before_any_work(
        tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "empty")
    line = _refused(["pipeline", str(PIPELINE), "-o", str(tmp_path / "link")])
    assert line == ("error: -o/--output: directory: expected a new or empty directory, not a "
                    "symbolic link (the finished run is renamed into place) "
                    f"(got '{tmp_path / 'link'}')")  # was 'Not a directory', after the run
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty", "link"]


@pytest.mark.parametrize("args", [
    ["pipeline", str(PIPELINE), "-o", "{ro}/out"],
    ["simulate", str(LEO), "-o", "{ro}/run.t13.h5"],
    ["iter", str(SWEEP), "--serial", "-o", "{ro}/r.h5"],
])
def test_a_read_only_output_folder_is_named_by_its_option_never_by_a_temporary(
        tmp_path: Path, args: list[str]) -> None:
    with read_only_folder(tmp_path / "ro") as ro:
        line = _refused([a.format(ro=ro) for a in args])
        assert line.startswith(f"error: -o/--output: {ro}/"), line
        assert f"expected a path in a writable folder ({ro} is not writable)" in line
        assert ".tmp" not in line
        assert list(ro.iterdir()) == []


def test_a_search_horizon_of_1e308_s_is_refused_before_allocating_its_scan(
        tmp_path: Path) -> None:
    path = tmp_path / "search.toml"
    text = (SCENARIOS / "search_bplane.toml").read_text()
    path.write_text(text.replace("max_flight_time_s = 691200.0", "max_flight_time_s = 1e308"))
    _refused(["search", str(path)], says=f"{path}: target.max_flight_time_s: expected at most "
             "1,000,000 scan steps")


def test_an_unwritable_save_obs_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "a_file").write_text("")
    _refused(["dc", "--orbit", "SATORB1", "--save-obs", str(tmp_path / "a_file" / "o.h5")],
             says="error: --save-obs:")


@pytest.mark.parametrize("sets", ["1000000000000", "1e12"])
def test_a_sweep_of_1e12_cases_is_refused_before_generating_them(tmp_path: Path,
                                                                 sets: str) -> None:
    path = tmp_path / "big.toml"
    path.write_text(SWEEP.read_text().replace("type = 1 ", "type = 2 ").replace(
        "sets = 5 ", f"sets = {sets} ").replace("vary = [96.0, 99.0, 102.0, 105.0, 108.0]",
                                               "vary = [96.0]\ndelta = [1.0]"))
    _refused(["iter", str(path), "--serial", "-o", str(tmp_path / "big.h5")],
             says=f"{path}: loop[0].sets")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.toml"]


def _forge(f: h5py.File, name: str, index: int, value: object) -> None:
    """Change one value and its digest too (a consistent forgery: the layout checks catch it)."""
    f[name][index] = value
    f[name].attrs["sha256"] = values_digest(f[name][()], text=False)


@pytest.mark.parametrize(("tamper", "says"), [
    (lambda f: f["elapsed_s"].__setitem__(0, 1e300), "elapsed_s: expected values matching "
     "its sha256 attribute"),
    (lambda f: f["status"].__setitem__(0, 1), "status: expected values matching its sha256"),
    (lambda f: _forge(f, "status", 0, 7), "status: expected codes [0, 1]"),
    (lambda f: f.__delitem__("elapsed_s"), "elapsed_s: expected a one-dimensional dataset"),
    (lambda f: _forge(f, "case", 1, 0), "case: expected distinct case numbers"),
    (lambda f: (f.__delitem__("error"), f.create_dataset("error", data=np.zeros(2))),
     "error: expected"),
    (lambda f: f.attrs.__setitem__("n_cases", "five"), "n_cases: expected a whole number"),
])
def test_a_tampered_results_file_is_one_line_exit_2_and_left_alone(tmp_path: Path, tamper,
                                                                   says: str) -> None:
    out = tmp_path / "r.h5"
    assert runner.invoke(app, ["iter", str(SWEEP), "-o", str(out), "--serial"]).exit_code == 0
    with h5py.File(out, "r+") as f:
        tamper(f)
    before = _digest(out)
    _refused(["iter", str(SWEEP), "-o", str(out), "--serial"], says=says)
    assert _digest(out) == before


# --- class 8: one exit-code contract -----------------------------------------------------------


def test_a_truncated_tape_is_bad_input_exit_2(tmp_path: Path) -> None:
    out = tmp_path / "leo.t13.h5"
    assert runner.invoke(app, ["simulate", str(LEO), "-o", str(out)]).exit_code == 0
    with out.open("r+b") as stream:
        stream.truncate(out.stat().st_size // 2)
    _refused(["tape", "info", str(out)], says=f"error: {out}:")


def test_usage_errors_are_one_line_exit_2() -> None:
    _refused(["propagate"], says="Missing option '--orbit'")
    _refused(["propagate", "--orbit", "SATORB1", "--no-such-option"], says="--no-such-option")
    _refused(["dc", "--orbit", "SATORB1", "--max-iter", "1e5"], says="'--max-iter'")


def test_numerical_outcomes_keep_their_codes() -> None:
    res = runner.invoke(app, ["dc", "--orbit", "SATORB1", "--arc", "24h", "--stm", "J0",
                              "--json", "-"])
    assert res.exit_code == 3


def test_a_stop_signal_that_an_extension_loader_hid_still_stops_the_run() -> None:
    """CI caught SIGTERM landing while SciPy's HiGHS module initialised: pybind11 replaced
    the handler's Interrupted with ``ImportError: initialization failed``, and the run
    ended with a traceback instead of one line and exit 143 (tests/test_kill.py, seldom)."""
    import signal

    from tapp.cli.common import Interrupted, stopping_on_signals

    with pytest.raises(Interrupted) as stopped, stopping_on_signals():
        try:
            signal.raise_signal(signal.SIGTERM)
        except Interrupted as exc:  # as the loader does: the signal's exception replaced
            raise ImportError("initialization failed") from exc
    assert stopped.value.exit_code == 128 + signal.SIGTERM
    assert isinstance(stopped.value.__cause__, ImportError)


def test_an_error_without_a_stop_signal_is_left_as_it_is() -> None:
    from tapp.cli.common import stopping_on_signals

    with pytest.raises(ImportError), stopping_on_signals():
        raise ImportError("initialization failed")

"""Running sweeps: serial and Dask agree, failures are recorded, re-runs resume, programs."""

from __future__ import annotations

import math
import os
import socket
import sys
import tempfile
import time
from pathlib import Path

import h5py
import pytest

from iter import (
    AllCasesFailed,
    CallableBody,
    Case,
    CaseStatus,
    ClusterError,
    Execution,
    Loop,
    ProgramBody,
    SchedulerError,
    Sweep,
    SweepInputError,
    load_sweep,
    parse_sweep,
    read_hdf5,
    run_sweep,
)
from iter.execute import available_cores, local_cluster
from iter.run import PROBE_CASES
from tapp.examples import FOLDER as EXAMPLES

HERE = Path(__file__).resolve().parent
SCENARIOS = EXAMPLES
SERIAL = Execution(serial=True, checkpoint_interval_s=0.0)
AZIMUTHS = Loop(type=2, names=("azimuth_deg",), sets=5, vary=(96.0,), delta=(3.0,))


@pytest.fixture(scope="module")
def cluster_address():
    """A 2-worker local Dask cluster shared by this module's Dask tests."""
    with local_cluster(2) as address:
        yield address


@pytest.fixture
def bodies(monkeypatch):
    """The helper module iter_bodies, importable by name for CallableBody."""
    monkeypatch.syspath_prepend(str(HERE))
    import iter_bodies

    return iter_bodies


def _closed_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_local_dask_cluster_equals_serial_row_for_row(cluster_address):
    sweep = load_sweep(SCENARIOS / "iter_days_azimuths.toml")
    serial = run_sweep(sweep, execution=SERIAL)
    # chunk_size 7 spreads 22 chunks over both workers, so they complete out of order.
    on_dask = run_sweep(sweep, execution=Execution(scheduler=cluster_address, chunk_size=7))
    assert on_dask.summary.mode.startswith(f"scheduler {cluster_address}")
    assert serial.table.n_succeeded == on_dask.table.n_succeeded == 150
    assert [row.index for row in on_dask.table.rows] == list(range(150))
    assert on_dask.table.rows == serial.table.rows


def test_failure_on_dask_is_recorded_and_the_sweep_goes_on(cluster_address):
    # An altitude below the Earth's centre makes sqrt of a negative number: ValueError.
    loop = Loop(type=1, names=("altitude_km",), sets=3, vary=(185.0, -7000.0, 400.0))
    body = CallableBody("tapp.targeting.launch_azimuth:launch_azimuth_case",
                        {"launch_day": 0.0, "azimuth_deg": 90.0, "latitude_deg": 28.5,
                         "east_longitude_deg": 0.0})
    result = run_sweep(Sweep(loops=(loop,), body=body),
                       execution=Execution(scheduler=cluster_address, chunk_size=1))
    statuses = [row.status for row in result.table.rows]
    assert statuses == [CaseStatus.OK, CaseStatus.FAILED, CaseStatus.OK]
    assert result.table.rows[1].error == "ValueError: math domain error"
    assert result.table.rows[1].outputs == {}


def test_failing_case_is_recorded_and_a_rerun_resumes(tmp_path, bodies):
    calls_dir = tmp_path / "calls"
    calls_dir.mkdir()
    (calls_dir / "fail").touch()
    sweep = Sweep(loops=(AZIMUTHS,), body=CallableBody("iter_bodies:counting_body",
                                                       {"calls_dir": str(calls_dir)}))
    output = tmp_path / "out.h5"

    first = run_sweep(sweep, output_h5=output, execution=SERIAL)
    first.raise_if_all_failed()  # four cases succeeded: an answer
    assert bodies.calls(calls_dir) == [96.0, 99.0, 102.0, 105.0, 108.0]
    assert [row.status for row in first.table.rows] == [
        CaseStatus.OK, CaseStatus.OK, CaseStatus.FAILED, CaseStatus.OK, CaseStatus.OK]
    assert first.table.rows[2].error == "ValueError: cannot fly at 102.0 deg"
    assert first.table.rows[3].outputs == {"double_deg": 210.0}
    assert (first.summary.n_succeeded, first.summary.n_failed) == (4, 1)
    stored = read_hdf5(output)
    assert stored.table.rows == first.table.rows

    (calls_dir / "fail").unlink()
    second = run_sweep(sweep, output_h5=output, execution=SERIAL)
    # Only the failed case ran again.
    assert bodies.calls(calls_dir) == [96.0, 99.0, 102.0, 105.0, 108.0, 102.0]
    assert second.summary.n_resumed == 4
    assert second.table.n_succeeded == 5
    assert second.table.rows[2].outputs == {"double_deg": 204.0}

    third = run_sweep(sweep, output_h5=output, execution=SERIAL)
    assert len(bodies.calls(calls_dir)) == 6
    assert third.summary.n_resumed == 5


def test_an_interrupted_sweep_resumes_where_it_stopped(tmp_path, bodies):
    calls_dir = tmp_path / "calls"
    calls_dir.mkdir()
    (calls_dir / "interrupt").touch()
    sweep = Sweep(loops=(AZIMUTHS,), body=CallableBody("iter_bodies:interrupting_body",
                                                       {"calls_dir": str(calls_dir)}))
    output = tmp_path / "out.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep, output_h5=output, execution=SERIAL)
    assert [row.index for row in read_hdf5(output).table.rows] == [0, 1, 2]
    assert list(tmp_path.glob(".out.h5.*")) == []

    (calls_dir / "interrupt").unlink()
    result = run_sweep(sweep, output_h5=output, execution=SERIAL)
    assert bodies.calls(calls_dir) == [96.0, 99.0, 102.0, 105.0, 108.0]
    assert result.summary.n_resumed == 3
    assert result.table.n_succeeded == 5


def test_resuming_a_different_sweep_is_refused(tmp_path):
    output = tmp_path / "out.h5"
    run_sweep(load_sweep(SCENARIOS / "iter_azimuth_type1.toml"), output_h5=output,
              execution=SERIAL)
    with pytest.raises(SweepInputError, match="definition_json"):
        run_sweep(load_sweep(SCENARIOS / "iter_days_azimuths.toml"), output_h5=output,
                  execution=SERIAL)


def test_outputs_that_are_not_a_mapping_fail_the_case(bodies):
    sweep = Sweep(loops=(AZIMUTHS,), body=CallableBody("iter_bodies:not_a_mapping"))
    result = run_sweep(sweep, execution=SERIAL)
    assert result.table.n_failed == 5
    assert "outputs must be a mapping" in result.table.rows[0].error


# A tiny program: reads --azimuth_deg and --scale, refuses 102 deg, prints one JSON object.
PROGRAM = """
import argparse, json
parser = argparse.ArgumentParser()
parser.add_argument("--azimuth_deg", type=float, required=True)
parser.add_argument("--scale", type=float, required=True)
parser.add_argument("--json")
args = parser.parse_args()
if args.azimuth_deg == 102.0:
    raise SystemExit("refusing 102 deg")
print(json.dumps({"scaled_deg": args.scale * args.azimuth_deg, "r_km": [1, 2],
                  "meta": {"json_to": args.json, "label": "ok", "none": None}}))
"""


def test_program_body_outputs_and_failures():
    document = {"body": {"program": [sys.executable, "-c", PROGRAM],
                         "constants": {"scale": 2.0}},
                "loop": [{"type": 2, "names": ["azimuth_deg"], "sets": 5, "vary": [96.0],
                          "delta": [3.0]}]}
    result = run_sweep(parse_sweep(document, source="program.toml"), execution=SERIAL)
    rows = result.table.rows
    assert [row.status for row in rows] == [
        CaseStatus.OK, CaseStatus.OK, CaseStatus.FAILED, CaseStatus.OK, CaseStatus.OK]
    outputs = dict(rows[0].outputs)
    assert math.isnan(outputs.pop("meta.none"))
    assert outputs == {"scaled_deg": 192.0, "r_km[0]": 1.0, "r_km[1]": 2.0,
                       "meta.json_to": "-", "meta.label": "ok"}
    assert rows[2].error == (f"CaseFailure: {sys.executable} exited with status 1: "
                             "refusing 102 deg")


def test_program_body_with_dashes_and_flags():
    body = ProgramBody(argv=("prog", "sub"), constants={"step_s": 10.0, "fast": True,
                                                        "slow": False},
                       json_option=False, dashes=True)
    command = body.command(Case(index=0, names=("azimuth_deg",), values=(96.0,)))
    assert command[1:] == ["sub", "--step-s", "10.0", "--fast", "--azimuth-deg", "96.0"]


def test_program_timeout_fails_the_case():
    body = ProgramBody(argv=(sys.executable, "-c", "import time; time.sleep(30)"),
                       json_option=False, timeout_s=0.5)
    loop = Loop(type=1, names=("x_km",), sets=1, vary=(1.0,))
    result = run_sweep(Sweep(loops=(loop,), body=body), execution=SERIAL)
    assert "timed out after 0.5 s" in result.table.rows[0].error


def test_unreachable_scheduler_fails_fast():
    address = f"tcp://127.0.0.1:{_closed_port()}"
    sweep = load_sweep(SCENARIOS / "iter_azimuth_type1.toml")
    start_s = time.perf_counter()
    with pytest.raises(SchedulerError) as info:
        run_sweep(sweep, execution=Execution(scheduler=address, connect_timeout_s=1.0))
    assert time.perf_counter() - start_s < 10.0  # a hang would be caught here
    assert info.value.address == address
    assert str(info.value).startswith(f"no Dask scheduler at {address} within 1 s")


def test_a_server_that_never_answers_is_not_a_hang():
    # Accepts the connection and says nothing: Client(timeout=...) alone would wait forever.
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        start_s = time.perf_counter()
        with pytest.raises(SchedulerError, match="timed out"):
            run_sweep(load_sweep(SCENARIOS / "iter_azimuth_type1.toml"),
                      execution=Execution(scheduler=address, connect_timeout_s=1.0))
        assert time.perf_counter() - start_s < 10.0


def test_an_automatic_sweep_too_small_for_a_cluster_runs_in_this_process(bodies):
    sweep = Sweep(loops=(AZIMUTHS,), body=CallableBody("iter_bodies:process_facts"))
    result = run_sweep(sweep, execution=Execution())
    assert Execution().automatic and not Execution(workers=1).automatic
    assert result.summary.mode.startswith("this process (")  # no cluster for 5 tiny cases
    assert {row.outputs["pid"] for row in result.table.rows} == {os.getpid()}


@pytest.mark.skipif(available_cores() < 2, reason="one core: a local cluster never pays")
def test_an_automatic_sweep_worth_a_cluster_probes_here_then_runs_on_one_blas_thread(
        bodies, monkeypatch):
    monkeypatch.setattr("iter.run.DASK_MIN_WORK_S", 0.0)  # any work repays a cluster
    for name in ("MALLOC_TRIM_THRESHOLD_", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                 "MKL_NUM_THREADS"):  # unset here, and put back after (a nanny sets them)
        monkeypatch.delenv(name, raising=False)
    sweep = Sweep(loops=(AZIMUTHS,), body=CallableBody("iter_bodies:process_facts"))
    result = run_sweep(sweep, execution=Execution())
    assert result.summary.mode.startswith("local cluster (")
    assert result.summary.mode.endswith(f", after {PROBE_CASES} cases in this process")
    rows = [row.outputs for row in result.table.rows]
    assert [row["pid"] == os.getpid() for row in rows] == [True] * PROBE_CASES + [False] * 3
    assert {(row["blas_threads"], row["malloc_trim"]) for row in rows[PROBE_CASES:]} == {
        (1, "")}  # one BLAS thread, and no trim threshold, in every worker


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"scheduler": "localhost"}, "scheduler"),
    ({"scheduler": "tcp://host:port"}, "scheduler"),
    ({"serial": True, "workers": 2}, "serial"),
    ({"serial": True, "workers": 0}, "workers"),  # a bad count before a conflict
    ({"scheduler": "tcp://h:8786", "workers": 2}, "workers"),
    ({"workers": 0}, "workers"),
    ({"chunk_size": 0}, "chunk_size"),
])
def test_bad_execution_options(kwargs, field):
    with pytest.raises(SweepInputError) as info:
        Execution(**kwargs)
    assert (info.value.source, info.value.field) == ("options", field)


def test_results_file_layout(tmp_path):
    output = tmp_path / "days.h5"
    run_sweep(load_sweep(SCENARIOS / "iter_days_azimuths.toml"), output_h5=output,
              execution=SERIAL)
    with h5py.File(output, "r") as f:
        assert f.attrs["n_cases"] == 150
        assert '"sets": 30' in f.attrs["sweep_json"]
        assert f.attrs["created_utc"].endswith("Z")
        assert f.attrs["generator"].startswith("iter, tapp ")
        assert list(f["inputs"]) == ["launch_day", "azimuth_deg"]
        assert f["inputs/azimuth_deg"].attrs["units"] == "deg"
        assert f["outputs/delta_v_km_s"].attrs["units"] == "km/s"
        assert f["inputs/launch_day"][77] == 5745.0
        assert f["inputs/azimuth_deg"][77] == 102.0
        assert f["case"][-1] == 149
        assert set(f["status"][()]) == {0}


def test_outputs_named_like_reserved_columns_are_prefixed() -> None:
    from iter.body import rename_clashes

    out = rename_clashes({"status": "converged", "case": 3, "arc": 1.0, "rms": 2.0}, ("arc",))
    assert out == {"output.status": "converged", "output.case": 3, "output.arc": 1.0,
                   "rms": 2.0}


@pytest.fixture
def temporary_base(tmp_path, monkeypatch) -> Path:
    """An empty folder that is tempfile's, and TMPDIR of the processes started."""
    base = tmp_path / "tmp"
    base.mkdir()
    monkeypatch.setenv("TMPDIR", str(base))
    monkeypatch.setattr(tempfile, "tempdir", str(base))
    return base


def test_a_callable_that_never_returns_is_stopped_at_its_timeout(bodies, temporary_base):
    """Issue 10, class 7: a hanging callable fails its case (with its time); others run; the
    temporary folder it made before it was stopped is gone (issue 23)."""
    body = CallableBody("iter_bodies:hanging_body", {"hang_at_deg": 99.0}, timeout_s=3.0)
    loop = Loop(type=1, names=("azimuth_deg",), sets=2, vary=(96.0, 99.0))
    start = time.perf_counter()
    rows = run_sweep(Sweep(loops=(loop,), body=body), execution=SERIAL).table.rows
    assert time.perf_counter() - start < 20.0
    assert rows[0].status is CaseStatus.OK and rows[0].outputs == {"double_deg": 192.0}
    assert rows[1].status is CaseStatus.FAILED
    assert rows[1].error == "CaseTimeout: iter_bodies:hanging_body timed out after 3 s"
    assert 3.0 <= rows[1].elapsed_s < 15.0
    assert list(temporary_base.iterdir()) == []


def test_a_local_cluster_keeps_its_scratch_space_in_a_temporary_folder_it_removes(
        temporary_base):
    with local_cluster(1) as address:
        assert address.startswith("tcp://")
        workers = [p for p in temporary_base.glob("dask-cluster-*/dask-scratch-space/*")
                   if p.is_dir() and p.name.startswith("worker-")]
        assert len(workers) == 1, sorted(temporary_base.rglob("*"))
    assert list(temporary_base.iterdir()) == []


def test_a_local_cluster_that_does_not_start_is_one_error(temporary_base, monkeypatch):
    monkeypatch.setattr(sys, "executable", "/bin/false")  # exits 1 at once, says nothing
    with pytest.raises(ClusterError) as info, local_cluster(2):
        pass
    assert str(info.value) == ("a local Dask cluster of 2 workers did not start (its process "
                               "exited with status 1): (nothing logged)")
    assert list(temporary_base.iterdir()) == []


def test_a_callable_with_a_timeout_fails_as_it_would_in_process(bodies):
    loop = Loop(type=1, names=("azimuth_deg",), sets=1, vary=(96.0,))
    for timeout_s in (None, 30.0):
        body = CallableBody("iter_bodies:raising_body", timeout_s=timeout_s)
        row = run_sweep(Sweep(loops=(loop,), body=body), execution=SERIAL).table.rows[0]
        assert row.error == "ValueError: cannot fly at 96.0 deg", timeout_s


def test_program_bodies_have_a_default_timeout():
    from iter.body import DEFAULT_PROGRAM_TIMEOUT_S

    assert DEFAULT_PROGRAM_TIMEOUT_S == 3600.0
    assert "timeout_s" not in ProgramBody(argv=("tapp",)).definition()  # resumes old files


def test_a_sweep_whose_every_case_failed_has_no_answer(tmp_path, bodies):
    sweep = Sweep(loops=(AZIMUTHS,), body=CallableBody("iter_bodies:raising_body"),
                  source="all.toml")
    output = tmp_path / "all.h5"
    result = run_sweep(sweep, output_h5=output, execution=SERIAL)
    with pytest.raises(AllCasesFailed) as info:
        result.raise_if_all_failed()
    assert (info.value.first_index, info.value.n_cases) == (0, 5)
    assert str(info.value) == ("all.toml: every case failed (5 of 5); case 0: ValueError: "
                               f"cannot fly at 96.0 deg (every failure is recorded in {output})")
    assert [row.status for row in read_hdf5(output).table.rows] == [CaseStatus.FAILED] * 5


def _scaled_sweep(folder: Path, scale: str, constants: dict | None = None,
                  files: dict | None = None) -> Sweep:
    """Five azimuths through iter_bodies:scaled_body, which reads ``folder/scale.txt``."""
    (folder / "calls").mkdir(exist_ok=True)
    (folder / "scale.txt").write_text(scale)
    body = CallableBody("iter_bodies:scaled_body",
                        {"calls_dir": str(folder / "calls"), **(constants or {})},
                        files={"scale_file": str(folder / "scale.txt"), **(files or {})})
    return Sweep(loops=(AZIMUTHS,), body=body, source="scaled.toml")


def test_a_body_reading_a_file_runs_every_case(tmp_path, bodies):
    result = run_sweep(_scaled_sweep(tmp_path, "2"), execution=SERIAL)
    assert [row.outputs["scaled_deg"] for row in result.table.rows] == [
        192.0, 198.0, 204.0, 210.0, 216.0]


@pytest.mark.parametrize(("scale", "constants", "files", "field", "fragment"), [
    # the body's own input check refuses the file it reads: its error, naming that file
    ("fast", {}, {}, "file", "expected a number (got 'fast')"),
    ("2", {}, {"scale_file": "/no/such/scale.txt"}, "body.files.scale_file",
     "expected an existing file"),
    ("2", {"scael": 1.0}, {}, "body.constants.scael",
     "expected an argument of iter_bodies:scaled_body (azimuth_deg, scale_file, calls_dir)"),
    ("2", {}, {"calls": "."}, "body.files.calls", "expected an argument of"),
])
def test_bad_input_stops_the_sweep_before_any_case_runs_or_anything_is_written(
        tmp_path, bodies, scale, constants, files, field, fragment):
    sweep = _scaled_sweep(tmp_path, scale, constants, files)
    output = tmp_path / "out.h5"
    with pytest.raises(SweepInputError) as info:
        run_sweep(sweep, output_h5=output, execution=SERIAL)
    source = str(tmp_path / "scale.txt") if field == "file" else "scaled.toml"
    assert (info.value.source, info.value.field) == (source, field)
    assert fragment in str(info.value)
    assert bodies.calls(tmp_path / "calls") == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["calls", "scale.txt"]


@pytest.mark.parametrize(("target", "names", "field", "fragment"), [
    ("tapp.targeting.launch_azimuth:launch_azimuth_case", ("azimuth_deg",), "body.constants",
     "a value for the argument 'launch_day' of tapp.targeting.launch_azimuth:launch_azimuth_case"),
    ("iter_bodies:raising_body", ("azimut_deg",), "loop[0].names",
     "an argument of iter_bodies:raising_body (azimuth_deg)"),
])
def test_arguments_are_checked_against_the_signature(bodies, target, names, field, fragment):
    loop = Loop(type=1, names=names, sets=1, vary=(96.0,))
    with pytest.raises(SweepInputError) as info:
        run_sweep(Sweep(loops=(loop,), body=CallableBody(target)), execution=SERIAL)
    assert info.value.field == field
    assert fragment in info.value.expected


@pytest.mark.parametrize(("target", "outputs"), [
    # dict declares no signature to inspect: nothing to check (it takes any keyword)
    ("builtins:dict", {"k": 1.0, "output.azimuth_deg": 96.0}),
    ("iter_bodies:keywords_body", {"total": 97.0}),  # **values takes any name
])
def test_a_function_taking_any_keyword_is_called_with_every_name(bodies, target, outputs):
    loop = Loop(type=1, names=("azimuth_deg",), sets=1, vary=(96.0,))
    result = run_sweep(Sweep(loops=(loop,), body=CallableBody(target, {"k": 1.0})),
                       execution=SERIAL)
    assert result.table.rows[0].outputs == outputs

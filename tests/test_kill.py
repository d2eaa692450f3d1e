"""Runs stopped by a signal (issues 10 and 23).

A ``tapp simulate`` writing a tape and an OEM, killed (SIGKILL) at random moments (issue 10,
class 2): afterwards the old outputs or the new ones exist, each complete and readable, from
the same run; after the next successful write no temporary is left. Each seed kills twice:
once at a random moment of the run's second half, and once within 0.3 s of the first new
temporary appearing (while the outputs are being written, which a random moment rarely
hits; some of these runs finish first). Runs in about 20 s.

SIGTERM and SIGINT (issue 23) stop a run cleanly: one line on stderr, exit 143 or 130, the
old outputs intact (or the new ones, complete, when the signal came after they were
renamed), no temporary, and the run's temporary folder gone with the Dask cluster's scratch
space. A Ctrl-C at a terminal reaches the whole process group: the Dask commands are sent
SIGINT that way, once their cluster's workers are up. A pipeline killed outright leaves its
hidden directory and its temporary folder, which the next run removes.
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest
import tomli_w
from typer.testing import CliRunner

from iter import read_hdf5
from tapp.cli import app
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.tape.t13_hdf5 import read_t13
from tests.faults import names, one_line, processes_in, tapp_command, tapp_env

ROOT = Path(__file__).resolve().parents[1]
LEO = EXAMPLES / "leo_equatorial.toml"
#: A longer run (about 3 s of simulation after the imports, where LEO's is under one).
DEEP_SPACE = EXAMPLES / "deep_space.toml"
IDENS = {LEO: "LEO-EQ-SATORB1", DEEP_SPACE: "DSN-LUNAR-2026-03-10"}
SEEDS = (1, 2, 3)
#: State lines of the OEM of leo_equatorial.toml.
LEO_STATES = 2881


#: The deep-space runs here are killed and signalled, not checked: Newtonian light time keeps
#: each run at 2.5 s instead of the 6.4 s of the relativistic one (the default beyond the Moon).
NEWTONIAN = ('light_time = "two_way"', 'light_time = "two_way"\nrelativity = false')


def _scenario(folder: Path, iden: str, source: Path = LEO) -> Path:
    text = source.read_text()
    assert f'iden = "{IDENS[source]}"' in text
    if source == DEEP_SPACE:
        assert NEWTONIAN[0] in text
        text = text.replace(*NEWTONIAN, 1)
    path = folder / f"{iden.lower()}.toml"
    path.write_text(text.replace(f'iden = "{IDENS[source]}"', f'iden = "{iden}"'))
    return path


def _command(scenario: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "tapp.cli", "simulate", str(scenario), "-o",
            str(out / "out.t13.h5"), "--oem", str(out / "out.oem"), "--raw", "--json", "-"]


def _run(scenario: Path, out: Path) -> float:
    start = time.perf_counter()
    proc = subprocess.run(_command(scenario, out), capture_output=True, text=True, check=False,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    return time.perf_counter() - start


def _oem_iden(path: Path, n_states: int = LEO_STATES) -> str:
    """Return the OEM's OBJECT_NAME, checking the file is complete (every state line)."""
    lines = path.read_text().splitlines()
    assert lines[0] == "CCSDS_OEM_VERS = 2.0"
    data = lines[lines.index("META_STOP") + 1:]
    states = [line for line in data if line and not line.startswith("COMMENT")]
    assert len(states) == n_states and all(len(s.split()) == 7 for s in states), path
    return next(line.split("=", 1)[1].strip() for line in lines
                if line.startswith("OBJECT_NAME"))


def _kill_writing(command: list[str], out: Path, rng: random.Random) -> None:
    """Start ``command``; SIGKILL it a random moment after it starts writing ``out``."""
    stale = {p.name for p in out.iterdir()}  # temporaries of earlier kills do not count
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60.0
    while proc.poll() is None and time.monotonic() < deadline:
        if any(p.name.startswith(".") and p.name not in stale for p in out.iterdir()):
            time.sleep(rng.uniform(0.0, 0.3))
            break
        time.sleep(0.001)
    if proc.poll() is None:
        os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)


def _outputs_iden(out: Path, n_states: int = LEO_STATES) -> str:
    """Return the iden of the tape and the OEM in ``out``, both complete and from one run."""
    tape_iden = read_t13(out / "out.t13.h5").iden
    oem_iden = _oem_iden(out / "out.oem", n_states)
    assert tape_iden == oem_iden, f"tape of {tape_iden} beside an OEM of {oem_iden}"
    return tape_iden


def test_killed_simulate_leaves_old_or_new_outputs_and_the_next_write_cleans_up(
        tmp_path: Path) -> None:
    if not hasattr(signal, "SIGKILL"):
        pytest.skip("needs SIGKILL")
    old, new = _scenario(tmp_path, "OLD-RUN"), _scenario(tmp_path, "NEW-RUN")
    out = tmp_path / "out"
    out.mkdir()
    full_s = _run(old, out)
    assert _outputs_iden(out) == "OLD-RUN"
    seen = set()
    for seed in SEEDS:
        rng = random.Random(seed)
        delay_s = rng.uniform(0.5 * full_s, 1.05 * full_s)
        proc = subprocess.Popen(_command(new if seed % 2 else old, out),
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay_s)
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
        seen.add(_outputs_iden(out))  # old or new, complete, and the same run for both
        _kill_writing(_command(old if seed % 2 else new, out), out, rng)
        seen.add(_outputs_iden(out))
    assert seen <= {"OLD-RUN", "NEW-RUN"}
    _run(new, out)
    assert _outputs_iden(out) == "NEW-RUN"
    assert sorted(p.name for p in out.iterdir()) == ["out.oem", "out.t13.h5"]


#: The one line of a run stopped by each signal, and its exit code.
STOPPED = {signal.SIGTERM: ("error: terminated (SIGTERM)", 143),
           signal.SIGINT: ("error: interrupted (SIGINT)", 130)}
#: Longest a stopped run takes to clean up and exit, s.
STOP_S = 60.0


def _start(command: list[str], temporary: Path) -> subprocess.Popen[str]:
    """Start a run as a terminal would: in a process group of its own, its temporaries in
    ``temporary``."""
    return subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=tapp_env(temporary), start_new_session=True)


def _stopped(proc: subprocess.Popen[str], sig: int, *, group: bool = False) -> tuple[int, str]:
    """Send ``sig`` to the run (to its whole process group: Ctrl-C at a terminal); return its
    exit code and stderr once it has exited."""
    if group:
        os.killpg(proc.pid, sig)
    else:
        proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=STOP_S)
    return proc.returncode, stderr


def _wait_for(paths, proc: subprocess.Popen[str], what: str) -> None:
    """Wait until ``paths()`` finds something (the run is where the test wants it)."""
    deadline = time.monotonic() + 120.0
    while not paths():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            _, stderr = proc.communicate()
            pytest.fail(f"no {what} in the run (exit {proc.returncode}): {stderr[-2000:]}")
        time.sleep(0.05)


def _nothing_left(temporary: Path) -> None:
    """No process of the run is left, and nothing in its temporary folder."""
    deadline = time.monotonic() + STOP_S
    while processes_in(temporary) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert processes_in(temporary) == []
    assert names(temporary) == []


@pytest.fixture(scope="module")
def old_deep_space_outputs(tmp_path_factory) -> Path:
    """The folder of an old deep-space run's outputs (tape and OEM), run once: each test
    starts from a copy (:func:`_old_run`)."""
    folder = tmp_path_factory.mktemp("old")
    out = folder / "out"
    out.mkdir()
    _run(_scenario(folder, "OLD-RUN", DEEP_SPACE), out)
    return out


def _old_run(tmp_path: Path, old_outputs: Path) -> tuple[Path, Path, int]:
    """Outputs of an old deep-space run in ``tmp_path/out`` (copied from ``old_outputs``); the
    new run's scenario and the OEM's state count."""
    new = _scenario(tmp_path, "NEW-RUN", DEEP_SPACE)
    out = tmp_path / "out"
    shutil.copytree(old_outputs, out)
    lines = (out / "out.oem").read_text().splitlines()
    n_states = sum(1 for line in lines[lines.index("META_STOP") + 1:]
                   if line and not line.startswith("COMMENT"))
    return out, new, n_states


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signalled_simulate_stops_cleanly_with_the_old_outputs(
        tmp_path: Path, old_deep_space_outputs: Path, sig: int) -> None:
    out, new, n_states = _old_run(tmp_path, old_deep_space_outputs)
    temporary = tmp_path / "tmp"
    proc = _start(_command(new, out), temporary)
    _wait_for(lambda: list(temporary.glob("tapp-run-*")), proc, "run folder")
    time.sleep(0.5)  # simulating: long before anything is written
    code, stderr = _stopped(proc, sig)
    line, expected_code = STOPPED[sig]
    assert (code, one_line(stderr)) == (expected_code, line)  # was no word (SIGTERM) or a
    assert _outputs_iden(out, n_states) == "OLD-RUN"          # traceback (SIGINT)
    assert names(out) == ["out.oem", "out.t13.h5"]
    _nothing_left(temporary)


@pytest.mark.parametrize("sig", [signal.SIGTERM,
                                 pytest.param(signal.SIGINT, marks=pytest.mark.slow)])
def test_a_simulate_signalled_while_writing_leaves_old_or_new_outputs_and_no_temporary(
        tmp_path: Path, old_deep_space_outputs: Path, sig: int) -> None:
    """The temporaries live for milliseconds (each written in one plain write): the signal
    is sent when one is seen, if the run has not ended before."""
    out, new, n_states = _old_run(tmp_path, old_deep_space_outputs)
    temporary = tmp_path / "tmp"
    proc = _start(_command(new, out), temporary)
    while proc.poll() is None and not any(p.name.startswith(".") for p in out.iterdir()):
        time.sleep(0.001)
    code, stderr = _stopped(proc, sig)  # nothing is sent to a run that has ended
    line, expected_code = STOPPED[sig]
    if code != 0:  # the signal came before the outputs were renamed (else: they are new)
        assert (code, one_line(stderr)) == (expected_code, line)
    assert _outputs_iden(out, n_states) == ("OLD-RUN" if code else "NEW-RUN")
    assert names(out) == ["out.oem", "out.t13.h5"]
    _nothing_left(temporary)


@pytest.fixture(scope="module")
def deep_space_t32(tmp_path_factory) -> Path:
    """The T32 tape of deep_space.toml cut to 3 days (as in the pipeline tests)."""
    folder = tmp_path_factory.mktemp("t32")
    scenario = tomllib.loads((EXAMPLES / "deep_space.toml").read_text())
    scenario["tracking"]["end"] = scenario["times"]["end"] = 3 * 86400.0
    scenario["times"]["epochs"] = []
    (folder / "scenario.toml").write_text(tomli_w.dumps(scenario))
    deck = tomllib.loads((EXAMPLES / "tapp3_deep_space.toml").read_text())
    deck["times"]["print"] = [1, 2, 3]
    deck["tape"]["n_o"] = 30  # 3 days of 2-day stochastic batches: 24 + 2 x 3
    (folder / "deck.toml").write_text(tomli_w.dumps(deck))
    for args in (["simulate", folder / "scenario.toml", "-o", folder / "run.t13.h5"],
                 ["process", folder / "run.t13.h5", folder / "deck.toml", "--tape",
                  folder / "run.t32.h5", "--print", folder / "o3.txt"]):
        res = CliRunner().invoke(app, [str(a) for a in args])
        assert res.exit_code == 0, res.output
    return folder / "run.t32.h5"


def _workers_up(temporary: Path):
    """A finder of the scratch folders of a run's Dask workers (they are up)."""
    return lambda: [p for p in temporary.glob(
        "tapp-run-*/dask-cluster-*/dask-scratch-space/worker-*") if p.is_dir()]


def test_ctrl_c_at_a_terminal_stops_guide_and_its_dask_workers_with_one_line(
        tmp_path: Path, deep_space_t32: Path) -> None:
    guide_json, temporary = tmp_path / "guide.json", tmp_path / "tmp"
    guide_json.write_text("{}")  # an earlier run's
    proc = _start(tapp_command("guide", deep_space_t32,
                               EXAMPLES / "tapp2_deep_space.toml", "--samples",
                               "2000000", "--seed", "1", "--workers", "2", "--json",
                               guide_json), temporary)
    _wait_for(_workers_up(temporary), proc, "Dask worker")
    code, stderr = _stopped(proc, signal.SIGINT, group=True)
    assert (code, one_line(stderr)) == (130, "error: interrupted (SIGINT)")  # was 62 lines
    assert guide_json.read_text() == "{}"
    assert names(tmp_path) == ["guide.json", "tmp"]
    _nothing_left(temporary)


@pytest.fixture
def pipeline_file(tmp_path: Path, deep_space_t32: Path) -> Path:
    """A pipeline of the 3-day deep-space scenario (the parts beside the tape)."""
    folder = deep_space_t32.parent
    path = tmp_path / "pipe.toml"
    path.write_text(tomli_w.dumps({
        "scenario": str(folder / "scenario.toml"), "deck": str(folder / "deck.toml"),
        "guidance": str(EXAMPLES / "tapp2_deep_space.toml"),
        "guide": {"samples": 2_000_000, "seed": 1}}))
    return path


@pytest.mark.slow
def test_ctrl_c_at_a_terminal_stops_a_pipeline_on_dask_and_leaves_its_directory_empty(
        tmp_path: Path, pipeline_file: Path) -> None:
    out, temporary = tmp_path / "out", tmp_path / "tmp"
    out.mkdir()  # new or empty: an empty one is there before
    proc = _start(tapp_command("pipeline", pipeline_file, "-o", out, "--workers", "2"),
                  temporary)
    _wait_for(_workers_up(temporary), proc, "Dask worker")
    code, stderr = _stopped(proc, signal.SIGINT, group=True)
    assert (code, one_line(stderr)) == (130, "error: interrupted (SIGINT)")
    assert names(tmp_path) == ["out", "pipe.toml", "tmp"] and names(out) == []
    _nothing_left(temporary)


@pytest.mark.slow
def test_ctrl_c_at_a_terminal_stops_a_sweep_on_dask_and_keeps_a_resumable_checkpoint(
        tmp_path: Path) -> None:
    results, temporary = tmp_path / "r.h5", tmp_path / "tmp"
    proc = _start(tapp_command("iter", EXAMPLES / "iter_pipeline_tracking.toml",
                               "-o", results, "--workers", "2"), temporary)
    _wait_for(_workers_up(temporary), proc, "Dask worker")
    time.sleep(5.0)  # cases running on the workers
    code, stderr = _stopped(proc, signal.SIGINT, group=True)
    assert (code, one_line(stderr)) == (130, "error: interrupted (SIGINT)")
    assert read_hdf5(results).n_cases == 9  # the checkpoint a rerun resumes from
    assert names(tmp_path) == ["r.h5", "tmp"]
    _nothing_left(temporary)


@pytest.mark.slow
def test_a_killed_pipeline_s_directory_and_temporary_folder_go_with_the_next_run(
        tmp_path: Path, pipeline_file: Path) -> None:
    out, temporary = tmp_path / "out", tmp_path / "tmp"
    proc = _start(tapp_command("pipeline", pipeline_file, "-o", out, "--workers", "2"),
                  temporary)
    _wait_for(_workers_up(temporary), proc, "Dask worker")
    proc.kill()
    proc.communicate(timeout=STOP_S)
    hidden = [p.name for p in tmp_path.iterdir() if p.name.startswith(".out.")]
    assert len(hidden) == 1 and (tmp_path / hidden[0] / "run.t13.h5").exists()
    assert len(list(temporary.glob("tapp-run-*"))) == 1  # left by the kill
    deadline = time.monotonic() + STOP_S  # its cluster, left alone, stops by itself
    while processes_in(temporary) and time.monotonic() < deadline:
        time.sleep(0.2)
    doc = tomllib.loads(pipeline_file.read_text())
    doc["guide"]["samples"] = 3000
    pipeline_file.write_text(tomli_w.dumps(doc))
    res = subprocess.run(tapp_command("pipeline", pipeline_file, "-o", out, "--serial"),
                         capture_output=True, text=True, env=tapp_env(temporary),
                         timeout=600, check=False)
    assert res.returncode == 0, res.stderr
    assert names(tmp_path) == ["out", "pipe.toml", "tmp"]
    _nothing_left(temporary)

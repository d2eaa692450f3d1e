"""Faults from outside the input (issue 23, the output side): a full disk, and a standard
output that is full, closed or broken. Each is one line on stderr and exit 1; the old
outputs stay as they were, and no temporary, no scratch folder (the run's temporary folder,
``TMPDIR`` here) and no folder made for the outputs is left. Signals are tests/test_kill.py.

Every command runs as a process: on a full disk h5py crashed the process (segmentation
fault, exit -11) while closing a tape it could not write, which an in-process test would not
survive. The full disk is a 2 MB tmpfs filled to a few bytes (root only: skipped otherwise).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.faults import (
    SCENARIOS,
    fill,
    mounted_tmpfs,
    names,
    one_line,
    run_tapp,
    tapp_command,
    tapp_env,
)

LEO = SCENARIOS / "leo_equatorial.toml"
LEO_DECK = SCENARIOS / "tapp3_leo_equatorial.toml"
SWEEP = SCENARIOS / "iter_azimuth_type1.toml"
NO_SPACE = "not written (No space left on device)"
#: Bytes left free on the full disk: fewer than any tape or results file needs.
FREE_BYTES = 20_000


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def leo_tape(tmp_path_factory) -> Path:
    """The T13 tape of leo_equatorial.toml (354 kB; 522 kB with --raw)."""
    folder = tmp_path_factory.mktemp("leo")
    res = run_tapp(folder / "tmp", "simulate", LEO, "-o", folder / "leo.t13.h5")
    assert res.returncode == 0, res.stderr
    return folder / "leo.t13.h5"


@pytest.fixture
def full(tmp_path: Path):
    """A tmpfs of 2 MB (root only), filled by each test."""
    with mounted_tmpfs(tmp_path / "full") as folder:
        yield folder


@pytest.fixture
def temporary(tmp_path: Path) -> Path:
    """The runs' temporary folder (their TMPDIR): empty after every run."""
    return tmp_path / "tmp"


# --- a full disk --------------------------------------------------------------------------


@pytest.mark.parametrize("raw", [False, True])
def test_simulate_onto_a_full_disk_is_one_line_and_keeps_the_old_tape(
        full: Path, temporary: Path, leo_tape: Path, raw: bool) -> None:
    tape = full / "run.t13.h5"
    shutil.copy(leo_tape, tape)
    before = _digest(tape)
    fill(full, FREE_BYTES)
    res = run_tapp(temporary, "simulate", LEO, "-o", tape, *(["--raw"] if raw else []))
    assert res.returncode == 1, res.stderr[-3000:]  # was -11 (segfault), after 189 lines
    assert one_line(res.stderr) == f"error: -o/--output: {tape}: {NO_SPACE}"
    assert _digest(tape) == before
    assert names(full) == ["fill", "run.t13.h5"]
    assert names(temporary) == []


def test_process_onto_a_full_disk_writes_none_of_its_outputs_and_no_folder(
        full: Path, temporary: Path, tmp_path: Path, leo_tape: Path) -> None:
    fill(full, FREE_BYTES)
    t32 = full / "a" / "b" / "run.t32.h5"
    res = run_tapp(temporary, "process", leo_tape, LEO_DECK, "--tape", t32, "--print",
                   tmp_path / "o3.txt")
    assert res.returncode == 1, res.stderr[-3000:]
    assert one_line(res.stderr) == f"error: --tape: {t32}: {NO_SPACE}"
    assert names(full) == ["fill"]  # no a/, no a/b/
    assert not (tmp_path / "o3.txt").exists()  # on another disk, but all or none
    assert names(temporary) == []


def test_iter_onto_a_full_disk_is_one_line_before_any_case_runs(
        full: Path, temporary: Path) -> None:
    fill(full, 0)
    results = full / "a" / "r.h5"
    res = run_tapp(temporary, "iter", SWEEP, "-o", results, "--serial")
    assert res.returncode == 1, res.stderr[-3000:]
    assert one_line(res.stderr) == f"error: -o/--output: {results}: {NO_SPACE}"
    assert names(full) == ["fill"]
    assert names(temporary) == []


@pytest.mark.slow
def test_dc_saving_observations_onto_a_full_disk_is_one_line(full: Path,
                                                              temporary: Path) -> None:
    fill(full, 0)
    obs = full / "obs.h5"
    res = run_tapp(temporary, "dc", "--orbit", "SATORB1", "--arc", "2h", "--save-obs", obs)
    assert res.returncode == 1, res.stderr[-3000:]
    assert one_line(res.stderr) == f"error: --save-obs: {obs}: {NO_SPACE}"
    assert names(full) == ["fill"]


@pytest.mark.slow
def test_a_tape_never_crashes_the_process_however_full_the_disk(
        full: Path, temporary: Path, leo_tape: Path) -> None:
    """Twelve fill levels, from 10 kB to 450 kB free, against the 522 kB of a raw tape: h5py
    crashed the process at every level tried (24 of 24 in the measurement of
    tapp.io.tape.hdf5io.create)."""
    tape = full / "run.t13.h5"
    shutil.copy(leo_tape, tape)
    before = _digest(tape)
    for free_bytes in range(10_000, 490_000, 40_000):
        fill(full, free_bytes)
        res = run_tapp(temporary, "simulate", LEO, "-o", tape, "--raw")
        assert (res.returncode, one_line(res.stderr)) == (
            1, f"error: -o/--output: {tape}: {NO_SPACE}"), free_bytes
        assert _digest(tape) == before and names(full) == ["fill", "run.t13.h5"]
        (full / "fill").unlink()
    assert names(temporary) == []


# --- standard output that cannot be written ------------------------------------------------


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_full_standard_output_is_one_line_exit_1(temporary: Path, leo_tape: Path) -> None:
    with open("/dev/full", "w") as stdout:
        res = run_tapp(temporary, "process", leo_tape, LEO_DECK, stdout=stdout)
    assert res.returncode == 1  # was an OSError traceback
    assert one_line(res.stderr) == f"error: standard output: {NO_SPACE}"
    assert names(temporary) == []


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize("args", [
    ["simulate", LEO, "-o", "{out}/run.t13.h5", "--oem", "{out}/new/run.oem"],
    ["examples", "{out}/examples", "--json", "{out}/examples.json"],
    ["tape", "info", "{tape}", "--json", "{out}/info.json"],
])
def test_a_report_that_cannot_be_printed_leaves_no_new_output(
        temporary: Path, tmp_path: Path, leo_tape: Path, args: list[object]) -> None:
    """The report is printed before the outputs are renamed into place (issue 28:
    ``tapp simulate -o p.t13.h5 | head -1`` exited 1 and left p.t13.h5)."""
    out = tmp_path / "out"
    out.mkdir()
    with open("/dev/full", "w") as stdout:
        res = run_tapp(temporary, *(str(a).format(out=out, tape=leo_tape) for a in args),
                       stdout=stdout)
    assert res.returncode == 1
    assert one_line(res.stderr) == f"error: standard output: {NO_SPACE}"
    assert names(out) == []
    assert names(temporary) == []


def test_a_closed_standard_output_is_one_line_exit_1(temporary: Path, tmp_path: Path) -> None:
    tape = tmp_path / "leo.t13.h5"
    res = subprocess.run(["sh", "-c", 'exec "$@" >&-', "sh",
                          *tapp_command("simulate", LEO, "-o", tape, "--json", "-")],
                         capture_output=True, text=True, env=tapp_env(temporary),
                         timeout=300, check=False)
    assert res.returncode == 1  # was an AttributeError traceback
    assert one_line(res.stderr) == "error: standard output: not written (Bad file descriptor)"
    assert names(temporary) == []


@pytest.mark.parametrize("args", [["tape", "info", "{tape}"], ["--help"]])
def test_a_broken_pipe_on_standard_output_is_one_line_exit_1(temporary: Path, leo_tape: Path,
                                                             args: list[str]) -> None:
    command = tapp_command(*(a.format(tape=leo_tape) for a in args))
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          env=tapp_env(temporary)) as proc:
        proc.stdout.close()  # like `| head -0`: nothing reads what it prints
        stderr = proc.stderr.read()
    assert proc.returncode == 1  # was exit 1 and no word (typer's own handling)
    assert one_line(stderr) == "error: standard output: not written (Broken pipe)"
    assert os.listdir(temporary) == []

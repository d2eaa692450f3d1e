"""A ``tapp simulate`` writing a tape and an OEM, killed (SIGKILL) at random moments (issue 10,
class 2): afterwards the old outputs or the new ones exist, each complete and readable, from
the same run; after the next successful write no temporary is left.

Each seed kills twice: once at a random moment of the run's second half, and once within
0.3 s of the first new temporary appearing (while the outputs are being written, which a
random moment rarely hits; some of these runs finish first). Runs in about 20 s.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tapp.examples import FOLDER as EXAMPLES
from tapp.tape.t13_hdf5 import read_t13

ROOT = Path(__file__).resolve().parents[1]
LEO = EXAMPLES / "leo_equatorial.toml"
SEEDS = (1, 2, 3)


def _scenario(folder: Path, iden: str) -> Path:
    text = LEO.read_text()
    assert 'iden = "LEO-EQ-SATORB1"' in text
    path = folder / f"{iden.lower()}.toml"
    path.write_text(text.replace('iden = "LEO-EQ-SATORB1"', f'iden = "{iden}"'))
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


def _oem_iden(path: Path) -> str:
    """Return the OEM's OBJECT_NAME, checking the file is complete (every state line)."""
    lines = path.read_text().splitlines()
    assert lines[0] == "CCSDS_OEM_VERS = 2.0"
    data = lines[lines.index("META_STOP") + 1:]
    states = [line for line in data if line and not line.startswith("COMMENT")]
    assert len(states) == 2881 and all(len(s.split()) == 7 for s in states), path
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


def _outputs_iden(out: Path) -> str:
    """Return the iden of the tape and the OEM in ``out``, both complete and from one run."""
    tape_iden = read_t13(out / "out.t13.h5").iden
    oem_iden = _oem_iden(out / "out.oem")
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

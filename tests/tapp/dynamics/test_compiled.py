"""The compile cache (tapp.dynamics.compiled): one driver object per method, one library per
force model, made once however many processes ask at the same time, and a missing compiler
is one clear error."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tapp.dynamics import Propagator, earth_model
from tapp.dynamics.compiled import CompileError

#: Builds the J3 propagator of both methods in a fresh process and prints one state.
_BUILD = """
import sys, numpy as np
from tapp.dynamics import Propagator, earth_model
x0 = np.array([7000.0, 0.0, 0.0, 0.0, 4.7, 6.0])
for method in ("dop853", "rkn12"):
    y = Propagator(earth_model("J3"), method=method).propagate(x0, np.array([0.0, 600.0]),
                                                                stm=False)
    print(repr(float(y.states[-1, 0])))
"""


def _build(cache: Path, cc: Path) -> subprocess.Popen:
    env = {**os.environ, "TAPP_CACHE_DIR": str(cache), "CC": str(cc)}
    return subprocess.Popen([sys.executable, "-c", _BUILD], stdout=subprocess.PIPE, text=True,
                            env=env)


def test_processes_that_ask_at_once_get_one_compile_and_the_same_numbers(tmp_path) -> None:
    cache, calls = tmp_path / "cache", tmp_path / "calls"
    cc = tmp_path / "cc"  # the system compiler, each call logged
    cc.write_text(f'#!/bin/sh\necho "$@" >> {calls}\nexec cc "$@"\n')
    cc.chmod(0o755)
    runs = [_build(cache, cc) for _ in range(3)]
    outputs = [run.communicate(timeout=300)[0] for run in runs]
    assert all(run.returncode == 0 for run in runs)
    assert len(set(outputs)) == 1
    made = sorted(p.suffix for p in cache.iterdir() if not p.name.startswith("."))
    # one driver object per method, one library per (model, method); no temporary left
    assert made == [".o", ".o", ".so", ".so"], made
    assert len(calls.read_text().splitlines()) == 4  # the others waited, then loaded


def test_a_missing_compiler_is_one_clear_error(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("TAPP_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CC", "no-such-cc")
    with pytest.raises(CompileError, match="'no-such-cc' not found"):
        Propagator(earth_model("J4")).propagate(np.array([7000.0, 0, 0, 0, 7.5, 0]),
                                                np.array([0.0, 60.0]))
    assert not any(tmp_path.glob("*.so"))

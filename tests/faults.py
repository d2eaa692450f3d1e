"""What the fault tests share: ``tapp`` run as a process with a temporary folder of its own,
a small tmpfs to fill, a read-only folder, and the one line a failure prints.

Folders made by :func:`mounted_tmpfs` and :func:`read_only_folder` need root (``mount``);
without it the tests that use them are skipped, with the reason.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tapp.examples import FOLDER as EXAMPLES

SCENARIOS = EXAMPLES
#: Size of the tmpfs that the disk-full tests fill.
TMPFS_SIZE = "2m"


def tapp_command(*args: object) -> list[str]:
    """The command line of ``tapp ARGS`` (this interpreter's ``python -m tapp.cli``)."""
    return [sys.executable, "-m", "tapp.cli", *map(str, args)]


def tapp_env(temporary: Path) -> dict[str, str]:
    """The environment of a ``tapp`` process whose temporaries go into ``temporary``."""
    temporary.mkdir(exist_ok=True)
    return {**os.environ, "TMPDIR": str(temporary)}


def run_tapp(temporary: Path, *args: object, stdout: object = subprocess.PIPE,
             timeout_s: float = 300.0) -> subprocess.CompletedProcess[str]:
    """Run ``tapp ARGS`` to its end, its temporaries in ``temporary``."""
    return subprocess.run(tapp_command(*args), stdout=stdout, stderr=subprocess.PIPE,
                          text=True, env=tapp_env(temporary), timeout=timeout_s, check=False)


def one_line(stderr: str) -> str:
    """Return the only line of ``stderr``, checking it is one ``error:`` line."""
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), stderr[-3000:]
    return lines[0]


def names(folder: Path) -> list[str]:
    """Every name in ``folder``, hidden ones included, sorted."""
    return sorted(p.name for p in folder.iterdir())


def _root_or_skip(what: str) -> None:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip(f"{what} needs root (mount)")


@contextlib.contextmanager
def mounted_tmpfs(folder: Path, options: str = f"size={TMPFS_SIZE}") -> Iterator[Path]:
    """Mount a tmpfs on ``folder`` (made) for the block; skip the test without root."""
    _root_or_skip("a tmpfs")
    folder.mkdir(parents=True, exist_ok=True)
    mount = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)],
                           capture_output=True, text=True, check=False)
    if mount.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs: {mount.stderr.strip()}")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=True)


def fill(folder: Path, free_bytes: int) -> Path:
    """Fill the file system of ``folder`` (a tmpfs) until ``free_bytes`` are left; return
    the file that fills it."""
    stat = os.statvfs(folder)
    filler = folder / "fill"
    filler.write_bytes(b"\0" * max(0, stat.f_bavail * stat.f_frsize - free_bytes))
    return filler


@contextlib.contextmanager
def read_only_folder(folder: Path) -> Iterator[Path]:
    """``folder`` (made), empty and read-only for the block: a read-only tmpfs under root
    (which permissions do not stop), permissions 0500 otherwise."""
    if os.geteuid() == 0:
        with mounted_tmpfs(folder, "size=64k,ro"):
            yield folder
        return
    folder.mkdir(mode=0o500)
    try:
        yield folder
    finally:
        folder.chmod(0o700)


def processes_in(temporary: Path) -> list[int]:
    """The processes whose TMPDIR lies in ``temporary`` (started by a run given it, the
    Dask cluster's included), from Linux's /proc."""
    marker = f"TMPDIR={temporary}".encode()
    found = []
    for entry in Path("/proc").glob("[0-9]*"):
        try:
            if marker in (entry / "environ").read_bytes():
                found.append(int(entry.name))
        except OSError:  # gone meanwhile, or another user's
            continue
    return found

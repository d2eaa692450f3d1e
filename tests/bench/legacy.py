"""An earlier commit's code, timed in a child process: the "before" column of a section.

:func:`extract` writes ``git archive <commit> tapp search iter`` into a folder; :func:`run_child`
runs a timing script in a child interpreter with ``PYTHONPATH`` set to that folder and its
working directory there (so the working tree is not on its path), with its own ``TAPP_CACHE_DIR``
(compiled right-hand sides of that code stay apart from the working tree's). The child runs,
in order: a prelude that fails unless ``tapp``, ``search`` and ``iter`` come from the folder,
loads :mod:`tests.bench.common` by its file (standard library only, so it imports no tapp)
as ``common`` and defines ``ARGS`` (the JSON argument) and ``reply`` (prints a result as JSON
on the child's last stdout line); the source of the section's own timed functions (so both
sides time the same code, against different libraries); then the script.

Used by the TAPP I (``tracking``) and TAPP III (``processor``) sections for the normal-matrix
form of commit :data:`NORMAL_MATRIX_COMMIT`, the last before square-root information.
"""

from __future__ import annotations

import inspect
import json
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tests.bench import common
from tests.bench.common import REPO_ROOT

#: The last commit with the normal-matrix TAPP I and TAPP III (T13 version 2).
NORMAL_MATRIX_COMMIT = "fa859a7"
PACKAGES = ("tapp", "search", "iter")

#: Prepended to every child script (argv: the extracted folder, the JSON argument, the path
#: of tests/bench/common.py).
_PRELUDE = """from __future__ import annotations
import importlib.util, json, sys, time
from pathlib import Path
_ROOT = Path(sys.argv[1]).resolve()
import tapp, search
import iter as _sweeps
for _mod in (tapp, search, _sweeps):
    if _ROOT not in Path(_mod.__file__).resolve().parents:
        raise SystemExit(f"{_mod.__name__} imported from {_mod.__file__}, not from {_ROOT}")
# An editable install of the working tree maps every submodule the old commit lacks to the
# working tree's (setuptools' _EditableFinder): drop it so that such an import fails instead.
sys.meta_path[:] = [f for f in sys.meta_path if getattr(f, "__name__", "") != "_EditableFinder"]
ARGS = json.loads(sys.argv[2])
_spec = importlib.util.spec_from_file_location("bench_common", sys.argv[3])
common = importlib.util.module_from_spec(_spec)
sys.modules["bench_common"] = common
_spec.loader.exec_module(common)

def reply(result):
    sys.stdout.write("\\n" + json.dumps(result) + "\\n")
"""


@dataclass(frozen=True, slots=True)
class Checkout:
    """The packages of ``commit`` (full hash) extracted under ``root``."""

    commit: str
    root: Path


def extract(folder: Path, commit: str = NORMAL_MATRIX_COMMIT) -> tuple[Checkout | None, str]:
    """Extract :data:`PACKAGES` of ``commit`` into ``folder / <its hash, 12 digits>``.

    Returns (checkout, "") or (None, why not) when git, the repository or the commit is
    unavailable, so that a section can skip its column with that note rather than fail.
    """
    git = shutil.which("git")
    if git is None:
        return None, "git not found"

    def git_run(*args: str, **kwargs) -> subprocess.CompletedProcess:
        return subprocess.run([git, "-C", str(REPO_ROOT), *args], check=False, **kwargs)

    found = git_run("rev-parse", "--verify", "--quiet", f"{commit}^{{commit}}",
                    capture_output=True, text=True)
    if found.returncode != 0:
        return None, f"commit {commit} not found in {REPO_ROOT}"
    full = found.stdout.strip()
    root = folder / full[:12]
    root.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryFile() as archive:
        done = git_run("archive", "--format=tar", full, *PACKAGES, stdout=archive,
                       stderr=subprocess.PIPE, text=False)
        if done.returncode != 0:
            return None, f"git archive {commit} failed: {done.stderr.decode().strip()}"
        archive.seek(0)
        with tarfile.open(fileobj=archive) as tar:
            tar.extractall(root, filter="data")
    missing = [p for p in PACKAGES if not (root / p / "__init__.py").is_file()]
    if missing:
        return None, f"commit {commit} has no package(s) {', '.join(missing)}"
    return Checkout(full, root), ""


def file_at(path: str, commit: str = NORMAL_MATRIX_COMMIT) -> str | None:
    """The text of ``path`` (from the repository root) at ``commit``, or None without git,
    the repository, the commit or the file."""
    git = shutil.which("git")
    if git is None:
        return None
    done = subprocess.run([git, "-C", str(REPO_ROOT), "show", f"{commit}:{path}"],
                          capture_output=True, text=True, check=False)
    return done.stdout if done.returncode == 0 else None


def run_child(checkout: Checkout, script: str, args: dict[str, Any], *, cache_dir: Path,
              functions: Sequence[Callable] = (), timeout_s: float = 1800.0
              ) -> dict[str, Any]:
    """Run ``script`` on the checkout's code (module docstring); return its JSON reply.

    ``functions``: module-level functions of the section whose source the child defines
    before the script (the names they use must be imported or defined by the script).
    The child inherits this process's environment (BLAS threads included) but for
    ``PYTHONPATH`` (the checkout only) and ``TAPP_CACHE_DIR`` (``cache_dir``).

    Raises
    ------
    RuntimeError
        If the child exits non-zero or prints no JSON reply (its stderr is quoted).
    """
    env = dict(os.environ)
    env["PYTHONPATH"] = str(checkout.root)
    env["TAPP_CACHE_DIR"] = str(cache_dir)
    shipped = "".join("\n" + inspect.getsource(fn) for fn in functions)
    cmd = [sys.executable, "-c", _PRELUDE + shipped + script, str(checkout.root),
           json.dumps(args), common.__file__]
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=checkout.root, env=env,
                          timeout=timeout_s, check=False)
    lines = done.stdout.strip().splitlines()
    if done.returncode != 0 or not lines:
        raise RuntimeError(f"child on {checkout.commit[:7]} exited {done.returncode}: "
                           f"{done.stderr.strip()[-2000:]}")
    return json.loads(lines[-1])


def cache_files(cache_dir: Path) -> list[str]:
    """Names of the files in a child's cache folder (what it compiled), sorted."""
    return sorted(p.name for p in cache_dir.iterdir()) if cache_dir.is_dir() else []

"""The package installs like one: a wheel, a fresh virtual environment, every command run from
an empty folder on the examples ``tapp examples`` copies.

How it installs (robust offline, on CI too):

1. the wheel is built from a copy of the sources (``pyproject.toml``, ``README.md``, ``tapp``,
   ``search``, ``iter``: the build writes ``build/`` beside them) by ``pip wheel --no-deps
   --no-build-isolation --no-index``, with the build requirements of the test environment
   (setuptools is in the ``test`` extra): no network;
2. a fresh virtual environment (``python -m venv --without-pip``, no system site-packages) gets
   the wheel by ``pip --python VENV install --no-deps --no-index``;
3. its dependencies are this environment's: one ``.pth`` line puts this environment's
   site-packages after its own (a directory named by a ``.pth`` line is not a site directory,
   so the editable install's finder there is not loaded: ``tapp``, ``search`` and ``iter``
   come from the wheel, which the test checks).

Every command then runs from an empty folder: ``tapp examples`` and ``tapp dc`` (the two that
failed on an installed tapp) through the console script, the others in one process of the
new environment (``tests/install_smoke.py``: the start-up is paid once). Built once per
session; about 25 s in all.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What the wheel is built from.
SOURCES = ("pyproject.toml", "README.md", "tapp", "search", "iter")
#: Generous wall-time limit of one step, s (a stuck build or run fails the test, never hangs).
STEP_TIMEOUT_S = 600


@dataclass(frozen=True)
class Installed:
    venv: Path
    work: Path
    wheel: Path

    def env(self) -> dict[str, str]:
        """The environment of a user: nothing pointing into the repository."""
        env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
        env["PATH"] = f"{self.venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
        return env

    def run(self, argv: list[str], stdin: str | None = None) -> subprocess.CompletedProcess:
        return subprocess.run(argv, input=stdin, capture_output=True, text=True, cwd=self.work,
                              env=self.env(), timeout=STEP_TIMEOUT_S, check=False)


def _checked(argv: list, cwd: Path) -> None:
    # Without PYTHONPATH: one pointing at a checkout (a worktree's tests) made pip take tapp
    # for installed already, and the new environment got no console script.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run([str(a) for a in argv], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=STEP_TIMEOUT_S, check=False)
    assert proc.returncode == 0, f"{' '.join(map(str, argv))}:\n{proc.stdout}\n{proc.stderr}"


@pytest.fixture(scope="session")
def installed(tmp_path_factory) -> Installed:
    root = tmp_path_factory.mktemp("install")
    src, dist, venv, work = (root / name for name in ("src", "dist", "venv", "work"))
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info", "build")
    for name in SOURCES:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, src / name, ignore=ignore)
        else:
            shutil.copy2(ROOT / name, src / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    _checked([*pip, "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-w", dist,
              src], root)
    (wheel,) = dist.glob("tapp-*.whl")
    _checked([sys.executable, "-m", "venv", "--without-pip", venv], root)
    python = venv / "bin" / "python"
    site = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()"
                           "['purelib'])"], capture_output=True, text=True, check=True)
    ours = {sysconfig.get_paths()[key] for key in ("purelib", "platlib")}
    Path(site.stdout.strip(), "_tapp_test_dependencies.pth").write_text(
        "".join(f"{path}\n" for path in sorted(ours)))
    _checked([*pip, "--python", python, "install", "--no-deps", "--no-index", wheel], root)
    work.mkdir()
    return Installed(venv, work, wheel)


def test_the_wheel_holds_the_run_time_data(installed: Installed) -> None:
    import zipfile

    from tapp.examples import FILES

    names = set(zipfile.ZipFile(installed.wheel).namelist())
    assert {"tapp/dynamics/dop853_driver.c", "tapp/data/egm96_deg8.txt"} <= names
    assert {f"tapp/examples/{name}" for name in FILES} <= names
    assert not any(n.startswith(("scenarios/", "tests/", "docs/")) for n in names)


@pytest.fixture(scope="session")
def console(installed: Installed) -> dict[str, subprocess.CompletedProcess]:
    """``tapp examples ex`` then ``tapp dc`` through the installed console script."""
    tapp = str(installed.venv / "bin" / "tapp")
    return {"examples": installed.run([tapp, "examples", "ex"]),
            "dc": installed.run([tapp, "dc", "--orbit", "SATORB1", "--arc", "1h"])}


def test_the_console_script_copies_the_examples(installed: Installed, console) -> None:
    from tapp.examples import FILES

    assert console["examples"].returncode == 0, console["examples"].stderr
    ex = installed.work / "ex"
    assert sorted(str(p.relative_to(ex)) for p in ex.rglob("*") if p.is_file()) == sorted(FILES)


def test_the_console_script_reads_the_shipped_study(console) -> None:
    """The issue's first failure: ``tapp dc --orbit SATORB1`` looked for site-packages/
    scenarios/approx_stm.toml."""
    proc = console["dc"]
    assert proc.returncode == 0, proc.stderr
    assert "converged" in proc.stdout and proc.stderr == ""


#: Every other command on the copied examples, in order (later ones read earlier outputs):
#: its arguments, a text its output must hold and the file it must write. Small where a file
#: allows it: the Table D-1 scenario (1 s) for TAPP I and III, the pipeline's T32 tape for
#: TAPP II, the type 1 azimuth sweep.
COMMANDS = {
    "info": (["info"], "DE421 ephemeris", None),
    "schema": (["schema", "scenario"], '"var_gravity"', None),
    "propagate": (["propagate", "--orbit", "SATORB1", "--arc", "1h", "--step", "600s",
                   "--json", "-"], '"stm"', None),
    "ekf": (["ekf", "--orbit", "SATORB1", "--arc", "2h"], "max|O-C| range", None),
    "rsig": (["rsig", "--orbit", "SATORB1", "--span", "2h", "--step", "600s", "--stm", "J0"],
             "R(t) SATORB1", None),
    "simulate": (["simulate", "ex/tapp1_table_d1.toml", "-o", "d1.t13.h5"], "n_o = 29",
                 "d1.t13.h5"),
    "tape": (["tape", "info", "d1.t13.h5"], "LEO-EQ-TABLE-D1", None),
    "process": (["process", "d1.t13.h5", "ex/tapp3_table_d1.toml", "--print", "d1.o3.txt"],
                "", "d1.o3.txt"),
    "search": (["search", "ex/search_bplane.toml"], "CONVERGED", None),
    "mission": (["simulate", "ex/mission/mission.toml", "-o", "mission.t13.h5"],
                "Fitted to the reference", "mission.t13.h5"),
    "pipeline": (["pipeline", "ex/pipeline_deep_space.toml", "-o", "pipe", "--serial"],
                 "pipe/report.md", "pipe/report.md"),
    "guide": (["guide", "pipe/run.t32.h5", "ex/tapp2_deep_space.toml", "--samples", "2000",
               "--seed", "1", "--serial"], "Final miss", None),
    "iter": (["iter", "ex/iter_azimuth_type1.toml", "-o", "az.h5", "--serial"], "succeeded",
             "az.h5"),
}


@pytest.fixture(scope="session")
def smoke(installed: Installed, console) -> dict:
    assert console["examples"].returncode == 0, console["examples"].stderr
    commands = [[name, argv] for name, (argv, _, _) in COMMANDS.items()]
    # -I: the script's folder (tests/, which holds a package named tapp) is not on sys.path
    proc = installed.run([str(installed.venv / "bin" / "python"), "-I",
                          str(ROOT / "tests" / "install_smoke.py")], json.dumps(commands))
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_the_packages_come_from_the_wheel(installed: Installed, smoke: dict) -> None:
    for name, path in smoke["modules"].items():
        assert Path(path).is_relative_to(installed.venv), (name, path)
    assert not any(installed.work.glob("**/*.py"))  # nothing of the sources in the folder


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_runs_from_an_empty_folder(installed: Installed, smoke: dict,
                                                name: str) -> None:
    _, text, written = COMMANDS[name]
    result = smoke["results"][name]
    assert result["exit_code"] == 0, result["output"]
    assert text in result["output"]
    assert written is None or (installed.work / written).stat().st_size > 0

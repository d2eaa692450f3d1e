"""The ``tapp`` command as a whole: what its help loads and shows, one JSON convention, and
one BLAS thread (the conventions of :mod:`tapp.cli.common`). Start-up times are measured by
``make bench`` (section ``cli``), not here."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import typing
from pathlib import Path

import pytest
import typer
from threadpoolctl import threadpool_info, threadpool_limits
from typer.testing import CliRunner

from iter.execute import available_cores
from tapp.cli import app
from tapp.cli.common import EXIT_INPUT, JsonOpt, run_guarded
from tapp.io.tape.t13 import VERSION
from tests.tapp.io.tape.legacy import write_t13_version
from tests.tapp.processor.helpers import leo_tape

runner = CliRunner()
#: Modules a help or ``--version`` must not wait for: each costs 0.1-0.7 s to import.
HEAVY = ("numpy", "scipy", "dask", "distributed", "matplotlib", "casadi", "h5py", "pydantic",
         "erfa", "jplephem", "filterpy", "astropy", "threadpoolctl")
#: Wide enough that rich wraps no help line (a wrapped fragment would not be found).
WIDE = {"COLUMNS": "1000"}


def _commands() -> list[tuple[str, ...]]:
    """Every command, as the words that name it."""
    paths: list[tuple[str, ...]] = []

    def walk(group, prefix: tuple[str, ...]) -> None:
        for name, command in group.commands.items():
            if hasattr(command, "commands"):
                walk(command, (*prefix, name))
            else:
                paths.append((*prefix, name))

    walk(typer.main.get_command(app), ())
    return paths


COMMANDS = _commands()


def _command(path: tuple[str, ...]):
    command = typer.main.get_command(app)
    for name in path:
        command = command.commands[name]
    return command


def test_every_command_is_found():
    assert set(COMMANDS) == {("guide",), ("iter",), ("pipeline",), ("process",),
                             ("propagate",), ("dc",), ("ekf",), ("rsig",), ("simulate",),
                             ("search",), ("info",), ("tape", "info"), ("examples",),
                             ("schema",)}


def test_help_and_version_load_no_heavy_module():
    # a fresh interpreter: this one has imported everything already
    child = ("import sys\n"
             "from typer.testing import CliRunner\n"
             "from tapp.cli import app\n"
             f"for args in {[['--help'], ['--version']] + [[*p, '--help'] for p in COMMANDS]}:\n"
             "    result = CliRunner().invoke(app, args)\n"
             "    assert result.exit_code == 0, (args, result.output)\n"
             f"print(sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY})))\n")
    done = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                          check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def _unescaped(text: str | None) -> str:
    """Help text as written in the source (the app escapes rich's brackets when built)."""
    return (text or "").replace("\\[", "[")


def _help_texts(command) -> list[str]:
    return [_unescaped(command.help),
            *(_unescaped(getattr(p, "help", None)) for p in command.params)]


def _squashed(text: str) -> str:
    return " ".join(text.split())


@pytest.mark.parametrize("path", [(), *COMMANDS], ids=lambda p: " ".join(p) or "tapp")
def test_help_keeps_every_bracket_and_every_default(path: tuple[str, ...]):
    command = _command(path)
    result = runner.invoke(app, [*path, "--help"], env=WIDE)
    assert result.exit_code == 0, result.output
    shown = _squashed(result.stdout)
    brackets = [b for text in _help_texts(command)
                for b in re.findall(r"\[\[?[^\[\]]*\]?\]", _squashed(text))]
    missing = [b for b in brackets if b not in shown]
    assert not missing, f"eaten by the help renderer: {missing}"
    defaults = [f"[default: {p.default}]" for p in command.params
                if isinstance(p, typer.core.TyperOption) and p.default is not None
                and not p.is_flag and p.show_default is not False]
    missing = [d for d in defaults if d not in shown]
    assert not missing, f"defaults not shown: {missing}"


def test_the_brackets_checked_include_those_once_eaten():
    iter_help = _squashed(runner.invoke(app, ["iter", "--help"], env=WIDE).stdout)
    pipeline_help = _squashed(runner.invoke(app, ["pipeline", "--help"], env=WIDE).stdout)
    assert "Sweep file (TOML): [body] and [[loop]]s." in iter_help
    assert "[default: SWEEP.h5 in the current directory]" in iter_help
    assert "scenario, deck, guidance, [simulate], [guide]." in pipeline_help


def test_the_limits_and_crossovers_stated_are_those_applied():
    from iter.execute import DASK_MIN_WORK_S
    from iter.loops import MAX_CASES
    from tapp.guidance.shards import DASK_MIN_SAMPLES
    from tapp.guidance.study import MAX_SAMPLES

    guide_help = _squashed(runner.invoke(app, ["guide", "--help"], env=WIDE).stdout)
    iter_help = _squashed(runner.invoke(app, ["iter", "--help"], env=WIDE).stdout)
    assert f"Samples: 2 to {MAX_SAMPLES:,}. In this process below {DASK_MIN_SAMPLES:,} " \
           "samples" in guide_help
    assert f"At most {MAX_CASES:,} cases." in iter_help
    assert f"reaches {DASK_MIN_WORK_S:g} s" in iter_help


@pytest.mark.parametrize("path", COMMANDS, ids=" ".join)
def test_a_default_an_option_states_is_stated_in_one_form(path: tuple[str, ...]):
    for text in _help_texts(_command(path)):
        assert not re.search(r"\(default:|[;,] default:", text), text


@pytest.mark.parametrize("path", COMMANDS, ids=" ".join)
def test_every_command_takes_json_as_a_path(path: tuple[str, ...]):
    [option] = [p for p in _command(path).params if "--json" in getattr(p, "opts", ())]
    common = typing.get_args(JsonOpt)[1]  # the typer.Option of tapp.cli.common
    assert (_unescaped(option.help), option.metavar, option.is_flag) == (common.help, "PATH",
                                                                        False)


@pytest.mark.parametrize("args, got", [
    (["dc", "--orbit", "SATORB1", "--json"], "'no value'"),             # the flag, last
    (["dc", "--json", "--orbit", "SATORB1"], "'--orbit'"),              # the flag, then more
    (["iter", "SWEEP.toml", "--json", "--serial"], "'--serial'"),
    (["tape", "info", "run.t13.h5", "--json"], "'no value'"),
])
def test_the_old_json_flag_is_refused_naming_the_new_form(args: list[str], got: str):
    result = runner.invoke(app, args)
    assert result.exit_code == EXIT_INPUT
    assert result.stderr.splitlines() == [
        "error: --json: value: expected a file path, or - for standard output (the flag "
        f"--json is now written --json -) (got {got})"]


def test_json_to_a_file_keeps_the_report_and_equals_json_on_standard_output(tmp_path: Path):
    args = ["propagate", "--orbit", "SATORB1", "--arc", "0.1h", "--step", "120s"]
    to_file = runner.invoke(app, [*args, "--json", str(tmp_path / "p.json")])
    to_stdout = runner.invoke(app, [*args, "--json", "-"])
    assert to_file.exit_code == 0 and to_stdout.exit_code == 0, to_file.output
    assert "RHS evaluations" in to_file.stdout and "RHS evaluations" not in to_stdout.stdout
    assert json.loads((tmp_path / "p.json").read_text()) == json.loads(to_stdout.stdout)


def test_json_to_an_input_is_refused_before_any_work(tmp_path: Path):
    study = Path(__file__).resolve().parents[3] / "scenarios" / "approx_stm.toml"
    result = runner.invoke(app, ["rsig", "--orbit", "SATORB1", "--scenario", str(study),
                                 "--json", str(study)])
    assert result.exit_code == EXIT_INPUT
    assert result.stderr.startswith(f"error: --json: {study}: expected a file other than the "
                                    "input --scenario")


def _blas_threads() -> set[int]:
    return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


@pytest.mark.skipif(available_cores() < 2, reason="one core: BLAS has one thread anyway")
def test_commands_run_on_one_blas_thread():
    with threadpool_limits(limits=2, user_api="blas"):
        assert _blas_threads() == {2}  # what a command would have without the limit
        assert run_guarded(_blas_threads) == {1}
        assert _blas_threads() == {2}  # and the limit ends with the command


def test_a_library_warning_is_one_line(tmp_path: Path):
    """A version-1 T13 tape's two warnings (no checksums; normal matrices), each one
    ``warning:`` line (issue 28: Python's lines, with the source path and the code line)."""
    tape = write_t13_version(tmp_path / "v1.t13.h5", leo_tape(), 1)
    # a process of its own: in this one, pytest records warnings (the suite makes them errors)
    res = subprocess.run([sys.executable, "-m", "tapp.cli", "tape", "info", str(tape), "--json",
                          "-"], capture_output=True, text=True, check=False, timeout=120,
                         env={**os.environ, "PYTHONWARNINGS": "default"})
    assert res.returncode == 0, res.stderr
    assert res.stderr.splitlines() == [
        f"warning: {tape}: T13 version 1 carries no checksums: corruption cannot be detected",
        f"warning: {tape}: T13 version 1 carries normal matrices, not square-root information: "
        "its factors are formed from them and hold only the digits they kept (about 16 - 2 "
        f"log10 of the condition number of the data); simulate it again for version {VERSION}"]

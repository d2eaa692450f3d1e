"""The Python front door (:mod:`tapp.api`, exported by :mod:`tapp`) against the commands.

The study is the 3-day deep-space pipeline of ``tests/tapp/cli/test_pipeline_cmd.py`` (its
``parts`` fixture): ``tapp.simulate -> process -> guide`` in memory must give the numbers of
``tapp simulate``, ``tapp process`` and ``tapp guide`` run on the same files, paths the same
as objects in memory, bad input the commands' errors, and the plots must draw on the axes
they are given, the ellipses the JSON states.
"""

from __future__ import annotations

import csv
import json
import re
import tomllib
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import tomli_w
from matplotlib.figure import Figure
from typer.testing import CliRunner

import tapp
import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app
from tapp.errors import InputError
from tapp.examples import FOLDER as EXAMPLES
from tests.tapp.cli.test_pipeline_cmd import SAMPLES, SEED, _numbers, parts  # noqa: F401

runner = CliRunner()

#: How far a drawn ellipse (181 points) may fall short of its extreme: 1 - cos(1°) of it.
ELLIPSE_POINTS = 2e-4


def _cli(args: list[str], code: int = 0):
    res = runner.invoke(app, args)
    assert res.exit_code == code, (res.output, res.exception)
    return res


@pytest.fixture(scope="module")
def commands(parts, tmp_path_factory) -> dict[str, Path]:  # noqa: F811  (parts: a fixture)
    """The three commands run on the part files: their tapes, JSON, printout and report."""
    folder = tmp_path_factory.mktemp("commands")
    out = {name: folder / name for name in ("run.t13.h5", "run.t32.h5", "s.json", "p.json",
                                            "o3.txt", "g.json")}
    _cli(["simulate", str(parts["scenario"]), "-o", str(out["run.t13.h5"]), "--json",
          str(out["s.json"])])
    _cli(["process", str(out["run.t13.h5"]), str(parts["deck"]), "--tape",
          str(out["run.t32.h5"]), "--json", str(out["p.json"]), "--print", str(out["o3.txt"])])
    res = _cli(["guide", str(out["run.t32.h5"]), str(parts["guidance"]), "--samples",
                str(SAMPLES), "--seed", str(SEED), "--json", str(out["g.json"])])
    out["guide.md"] = folder / "guide.md"
    out["guide.md"].write_text(res.stdout)
    return out


@pytest.fixture(scope="module")
def in_memory(parts):  # noqa: F811
    """simulate -> process -> guide through the front door, every step's input in memory."""
    simulated = tapp.simulate(tapp.read_scenario(parts["scenario"]))
    processed = tapp.process(simulated.tape, parts["deck"])
    guided = tapp.guide(processed.t32(), parts["guidance"], samples=SAMPLES, seed=SEED)
    return simulated, processed, guided


def _read(path: Path) -> dict:
    return json.loads(path.read_text())


def _plain(content: dict) -> dict:
    """A result's JSON as the commands write it (arrays as lists)."""
    return json.loads(json.dumps(content, default=lambda a: a.tolist()))


def test_the_front_door_gives_the_numbers_of_the_three_commands(commands, in_memory) -> None:
    simulated, processed, guided = in_memory
    command = _read(commands["s.json"])
    assert command["bytes"] > 0
    assert _numbers({**_plain(simulated.to_json()), "bytes": None}) == _numbers(
        {**command, "bytes": None})
    for result, name in ((processed, "p.json"), (guided, "g.json")):
        assert _numbers(_plain(result.to_json())) == _numbers(_read(commands[name])), name


def _untimed(report: str) -> str:
    """A guidance report without its wall time (``..., 0.02 s.``)."""
    return re.sub(r"\d+\.\d+ s\.", "<wall time>.", report)


def test_paths_give_the_commands_printout_and_report(parts, commands) -> None:  # noqa: F811
    processed = tapp.process(commands["run.t13.h5"], parts["deck"])
    assert processed.o3() == commands["o3.txt"].read_text()
    guided = tapp.guide(str(commands["run.t32.h5"]), str(parts["guidance"]), samples=SAMPLES,
                        seed=SEED)
    # the report states the Monte Carlo's wall time, which no two runs share
    assert _untimed(guided.markdown()) == _untimed(commands["guide.md"].read_text())
    assert {k: v for k, v in _plain(guided.to_json()).items() if k != "wall_s"} == {
        k: v for k, v in _read(commands["g.json"]).items() if k != "wall_s"}


def test_a_scenario_file_is_the_same_as_the_scenario(parts, in_memory) -> None:  # noqa: F811
    by_path = tapp.simulate(parts["scenario"])
    assert _numbers(_plain(by_path.to_json())) == _numbers(_plain(in_memory[0].to_json()))


def test_written_tapes_are_the_commands_tapes(parts, commands, in_memory,  # noqa: F811
                                              tmp_path: Path) -> None:
    simulated, processed, _ = in_memory
    t13, t32 = simulated.write(tmp_path / "a.t13.h5"), processed.write_t32(tmp_path / "a.t32.h5")
    assert (t13, t32) == (tmp_path / "a.t13.h5", tmp_path / "a.t32.h5")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.t13.h5", "a.t32.h5"]  # no temps
    again = tapp.process(t13, parts["deck"])
    assert _numbers(_plain(again.to_json())) == _numbers(_read(commands["p.json"]))
    guided = tapp.guide(t32, parts["guidance"], samples=SAMPLES, seed=SEED)
    assert _numbers(_plain(guided.to_json())) == _numbers(_read(commands["g.json"]))


def _line(ax, label: str):
    return next(line for line in ax.get_lines() if line.get_label() == label)


def test_the_processor_plot_draws_the_printed_ellipse_on_the_given_axes(commands, in_memory
                                                                        ) -> None:
    backend = matplotlib.get_backend()
    ax = Figure().subplots()
    assert in_memory[1].plot(ax) is ax
    assert matplotlib.get_backend() == backend
    history = _read(commands["p.json"])["history"]
    bt = history["miss"].index("b_dot_t_km")
    # the last print or recycle time (a recycle at the last print time stands for it)
    last = max((r for r in history["rows"] if r["kind"] in ("print", "recycle")),
               key=lambda r: (r["t_s"], r["kind"] == "recycle"))
    assert f"{last['kind']} k = {last['k']}," in ax.get_title()
    real = next(line for line in ax.get_lines() if line.get_label().startswith("real 1σ"))
    sigma_bt_km = last["miss_sigma_real"][bt]  # the 1σ ellipse reaches ±σ(B·T) along T
    assert np.max(np.abs(real.get_xdata())) == pytest.approx(sigma_bt_km, rel=ELLIPSE_POINTS)


def test_the_guidance_plot_draws_the_monte_carlo_on_the_given_axes(commands, in_memory
                                                                   ) -> None:
    backend = matplotlib.get_backend()
    ax = Figure().subplots()
    assert in_memory[2].plot(ax) is ax
    assert matplotlib.get_backend() == backend
    content = _read(commands["g.json"])
    mc = content["monte_carlo"]
    bt = content["miss_name"].index("b_dot_t_km")
    one_sigma = _line(ax, f"{mc['method']} 1σ")
    reach_km = np.max(one_sigma.get_xdata()) - mc["miss_mean"][bt]
    assert reach_km == pytest.approx(np.sqrt(mc["miss_cov"][bt][bt]), rel=ELLIPSE_POINTS)
    assert len(_line(ax, f"samples ({SAMPLES:,})").get_xdata()) == SAMPLES


def test_a_plot_without_axes_has_a_figure_of_its_own(in_memory) -> None:
    backend = matplotlib.get_backend()
    ax = in_memory[1].plot()
    assert isinstance(ax.figure, Figure) and ax.get_lines()
    assert matplotlib.get_backend() == backend


def _command_error(args: list[str]) -> str:
    """The one line a command writes on stderr for bad input (exit 2)."""
    return _cli(args, code=2).stderr.strip()


def _error_line(exc: pytest.ExceptionInfo) -> str:
    return "error: " + " ".join(str(exc.value).split())


def test_a_bad_scenario_is_the_commands_error(parts, tmp_path: Path) -> None:  # noqa: F811
    scenario = tomllib.loads(parts["scenario"].read_text())
    scenario["tracking"]["end"] = -1.0
    bad = tmp_path / "bad.toml"
    bad.write_text(tomli_w.dumps(scenario))
    with pytest.raises(InputError) as exc:
        tapp.simulate(bad)
    assert str(bad) in str(exc.value) and "tracking.end" in str(exc.value)
    assert _error_line(exc) == _command_error(["simulate", str(bad), "-o",
                                               str(tmp_path / "x.t13.h5")])


def test_a_deck_that_does_not_fit_the_tape_is_the_commands_error(parts, commands,  # noqa: F811
                                                                 tmp_path: Path) -> None:
    deck = tomllib.loads(parts["deck"].read_text())
    deck["tape"]["n_o"] = 31
    bad = tmp_path / "deck.toml"
    bad.write_text(tomli_w.dumps(deck))
    with pytest.raises(InputError) as exc:
        tapp.process(commands["run.t13.h5"], bad)
    assert str(bad) in str(exc.value) and "tape.n_o" in str(exc.value)
    assert _error_line(exc) == _command_error(["process", str(commands["run.t13.h5"]),
                                               str(bad)])


def _without(content: dict, key: str) -> dict:
    return {k: v for k, v in content.items() if k != key}


def test_search_gives_the_commands_json_and_report() -> None:
    path = EXAMPLES / "search_bplane.toml"
    result = tapp.search(path)
    command = _cli(["search", str(path), "--json", "-"])
    assert result.status == "converged" and result.converged
    assert _without(_plain(result.to_json()), "wall_time_s") == _without(
        json.loads(command.stdout), "wall_time_s")
    printed = _cli(["search", str(path)]).stdout
    # all but the last line, which states the wall time
    assert result.report().splitlines()[:-1] == printed.splitlines()[:-1]


def test_a_search_that_cannot_converge_says_so(tmp_path: Path) -> None:
    path = tmp_path / "one.toml"
    path.write_text((EXAMPLES / "search_bplane.toml").read_text().replace(
        "iterations_per_partials = 3", "iterations_per_partials = 1").replace(
        "partial_sets = 3", "partial_sets = 1", 1))
    result = tapp.search(path)
    assert (result.status, result.converged) == ("diverged", False)
    assert result.to_json()["exit_code"] == _cli(["search", str(path)], code=3).exit_code


def _table(path: Path) -> list[dict]:
    """A sweep's CSV rows without the per-case wall time."""
    with path.open(newline="") as f:
        return [_without(row, "elapsed_s") for row in csv.DictReader(f)]


def test_sweep_gives_the_commands_table(tmp_path: Path) -> None:
    path = EXAMPLES / "iter_azimuth_type1.toml"
    result = tapp.sweep(path, output_h5=tmp_path / "a.h5", output_csv=tmp_path / "a.csv")
    summary = json.loads(_cli(["iter", str(path), "-o", str(tmp_path / "b.h5"), "--csv",
                               str(tmp_path / "b.csv"), "--json", "-"]).stdout)
    assert (result.summary.n_cases, result.summary.n_succeeded) == (
        summary["n_cases"], summary["n_succeeded"])
    assert _table(tmp_path / "a.csv") == _table(tmp_path / "b.csv")
    assert len(result.table.rows) == summary["n_cases"] > 1


def test_the_front_door_is_lazy_and_listed() -> None:
    assert {"simulate", "process", "guide", "search", "sweep", "read_scenario",
            "Scenario"} <= set(tapp.__all__) <= set(dir(tapp))
    with pytest.raises(AttributeError, match="no attribute 'simulation'"):
        tapp.simulation  # noqa: B018

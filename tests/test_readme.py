"""The README's figures (issue 18, item 6): every figure it quotes from a ``make scenario`` run
sits in a generated block that equals its rendering from the committed data file
(scenarios/readme_figures.json), every block is one the renderer knows and the reverse, and
every claim of the prose around the figures held in the run. No results/ needed: ``make
scenario`` itself checks the data file against results/ (scenarios/readme.py ``check``)."""

from __future__ import annotations

import dataclasses
import doctest

import pytest

from scenarios import figures, readme
from scenarios.figures import WALL_TIME, Figure, Figures, format_value, significant

TEXT = readme.README.read_text("utf-8")


@pytest.fixture(scope="module")
def committed() -> Figures:
    return figures.load()


def _with(data: Figures, values: dict) -> Figures:
    """``data`` with some figures' values replaced."""
    return Figures({**data.figures, **{name: dataclasses.replace(data.figures[name], value=v)
                                       for name, v in values.items()}}, data.claims)


def _content(text: str, name: str) -> str:
    return next(c for n, c, _ in readme.blocks(text) if n == name)


def test_the_readme_is_rendered_from_the_committed_figures(committed: Figures) -> None:
    assert readme.problems(TEXT, committed) == []
    assert readme.render(TEXT, committed) == TEXT
    assert [n for n, _, _ in readme.blocks(TEXT)] == list(readme.BLOCKS)


def test_every_figure_is_shown_and_every_claim_held(committed: Figures) -> None:
    assert readme.unused(committed) == []
    assert committed.claims and all(committed.claims.values()), committed.claims
    # every figure names the results file it came from
    assert all(f.source.startswith("results/") for f in committed.figures.values())


def test_the_committed_data_file_is_as_make_scenario_writes_it(committed: Figures) -> None:
    """Sorted and rounded: a rerun rewrites it byte for byte unless a figure changed."""
    assert figures.DATA.read_text("utf-8") == committed.dumps()
    assert Figures.loads(committed.dumps()) == committed
    for f in committed.figures.values():
        if f.digits is not None:
            assert all(v == significant(v, f.digits) for v in f.values)


def test_a_hand_edited_figure_fails(committed: Figures) -> None:
    """The Goldstone-only σ(B·T) of the trade study, edited back to the README's old value."""
    content = _content(TEXT, "tracking-goldstone")
    edited = TEXT.replace(content, "0.9-1.7 km", 1)
    found = readme.problems(edited, committed)
    assert found == [f"block tracking-goldstone: the README has '0.9-1.7 km', the figures give "
                     f"{content!r}"]


def test_stale_unknown_and_broken_blocks_fail(committed: Figures) -> None:
    start, end = readme.START.format, readme.END.format
    stale = TEXT + f"\nup to {start('tracking-old-corridor')}0.9 %{end('tracking-old-corridor')}"
    assert readme.problems(stale, committed) == [
        "block tracking-old-corridor: no such generated block (scenarios/readme.py BLOCKS)"]
    block = start("search-dv") + _content(TEXT, "search-dv") + end("search-dv")
    assert readme.problems(TEXT.replace(block, "191 m/s"), committed) == [
        "block search-dv: missing from the README"]
    assert readme.problems(TEXT + block, committed) == ["block search-dv appears 2 times"]
    unpaired = TEXT.replace(end("search-dv"), "", 1)
    assert any("without its partner" in p for p in readme.problems(unpaired, committed))
    with pytest.raises(ValueError, match="missing from the README"):
        readme.render(TEXT.replace(block, "191 m/s"), committed)


def _without_contents(text: str) -> str:
    """``text`` with every block emptied: what rendering must leave as it was."""
    for name, content, _ in readme.blocks(text):
        block = readme.START.format(name) + content + readme.END.format(name)
        text = text.replace(block, readme.START.format(name) + readme.END.format(name))
    return text


def test_rendering_changes_the_blocks_and_nothing_else(committed: Figures) -> None:
    changed = _with(committed, {"iter.tracking.goldstone_sigma_b_dot_t_km": (2.2, 2.7)})
    new = readme.render(TEXT, changed)
    assert _content(new, "tracking-goldstone") == "2.2-2.7 km"
    assert readme.problems(new, committed) != [] and readme.problems(new, changed) == []
    assert _without_contents(new) == _without_contents(TEXT)
    assert [c for n, c, _ in readme.blocks(new) if n != "tracking-goldstone"] == \
        [c for n, c, _ in readme.blocks(TEXT) if n != "tracking-goldstone"]


def test_outcomes_follow_the_data(committed: Figures) -> None:
    """The prose a block words from a status: a note only where its status holds, the
    noise-model verdict from the count of inconsistent fits."""
    row = "| SATORB1 24 h (J2,J0) | {} | 2.50 |"
    assert row.format("diverges, as in the brief") in \
        readme.render_block("approx-stm-outcomes", committed)
    converged = _with(committed, {"approx_stm.SATORB1.J2-J0.24h.status": "converged"})
    assert row.format("converges in 10") in readme.render_block("approx-stm-outcomes",
                                                                converged)
    failing = _with(committed, {"approx_stm.inconsistent_fits": 2})
    text = readme.render_block("approx-stm-noise-test", failing)
    assert text.startswith("2 of the 23 settled fits of the study fail that test (furthest: ")
    fewer = _with(committed, {"approx_stm.predicted_runs": 21})
    assert readme.render_block("approx-stm-predicted", fewer) == "21 of the 22"
    assert readme.render_block("approx-stm-predicted", committed) == "all 22"


def test_the_rounding_rule() -> None:
    """Significant digits with their trailing zeros; an exponent below 1e-3; counts grouped;
    grid values as they are. A rerun below the last digit prints alike, a change in it
    does not."""
    assert doctest.testmod(figures).failed == 0
    assert format_value(0.5665e3, 3) == "566"
    assert format_value(0.897, 2) == "0.90"
    assert format_value(8.35e-13, 3) == "8.35e-13"
    assert format_value(106846) == "106,846"
    assert format_value(132.5) == "132.5"
    assert format_value(330.0855, 3) == format_value(330.0246, 3) == "330"
    assert (format_value(1.635, 2), format_value(1.735, 2)) == ("1.6", "1.7")
    assert format_value(9.4, WALL_TIME) == format_value(10.1, WALL_TIME) == "10"
    assert (format_value(22.0, WALL_TIME), format_value(32.7, WALL_TIME)) == ("20", "30")
    again = Figure(significant(0.75190, 2), "results/x.json", 2)
    assert again == Figure(significant(0.75194, 2), "results/x.json", 2)


def test_make_scenario_tells_a_changed_figure_from_a_slower_machine() -> None:
    """``make scenario`` leaves the tracked README alone and lists the figures of its run that
    differ from the committed ones (scenarios/readme.py ``compare``): a number that changed
    is listed; a wall time only beyond a factor of 2, since it depends on the machine."""
    wall = Figure(30.0, "results/x.json", WALL_TIME)
    assert readme._agree(wall, dataclasses.replace(wall, value=50.0))
    assert readme._agree(wall, dataclasses.replace(wall, value=20.0))
    assert not readme._agree(wall, dataclasses.replace(wall, value=100.0))
    real = Figure(1.234, "results/x.json", 3)
    assert readme._agree(real, dataclasses.replace(real, value=1.2341))  # same text
    assert not readme._agree(real, dataclasses.replace(real, value=1.236))
    assert not readme._agree(Figure(30.0, "r", WALL_TIME), Figure(50.0, "r", 2))  # not both

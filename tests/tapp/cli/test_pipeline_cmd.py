"""``tapp pipeline``: simulate -> process -> guide in one run, against the three commands.

The scenario is deep_space.toml cut to 3 days (as in the TAPP II tests), the deck
tapp3_deep_space.toml with its print times inside those days, the guidance file
tapp2_deep_space.toml: the shipped study, made small.
"""

from __future__ import annotations

import errno
import json
import logging
import os
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from typer.testing import CliRunner

import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app
from tapp.examples import FOLDER as EXAMPLES
from tapp.pipeline.run import OUTPUTS, booked_slots, tape_case, tracking_case
from tests.faults import fill, mounted_tmpfs

runner = CliRunner()
SCENARIOS = EXAMPLES
DAY_S = 86400.0
SAMPLES, SEED = 3000, 7


@pytest.fixture(scope="module")
def parts(tmp_path_factory) -> dict[str, Path]:
    """The three part files of a 3-day pipeline, and the pipeline file naming them."""
    folder = tmp_path_factory.mktemp("pipeline")
    scenario = tomllib.loads((SCENARIOS / "deep_space.toml").read_text())
    scenario["tracking"]["end"] = 3 * DAY_S
    scenario["times"]["end"] = 3 * DAY_S
    scenario["times"]["epochs"] = []
    deck = tomllib.loads((SCENARIOS / "tapp3_deep_space.toml").read_text())
    deck["times"]["print"] = [1, 2, 3]
    deck["tape"]["n_o"] = 30  # 3 days of 2-day stochastic batches: 24 + 2 x 3
    out = {"scenario": folder / "scenario.toml", "deck": folder / "deck.toml",
           "guidance": folder / "guide.toml", "pipeline": folder / "pipe.toml"}
    out["scenario"].write_text(tomli_w.dumps(scenario))
    out["deck"].write_text(tomli_w.dumps(deck))
    out["guidance"].write_text((SCENARIOS / "tapp2_deep_space.toml").read_text())
    out["pipeline"].write_text(tomli_w.dumps({
        "title": "three days", "scenario": "scenario.toml", "deck": "deck.toml",
        "guidance": "guide.toml", "guide": {"samples": SAMPLES, "seed": SEED}}))
    return out


@pytest.fixture(scope="module")
def scheduler():
    """A running Dask cluster of two worker threads (``--scheduler``)."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp://",
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster:
        yield cluster.scheduler_address


def _ok(args: list[str]) -> str:
    res = runner.invoke(app, args)
    assert res.exit_code == 0, (res.output, res.exception)
    return res.stdout


#: Hidden directories of earlier runs to the same -o that were killed (SIGKILL): this
#: version's, and those of versions that named them with tempfile.mkdtemp.
KILLED_RUNS = (".run.0123456789abcdef.tmp", ".run.tmp-k2j4_x9q")


@pytest.fixture(scope="module")
def piped(parts, scheduler, tmp_path_factory) -> Path:
    """A run of the pipeline, into a folder where killed runs left their directories."""
    out = tmp_path_factory.mktemp("piped") / "run"
    for name in KILLED_RUNS:
        (out.parent / name / "plots").mkdir(parents=True)
        (out.parent / name / OUTPUTS["t13"]).write_text("half a tape")
    _ok(["pipeline", str(parts["pipeline"]), "-o", str(out), "--scheduler", scheduler])
    return out


def _numbers(content: object) -> object:
    """The numbers of a JSON document, without wall times, paths and provenance."""
    if isinstance(content, dict):
        return {k: _numbers(v) for k, v in content.items()
                if k not in ("wall_s", "tape", "deck", "guide", "where", "shard_samples")}
    if isinstance(content, list):
        return [_numbers(v) for v in content]
    return content


def test_the_pipeline_gives_the_numbers_of_the_three_commands(parts, piped, scheduler,
                                                              tmp_path: Path) -> None:
    t13, t32 = tmp_path / "run.t13.h5", tmp_path / "run.t32.h5"
    _ok(["simulate", str(parts["scenario"]), "-o", str(t13)])
    _ok(["process", str(t13), str(parts["deck"]), "--tape", str(t32), "--json",
         str(tmp_path / "p.json"), "--print", str(tmp_path / "o3.txt")])
    _ok(["guide", str(t32), str(parts["guidance"]), "--samples", str(SAMPLES), "--seed",
         str(SEED), "--json", str(tmp_path / "g.json"), "--scheduler", scheduler])
    for mine, theirs in (("process_json", "p.json"), ("guide_json", "g.json")):
        a = json.loads((piped / OUTPUTS[mine]).read_text())
        b = json.loads((tmp_path / theirs).read_text())
        assert _numbers(a) == _numbers(b), mine
    assert json.loads((piped / OUTPUTS["guide_json"]).read_text())["samples"] == SAMPLES


def test_the_directory_holds_every_output_and_a_report(piped) -> None:
    names = {p.name for p in piped.iterdir()}
    assert names == set(OUTPUTS.values())
    assert {p.name for p in (piped / "plots").iterdir()} == {
        "sigma_history.png", "bplane_ellipses.png", "bplane_scatter.png", "dv_histograms.png",
        "sigma_ric.png"}
    report = (piped / OUTPUTS["report"]).read_text()
    for heading in ("# Pipeline: three days", "## TAPP I", "## TAPP III", "## TAPP II",
                    "## Plots", "σ b_dot_r_km fit / real", "ΔV magnitude per manoeuvre",
                    "1σ B-plane dispersion ellipses", "σ radial R (m) fit / real"):
        assert heading in report, heading
    assert "Earth orientation iau2006" in report


def test_an_inline_part_is_the_same_as_its_file(parts, piped, tmp_path: Path) -> None:
    doc = tomllib.loads(parts["pipeline"].read_text())
    doc["deck"] = tomllib.loads(parts["deck"].read_text())
    doc["scenario"] = str(parts["scenario"])
    doc["guidance"] = str(parts["guidance"])
    pipe = tmp_path / "inline.toml"
    pipe.write_text(tomli_w.dumps(doc))
    out = tmp_path / "run"
    _ok(["pipeline", str(pipe), "-o", str(out), "--workers", "1"])
    a = json.loads((out / OUTPUTS["guide_json"]).read_text())
    b = json.loads((piped / OUTPUTS["guide_json"]).read_text())
    assert _numbers(a) == _numbers(b)


@pytest.mark.parametrize(("edit", "fragment"), [
    (lambda d: d.update(guide={"samples": 1}), "pipe.toml: guide.samples: expected"),
    (lambda d: d.update(deck={**d["deck"], "times": {"print": [99]}})
     if isinstance(d["deck"], dict) else d.update(deck={"times": {"print": [99]}}),
     "pipe.toml [deck]"),
    (lambda d: d.update(scenario="missing.toml"), "missing.toml: file: expected"),
    (lambda d: d.update(extra=1), "pipe.toml: extra: expected no such key"),
    (lambda d: d.update(simulate={"earth_orientation": "itrf"}),
     "pipe.toml: simulate.earth_orientation: expected"),
])
def test_bad_input_is_one_line_exit_2_and_no_directory(parts, tmp_path: Path, edit,
                                                       fragment: str) -> None:
    doc = tomllib.loads(parts["pipeline"].read_text())
    for key in ("scenario", "deck", "guidance"):
        doc[key] = str(parts[key])
    edit(doc)
    pipe = tmp_path / "pipe.toml"
    pipe.write_text(tomli_w.dumps(doc))
    out = tmp_path / "run"
    res = runner.invoke(app, ["pipeline", str(pipe), "-o", str(out), "--workers", "1"])
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, (res.output, res.exception)
    assert len(lines) == 1 and fragment in lines[0], lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe.toml"]


def test_the_directories_that_killed_runs_left_are_removed_by_the_next(piped) -> None:
    assert sorted(os.listdir(piped.parent)) == ["run"]


def test_a_failed_run_leaves_no_directory_and_no_folder_it_made(parts, tmp_path: Path,
                                                                monkeypatch) -> None:
    def no_space(pipeline, work: Path, *args) -> None:
        (work / OUTPUTS["t13"]).write_bytes(b"half a tape")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("tapp.pipeline.run._run", no_space)
    out = tmp_path / "a" / "b" / "run"
    res = runner.invoke(app, ["pipeline", str(parts["pipeline"]), "-o", str(out), "--serial"])
    assert res.exit_code == 1, (res.output, res.exception)
    assert res.stderr.splitlines() == [f"error: -o/--output: {out}: not written (No space "
                                       "left on device)"]
    assert list(tmp_path.iterdir()) == []  # was a/ and a/b/


def test_a_run_onto_a_full_disk_is_one_line_and_leaves_nothing(parts, tmp_path: Path) -> None:
    with mounted_tmpfs(tmp_path / "full") as full:
        fill(full, 20_000)
        out = full / "a" / "run"
        res = runner.invoke(app, ["pipeline", str(parts["pipeline"]), "-o", str(out),
                                  "--serial"])
        assert res.exit_code == 1, (res.output, res.exception)
        assert res.stderr.splitlines() == [f"error: -o/--output: {out}: not written (No "
                                           "space left on device)"]  # was a traceback
        assert sorted(os.listdir(full)) == ["fill"]


def test_an_earlier_run_is_never_overwritten(parts, piped) -> None:
    before = {p.name: p.stat().st_mtime_ns for p in piped.iterdir()}
    res = runner.invoke(app, ["pipeline", str(parts["pipeline"]), "-o", str(piped)])
    assert res.exit_code == 2
    assert "-o/--output: directory: expected a new or empty directory" in res.stderr
    assert {p.name: p.stat().st_mtime_ns for p in piped.iterdir()} == before


def test_the_tracking_sweep_body_switches_stations_off(parts) -> None:
    """Fewer stations in the sweep's network: the same tape, more final-miss dispersion."""
    common = {"pipeline": str(parts["pipeline"]), "data_interval_s": 600.0,
              "networks": "GOLDSTONE CANBERRA MADRID; GOLDSTONE", "samples": 2000, "seed": 1}
    all3 = tracking_case(network=0.0, **common)
    one = tracking_case(network=1.0, **common)
    # the tape is the same; Goldstone alone uses a part of it (issue 28: "observations" was
    # the tape's in every case)
    assert all3["observations_simulated"] == one["observations_simulated"] == \
        all3["observations_used"] > one["observations_used"] > 0
    assert one["bplane_semi_major_km"] > all3["bplane_semi_major_km"]
    assert np.isfinite(all3["dv_total_99_m_s"]) and all3["dv_total_99_m_s"] > 0
    with pytest.raises(Exception, match="network: value: expected a whole number 0..1"):
        tracking_case(network=2.0, **common)


def test_a_week_books_its_passes_in_turn() -> None:
    """N passes a week: N slots in each full week, each station's share within one of N/S;
    7 S is every station every day, 7 a pass every day."""
    stations = ("GOLDSTONE", "CANBERRA", "MADRID")
    for n in (1, 3, 7, 10, 21):
        slots = booked_slots(28, stations, n)
        assert len(slots) == 4 * n
        counts = [sum(1 for _, s in slots if s == name) for name in stations]
        assert max(counts) - min(counts) <= 4
    assert booked_slots(14, stations, 21) == {(d, s) for d in range(14) for s in stations}
    assert {d for d, _ in booked_slots(14, stations, 7)} == set(range(14))
    assert len(booked_slots(10, stations, 7)) == 10  # the last week cut at day 10


def test_the_tape_sweep_body_books_passes_on_one_tape(parts, piped) -> None:
    """The trade body on the pipeline's own tape: every pass booked uses every observation
    and gives the pipeline's numbers (same deck, samples and seed); fewer passes a week use
    fewer and widen the B-plane dispersion; what is not a day-record tape or a booking is
    refused before anything runs."""
    common = {"pipeline": str(parts["pipeline"]), "tape": str(piped / OUTPUTS["t13"]),
              "samples": SAMPLES, "seed": SEED}
    every = tape_case(ddor=1.0, passes_per_week=21.0, **common)
    fewer = tape_case(ddor=1.0, passes_per_week=2.0, **common)
    assert every["observations_used"] == every["observations_simulated"]
    assert 0 < fewer["observations_used"] < every["observations_used"]
    assert fewer["bplane_semi_major_km"] > every["bplane_semi_major_km"]
    mc = json.loads((piped / OUTPUTS["guide_json"]).read_text())["monte_carlo"]
    assert every["bplane_semi_major_km"] == mc["bplane_ellipse"]["semi_major_km"]
    assert every["sigma_b_dot_r_km"] == np.sqrt(mc["miss_cov"][0][0])
    with pytest.raises(Exception, match="passes_per_week: value: expected a whole number"):
        tape_case(ddor=1.0, passes_per_week=22.0, **common)
    with pytest.raises(Exception, match="ddor: value: expected 0"):
        tape_case(ddor=0.5, passes_per_week=7.0, **common)
    with pytest.raises(Exception, match="tape: file: expected the T13 tape"):
        tape_case(**{**common, "tape": str(piped / "missing.h5")}, ddor=1.0,
                  passes_per_week=7.0)


def _tracking_sweep(folder: Path, pipeline: Path) -> Path:
    """The shipped tracking sweep made small: 2 networks x 1 data interval, 1,000 samples,
    on the 3-day pipeline ``pipeline``, named by a path relative to the sweep's folder."""
    sweep = tomllib.loads((SCENARIOS / "iter_pipeline_tracking.toml").read_text())
    sweep["body"]["files"]["pipeline"] = os.path.relpath(pipeline, folder)
    sweep["body"]["constants"]["samples"] = 1000
    sweep["loop"][0].update(sets=2, vary=[0.0, 2.0])  # three complexes; Goldstone alone
    sweep["loop"][1].update(sets=1, vary=[600.0])
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "tracking.toml"
    path.write_text(tomli_w.dumps(sweep))
    return path


def test_the_tracking_sweep_runs_every_case_from_another_directory(parts, tmp_path,
                                                                    monkeypatch) -> None:
    """Issue 18: from outside the repository root every case failed, and the exit was 0."""
    _tracking_sweep(tmp_path / "sweeps", parts["pipeline"])
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    res = runner.invoke(app, ["iter", "../sweeps/tracking.toml", "-o", "out.h5", "--serial",
                              "--json", "-"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert (summary["n_cases"], summary["n_succeeded"], summary["n_failed"]) == (2, 2, 0)
    from iter import read_hdf5

    rows = read_hdf5(tmp_path / "elsewhere" / "out.h5").table.rows
    # Goldstone alone leaves a wider final B-plane dispersion than the three complexes
    assert rows[1].outputs["bplane_semi_major_km"] > rows[0].outputs["bplane_semi_major_km"]


def _broken_deck(parts, folder: Path) -> Path:
    """A copy of the 3-day pipeline whose deck has a misspelt key."""
    folder.mkdir()
    for name in ("scenario", "guidance", "pipeline"):
        (folder / parts[name].name).write_text(parts[name].read_text())
    deck = tomllib.loads(parts["deck"].read_text())
    deck["stations_offf"] = []
    (folder / parts["deck"].name).write_text(tomli_w.dumps(deck))
    return folder / parts["pipeline"].name


@pytest.mark.parametrize("broken", ["missing pipeline", "misspelt deck key", "bad network"])
def test_bad_tracking_sweep_input_is_refused_before_any_case_runs(parts, tmp_path,
                                                                   broken) -> None:
    pipeline = parts["pipeline"]
    if broken == "missing pipeline":
        pipeline = tmp_path / "no_such_pipeline.toml"
    elif broken == "misspelt deck key":
        pipeline = _broken_deck(parts, tmp_path / "broken")
    path = _tracking_sweep(tmp_path / "sweeps", pipeline)
    if broken == "bad network":
        sweep = tomllib.loads(path.read_text())
        sweep["body"]["constants"]["networks"] = "WOOMERA; GOLDSTONE"
        path.write_text(tomli_w.dumps(sweep))
    expected = {
        "missing pipeline": f"{path}: body.files.pipeline: expected an existing file",
        "misspelt deck key": (f"{tmp_path / 'broken' / 'deck.toml'} (overridden: stations_off):"
                              " stations_offf: expected no such key"),
        "bad network": "networks: stations: expected stations of the scenario",
    }[broken]
    out = tmp_path / "out.h5"
    res = runner.invoke(app, ["iter", str(path), "-o", str(out), "--serial"])
    assert res.exit_code == 2, res.output
    assert res.stderr.startswith(f"error: {expected}"), res.stderr
    assert res.stderr.count("\n") == 1
    assert not out.exists()

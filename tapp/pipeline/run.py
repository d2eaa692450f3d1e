"""Run a pipeline: TAPP I (simulate) -> TAPP III (process) -> TAPP II (guide), one directory.

The steps are those of ``tapp simulate``, ``tapp process --tape`` and ``tapp guide``, on the
same library calls, and the hand-over between them goes through the tapes on disk exactly as
between the three commands (the T13 tape is written, then read lazily by the processor; the
T32 tape is written, then read back by the guidance study), so the pipeline gives the same
numbers as the three commands run one after another (tested).

Outputs (:data:`OUTPUTS`) are written into a hidden directory ``.NAME.<random>.tmp`` beside
``out_dir`` and renamed to it at the end: a failed or interrupted run leaves no partial
directory, and no folder it made to hold ``out_dir``; the hidden directory of an earlier run
that was killed (SIGKILL) is removed by the next run to the same ``out_dir``.
"""

from __future__ import annotations

import json
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from iter.body import input_check
from iter.execute import Execution
from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError
from tapp.guidance.guidefile import GuideFile
from tapp.guidance.study import GuidanceResult, check_samples, check_seed, guidance_study
from tapp.io.outputs import check_new_directory, new_directory
from tapp.io.schema import validate
from tapp.io.tape.t13_hdf5 import t13_file_writer
from tapp.io.tape.t32_hdf5 import read_t32, t32_file_writer
from tapp.pipeline.spec import Pipeline, read_pipeline, with_overrides
from tapp.pipeline.steps import process_tape
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import observations_used
from tapp.processor.printout import o3_text, run_dict
from tapp.processor.tape32 import build_t32, t32_provenance
from tapp.tracking.scenario import Scenario
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate

#: What a pipeline directory holds.
OUTPUTS = {
    "t13": "run.t13.h5",
    "o3": "o3.txt",
    "process_json": "process.json",
    "t32": "run.t32.h5",
    "guide_json": "guide.json",
    "guide_md": "guide.md",
    "report": "report.md",
    "plots": "plots",
}

_NEVER_OVERWRITES = "a pipeline never overwrites an earlier run"

#: Progress callback: (stage, done, total).
Progress = Callable[[str, int, int], None]


@dataclass(frozen=True, slots=True)
class PipelineResult:
    """What a pipeline run produced (paths are inside the run's directory): the scalar
    observations TAPP I simulated and those TAPP III used (the deck's time-station flags
    leave some out), and TAPP I's ``warnings``
    (:attr:`tapp.tracking.simulate.Simulation.warnings`)."""

    directory: Path
    observations_simulated: int
    observations_used: int
    process: dict
    guidance: GuidanceResult
    wall_s: dict[str, float]
    warnings: tuple[str, ...] = ()


def _nothing(stage: str, done: int, total: int) -> None:
    """The default progress callback."""


def check_out_dir(out_dir: Path) -> Path:
    """Return ``out_dir`` if it does not exist or is an empty directory in a folder that can
    be written, else raise.

    Raises
    ------
    InputError
        Naming ``-o`` : a file, a directory with something in it (never overwritten), a
        symbolic link (the run's directory is renamed into place: it would replace the
        link), or a path in a folder that is a file or cannot be written.
    """
    return check_new_directory(out_dir, "-o/--output", _NEVER_OVERWRITES)


def run_pipeline(pipeline: Pipeline, out_dir: Path, *, execution: Execution | None = None,
                 plots: bool = True, progress: Progress = _nothing,
                 t13: Path | None = None) -> PipelineResult:
    """Run the three steps into ``out_dir`` (new or empty); return the result. With ``t13``
    (a tape of the pipeline's scenario, simulated once for many decks: :func:`tape_case`),
    TAPP III and II on that tape, not TAPP I.

    Raises
    ------
    InputError
        From any part (naming its file or the pipeline file and the part), or ``out_dir``
        (naming ``-o``, also when it cannot be written).
    WriteError
        ``out_dir`` could not be written for want of room, or a device error.
    """
    with running_pipeline(pipeline, out_dir, execution=execution, plots=plots,
                          progress=progress, t13=t13) as result:
        return result


@contextmanager
def running_pipeline(pipeline: Pipeline, out_dir: Path, *, execution: Execution | None = None,
                     plots: bool = True, progress: Progress = _nothing,
                     t13: Path | None = None) -> Iterator[PipelineResult]:
    """Run the three steps into a hidden directory beside ``out_dir`` (new or empty), yield
    the result and rename the directory to ``out_dir`` once the block has run (the report
    of the run printed): :func:`run_pipeline` with a block before the directory appears.
    If the block raises, no ``out_dir`` appears. Raises as :func:`run_pipeline`.
    """
    with new_directory(out_dir, "-o/--output", _NEVER_OVERWRITES) as work:
        yield replace(_run(pipeline, work, execution, plots, progress, t13),
                      directory=out_dir)


def bind_parts(pipeline: Pipeline) -> tuple[Scenario, Deck, GuideFile]:
    """Return the scenario, deck and guidance file, each validated by its own schema.

    Cheap (reading and checking, no computation): the input check of a sweep over pipelines.

    Raises
    ------
    InputError
        Naming the part's file (or the pipeline file and the part) and the field.
    """
    part = pipeline.scenario
    scenario = parse_scenario(part.document, part.source, pipeline.earth_orientation)
    deck = validate(Deck, pipeline.deck.document, pipeline.deck.source)
    guide = validate(GuideFile, pipeline.guidance.document, pipeline.guidance.source)
    return scenario, deck, guide


def _run(pipeline: Pipeline, work: Path, execution: Execution | None, plots: bool,
         progress: Progress, t13: Path | None) -> PipelineResult:
    """The three steps into ``work`` (:func:`run_pipeline`)."""
    wall: dict[str, float] = {}
    start = time.perf_counter()
    scenario, deck, guide = bind_parts(pipeline)
    if t13 is None:
        sim = simulate(scenario, progress=lambda stage, done, total: progress(
            f"TAPP I: {stage}", done, total))
        t13_path = work / OUTPUTS["t13"]
        t13_file_writer(sim.tape, source=t13_path.name)(t13_path)
        warnings = sim.warnings
    else:
        t13_path, warnings = t13, ()
    wall["simulate"] = time.perf_counter() - start

    start = time.perf_counter()
    run, plan, header = process_tape(t13_path, deck, pipeline.deck.source,
                                     lambda k, n: progress("TAPP III", k, n))
    content = run_dict(run, header, pipeline.deck.source, t13_path.name)
    (work / OUTPUTS["o3"]).write_text(o3_text(run, header, pipeline.deck.source,
                                              str(t13_path.name)), "utf-8")
    (work / OUTPUTS["process_json"]).write_text(json.dumps(content), "utf-8")
    t32_path = work / OUTPUTS["t32"]
    t32_file_writer(build_t32(run, plan, header, t32_provenance(
        header, deck, pipeline.deck.source, t13_path.name)), source=t32_path.name)(t32_path)
    wall["process"] = time.perf_counter() - start

    start = time.perf_counter()
    guidance = guidance_study(
        read_t32(t32_path), guide, samples=pipeline.samples, seed=pipeline.seed,
        execution=execution, shard_samples=pipeline.shard_size,
        progress=lambda done, total: progress("TAPP II", done, total),
        guide_source=pipeline.guidance.source, tape_source=t32_path.name)
    wall["guide"] = time.perf_counter() - start

    from tapp.report.guidance import guidance_dict, guidance_markdown
    from tapp.report.pipeline import write_report

    (work / OUTPUTS["guide_json"]).write_text(json.dumps(guidance_dict(guidance)), "utf-8")
    (work / OUTPUTS["guide_md"]).write_text(guidance_markdown(guidance), "utf-8")
    pairs = header.pairs  # the tape's, as TAPP III read it
    observations = int(pairs.n_obs.sum())
    write_report(work, pipeline, run, header, content, guidance, observations, wall, plots)
    return PipelineResult(work, observations,
                          observations_used(plan, pairs.k, pairs.station, pairs.n_obs),
                          content, guidance, wall, warnings)


def check_tracking_case(pipeline: str, data_interval_s: float, network: float,
                        networks: str, samples: int = 5000, seed: int = 1) -> Pipeline:
    """Return the pipeline of one :func:`tracking_case`, its parts read and validated.

    The body's input check (ITER runs it on the first case before any case runs): the
    pipeline file and the files of its parts, the station set, the sample count and the seed.

    Raises
    ------
    InputError
        Naming the file (or the argument) and the field: a file missing or invalid, a
        ``network`` that picks no set of ``networks``, a station the scenario does not have,
        a sample count or seed out of range.
    """
    if not isinstance(networks, str):
        raise InputError("networks", "value", "station sets as text, separated by ';'",
                         networks)
    sets = [s.split() for s in networks.split(";")]
    index = _whole(network)
    if (isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(sets)
            or not sets[index]):
        raise InputError("network", "value", f"a whole number 0..{len(sets) - 1} picking a "
                         "station set of networks", network)
    base = read_pipeline(pipeline)
    stations = base.scenario.document.get("tracking", {}).get("stations", [])
    off = [{"station": name} for name in stations if name not in sets[index]]
    unknown = [name for name in sets[index] if name not in stations]
    if unknown:
        raise InputError("networks", "stations", f"stations of the scenario {stations}",
                         unknown)
    pipe = with_overrides(base, {
        "scenario.tracking.data_interval_s": data_interval_s,
        "deck.stations_off": [*base.deck.document.get("stations_off", []), *off],
    })
    pipe = replace(pipe, samples=check_samples(_whole(samples), "samples"),
                   seed=check_seed(_whole(seed), "seed"))
    bind_parts(pipe)
    return pipe


def booked_slots(days: int, stations: tuple[str, ...], passes_per_week: int
                 ) -> set[tuple[int, str]]:
    """Return the (day, station) slots a schedule of ``passes_per_week`` books over ``days``
    days: in each week the i-th of its N passes falls on day ⌊7 i / N⌋ at station i mod S (the
    stations in turn), so N = 7 S is every station every day and N = 7 a pass a day in turn.
    A deep-space spacecraft is seen once a day by each complex: a slot is a pass."""
    per_week = {(7 * i // passes_per_week, stations[i % len(stations)])
                for i in range(passes_per_week)}
    return {(7 * w + d, name) for w in range(-(-days // 7)) for d, name in per_week
            if 7 * w + d < days}


def check_tape_case(pipeline: str, tape: str, ddor: float, passes_per_week: float,
                    samples: int = 5000, seed: int = 1) -> tuple[Pipeline, Path]:
    """Return the pipeline of one :func:`tape_case` (its deck's time-station flags set) and
    the tape, checked: the body's input check (ITER runs it before any case).

    Raises
    ------
    InputError
        Naming the argument or the file: a tape that is not a file, ``ddor`` not 0 or 1,
        ``passes_per_week`` not a whole number from 1 to 7 x the scenario's stations, a
        scenario whose T13 times are not whole days, or any part's own errors.
    """
    path = Path(tape)
    if not path.is_file():
        raise InputError("tape", "file", "the T13 tape of the pipeline's scenario (tapp "
                         "simulate SCENARIO -o TAPE)", tape)
    if _whole(ddor) not in (0, 1):
        raise InputError("ddor", "value", "0 (no ΔDOR) or 1 (the scenario's ΔDOR)", ddor)
    base = read_pipeline(pipeline)
    scenario = parse_scenario(base.scenario.document, base.scenario.source,
                              base.earth_orientation)
    stations = tuple(s.station.name for s in scenario.stations)
    n = _whole(passes_per_week)
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 7 * len(stations):
        raise InputError("passes_per_week", "value", f"a whole number 1..{7 * len(stations)} "
                         f"(7 days x {len(stations)} stations)", passes_per_week)
    times = scenario.times.t13_s
    days = np.round(times / SECONDS_PER_DAY)
    if np.any(np.abs(times - days * SECONDS_PER_DAY) > 1e-6) or np.any(np.diff(days) != 1):
        raise InputError(base.scenario.source, "times", "T13 times a day apart on whole days "
                         "(a pass per day and station is switched on or off)", times[:3])
    booked = booked_slots(int(days[-1]), stations, n)
    # Record k holds the data of (t_k-1, t_k]: day d is the record ending at d + 1 days
    # (the first record, ending at t_0, holds what came before it).
    off = [{"station": name, "start": float(d * SECONDS_PER_DAY),
            "end": float((d + 1) * SECONDS_PER_DAY)}
           for d in range(int(days[0]), int(days[-1])) for name in stations
           if (d, name) not in booked]
    if not _whole(ddor):
        off += [{"station": b.name} for b in scenario.baselines]
    pipe = with_overrides(base, {
        "deck.stations_off": [*base.deck.document.get("stations_off", []), *off]})
    pipe = replace(pipe, samples=check_samples(_whole(samples), "samples"),
                   seed=check_seed(_whole(seed), "seed"))
    bind_parts(pipe)
    return pipe, path


@input_check(check_tape_case)
def tape_case(pipeline: str, tape: str, ddor: float, passes_per_week: float,
              samples: int = 5000, seed: int = 1) -> dict[str, float]:
    """ITER body: TAPP III and TAPP II of a pipeline on its scenario's T13 tape, simulated
    once (``tape``), with the tracking thinned by the deck's time-station flags; return the
    trade-study outputs (:func:`trade_outputs`).

    ``passes_per_week`` passes are kept in each week (:func:`booked_slots`; the scenario's
    T13 times must be a day apart, so that a day's record of a station is its pass), the
    other (day, station) records switched off; ``ddor`` = 0 switches the scenario's ΔDOR
    baselines off for the whole run, 1 keeps them. The tape is not copied or changed; TAPP
    III checks that it is the deck's (its iden). Serial, in a temporary directory.
    """
    pipe, path = check_tape_case(pipeline, tape, ddor, passes_per_week, samples, seed)
    with tempfile.TemporaryDirectory() as tmp:
        result = run_pipeline(pipe, Path(tmp) / "run", execution=Execution(serial=True),
                              plots=False, t13=path)
    return trade_outputs(result)


def _whole(value: object) -> object:
    """Return a float with no fraction (a varied value, 2.0) as an int; anything else as it
    is, for the check that follows to accept or refuse."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


@input_check(check_tracking_case)
def tracking_case(pipeline: str, data_interval_s: float, network: float, networks: str,
                  samples: int = 5000, seed: int = 1) -> dict[str, float]:
    """ITER body: the pipeline with the tracking varied; return the trade-study outputs.

    ``pipeline`` is the pipeline file (a sweep gives it in ``[body.files]``, so that it is
    taken from the sweep file's folder). ``network`` (a whole number, 0-based) picks a
    station set from ``networks``, sets of station names separated by ``;`` (``"GOLDSTONE
    CANBERRA MADRID; GOLDSTONE"``); the stations of the scenario outside the set are switched
    off in the deck for the whole run (TAPP III's time-station flags: the tape and the
    parameter vector stay the same), and the scenario's data interval is
    ``data_interval_s``. The run is serial (it is one case of a sweep that is itself spread
    over workers) in a temporary directory. Inputs are checked first
    (:func:`check_tracking_case`, also the sweep's input check).

    Outputs: σ of each final-miss component (Monte Carlo) and the semi-axes of the 1σ
    B-plane dispersion ellipse, the 99 % and mean total ΔV (m/s), the fraction outside the
    corridor, and the observations simulated and those used (the network's).
    """
    pipe = check_tracking_case(pipeline, data_interval_s, network, networks, samples, seed)
    with tempfile.TemporaryDirectory() as tmp:
        result = run_pipeline(pipe, Path(tmp) / "run", execution=Execution(serial=True),
                              plots=False)
    return trade_outputs(result)


def trade_outputs(result: PipelineResult) -> dict[str, float]:
    """The numbers a tracking trade study tabulates (Monte Carlo; ΔV in m/s).

    σ of each final-miss component (``sigma_<name>``), the 1σ B-plane ellipse's semi-axes
    (km), the mean and 99 % total ΔV, the fraction of samples outside the corridor (NaN
    without one), the scalar observations TAPP I simulated (``observations_simulated``) and
    those TAPP III used (``observations_used``: the deck's time-station flags, a sweep's
    network, leave the others out).
    """
    mc = result.guidance.monte_carlo
    out = {"observations_simulated": float(result.observations_simulated),
           "observations_used": float(result.observations_used)}
    for i, name in enumerate(result.guidance.miss_name):
        out[f"sigma_{name}"] = float(np.sqrt(mc.miss_cov[i, i]))
    if mc.ellipse is not None:
        out["bplane_semi_major_km"] = mc.ellipse.semi_major_km
        out["bplane_semi_minor_km"] = mc.ellipse.semi_minor_km
    out["dv_total_mean_m_s"] = mc.total.mean_km_s * 1e3
    out["dv_total_99_m_s"] = dict(mc.total.percentiles_km_s)[99.0] * 1e3
    out["outside_corridor"] = float("nan") if mc.outside is None else mc.outside.either
    return out

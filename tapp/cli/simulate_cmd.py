"""``tapp simulate``: TAPP I, a scenario -> a T13 tape (and its OEM, TDM and SPK).

Bad input (scenario file or field, an unreadable or corrupt tape, an output path that is the
scenario or the other output, a ``[reference]`` file that cannot be read or fitted within its
limit) is one line on stderr naming the file and the field or dataset, or the option, exit
code 2 (1 for other failures; see :mod:`tapp.cli.common`). The tape, the OEM, the TDM and the
SPK are written together or not at all (:class:`tapp.io.outputs.OutputSet`). A station that
yields no observation while others do is a ``warning:`` line on stderr naming the file and
``tracking.stations[i]``, and in the JSON's ``warnings``; the tape is written; so is a
reference fit worse than its limit that ``--force`` accepted. The reference fit (per arc: RMS
and largest position difference) is in the report, the JSON's ``reference`` and the OEM's and
SPK's comments.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from tapp.cli.common import (
    EXIT_FAILURE,
    STDOUT,
    EarthOrientationOpt,
    JsonOpt,
    app,
    delivering,
    earth_orientation_option,
    echo_error,
    echo_warning,
    json_file,
    progress_bar,
    run_guarded,
)
from tapp.targeting.exits import exit_code as search_exit_code

if TYPE_CHECKING:
    from rich.console import Console

    from tapp.api.tracking import SimulateResult
    from tapp.io.outputs import OutputSet
    from tapp.io.tape.t13 import T13
    from tapp.tracking.reference import ReferenceFit
    from tapp.tracking.scenario import Scenario
    from tapp.tracking.simulate import Simulation

#: NAIF id of the spacecraft in an SPK written without --spk-id or an SPK reference (NAIF
#: gives spacecraft negative ids; this one is no mission's).
DEFAULT_SPK_ID = -999


def _spk_body(spk_id: int | None, fit: ReferenceFit | None) -> int:
    """The SPK's NAIF id: --spk-id, else the reference SPK's, else :data:`DEFAULT_SPK_ID`."""
    if spk_id is not None:
        return spk_id
    if fit is not None and fit.trajectory.kind == "SPK":
        return int(fit.trajectory.body)
    return DEFAULT_SPK_ID


def _simulate_with_bar(scenario: Scenario, raw: bool, quiet: bool, force: bool = False
                       ) -> SimulateResult:
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    from tapp.api.tracking import simulate as run_simulation

    columns = (TextColumn("{task.description:<28}"), BarColumn(), TextColumn(
        "{task.completed}/{task.total}"), TimeElapsedColumn())
    with progress_bar(*columns, quiet=quiet) as bar:
        task = bar.add_task("TAPP I", total=None)

        def progress(stage: str, done: int, total: int) -> None:
            bar.update(task, description=stage, completed=done, total=total)

        return run_simulation(scenario, raw=raw, progress=progress, accept_poor_fit=force)


def _outputs(output: Path, sim: Simulation, oem: Path | None,
             oem_text: str | None, tdm: Path | None = None,
             tdm_text: str | None = None, sizes: dict | None = None,
             spk: Callable[[Path], None] | None = None, spk_path: Path | None = None
             ) -> OutputSet:
    """The tape, the OEM, the TDM and the SPK (``spk`` writes it), to be written together or
    not at all; the tape's size goes into ``sizes["bytes"]`` as soon as it is written (before
    the outputs added later)."""
    from tapp.io.outputs import OutputSet
    from tapp.io.tape.t13_hdf5 import t13_file_writer

    write_t13 = t13_file_writer(sim.tape, source=str(output))

    def write_tape(tmp: Path) -> None:
        write_t13(tmp)
        if sizes is not None:
            sizes["bytes"] = tmp.stat().st_size

    outputs = OutputSet()
    outputs.add("-o/--output", output, write_tape)
    if oem is not None:
        outputs.add("--oem", oem, lambda tmp: tmp.write_text(oem_text, encoding="utf-8"))
    if tdm is not None:
        outputs.add("--tdm", tdm, lambda tmp: tmp.write_text(tdm_text, encoding="utf-8"))
    if spk is not None:
        outputs.add("--spk", spk_path, spk)
    return outputs


def _tdm_text(sim: Simulation, scenario: Path, parsed: Scenario) -> str:
    """The observations of the tape's raw rows as a CCSDS TDM (one segment per station),
    stating the Earth orientation they were made under (:mod:`tapp.io.obsfile`)."""
    import numpy as np

    from tapp.io.ccsds.tdm import KEYWORD_OF_KIND, format_tdm, tdm_from_tracks, tracks_from_rows
    from tapp.io.obsfile import TDM_PREFIX, made_under_statements
    from tapp.measurements.observations import MadeUnder

    tape, raw = sim.tape, sim.tape.raw
    st = tape.stations
    schedule = parsed.schedule
    # The single-station kinds only: ΔDOR rows (baselines) have no keyword of this writer.
    rows = np.isin(raw.kind, [i for i, k in enumerate(raw.kinds) if k in KEYWORD_OF_KIND])
    tracks = tracks_from_rows(raw.t_s[rows], raw.station[rows] - 1, raw.kind[rows],
                              raw.value[rows], raw.kinds,
                              st.name, tape.iden,
                              path="2,1" if schedule.light_time == "one_way" else "1,2,1",
                              span_end_s=min(schedule.end_s, float(sim.t_s[-1])))
    where = {n: f"station {n}: geodetic lat {lat:.6f} deg, lon {lon:.6f} deg, h {h:.4f} km "
             f"(WGS84), mask {m:g} deg" for n, lat, lon, h, m in
             zip(st.name, st.lat_deg, st.lon_deg, st.h_km, st.elev_mask_deg, strict=True)}
    tracks = [dataclasses.replace(t, comments=(where[t.station],)) for t in tracks]
    return format_tdm(tdm_from_tracks(tracks, tape.epoch, comments=(
        f"TAPP I observations of {scenario.name}, tape {tape.iden}: the models' values, "
        "noise-free", *made_under_statements(MadeUnder.of(parsed.orientation), TDM_PREFIX))))


def _print_encounter(console: Console, miss: dict, targeting: dict | None) -> None:
    """The targeted injection (when SEARCH moved it) and the miss achieved on the tape."""
    aim = {} if targeting is None else targeting["aim"]
    if targeting is not None:
        v0, before = targeting["v0_targeted_km_s"], targeting["v0_file_km_s"]
        change_m_s = 1e3 * sum((a - b) ** 2 for a, b in zip(v0, before, strict=True)) ** 0.5
        console.print(
            f"Injection retargeted by SEARCH ({targeting['first_guess']} first guess; "
            f"{', '.join(targeting['vary'])} varied)\n  {targeting['status']} in "
            f"{targeting['cases']} cases, {targeting['partial_sets']} sets of partials, "
            f"{targeting['wall_time_s']:.2f} s; periapsis radius "
            f"{targeting['periapsis_radius_km']:.3f} km\n  v0 = "
            f"[{', '.join(f'{v:.9f}' for v in v0)}] km/s (changed by {change_m_s:.3f} m/s)")
    console.print(f"Miss ({miss['kind']}) at {miss['utc']} UTC (t = {miss['t_s']:.3f} s):")
    for name, value in zip(miss["names"], miss["nominal"], strict=True):
        console.print(f"  {name} = {value:.10g}"
                      + (f" (aim {aim[name]:.10g})" if name in aim else ""))


def _events_line(events: list[dict]) -> str:
    """One line: how many integration events of each kind, first and last (the JSON and the
    OEM list them all)."""
    kinds: dict[str, int] = {}
    for e in events:
        kinds[e["event"]] = kinds.get(e["event"], 0) + 1
    counts = ", ".join(f"{n} {kind}" for kind, n in kinds.items())
    return (f"Integration events: {len(events)} ({counts}), {events[0]['utc']} to "
            f"{events[-1]['utc']} UTC")


def _print_report(out: dict, tape: T13, oem_states: tuple[int, int],
                  fit_lines: tuple[str, ...] = ()) -> None:
    """What ``tapp simulate`` wrote: the tape's sizes, its stations, the reference fit, the
    OEM, TDM and SPK (``oem_states``: their states and segments), the miss."""
    from rich.console import Console

    from tapp.cli.tape_cmd import editing_table

    console = Console(width=100)
    console.print(f"T13 tape {out['tape']} ({out['bytes'] / 1e6:.2f} MB) written in "
                  f"{out['wall_s']:.2f} s: n_o = {tape.n_o}, n_p = {tape.n_p}, n_m = "
                  f"{tape.n_m}, n_ts = {tape.n_ts}, n_it = {tape.n_it}; "
                  f"{out['observations']} observations in {out['passes']} passes")
    console.print(editing_table(out["stations"]))
    for line in fit_lines:
        console.print(line)
    if out["events"]:
        console.print(_events_line(out["events"]))
    states, segments = oem_states
    held = f"{states} states" + (f" in {segments} segments" if segments > 1 else "")
    if out["oem"] is not None:
        console.print(f"OEM {out['oem']} ({held})")
    if out["tdm"] is not None:
        console.print(f"TDM {out['tdm']} ({out['observations']} observations)")
    if out["spk"] is not None:
        console.print(f"SPK {out['spk']['path']} (type 13, body {out['spk']['body']}, "
                      f"{held})")
    _print_encounter(console, out["miss"], out["targeting"])


@app.command()
def simulate(
    scenario: Annotated[Path, typer.Argument(help="Scenario file (TOML).")],
    output: Annotated[Path, typer.Option("--output", "-o", help="T13 tape to write "
                                         "(RUN.t13.h5).")],
    raw: Annotated[bool, typer.Option("--raw", help="Also store every observation's partial "
                                      "row, weight and real-world noise (raw/ group).")] = False,
    oem: Annotated[Path | None, typer.Option("--oem", help="Also write the trajectory as a "
                                             "CCSDS OEM 2.0 (KVN) file.")] = None,
    tdm: Annotated[Path | None, typer.Option("--tdm", help="Also write the observations as a "
                                             "CCSDS TDM 2.0 (KVN) file.")] = None,
    spk: Annotated[Path | None, typer.Option("--spk", help="Also write the trajectory as a "
                                             "SPICE SPK (type 13, about the Earth, J2000).")
                   ] = None,
    spk_id: Annotated[int | None, typer.Option(
        "--spk-id", help=f"NAIF id of the spacecraft in the SPK [default: the [reference] "
        f"SPK's, else {DEFAULT_SPK_ID}].")] = None,
    force: Annotated[bool, typer.Option("--force", help="Fly a [reference] fit worse than its "
                                        "max_fit_error_m (refused otherwise), with a warning "
                                        "stating it.")] = False,
    earth_orientation: EarthOrientationOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """TAPP I: simulate the tracking of a scenario and write its T13 tape.

    A B-plane miss must be an encounter (exit 2 naming the closest approach otherwise); a
    [targeting] table retargets the injection by SEARCH first (exit 3 diverged, 4 singular,
    1 a case that failed; no tape then). A [reference] trajectory is fitted first, and a fit
    worse than its limit is exit 2 unless --force.
    """

    def body() -> int:
        from tapp.io.ccsds.oem import INTERPOLATION, INTERPOLATION_DEGREE, format_oem
        from tapp.io.outputs import check_paths
        from tapp.tracking.encounter import TargetingError
        from tapp.tracking.oem_states import (
            burn_comments,
            oem_trajectory,
            segment_comments,
            write_trajectory_spk,
        )
        from tapp.tracking.scenario_build import read_scenario

        outputs = {"-o/--output": output, "--oem": oem, "--tdm": tdm, "--spk": spk,
                   "--json": json_file(json_out)}
        check_paths({"SCENARIO": scenario}, outputs)
        parsed = read_scenario(scenario, earth_orientation_option(earth_orientation))
        if parsed.schedule.passes is not None:  # inputs too
            check_paths({"tracking.schedule": Path(parsed.schedule.passes.source)}, outputs)
        if parsed.reference is not None:
            check_paths({"reference.file": Path(parsed.reference.trajectory.source)}, outputs)
        try:
            result = _simulate_with_bar(parsed, raw or tdm is not None,
                                        quiet=json_out == STDOUT, force=force)
        except TargetingError as exc:
            echo_error(exc)
            code = search_exit_code(exc.status)
            return EXIT_FAILURE if code is None else code
        sim, tdm_text = result.simulation, None
        if tdm is not None:
            tdm_text = _tdm_text(sim, scenario, parsed)
            if not raw:  # the raw rows were for the TDM only
                sim = dataclasses.replace(sim, tape=dataclasses.replace(sim.tape, raw=None))
                result = dataclasses.replace(result, simulation=sim)
        tape = sim.tape
        fit = sim.reference_fit
        fit_lines = () if fit is None else fit.lines(tape.epoch)
        comments = (f"TAPP I trajectory of {scenario.name}", *fit_lines,
                    *burn_comments(tape.epoch, sim.scenario.manoeuvres, fit))
        oem_text, oem_states, write_spk, spk_info = None, (0, 0), None, None
        if oem is not None or spk is not None:
            traj = oem_trajectory(sim.scenario, float(sim.t_s[-1]))
            oem_states = (traj.t_s.size, len(traj.spans))
        if oem is not None:
            oem_text = format_oem(tape.epoch, traj.t_s, traj.states, object_name=tape.iden,
                                  object_id=tape.iden, ref_frame=traj.ref_frame,
                                  interpolation=INTERPOLATION,
                                  interpolation_degree=INTERPOLATION_DEGREE,
                                  comments=comments, meta_comments=traj.comments,
                                  segment=traj.segment,
                                  segment_comments=segment_comments(traj, sim.scenario),
                                  center_name=sim.scenario.state_model.center.upper())
        if spk is not None:
            body = _spk_body(spk_id, fit)
            spk_info = {"path": str(spk), "body": body}

            def write_spk(tmp: Path) -> None:
                spk_info["error_km"], spk_info["error_km_s"] = write_trajectory_spk(
                    tmp, sim.scenario, traj, body, comments + traj.comments)
        out = result.to_json(tape=str(output), oem=None if oem is None else str(oem),
                             tdm=None if tdm is None else str(tdm), spk=spk_info)
        # the JSON is written after the tape's temporary, whose size it then holds
        outputs = _outputs(output, sim, oem, oem_text, tdm, tdm_text, sizes=out,
                           spk=write_spk, spk_path=spk)
        with delivering(json_out, out, outputs) as report:
            if report:
                _print_report(out, tape, oem_states, fit_lines)
        warnings = list(sim.warnings)
        if fit is not None and fit.forced:
            warnings.append(f"{scenario}: reference.max_fit_error_m: the fit to "
                            f"{fit.trajectory.source} misses it by {fit.worst.max_m:.4g} m "
                            f"(RMS {fit.worst.rms_m:.4g} m), more than "
                            f"{fit.max_fit_error_m:g} m; flown as --force asked")
        for warning in warnings:  # last: a failed run's one line is its error
            echo_warning(warning)
        return 0

    code = run_guarded(body)
    if code:
        raise typer.Exit(code)

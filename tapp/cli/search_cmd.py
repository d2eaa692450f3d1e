"""``tapp search``: SEARCH's Newton-Raphson targeting of a B-plane scenario.

The scenario is a SEARCH file (the example ``search_bplane.toml``: a ``[search]`` table) or a
tracking scenario with a ``[targeting]`` table
(:func:`tapp.targeting.searchfile.scenario_targeting`: the aim point of its B-plane miss, SEARCH
on its own models). Prints SEARCH's report in the spirit of the seed's Figs. 4 and 5 (inputs,
each case's dependent variables, the partials, their inverse, the increments and total
increments, the exit taken) followed by the encounter of the final trajectory, or one JSON
object with ``--json``. Exit codes follow SEARCH's three
non-standard exits (:data:`search.EXIT_FLAG`): 0 converged, FLAG + 1 otherwise (3 diverged,
4 singular), so that they stay clear of 1 (a failed case or any other error) and 2 (bad
input, one line on stderr naming file and field).

``--write-scenario PATH`` writes the input file again with the targeted injection (position
and velocity, ``[injection]`` as ``r_km`` and ``v_km_s``) and, for a tracking scenario,
without its ``[targeting]`` table: a scenario that ``tapp simulate`` flies to the aim point
as it stands. A SEARCH file gets the targets reached instead of its theta (``[search.targets]``
with ``y_0 + theta``, no ``[search.target_increments]``), so that searching it again starts
converged. Comments and layout are kept; the file is written atomically, never over an
input, and only when SEARCH converged.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from tapp.cli.common import (
    EarthOrientationOpt,
    JsonOpt,
    app,
    delivering,
    earth_orientation_option,
    json_file,
    run_guarded,
)
from tapp.errors import InputError

if TYPE_CHECKING:
    from tapp.targeting.program import BPlaneSearch, TargetingRun

# Column names in the report (the seed's IV1N.., DV1N..), at most 17 characters.
_X_LABELS = ("VX (KM/S)", "VY (KM/S)", "VZ (KM/S)")
_Y_LABELS = ("B.R (KM)", "B.T (KM)", "TF (S)")


def exit_code(status: str) -> int | None:
    """The exit code of a SEARCH exit: 0 converged, the seed's FLAG + 1 otherwise (3
    diverged, 4 singular); None for a status that is not one of SEARCH's exits."""
    from search import EXIT_FLAG

    flag = EXIT_FLAG.get(status)
    return None if flag is None else 0 if status == "converged" else flag + 1


def is_tracking_scenario(data: dict) -> bool:
    """Whether a parsed file is a tracking scenario (else a SEARCH file)."""
    return "tracking" in data or "targeting" in data


def problem_of(data: dict, path: Path, earth_orientation: str | None) -> BPlaneSearch:
    """The search problem of a parsed scenario file (a SEARCH file, or a tracking scenario
    with a ``[targeting]`` table); ``earth_orientation`` overrides the file's model."""
    from tapp.targeting.searchfile import scenario_search
    from tapp.tracking.scenario import parse_scenario

    if is_tracking_scenario(data):
        problem = parse_scenario(data, str(path), earth_orientation).targeting
        if problem is None:
            raise InputError(str(path), "targeting", "a [targeting] table (the aim point) in "
                             "a tracking scenario given to tapp search")
        return problem
    if earth_orientation is not None:
        data["earth_orientation"] = earth_orientation
    return scenario_search(data, str(path))


def _written_scenario(path: Path, data: dict, problem: BPlaneSearch, run: TargetingRun
                      ) -> str:
    """The text of ``path`` (``data`` as read) with the targeted injection (and without
    ``[targeting]``)."""
    import datetime as dt

    from tapp.io.tomlfile import replace_tables
    from tapp.targeting.program import Y_NAMES

    text = path.read_text()
    injection = {"r_km": problem.program.r0_km.tolist(),
                 "v_km_s": run.encounter.v0_km_s.tolist()}
    if data["injection"].get("allow_subsurface"):
        injection["allow_subsurface"] = True
    result = run.result
    tables: dict = {"injection": injection}
    if is_tracking_scenario(data):
        tables["targeting"] = None
    else:  # the targets reached, theta resolved: searching the file again starts converged
        tables["search.targets"] = dict(zip(Y_NAMES, problem.targets.tolist(), strict=True))
        tables["search.targets"].update(zip(problem.y_names, result.targets.tolist(),
                                            strict=True))
        tables["search.target_increments"] = None
    reached = ", ".join(f"{name} = {value:.6f} (target {target:.6f})" for name, value, target
                        in zip(problem.y_names, result.y, result.targets, strict=True))
    stamp = dt.datetime.now(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    comment = (f"Targeted by tapp search from {path.name} on {stamp}: SEARCH converged in "
               f"{result.n_cases} cases to\n{reached}")
    return replace_tables(text, str(path), tables, comment=comment)


def _encounter_dict(problem: BPlaneSearch, run: TargetingRun) -> dict:
    from tapp.constants import RADIUS_km

    enc = run.encounter
    body = problem.program.target
    r_p = float(enc.b_plane.periapsis_radius_km)
    return {"body": body,
            "t_periapsis_s": enc.t_periapsis_s,
            "periapsis_utc": problem.program.epoch.iso_after(enc.t_periapsis_s, 3),
            "periapsis_radius_km": r_p,
            "periapsis_altitude_km": r_p - RADIUS_km[body],
            "v_inf_km_s": float(enc.b_plane.v_inf_km_s),
            "eccentricity": float(enc.b_plane.eccentricity),
            "ltof_s": float(enc.b_plane.ltof_s)}


def _history_dict(run: TargetingRun) -> dict:
    history = run.result.history
    return {
        "cases": [{"n": c.number, "kind": c.kind, "set": c.partial_set, "index": c.index,
                   "x": c.x, "y": c.y} for c in history.cases],
        "partial_sets": [{"set": ps.number, "update": ps.update, "source": ps.source,
                          "after_case": ps.after_case, "partials": ps.partials,
                          "determinant": ps.determinant,
                          "steps": [{"case": s.case, "step": s.step, "total_step": s.total_step}
                                    for s in ps.steps]}
                         for ps in history.partial_sets],
    }


def _json(path: Path, problem: BPlaneSearch, run: TargetingRun, analytic: bool,
          elapsed_s: float) -> dict:
    result = run.result
    return {
        "scenario": str(path),
        "status": result.status,
        "flag": result.flag,
        "exit_code": exit_code(result.status),
        "x_names": list(problem.x_names),
        "y_names": list(problem.y_names),
        "x": result.x,
        "y": result.y,
        "targets": result.targets,
        "miss": result.miss,
        "tolerances": result.inputs.tolerances,
        "total_increments_km_s": result.x - result.inputs.x0,
        "first_guess": problem.first_guess,
        "v0_km_s": run.encounter.v0_km_s,
        "v0_first_case_km_s": run.start_km_s,
        "cases_run": result.n_cases,
        "cases": {"nominal": result.n_nominal, "perturbed": result.n_perturbed,
                  "applied": result.n_applied},
        "trajectories": run.trajectories,
        "propagations": run.propagations,
        "analytic_partials": analytic,
        "wall_time_s": elapsed_s,
        "encounter": _encounter_dict(problem, run),
        "history": _history_dict(run),
    }


def _summary(problem: BPlaneSearch, run: TargetingRun, analytic: bool,
             elapsed_s: float) -> str:
    import numpy as np

    enc = _encounter_dict(problem, run)
    dv_m_s = 1e3 * float(np.linalg.norm(run.encounter.v0_km_s - problem.v0_km_s))
    partials = "ANALYTIC (VARIATIONAL EQUATIONS)" if analytic else "DIFFERENCED"
    return (
        f"ENCOUNTER WITH THE {enc['body'].upper()}: PERIAPSIS {enc['periapsis_utc']} UTC "
        f"(T = {enc['t_periapsis_s']:.3f} S), RADIUS {enc['periapsis_radius_km']:.3f} KM "
        f"(ALTITUDE {enc['periapsis_altitude_km']:.3f} KM), V_INF {enc['v_inf_km_s']:.6f} KM/S\n"
        f"TOTAL CHANGE OF THE INJECTION VELOCITY {dv_m_s:.3f} M/S\n"
        f"{run.trajectories} TRAJECTORIES ({run.propagations} PROPAGATIONS), PARTIALS "
        f"{partials}, {elapsed_s:.2f} S\n")


@app.command("search")
def search_command(
    scenario: Annotated[Path, typer.Argument(help="B-plane search scenario (TOML).")],
    json_out: JsonOpt = None,
    analytic_partials: Annotated[bool, typer.Option(
        "--analytic-partials",
        help="Partials from the variational equations (overrides the scenario).")] = False,
    earth_orientation: EarthOrientationOpt = None,
    write_scenario: Annotated[Path | None, typer.Option(
        "--write-scenario", help="Also write the scenario again with the targeted injection "
        "(and, for a tracking scenario, without its [targeting] table), if SEARCH "
        "converged.")] = None,
) -> None:
    """Target the injection velocity to B·R, B·T and flight time at the target body.

    SCENARIO is a SEARCH file or a tracking scenario with a [targeting] table. Exit codes: 0
    converged, 3 diverged, 4 singular (no --write-scenario then), 2 bad input, 1 a case that
    failed (the trajectory missed the target's sphere of influence, or was not hyperbolic
    there).
    """

    def body() -> int:
        import time

        from search import format_report
        from tapp.io.outputs import OutputSet, check_paths
        from tapp.io.tomlfile import read_toml
        from tapp.targeting.program import run_search

        check_paths({"SCENARIO": scenario}, {"--write-scenario": write_scenario,
                                             "--json": json_file(json_out)})
        orientation = earth_orientation_option(earth_orientation)
        data = read_toml(scenario)
        problem = problem_of(dict(data), scenario, orientation)
        if write_scenario is not None and orientation is not None and orientation != problem_of(
                dict(data), scenario, None).program.orientation.model:
            raise InputError("--write-scenario", str(write_scenario), "no --earth-orientation "
                             "other than the file's (the written scenario states the file's "
                             "model)", orientation)
        analytic = analytic_partials or problem.analytic_partials
        start = time.perf_counter()
        run = run_search(problem, analytic_partials=analytic)
        elapsed = time.perf_counter() - start
        outputs = OutputSet()
        if write_scenario is not None and run.result.status == "converged":
            text = _written_scenario(scenario, data, problem, run)
            outputs.add("--write-scenario", write_scenario,
                        lambda tmp: tmp.write_text(text, encoding="utf-8"))
        with delivering(json_out, _json(scenario, problem, run, analytic, elapsed),
                        outputs) as report:
            if report:
                labels = (tuple(_X_LABELS[i] for i in problem.vary),
                          tuple(_Y_LABELS[i] for i in problem.targeted))
                typer.echo(format_report(run.result, *labels), nl=False)
                typer.echo(_summary(problem, run, analytic, elapsed), nl=False)
        if write_scenario is not None and run.result.status != "converged":
            typer.echo(f"note: --write-scenario {write_scenario} not written: SEARCH "
                       f"{run.result.status}", err=True)
        return exit_code(run.result.status)

    code = run_guarded(body)
    if code:
        raise typer.Exit(code)

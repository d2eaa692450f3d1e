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
from tapp.targeting.exits import exit_code

if TYPE_CHECKING:
    from tapp.targeting.program import BPlaneSearch, TargetingRun


def _written_scenario(path: Path, data: dict, problem: BPlaneSearch, run: TargetingRun
                      ) -> str:
    """The text of ``path`` (``data`` as read) with the targeted injection (and without
    ``[targeting]``)."""
    import datetime as dt

    from tapp.api.targeting import is_tracking_scenario
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
        from tapp.api.targeting import problem_of, search
        from tapp.io.outputs import OutputSet, check_paths
        from tapp.io.tomlfile import read_toml

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
        result = search(problem, analytic_partials=analytic_partials, source=str(scenario))
        outputs = OutputSet()
        if write_scenario is not None and result.converged:
            text = _written_scenario(scenario, data, problem, result.run)
            outputs.add("--write-scenario", write_scenario,
                        lambda tmp: tmp.write_text(text, encoding="utf-8"))
        with delivering(json_out, result.to_json(), outputs) as report:
            if report:
                typer.echo(result.report(), nl=False)
        if write_scenario is not None and not result.converged:
            typer.echo(f"note: --write-scenario {write_scenario} not written: SEARCH "
                       f"{result.status}", err=True)
        return exit_code(result.status)

    code = run_guarded(body)
    if code:
        raise typer.Exit(code)

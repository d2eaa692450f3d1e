"""``tapp propagate``: a trajectory with its STM under a (truth, variational) model pair."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

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
from tapp.cli.durations import span_option, step_option, warn_deprecated
from tapp.errors import InputError
from tapp.io.options import DURATION_FORMS, check_grid_size, grid_samples


def _third_bodies(names: list[str]) -> tuple[str, ...]:
    """The ``--third-body`` values, each a DE421 body other than the Earth, each once."""
    from tapp.dynamics.ephemeris import BODIES

    allowed = [b for b in BODIES if b != "earth"]
    for name in names:
        if name not in allowed:
            raise InputError("--third-body", "third_bodies", f"one of {', '.join(allowed)}", name)
        if names.count(name) > 1:
            raise InputError("--third-body", "third_bodies", f"each body once ({name} given "
                             f"{names.count(name)} times would multiply its pull)", name)
    return tuple(names)


def _method(name: str) -> str:
    """The ``--method`` value, one of :data:`tapp.dynamics.compiled.METHODS`."""
    from tapp.dynamics.compiled import METHODS

    if name not in METHODS:
        raise InputError("--method", "method", f"one of {', '.join(METHODS)}", name)
    return name


@app.command()
def propagate(
    orbit: Annotated[str, typer.Option(help="a=..,e=..,i=..,raan=..,argp=..,M=.. (km, deg), "
                                       "x=..,..,vz=.. (km, km/s) or an orbit name")],
    arc: Annotated[str | None, typer.Option(
        help=f"Arc length with its unit: {DURATION_FORMS} [default: 24h].")] = None,
    step: Annotated[str, typer.Option(help=f"Output step with its unit: {DURATION_FORMS}.")]
    = "60s",
    truth: Annotated[str, typer.Option(help="State model: J0, Jn or NxM.")] = "J2",
    stm: Annotated[str, typer.Option(help="Variational model: J0, Jn or NxM.")] = "J2",
    third_body: Annotated[list[str] | None, typer.Option(
        "--third-body", help="Third body from DE421 (repeatable): sun, moon, ...")] = None,
    epoch: Annotated[str, typer.Option(help="UTC epoch of t = 0 (ISO 8601).")]
    = "2026-01-01T00:00:00",
    tol: Annotated[float, typer.Option(help="Relative and absolute tolerance, in [1e-15, "
                                       "1e-6].")] = 1e-13,
    method: Annotated[str, typer.Option(help="Integration method: dop853 or rkn12 "
                                        "(Runge-Kutta-Nystrom 12(10), ~4x fewer evaluations "
                                        "at 1e-12).")] = "dop853",
    scenario: Annotated[Path | None, typer.Option(
        help="Scenario file with named orbits [default: the shipped approx_stm.toml].")]
    = None,
    json_out: JsonOpt = None,
    allow_subsurface: Annotated[bool, typer.Option(
        "--allow-subsurface", help="Accept an orbit whose perigee is below the Earth's "
        "surface.")] = False,
    earth_orientation: EarthOrientationOpt = None,
    hours: Annotated[float | None, typer.Option(
        help="Arc length, hours (deprecated: --arc 24h).", hidden=True)] = None,
) -> None:
    """Propagate an Earth orbit with its state transition matrix (GCRS, km, km/s)."""

    def body() -> None:
        import numpy as np
        from rich.console import Console
        from rich.table import Table

        from tapp.constants import SECONDS_PER_DAY
        from tapp.dynamics import Propagator, earth_model
        from tapp.dynamics.ephemeris import check_coverage, utc_to_tdb_jd
        from tapp.dynamics.propagate import check_tolerance
        from tapp.frames.time import parse_epoch
        from tapp.io.eop_file import orientation_for
        from tapp.io.orbits import parse_orbit
        from tapp.io.outputs import check_paths

        check_paths({"--scenario": scenario}, {"--json": json_file(json_out)})
        x0 = parse_orbit(orbit, scenario=scenario, allow_subsurface=allow_subsurface)
        arc_s = span_option("--arc", arc, hours, "24h")
        dt = step_option(step)
        check_grid_size("--arc/--step", grid_samples(arc_s, dt))
        bodies = _third_bodies(third_body or [])
        ep = parse_epoch(epoch, source="--epoch")
        model = earth_orientation_option(earth_orientation) or "iau2006"
        orientation = orientation_for(model, ep, source="--epoch")
        prop = Propagator(earth_model(truth, bodies, source="--truth", field="model",
                                      earth_orientation=model),
                          earth_model(stm, bodies, source="--stm", field="model",
                                      earth_orientation=model),
                          rtol=check_tolerance(tol, "--tol", "value"), atol=tol,
                          method=_method(method))
        if bodies:
            check_coverage(utc_to_tdb_jd(ep.jd, source="--epoch"),
                           np.array([0.0, arc_s]) / SECONDS_PER_DAY,
                           source="--epoch/--arc", field="arc")
        t = np.append(np.arange(0.0, arc_s, dt), arc_s)
        start = time.perf_counter()
        orientation.check_covers(np.array([0.0, arc_s]), "--epoch/--arc")
        traj = prop.propagate(x0, t, epoch_jd_utc=ep.jd, orientation=orientation)
        elapsed = time.perf_counter() - start
        with delivering(json_out, {"t_s": traj.t_s, "state": traj.states, "stm": traj.stm}
                        ) as report:
            if report:
                table = Table(title=f"{orbit}: truth {truth}, STM {stm}, "
                              f"{arc_s / 3600.0:g} h, Earth orientation {model}")
                for col in ("t (s)", "x (km)", "y (km)", "z (km)", "vx (km/s)", "vy (km/s)",
                            "vz (km/s)", "|Φ|max"):
                    table.add_column(col, justify="right")
                for k in sorted({0, len(t) // 2, len(t) - 1}):
                    table.add_row(f"{t[k]:.0f}", *(f"{v:.6f}" for v in traj.states[k]),
                                  f"{np.abs(traj.stm[k]).max():.4g}")
                console = Console(width=130)
                console.print(table)
                console.print(f"{method}: {traj.steps} steps, {traj.rhs_evaluations} RHS "
                              f"evaluations, {elapsed * 1e3:.1f} ms")
        warn_deprecated("--arc", hours, step)

    run_guarded(body)

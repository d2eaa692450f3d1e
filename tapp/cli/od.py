"""``tapp dc``, ``tapp ekf``, ``tapp rsig``: the approximate-STM study's estimators."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from tapp.cli.common import (
    app,
    check_grid_size,
    grid_samples,
    nonnegative_option,
    positive_option,
    print_json,
    run_guarded,
    seed_option,
)
from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import Propagator, earth_model
from tapp.errors import InputError
from tapp.frames.elements import cartesian_to_elements
from tapp.od import setup
from tapp.od.batch import DCSettings, differential_correction
from tapp.od.ekf import extended_kalman_filter
from tapp.od.observations import Observations
from tapp.od.obsfile import observations_file_writer, read_observations
from tapp.od.rsig import r_signature
from tapp.orbits import DEFAULT_SCENARIO
from tapp.outputs import OutputSet, check_paths
from tapp.stations_file import load_stations

_ARC = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*([smhd]?)\s*$")
_UNIT_S = {"s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0, "": 3600.0}
_APRIORI_KEYS = ("sx", "sy", "sz", "svx", "svy", "svz")
#: Exit code of a DC that did not converge (its output is still printed).
EXIT_DIVERGED = 3

OrbitOpt = Annotated[str, typer.Option(help="Orbit name (SATORB1..8) or a=..,e=..,i=..,"
                                       "raan=..,argp=..,M=.. (km, deg)")]
TruthOpt = Annotated[str, typer.Option(help="State model of the data and the estimator.")]
StmOpt = Annotated[str, typer.Option(help="Variational model of the estimator.")]
ScenarioOpt = Annotated[Path, typer.Option(help="Study scenario file.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object.")]
SubsurfaceOpt = Annotated[bool, typer.Option(
    "--allow-subsurface", help="Accept an orbit whose perigee is below the Earth's surface.")]


def parse_arc_s(text: str, option: str = "--arc") -> float:
    """Return an arc length in seconds from '24h', '90m', '3600s', '1.5d' (bare = hours)."""
    m = _ARC.match(text)
    if m is None or float(m.group(1)) <= 0:
        raise InputError(option, "arc", "a positive duration such as 24h, 90m, 3600s, 2d",
                         text)
    return float(m.group(1)) * _UNIT_S[m.group(2)]


def _model_pair(truth: str, stm: str) -> Propagator:
    """The estimator's (state model, variational model) pair from the CLI options."""
    return Propagator(earth_model(truth, source="--truth", field="model"),
                      earth_model(stm, source="--stm", field="model"))


def _observations(x_true: np.ndarray, truth: str, stations: str | None, obs_file: Path | None,
                  scenario: Path, seed: int | None) -> Observations:
    if obs_file is not None:
        data = setup.load_study(scenario)
        return read_observations(obs_file, load_stations(data, str(scenario)),
                                 setup.tracking(scenario).sigma)
    return setup.simulated_observations(x_true, truth, _network(x_true, stations, scenario),
                                        scenario, seed)


def _network(x_true: np.ndarray, stations: str | None, scenario: Path) -> tuple:
    """The stations named by ``--stations`` (or the scenario's default for the orbit); an
    unknown name is the option's fault and names ``--stations``."""
    default = setup.network_for(x_true, None, scenario)  # a bad file names the file
    if stations is None:
        return default
    try:
        return setup.network_for(x_true, stations, scenario)
    except InputError as exc:
        if exc.field != "networks":
            raise
        raise InputError("--stations", "name", exc.expected, stations) from None


def _elements_dict(x: np.ndarray) -> dict[str, float]:
    a, e, i, raan, argp, mean = np.asarray(cartesian_to_elements(x, GM_EARTH_km3_s2), float)
    return {"a_km": a, "e": e, "i_deg": math.degrees(i), "raan_deg": math.degrees(raan),
            "argp_deg": math.degrees(argp), "M_deg": math.degrees(mean)}


@app.command()
def dc(
    orbit: OrbitOpt,
    arc: Annotated[str, typer.Option(help="Arc length: 24h, 12h, 90m, ...")] = "24h",
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    stations: Annotated[str | None, typer.Option(help="Network or station name.")] = None,
    max_iter: Annotated[int, typer.Option(help="Iteration limit (>= 1).")] = 12,
    seed: Annotated[int | None, typer.Option(help="Noise seed (default: scenario's).")] = None,
    obs: Annotated[Path | None, typer.Option(help="Observation file (.h5 or .csv) instead "
                                             "of simulated data.")] = None,
    save_obs: Annotated[Path | None, typer.Option(help="Write the observations used.")] = None,
    scenario: ScenarioOpt = DEFAULT_SCENARIO,
    allow_subsurface: SubsurfaceOpt = False,
    json_out: JsonOpt = False,
) -> None:
    """Batch differential correction from the brief's offset initial estimate."""

    def body() -> None:
        check_paths({"--obs": obs, "--scenario": scenario}, {"--save-obs": save_obs})
        arc_s = parse_arc_s(arc)
        if max_iter < 1:
            raise InputError("--max-iter", "value", "a whole number >= 1", max_iter)
        x_true = setup.true_orbit(orbit, scenario, allow_subsurface=allow_subsurface)
        prop = _model_pair(truth, stm)
        data = _observations(x_true, truth, stations, obs, scenario,
                             seed_option("--seed", seed))
        if save_obs is not None:
            outputs = OutputSet()
            outputs.add("--save-obs", save_obs, observations_file_writer(save_obs, data))
            outputs.commit()
        x_start = setup.initial_estimate(x_true, setup.offset(scenario))
        result = differential_correction(data.window(arc_s), prop, x_start,
                                         theta0_rad=setup.tracking(scenario).theta0_rad,
                                         settings=DCSettings(max_iterations=max_iter))
        err_km = float(np.linalg.norm(result.x0[:3] - x_true[:3]))
        if json_out:
            print_json({"converged": result.converged, "status": result.status,
                        "reason": result.reason, "iterations": len(result.iterations),
                        "rms": result.rms, "final_elements": _elements_dict(result.x0),
                        "position_error_km": err_km, "measurements": result.n_measurements})
        else:
            _print_dc(result, f"DC {orbit}, {arc}, ({truth},{stm}): {result.status}", err_km)
        if not result.converged:
            raise typer.Exit(EXIT_DIVERGED)

    run_guarded(body)


def _print_dc(result, title: str, err_km: float) -> None:
    table = Table(title=title)
    table.add_column("iteration", justify="right")
    table.add_column("RMS", justify="right")
    table.add_column("|δr| (m)", justify="right")
    for it in result.iterations:
        table.add_row(str(it.index), f"{it.rms:.4f}",
                      f"{np.linalg.norm(it.correction[:3]) * 1e3:.3f}")
    console = Console(width=100)
    console.print(table)
    console.print(f"{result.reason}; {result.n_measurements} measurements; epoch "
                  f"position error {err_km * 1e3:.3f} m")


def _apriori(text: str, scenario: Path) -> np.ndarray:
    table = setup.load_study(scenario).get("ekf", {}).get("apriori", {})
    if text in table:  # the scenario's a priori: a bad one is the file's fault, not --apriori
        try:
            sig = np.asarray(table[text], dtype=float)
        except (TypeError, ValueError):
            sig = np.empty(0)
        if sig.shape != (6,) or not np.all(np.isfinite(sig)) or np.any(sig <= 0):
            raise InputError(str(scenario), f"ekf.apriori.{text}",
                             "six standard deviations > 0 (km, km/s)", table[text])
    else:
        pairs = dict(item.partition("=")[::2] for item in text.split(","))
        if set(pairs) != set(_APRIORI_KEYS):
            raise InputError("--apriori", "apriori", f"one of {', '.join(table) or 'none'} or "
                             f"{','.join(k + '=..' for k in _APRIORI_KEYS)} (km, km/s)", text)
        try:
            sig = np.array([float(pairs[k]) for k in _APRIORI_KEYS])
        except ValueError:
            raise InputError("--apriori", "apriori", "numbers", text) from None
    if sig.shape != (6,) or not np.all(np.isfinite(sig)) or np.any(sig <= 0):
        raise InputError("--apriori", "apriori", "six standard deviations > 0", text)
    return np.diag(sig**2)


@app.command()
def ekf(
    orbit: OrbitOpt,
    arc: Annotated[str, typer.Option(help="Arc length: 18h, ...")] = "18h",
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    apriori: Annotated[str, typer.Option(help="1|2|3|4 (the brief's) or sx=..,sy=..,sz=..,"
                                         "svx=..,svy=..,svz=.. (km, km/s)")] = "1",
    stations: Annotated[str | None, typer.Option(help="Network or station name.")] = None,
    process_noise: Annotated[float, typer.Option(help="White-noise acceleration spectral "
                                                 "density q (km^2/s^3).")] = 0.0,
    seed: Annotated[int | None, typer.Option(help="Noise seed.")] = None,
    obs: Annotated[Path | None, typer.Option(help="Observation file (.h5 or .csv).")] = None,
    scenario: ScenarioOpt = DEFAULT_SCENARIO,
    allow_subsurface: SubsurfaceOpt = False,
    json_out: JsonOpt = False,
) -> None:
    """Extended Kalman filter from the brief's offset state; largest |O-C| per pass."""

    def body() -> None:
        arc_s = parse_arc_s(arc)
        x_true = setup.true_orbit(orbit, scenario, allow_subsurface=allow_subsurface)
        prop = _model_pair(truth, stm)
        p0 = _apriori(apriori, scenario)
        q_km2_s3 = nonnegative_option("--process-noise", process_noise)
        data = _observations(x_true, truth, stations, obs, scenario,
                             seed_option("--seed", seed)).window(arc_s)
        x_start = setup.initial_estimate(x_true, setup.offset(scenario))
        result = extended_kalman_filter(data, prop, x_start, p0,
                                        theta0_rad=setup.tracking(scenario).theta0_rad,
                                        q_km2_s3=q_km2_s3)
        per_pass = [{"range_m": p.max_abs[0] * 1e3, "range_rate_mm_s": p.max_abs[1] * 1e6}
                    for p in result.passes]
        if json_out:
            print_json({"passes": [{"station": p.station, "t_start_s": p.t_start_s,
                                    "t_end_s": p.t_end_s} for p in result.passes],
                        "max_abs_residual_per_pass": per_pass})
            return
        table = Table(title=f"EKF {orbit}, {arc}, ({truth},{stm}), a priori {apriori}")
        for col in ("pass", "station", "start (h)", "max|O-C| range (m)",
                    "max|O-C| range-rate (mm/s)"):
            table.add_column(col, justify="right")
        for k, (p, r) in enumerate(zip(result.passes, per_pass, strict=True), start=1):
            table.add_row(str(k), p.station, f"{p.t_start_s / 3600:.2f}", f"{r['range_m']:.1f}",
                          f"{r['range_rate_mm_s']:.1f}")
        Console(width=110).print(table)

    run_guarded(body)


@app.command()
def rsig(
    orbit: OrbitOpt,
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    hours: Annotated[float, typer.Option(help="Span, hours (> 0).")] = 48.0,
    step: Annotated[float, typer.Option(help="Output step, s (> 0).")] = 300.0,
    scenario: ScenarioOpt = DEFAULT_SCENARIO,
    allow_subsurface: SubsurfaceOpt = False,
    json_out: JsonOpt = False,
) -> None:
    """The error-growth signature R(t) = sqrt(Σ_{i<=3, j<=6} φ_ij²)."""

    def body() -> None:
        span_s = positive_option("--hours", hours) * 3600.0
        dt = positive_option("--step", step)
        check_grid_size("--hours/--step", grid_samples(span_s, dt))
        x_true = setup.true_orbit(orbit, scenario, allow_subsurface=allow_subsurface)
        prop = _model_pair(truth, stm)
        t = np.arange(0.0, span_s + 0.5 * dt, dt)
        sig = r_signature(prop, x_true, t, setup.tracking(scenario).theta0_rad)
        if json_out:
            print_json({"t_s": sig.t_s, "R": sig.r})
            return
        table = Table(title=f"R(t) {orbit} ({truth},{stm})")
        table.add_column("t (h)", justify="right")
        table.add_column("R", justify="right")
        for k in np.linspace(0, len(t) - 1, 9).astype(int):
            table.add_row(f"{t[k] / 3600:.1f}", f"{sig.r[k]:.6g}")
        Console(width=80).print(table)

    run_guarded(body)

"""``tapp dc``, ``tapp ekf``, ``tapp rsig``: the approximate-STM study's estimators.

Exit codes of ``tapp dc`` (the outcomes of :mod:`tapp.od.batch`; the output is printed and
``--save-obs`` written, after the DC and with its report, in each of them):

= ============================================================================================
0 converged: the RMS settled within the fit limit
3 diverged: the RMS grew, or failed to settle within the iteration limit
4 ill-conditioned: the normal matrix of the first iteration is too ill-conditioned for the
  data to determine the state; its condition number and the undetermined state directions
  are printed, and the DC does not iterate
5 stalled: the RMS settled above the fit limit (the data are not fitted)
6 converging: the iteration limit was reached while the RMS was still falling geometrically;
  the observed contraction factor and the projected iterations to the fit limit are printed
7 converged, residuals inconsistent with the noise model: the RMS settled within the fit
  limit but above the RMS a correct model exceeds with probability 0.1 % (the 99.9 % χ²
  bound of the residuals and the 6 estimated parameters, :func:`tapp.od.batch.rms_bound`):
  the data are not explained by the models and their σ, and the estimate may be far from
  the orbit (a wrong Earth orientation, force model, station or σ)
= ============================================================================================

The residual RMS and its bound are printed (JSON: ``rms``, ``rms_bound``,
``noise_model_probability``) with every outcome but ill-conditioned.

Earth orientation: every command uses the study file's ``earth_orientation`` and ``eop``
(:mod:`tapp.od.setup`) for the stations and the geopotential of the data and the estimator;
``--earth-orientation iau2006|gmst`` overrides the file's model. The outputs say which model
was used, the EOP source and whether predicted EOP were used (JSON: ``earth_orientation``).
Observations simulated here, and written by ``--save-obs`` or ``tapp simulate --tdm``,
record the model, EOP source and frame they were made under (:mod:`tapp.io.obsfile`); read
with ``--obs`` they are checked against the run's (:func:`tapp.od.setup.check_made_under`):
a mismatch is bad input (2), naming both and ``--earth-orientation``, unless that option
chose the run's model, which then fits them regardless with a note on stderr; a file that
states nothing (one written by another tool) is taken as made under the run's model, with a
note on stderr. JSON: ``observations_made_under`` (null when the file states nothing).
``tapp rsig`` reads no observations.

Bad input (2) includes an ``--arc`` without its unit (a duration is a number and one of
s, m, h, d: ``24h``, ``90m``, ``3600s``, ``2d``; a bare ``24`` is refused, naming those
forms), an arc longer than the data span (``--arc`` and the span named), an arc too short
to hold the measurements the estimator needs (``tapp dc`` 6, ``tapp ekf`` 1) where a longer
one would (``--arc`` and the time by which the data hold them named), an unknown
``--earth-orientation`` and an epoch or span outside the EOP table; data that hold too few
measurements in all fail like any computation that cannot start (1, "too few
measurements"). Observation files (``--obs``, ``--save-obs``): HDF5,
CSV, or a CCSDS TDM in KVN (``.tdm``; :mod:`tapp.io.obsfile`, :mod:`tapp.io.ccsds.tdm`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from tapp.cli.common import (
    EarthOrientationOpt,
    JsonOpt,
    app,
    check_grid_size,
    delivering,
    earth_orientation_option,
    grid_samples,
    json_file,
    nonnegative_option,
    run_guarded,
    seed_option,
)
from tapp.cli.durations import (
    DURATION_FORMS,
    parse_duration_s,
    span_option,
    step_option,
    warn_deprecated,
)
from tapp.errors import InputError, TooFewMeasurementsError

if TYPE_CHECKING:
    import numpy as np

    from tapp.dynamics import Propagator
    from tapp.frames.orientation import EarthOrientation
    from tapp.measurements.observations import Observations
    from tapp.od.batch import DCResult, DCSettings, IllConditionedError
    from tapp.od.rate import PredictedRate
    from tapp.od.setup import Study

_APRIORI_KEYS = ("sx", "sy", "sz", "svx", "svy", "svz")
#: Exit codes of ``tapp dc`` per outcome (module docstring); its output is still printed.
EXIT_DIVERGED = 3
EXIT_ILL_CONDITIONED = 4
EXIT_STALLED = 5
EXIT_CONVERGING = 6
EXIT_INCONSISTENT = 7

OrbitOpt = Annotated[str, typer.Option(help="Orbit name (SATORB1..8) or a=..,e=..,i=..,"
                                       "raan=..,argp=..,M=.. (km, deg)")]
TruthOpt = Annotated[str, typer.Option(help="State model of the data and the estimator.")]
StmOpt = Annotated[str, typer.Option(help="Variational model of the estimator.")]
ScenarioOpt = Annotated[Path | None, typer.Option(
    help="Study scenario file [default: the shipped approx_stm.toml].")]
SubsurfaceOpt = Annotated[bool, typer.Option(
    "--allow-subsurface", help="Accept an orbit whose perigee is below the Earth's surface.")]


def _short_arc(exc: TooFewMeasurementsError, data: Observations, arc: str
               ) -> InputError | TooFewMeasurementsError:
    """The error of an arc (``--arc`` as typed: ``arc``) of ``data`` holding fewer
    measurements than the estimator needs (``exc``): the option's (exit 2), naming the time
    by which the data hold enough, when they do; else ``exc`` (exit 1)."""
    import numpy as np

    if data.count < exc.need:
        return exc
    rows = math.ceil(exc.need / len(data.kinds))  # a row holds one value of each kind
    enough_s = float(np.sort(data.t_s)[rows - 1])
    return InputError("--arc", "value", f"an arc holding at least {exc.need} measurement"
                      f"{'s' if exc.need > 1 else ''} (it holds {exc.got}; these data hold "
                      f"them by t = {enough_s:.0f} s)", arc)


def _scenario(scenario: Path | None) -> Path:
    """The ``--scenario`` file, or the shipped approximate-STM study's."""
    from tapp.examples import STUDY_FILE

    return STUDY_FILE if scenario is None else scenario


def _read(path: Path, earth_orientation: str | None) -> tuple[Study, EarthOrientation]:
    """The study file, read once, and the run's Earth orientation: the file's, or
    ``--earth-orientation``'s model (the option checked first)."""
    from tapp.od import setup

    model = earth_orientation_option(earth_orientation)
    study = setup.read_study(path)
    return study, setup.orientation(study, model)


def _model_pair(truth: str, stm: str, orient: EarthOrientation) -> Propagator:
    """The estimator's (state model, variational model) pair from the CLI options."""
    from tapp.dynamics import Propagator
    from tapp.od import setup

    return Propagator(setup.force_model(truth, orient, "--truth", "model"),
                      setup.force_model(stm, orient, "--stm", "model"))


def _observations(x_true: np.ndarray, truth: str, stations: str | None, obs_file: Path | None,
                  study: Study, seed: int | None, orient: EarthOrientation,
                  chosen: bool) -> Observations:
    """The observations of ``--obs``, checked against the run's Earth orientation (``chosen``:
    by ``--earth-orientation``; :func:`tapp.od.setup.check_made_under`, whose note goes to
    stderr), or simulated under it."""
    from tapp.io.obsfile import read_observations
    from tapp.io.stations_file import load_stations
    from tapp.od import setup

    if obs_file is not None:
        obs = read_observations(obs_file, load_stations(study.data, str(study.path)),
                                setup.tracking(study).sigma, epoch=setup.epoch(study),
                                sigma_kinds=setup.KINDS)
        note = setup.check_made_under(obs, orient, str(obs_file), study, chosen)
        if note is not None:
            typer.echo(f"note: {note}", err=True)
        return obs
    return setup.simulated_observations(x_true, truth, _network(x_true, stations, study),
                                        study, seed, orient=orient)


def _made_under_json(data: Observations) -> dict[str, str] | None:
    """What the observations state they were made under (None: their file states none)."""
    return None if data.made_under is None else data.made_under.as_dict()


def _spacecraft(orbit: str) -> str:
    """The spacecraft's name in a TDM: the orbit's name, or SPACECRAFT for an element set."""
    return orbit if orbit.replace("_", "").replace("-", "").isalnum() else "SPACECRAFT"


def _settings(study: Study, max_iter: int | None) -> DCSettings:
    """The scenario's [dc_settings], with ``--max-iter`` in place of its iteration limit."""
    from tapp.od.batch import MAX_ITERATIONS, DCSettings

    table = study.file.dc_settings.model_dump()
    if max_iter is not None:
        if not 2 <= max_iter <= MAX_ITERATIONS:
            raise InputError("--max-iter", "value", f"a whole number in 2 .. "
                             f"{MAX_ITERATIONS:,} (two RMS values tell a falling RMS from a "
                             "rising one)", max_iter)
        table["max_iterations"] = max_iter
    return DCSettings(**table)


def _rate(data: Observations, prop: Propagator, x_true: np.ndarray, orient: EarthOrientation
          ) -> PredictedRate | None:
    import numpy as np

    from tapp.od.rate import predicted_rate

    try:
        return predicted_rate(data, prop.state_model, prop.var_model, x_true, orient)
    except np.linalg.LinAlgError:
        return None


def _eigen_json(rate: PredictedRate | None) -> list[dict[str, float]] | None:
    if rate is None:
        return None
    return [{"re": float(v.real), "im": float(v.imag), "abs": float(abs(v))}
            for v in rate.eigenvalues]


def _network(x_true: np.ndarray, stations: str | None, study: Study) -> tuple:
    """The stations named by ``--stations`` (or the scenario's default for the orbit); an
    unknown name is the option's fault and names ``--stations``."""
    from tapp.od import setup

    default = setup.network_for(x_true, None, study)  # a bad file names the file
    if stations is None:
        return default
    try:
        return setup.network_for(x_true, stations, study)
    except InputError as exc:
        if exc.field != "networks":
            raise
        raise InputError("--stations", "name", exc.expected, stations) from None


def _elements_dict(x: np.ndarray) -> dict[str, float]:
    import numpy as np

    from tapp.constants import GM_EARTH_km3_s2
    from tapp.orbit.elements import cartesian_to_elements

    a, e, i, raan, argp, mean = np.asarray(cartesian_to_elements(x, GM_EARTH_km3_s2), float)
    return {"a_km": a, "e": e, "i_deg": math.degrees(i), "raan_deg": math.degrees(raan),
            "argp_deg": math.degrees(argp), "M_deg": math.degrees(mean)}


def _exit_code(status: str) -> int:
    """The exit code of a DC outcome (module docstring)."""
    from tapp.od.batch import DCOutcome

    return {DCOutcome.CONVERGED: 0, DCOutcome.DIVERGED: EXIT_DIVERGED,
            DCOutcome.STALLED: EXIT_STALLED, DCOutcome.CONVERGING: EXIT_CONVERGING,
            DCOutcome.INCONSISTENT: EXIT_INCONSISTENT}[DCOutcome(status)]


@app.command()
def dc(
    orbit: OrbitOpt,
    arc: Annotated[str, typer.Option(help=f"Arc length with its unit: {DURATION_FORMS}.")]
    = "24h",
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    stations: Annotated[str | None, typer.Option(
        help="Network or station name [default: the scenario's network for the orbit].")]
    = None,
    max_iter: Annotated[int | None, typer.Option(help="Iteration limit, 2..10000 [default: "
                                                 "the scenario's [dc_settings]].")] = None,
    seed: Annotated[int | None, typer.Option(help="Noise seed [default: the scenario's].")]
    = None,
    obs: Annotated[Path | None, typer.Option(help="Observation file (.h5, .csv or a CCSDS "
                                             "TDM .tdm) instead of simulated data.")] = None,
    save_obs: Annotated[Path | None, typer.Option(help="Write the observations used (.h5, "
                                                  ".csv or .tdm).")] = None,
    scenario: ScenarioOpt = None,
    allow_subsurface: SubsurfaceOpt = False,
    earth_orientation: EarthOrientationOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """Batch differential correction from the brief's offset initial estimate.

    Exit 0 converged, 3 diverged, 4 ill-conditioned, 5 stalled, 6 converging (the limit was
    reached while converging), 7 converged with residuals inconsistent with the noise model
    (RMS above its 99.9 % χ² bound); the predicted rate ρ is printed beside the observed
    factor, the RMS beside its bound.
    """

    def body() -> int:
        import numpy as np

        from tapp.io.obsfile import observations_file_writer
        from tapp.io.outputs import OutputSet, check_paths
        from tapp.od import setup
        from tapp.od.batch import (
            NOISE_MODEL_PROBABILITY,
            IllConditionedError,
            differential_correction,
        )

        path = _scenario(scenario)
        check_paths({"--obs": obs, "--scenario": path},
                    {"--save-obs": save_obs, "--json": json_file(json_out)})
        arc_s = parse_duration_s(arc)
        study = setup.read_study(path)
        settings = _settings(study, max_iter)
        orient = setup.orientation(study, earth_orientation_option(earth_orientation))
        x_true = setup.true_orbit(orbit, study, allow_subsurface=allow_subsurface)
        prop = _model_pair(truth, stm, orient)
        data = _observations(x_true, truth, stations, obs, study,
                             seed_option("--seed", seed), orient, earth_orientation is not None)
        window = data.arc(arc_s, "--arc", got=arc)
        used = setup.orientation_record(orient, window.t_s)
        outputs = OutputSet()
        if save_obs is not None:
            notes = (f"observations of {orbit} for tapp dc (scenario {path.name})",
                     f"read from {obs.name}" if obs is not None else "simulated with Earth "
                     f"orientation {setup.describe_orientation(used)}")
            outputs.add("--save-obs", save_obs, observations_file_writer(
                save_obs, data, epoch=setup.epoch(study), spacecraft=_spacecraft(orbit),
                comments=notes))
        x_start = setup.initial_estimate(x_true, setup.offset(study))
        try:
            result = differential_correction(window, prop, x_start, orientation=orient,
                                             settings=settings)
        except TooFewMeasurementsError as exc:
            raise _short_arc(exc, data, arc) from None
        except IllConditionedError as exc:
            with delivering(json_out, _ill_conditioned_dict(exc, used), outputs) as report:
                if report:
                    _print_ill_conditioned(exc, used)
            return EXIT_ILL_CONDITIONED
        rate = _rate(window, prop, x_true, orient)
        err_km = float(np.linalg.norm(result.x0[:3] - x_true[:3]))
        code = _exit_code(result.status)
        q = result.contraction_factor
        content = {
            "converged": result.converged, "status": result.status, "exit_code": code,
            "reason": result.reason, "iterations": len(result.iterations),
            "converged_at": result.converged_at, "rms": result.rms,
            "rms_bound": result.rms_bound, "noise_model_probability": NOISE_MODEL_PROBABILITY,
            "contraction_factor": q if np.isfinite(q) else None,
            "projected_iterations": result.projected_iterations,
            "predicted_rate": None if rate is None else rate.rho,
            "eigenvalues": _eigen_json(rate), "final_elements": _elements_dict(result.x0),
            "position_error_km": err_km, "measurements": result.n_measurements,
            "earth_orientation": used, "observations_made_under": _made_under_json(window)}
        with delivering(json_out, content, outputs) as report:
            if report:
                _print_dc(result, rate, f"DC {orbit}, {arc}, ({truth},{stm}), {orient.model}: "
                          f"{result.status}", err_km, used)
        return code

    code = run_guarded(body)
    if code:
        raise typer.Exit(code)


def _print_dc(result, rate: PredictedRate | None, title: str, err_km: float, used: dict
              ) -> None:
    import numpy as np
    from rich.console import Console
    from rich.table import Table

    from tapp.od import setup

    table = Table(title=title)
    table.add_column("iteration", justify="right")
    table.add_column("RMS", justify="right")
    table.add_column("|δr| (m)", justify="right")
    table.add_column("|δx|_N", justify="right")
    for it in result.iterations:
        table.add_row(str(it.index), f"{it.rms:.4f}",
                      f"{np.linalg.norm(it.correction[:3]) * 1e3:.3f}", f"{it.step:.4g}")
    console = Console(width=100)
    console.print(table)
    q = result.contraction_factor
    observed = f"observed contraction factor q = {q:.4g}" if np.isfinite(q) else \
        "no contraction factor (one iteration)"
    if rate is None:
        predicted = "predicted rate ρ: none (singular normal matrix at the true state)"
    else:
        lead = ", ".join(f"{v.real:.4g}{v.imag:+.4g}i" if abs(v.imag) > 0 else f"{v.real:.4g}"
                         for v in rate.eigenvalues[:2])
        predicted = f"predicted rate ρ = {rate.rho:.4g} (largest eigenvalues of M: {lead})"
    console.print(f"{result.status}: {result.reason}")
    console.print(_noise_model_line(result))
    console.print(f"{predicted}; {observed}")
    console.print(f"{result.n_measurements} measurements; epoch position error "
                  f"{err_km * 1e3:.3f} m")
    console.print(f"Earth orientation: {setup.describe_orientation(used)}")


def _noise_model_line(result: DCResult) -> str:
    """The last RMS against the noise model's bound, and the verdict where there is an
    estimate to judge (the RMS settled within the fit limit: :mod:`tapp.od.batch`).

    A stalled DC's RMS settled too, above the fit limit: its one verdict is its outcome
    (the data are not fitted), and the line gives the numbers only.
    """
    from tapp.od.batch import N_STATE, NOISE_MODEL_PROBABILITY, DCOutcome

    verdict = {DCOutcome.CONVERGED: ": consistent with the noise model",
               DCOutcome.INCONSISTENT: ": inconsistent with the noise model",
               DCOutcome.STALLED: ""}.get(
        DCOutcome(result.status), f": not judged ({result.status}: no settled estimate)")
    return (f"residuals: RMS {result.rms[-1]:.5g} against {result.rms_bound:.5g}, the "
            f"{100 * NOISE_MODEL_PROBABILITY:g} % χ² bound of {result.n_measurements} "
            f"residuals and {N_STATE} estimated parameters{verdict}")


def _ill_conditioned_dict(exc: IllConditionedError, used: dict) -> dict:
    import numpy as np

    from tapp.od.batch import STATE_NAMES

    return {"converged": False, "status": "ill-conditioned",
            "exit_code": EXIT_ILL_CONDITIONED, "reason": str(exc),
            "condition_number": exc.condition if np.isfinite(exc.condition) else None,
            "max_condition": exc.limit, "measurements": exc.n_measurements,
            "undetermined_directions": [
                {"relative_eigenvalue": float(lam),
                 **{n: float(c) for n, c in zip(STATE_NAMES, d, strict=True)}}
                for d, lam in zip(exc.directions, exc.eigenvalues, strict=True)],
            "earth_orientation": used}


def _print_ill_conditioned(exc: IllConditionedError, used: dict) -> None:
    from rich.console import Console

    from tapp.od import setup
    from tapp.od.batch import describe_direction

    console = Console(width=100)
    console.print(f"ill-conditioned: the normal matrix of the first iteration has condition "
                  f"number {exc.condition:.3g} (scaled to a unit diagonal; limit "
                  f"{exc.limit:.3g}) with {exc.n_measurements} measurements; not iterated")
    console.print("state directions the data do not determine (unit vectors of the scaled "
                  "state, relative eigenvalue):")
    for d, lam in zip(exc.directions, exc.eigenvalues, strict=True):
        console.print(f"  {describe_direction(d)}   ({lam:.3g})")
    console.print(f"Earth orientation: {setup.describe_orientation(used)}")


def _apriori(text: str, study: Study) -> np.ndarray:
    import numpy as np

    table = study.data.get("ekf", {}).get("apriori", {})
    if text in table:  # the scenario's a priori: a bad one is the file's fault, not --apriori
        try:
            sig = np.asarray(table[text], dtype=float)
        except (TypeError, ValueError):
            sig = np.empty(0)
        if sig.shape != (6,) or not np.all(np.isfinite(sig)) or np.any(sig <= 0):
            raise InputError(str(study.path), f"ekf.apriori.{text}",
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
    arc: Annotated[str, typer.Option(help=f"Arc length with its unit: {DURATION_FORMS}.")]
    = "18h",
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    apriori: Annotated[str, typer.Option(help="1|2|3|4 (the brief's) or sx=..,sy=..,sz=..,"
                                         "svx=..,svy=..,svz=.. (km, km/s)")] = "1",
    stations: Annotated[str | None, typer.Option(
        help="Network or station name [default: the scenario's network for the orbit].")]
    = None,
    process_noise: Annotated[float, typer.Option(help="White-noise acceleration spectral "
                                                 "density q (km^2/s^3).")] = 0.0,
    seed: Annotated[int | None, typer.Option(help="Noise seed [default: the scenario's].")]
    = None,
    obs: Annotated[Path | None, typer.Option(help="Observation file (.h5, .csv or a CCSDS "
                                             "TDM .tdm).")] = None,
    scenario: ScenarioOpt = None,
    allow_subsurface: SubsurfaceOpt = False,
    earth_orientation: EarthOrientationOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """Extended Kalman filter from the brief's offset state; largest |O-C| per pass."""

    def body() -> None:
        from rich.console import Console
        from rich.table import Table

        from tapp.io.outputs import check_paths
        from tapp.od import setup
        from tapp.od.ekf import extended_kalman_filter

        path = _scenario(scenario)
        check_paths({"--obs": obs, "--scenario": path}, {"--json": json_file(json_out)})
        arc_s = parse_duration_s(arc)
        study, orient = _read(path, earth_orientation)
        x_true = setup.true_orbit(orbit, study, allow_subsurface=allow_subsurface)
        prop = _model_pair(truth, stm, orient)
        p0 = _apriori(apriori, study)
        q_km2_s3 = nonnegative_option("--process-noise", process_noise)
        every = _observations(x_true, truth, stations, obs, study,
                              seed_option("--seed", seed), orient, earth_orientation is not None)
        data = every.arc(arc_s, "--arc", got=arc)
        used = setup.orientation_record(orient, data.t_s)
        x_start = setup.initial_estimate(x_true, setup.offset(study))
        try:
            result = extended_kalman_filter(data, prop, x_start, p0, orientation=orient,
                                            q_km2_s3=q_km2_s3)
        except TooFewMeasurementsError as exc:
            raise _short_arc(exc, every, arc) from None
        per_pass = [{"range_m": p.max_abs[0] * 1e3, "range_rate_mm_s": p.max_abs[1] * 1e6}
                    for p in result.passes]
        content = {"passes": [{"station": p.station, "t_start_s": p.t_start_s,
                               "t_end_s": p.t_end_s} for p in result.passes],
                   "max_abs_residual_per_pass": per_pass, "earth_orientation": used,
                   "observations_made_under": _made_under_json(data)}
        with delivering(json_out, content) as report:
            if report:
                table = Table(title=f"EKF {orbit}, {arc}, ({truth},{stm}), a priori {apriori}, "
                              f"{orient.model}")
                for col in ("pass", "station", "start (h)", "max|O-C| range (m)",
                            "max|O-C| range-rate (mm/s)"):
                    table.add_column(col, justify="right")
                for k, (p, r) in enumerate(zip(result.passes, per_pass, strict=True), start=1):
                    table.add_row(str(k), p.station, f"{p.t_start_s / 3600:.2f}",
                                  f"{r['range_m']:.1f}", f"{r['range_rate_mm_s']:.1f}")
                console = Console(width=110)
                console.print(table)
                console.print(f"Earth orientation: {setup.describe_orientation(used)}")

    run_guarded(body)


@app.command()
def rsig(
    orbit: OrbitOpt,
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    span: Annotated[str | None, typer.Option(
        help=f"Span with its unit: {DURATION_FORMS} [default: 48h].")] = None,
    step: Annotated[str, typer.Option(help=f"Output step with its unit: {DURATION_FORMS}.")]
    = "300s",
    hours: Annotated[float | None, typer.Option(
        help="Span, hours (deprecated: --span 48h).", hidden=True)] = None,
    scenario: ScenarioOpt = None,
    allow_subsurface: SubsurfaceOpt = False,
    earth_orientation: EarthOrientationOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """The error-growth signature R(t) = sqrt(Σ_{i<=3, j<=6} φ_ij²)."""

    def body() -> None:
        import numpy as np
        from rich.console import Console
        from rich.table import Table

        from tapp.io.outputs import check_paths
        from tapp.od import setup
        from tapp.od.rsig import r_signature

        path = _scenario(scenario)
        check_paths({"--scenario": path}, {"--json": json_file(json_out)})
        span_s = span_option("--span", span, hours, "48h")
        dt = step_option(step)
        check_grid_size("--span/--step", grid_samples(span_s, dt))
        study, orient = _read(path, earth_orientation)
        x_true = setup.true_orbit(orbit, study, allow_subsurface=allow_subsurface)
        prop = _model_pair(truth, stm, orient)
        t = np.arange(0.0, span_s + 0.5 * dt, dt)
        orient.check_covers(t[[0, -1]], "--span")
        sig = r_signature(prop, x_true, t, orient)
        used = setup.orientation_record(orient, t)
        with delivering(json_out, {"t_s": sig.t_s, "R": sig.r, "earth_orientation": used}
                        ) as report:
            if report:
                table = Table(title=f"R(t) {orbit} ({truth},{stm}), {orient.model}")
                table.add_column("t (h)", justify="right")
                table.add_column("R", justify="right")
                for k in np.linspace(0, len(t) - 1, 9).astype(int):
                    table.add_row(f"{t[k] / 3600:.1f}", f"{sig.r[k]:.6g}")
                console = Console(width=80)
                console.print(table)
                console.print(f"Earth orientation: {setup.describe_orientation(used)}")
        warn_deprecated("--span", hours, step)

    run_guarded(body)

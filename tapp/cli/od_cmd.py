"""``tapp dc``, ``tapp ekf``, ``tapp rsig``: the approximate-STM study's estimators.

The commands are thin wrappers over the front door (:mod:`tapp.api.od`: ``fit``, ``ekf``,
``rsig``; the runs themselves are :mod:`tapp.od.runs`): they parse the options, print the
result's report or JSON and map the outcome to an exit code.

Exit codes of ``tapp dc`` (the outcomes of :mod:`tapp.od.batch`, :mod:`tapp.od.exits`; the
output is printed and ``--save-obs`` written, after the DC and with its report, in each of
them):

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
(:mod:`tapp.od.study_schema`, :mod:`tapp.od.setup`) for the stations and the geopotential of
the data and the estimator; ``--earth-orientation iau2006|gmst`` overrides the file's model.
The outputs say which model was used, the EOP source and whether predicted EOP were used (JSON:
``earth_orientation``). Observations simulated here, and written by ``--save-obs`` or ``tapp
simulate --tdm``, record the model, EOP source and frame they were made under
(:mod:`tapp.io.obsfile`); read with ``--obs`` they are checked against the run's
(:func:`tapp.od.setup.check_made_under`): a mismatch is bad input (2), naming both and
``--earth-orientation``, unless that option chose the run's model, which then fits them
regardless with a note on stderr; a file that states nothing (one written by another tool) is
taken as made under the run's model, with a note on stderr. JSON: ``observations_made_under``
(null when the file states nothing). ``tapp rsig`` reads no observations.

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

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from tapp.cli.common import (
    EarthOrientationOpt,
    JsonOpt,
    app,
    delivering,
    json_file,
    run_guarded,
)
from tapp.cli.durations import span_option, step_option, warn_deprecated
from tapp.io.options import DURATION_FORMS
from tapp.od.exits import EXIT_ILL_CONDITIONED

if TYPE_CHECKING:
    from tapp.io.outputs import OutputSet
    from tapp.od.runs import FitRun, IllConditionedFit
    from tapp.report.od_runs import Printout

OrbitOpt = Annotated[str, typer.Option(help="Orbit name (SATORB1..8) or a=..,e=..,i=..,"
                                       "raan=..,argp=..,M=.. (km, deg)")]
TruthOpt = Annotated[str, typer.Option(help="State model of the data and the estimator.")]
StmOpt = Annotated[str, typer.Option(help="Variational model of the estimator.")]
ScenarioOpt = Annotated[Path | None, typer.Option(
    help="Study scenario file [default: the shipped approx_stm.toml].")]
SubsurfaceOpt = Annotated[bool, typer.Option(
    "--allow-subsurface", help="Accept an orbit whose perigee is below the Earth's surface.")]
StationsOpt = Annotated[str | None, typer.Option(
    help="Network or station name [default: the scenario's network for the orbit].")]
SeedOpt = Annotated[int | None, typer.Option(help="Noise seed [default: the scenario's].")]


def _scenario(scenario: Path | None) -> Path:
    """The ``--scenario`` file, or the shipped approximate-STM study's."""
    from tapp.examples import STUDY_FILE

    return STUDY_FILE if scenario is None else scenario


def _note(note: str) -> None:
    """A note of the observations' check, on stderr as it is made."""
    typer.echo(f"note: {note}", err=True)


def _print(printout: Printout) -> None:
    """A report on standard output (styled on a terminal)."""
    from rich.console import Console

    printout.print(Console(width=printout.width))


def _spacecraft(orbit: str) -> str:
    """The spacecraft's name in a TDM: the orbit's name, or SPACECRAFT for an element set."""
    return orbit if orbit.replace("_", "").replace("-", "").isalnum() else "SPACECRAFT"


def _save_obs(path: Path, run: FitRun | IllConditionedFit, obs: Path | None,
              scenario: Path) -> OutputSet:
    """The ``--save-obs`` file of the observations a DC used (every one, not only the arc's),
    to be written with its report."""
    from tapp.io.obsfile import observations_file_writer
    from tapp.io.outputs import OutputSet
    from tapp.od.setup import describe_orientation
    from tapp.od.study_file import epoch

    s = run.setup
    notes = (f"observations of {s.orbit} for tapp dc (scenario {scenario.name})",
             f"read from {obs.name}" if obs is not None else "simulated with Earth "
             f"orientation {describe_orientation(run.earth_orientation)}")
    outputs = OutputSet()
    outputs.add("--save-obs", path, observations_file_writer(
        path, run.observations, epoch=epoch(s.study), spacecraft=_spacecraft(s.orbit),
        comments=notes))
    return outputs


@app.command()
def dc(
    orbit: OrbitOpt,
    arc: Annotated[str, typer.Option(help=f"Arc length with its unit: {DURATION_FORMS}.")]
    = "24h",
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    stations: StationsOpt = None,
    max_iter: Annotated[int | None, typer.Option(help="Iteration limit, 2..10000 [default: "
                                                 "the scenario's [dc_settings]].")] = None,
    seed: SeedOpt = None,
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
        from tapp.api.od import fit
        from tapp.io.outputs import OutputSet, check_paths
        from tapp.od.runs import IllConditionedFit
        from tapp.report.od_runs import ill_conditioned_json, ill_conditioned_printout

        path = _scenario(scenario)
        check_paths({"--obs": obs, "--scenario": path},
                    {"--save-obs": save_obs, "--json": json_file(json_out)})
        try:
            result = fit(orbit, arc=arc, truth=truth, stm=stm, stations=stations,
                         max_iter=max_iter, seed=seed, obs=obs, study=scenario,
                         allow_subsurface=allow_subsurface,
                         earth_orientation=earth_orientation, notify=_note)
        except IllConditionedFit as exc:
            outputs = OutputSet() if save_obs is None else _save_obs(save_obs, exc, obs, path)
            with delivering(json_out, ill_conditioned_json(exc), outputs) as report:
                if report:
                    _print(ill_conditioned_printout(exc))
            return EXIT_ILL_CONDITIONED
        outputs = OutputSet() if save_obs is None else _save_obs(save_obs, result.run, obs,
                                                                 path)
        with delivering(json_out, result.to_json(), outputs) as report:
            if report:
                _print(result.printout())
        return result.exit_code

    code = run_guarded(body)
    if code:
        raise typer.Exit(code)


@app.command()
def ekf(
    orbit: OrbitOpt,
    arc: Annotated[str, typer.Option(help=f"Arc length with its unit: {DURATION_FORMS}.")]
    = "18h",
    truth: TruthOpt = "J2",
    stm: StmOpt = "J2",
    apriori: Annotated[str, typer.Option(help="1|2|3|4 (the brief's) or sx=..,sy=..,sz=..,"
                                         "svx=..,svy=..,svz=.. (km, km/s)")] = "1",
    stations: StationsOpt = None,
    process_noise: Annotated[float, typer.Option(help="White-noise acceleration spectral "
                                                 "density q (km^2/s^3).")] = 0.0,
    seed: SeedOpt = None,
    obs: Annotated[Path | None, typer.Option(help="Observation file (.h5, .csv or a CCSDS "
                                             "TDM .tdm).")] = None,
    scenario: ScenarioOpt = None,
    allow_subsurface: SubsurfaceOpt = False,
    earth_orientation: EarthOrientationOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """Extended Kalman filter from the brief's offset state; largest |O-C| per pass."""

    def body() -> None:
        from tapp.api.od import ekf as run_ekf
        from tapp.io.outputs import check_paths

        check_paths({"--obs": obs, "--scenario": _scenario(scenario)},
                    {"--json": json_file(json_out)})
        result = run_ekf(orbit, arc=arc, truth=truth, stm=stm, apriori=apriori,
                         stations=stations, process_noise=process_noise, seed=seed, obs=obs,
                         study=scenario, allow_subsurface=allow_subsurface,
                         earth_orientation=earth_orientation, notify=_note)
        with delivering(json_out, result.to_json()) as report:
            if report:
                _print(result.printout())

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
        from tapp.api.od import rsig as run_rsig
        from tapp.io.outputs import check_paths

        check_paths({"--scenario": _scenario(scenario)}, {"--json": json_file(json_out)})
        result = run_rsig(orbit, truth=truth, stm=stm,
                          span=span_option("--span", span, hours, "48h"),
                          step=step_option(step), study=scenario,
                          allow_subsurface=allow_subsurface,
                          earth_orientation=earth_orientation)
        with delivering(json_out, result.to_json()) as report:
            if report:
                _print(result.printout())
        warn_deprecated("--span", hours, step)

    run_guarded(body)

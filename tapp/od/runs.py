"""One DC, EKF or R(t) run on the approximate-STM study's set-up: the programs of ``tapp dc``,
``tapp ekf`` and ``tapp rsig`` and of the front door's :func:`tapp.api.od.fit`,
:func:`~tapp.api.od.ekf` and :func:`~tapp.api.od.rsig`.

Each run reads the study (a :class:`tapp.od.study_file.Study`, or its file), takes the orbit
(a name of its ``[orbits]`` or an element set, :mod:`tapp.io.orbits`), builds the (state,
variational) model pair under the run's Earth orientation (the file's, or the
``earth_orientation`` passed in: :mod:`tapp.od.setup`), takes the observations (simulated
with the state model from the study's tracking, or given: a file or
:class:`~tapp.measurements.observations.Observations`, checked against the run's Earth
orientation by :func:`tapp.od.setup.check_made_under`), cuts the arc and runs the estimator
from the brief's offset initial estimate. The checks run in the order the commands have always
made them, so that an input with two faults is refused for the same one; errors name the
options as the commands spell them (``--arc``, ``--stations``, ``--max-iter``,
``--apriori``, ...).

Durations (``arc``, ``span``, ``step``) are text with a unit (``"24h"``) or seconds
(:func:`tapp.io.options.duration_s`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tapp.dynamics import Propagator
from tapp.errors import InputError, TooFewMeasurementsError
from tapp.frames.orientation import EarthOrientation, check_model
from tapp.io.obsfile import read_observations
from tapp.io.options import (
    check_grid_size,
    check_nonnegative,
    check_seed,
    duration_s,
    grid_samples,
)
from tapp.io.stations_file import load_stations
from tapp.measurements.observations import Observations
from tapp.measurements.stations import Station
from tapp.od import setup
from tapp.od.batch import (
    MAX_ITERATIONS,
    DCResult,
    DCSettings,
    IllConditionedError,
    differential_correction,
)
from tapp.od.ekf import EKFResult, extended_kalman_filter
from tapp.od.rate import PredictedRate, predicted_rate
from tapp.od.rsig import RSignature, r_signature
from tapp.od.study_file import KINDS, Study, epoch, offset, read_study, tracking

#: Name of observations given in memory, in notes and errors (a file's is its path).
MEMORY_OBSERVATIONS = "observations"
#: The a priori σ keys of an ``apriori`` given as text (km, km/s).
APRIORI_KEYS = ("sx", "sy", "sz", "svx", "svy", "svz")

Notify = Callable[[str], None]


@dataclass(frozen=True, slots=True)
class RunSetup:
    """What every run is made of: the study, the orbit as named and its true epoch state
    ``x_true`` (6,) km, km/s, the (state, variational) model specs and the propagator built
    of them, and the run's Earth orientation."""

    study: Study
    orbit: str
    x_true: np.ndarray
    truth: str
    stm: str
    propagator: Propagator
    orientation: EarthOrientation


@dataclass(frozen=True, slots=True)
class FitRun:
    """A batch DC run (:func:`run_dc`).

    Attributes
    ----------
    setup : the study, orbit, models and Earth orientation.
    arc : the arc as given (text or seconds); ``arc_s`` the same in seconds.
    observations : every observation (simulated or given); ``window`` those of the arc.
    earth_orientation : :func:`tapp.od.setup.orientation_record` over the arc.
    x_start : (6,) the brief's offset initial estimate.
    result : the DC (iterations, estimate, covariance, outcome).
    rate : the predicted rate ρ at the true state (None: singular normal matrix there).
    notes : what the observations' check said (:func:`tapp.od.setup.check_made_under`).
    """

    setup: RunSetup
    arc: str | float
    arc_s: float
    observations: Observations
    window: Observations
    earth_orientation: dict
    x_start: np.ndarray
    result: DCResult
    rate: PredictedRate | None
    notes: tuple[str, ...]

    @property
    def position_error_km(self) -> float:
        """|r̂(t0) − r(t0)|, km: the estimate's epoch position against the true orbit."""
        return float(np.linalg.norm(self.result.x0[:3] - self.setup.x_true[:3]))


class IllConditionedFit(IllConditionedError):
    """A DC refused before its first correction (:class:`tapp.od.batch.IllConditionedError`),
    with what the run used: ``setup``, ``observations`` (every one), ``window`` (the arc's)
    and ``earth_orientation`` (:func:`tapp.od.setup.orientation_record` over the arc), for
    reporting it as ``tapp dc`` does (exit 4)."""

    def __init__(self, exc: IllConditionedError, setup: RunSetup, observations: Observations,
                 window: Observations, earth_orientation: dict):
        super().__init__(exc.condition, exc.limit, exc.directions, exc.eigenvalues,
                         exc.n_measurements)
        self.setup = setup
        self.observations = observations
        self.window = window
        self.earth_orientation = earth_orientation


@dataclass(frozen=True, slots=True)
class FilterRun:
    """An EKF run (:func:`run_ekf`): as :class:`FitRun`, with the a priori as given
    (``apriori``) and its covariance ``p0`` (6, 6), the process noise q (km²/s³) and the
    filter's output (gains, covariances, residuals: :class:`tapp.od.ekf.EKFResult`)."""

    setup: RunSetup
    arc: str | float
    arc_s: float
    apriori: str
    p0: np.ndarray
    q_km2_s3: float
    observations: Observations
    window: Observations
    earth_orientation: dict
    x_start: np.ndarray
    result: EKFResult
    notes: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class SignatureRun:
    """An R(t) run (:func:`run_rsig`): the grid's span and step (s), the signature
    (``t_s`` (N,), ``r`` (N,)) and the Earth orientation record over it."""

    setup: RunSetup
    span_s: float
    step_s: float
    signature: RSignature
    earth_orientation: dict


def _read(study: Study | Path | str) -> Study:
    return study if isinstance(study, Study) else read_study(study)


def _run_setup(study: Study, orbit: str, truth: str, stm: str, orient: EarthOrientation,
               allow_subsurface: bool) -> RunSetup:
    """The orbit, then the model pair (a bad spec names ``--truth`` or ``--stm``)."""
    x_true = setup.true_orbit(orbit, study, allow_subsurface=allow_subsurface)
    prop = Propagator(setup.force_model(truth, orient, "--truth", "model"),
                      setup.force_model(stm, orient, "--stm", "model"))
    return RunSetup(study, orbit, x_true, truth, stm, prop, orient)


def _study_and_orientation(study: Study | Path | str, earth_orientation: str | None
                           ) -> tuple[Study, EarthOrientation]:
    """The study, read once, and the run's Earth orientation: the file's, or
    ``earth_orientation`` (checked first, naming ``--earth-orientation``)."""
    if earth_orientation is not None:
        check_model(earth_orientation, "--earth-orientation", "value")
    study = _read(study)
    return study, setup.orientation(study, earth_orientation)


def dc_settings(study: Study, max_iter: int | None) -> DCSettings:
    """The study's ``[dc_settings]``, with ``max_iter`` (``--max-iter``) in place of its
    iteration limit."""
    table = study.file.dc_settings.model_dump()
    if max_iter is not None:
        if not 2 <= max_iter <= MAX_ITERATIONS:
            raise InputError("--max-iter", "value", f"a whole number in 2 .. "
                             f"{MAX_ITERATIONS:,} (two RMS values tell a falling RMS from a "
                             "rising one)", max_iter)
        table["max_iterations"] = max_iter
    return DCSettings(**table)


def _network(run: RunSetup, stations: str | None) -> tuple[Station, ...]:
    """The stations named by ``stations`` (or the study's default for the orbit); an
    unknown name is the option's fault and names ``--stations``."""
    default = setup.network_for(run.x_true, None, run.study)  # a bad file names the file
    if stations is None:
        return default
    try:
        return setup.network_for(run.x_true, stations, run.study)
    except InputError as exc:
        if exc.field != "networks":
            raise
        raise InputError("--stations", "name", exc.expected, stations) from None


def _observations(run: RunSetup, stations: str | None, given: Observations | Path | str | None,
                  seed: int | None, chosen: bool, notify: Notify | None
                  ) -> tuple[Observations, tuple[str, ...]]:
    """The given observations (a file read with the study's stations, σ and epoch), checked
    against the run's Earth orientation (``chosen``: by the caller), with the check's note;
    or the study's observations simulated under it."""
    study = run.study
    if given is None:
        return setup.simulated_observations(run.x_true, run.truth, _network(run, stations),
                                            study, seed, orient=run.orientation), ()
    if isinstance(given, Observations):
        obs, source = given, MEMORY_OBSERVATIONS
    else:
        obs = read_observations(given, load_stations(study.data, str(study.path)),
                                tracking(study).sigma, epoch=epoch(study), sigma_kinds=KINDS)
        source = str(given)
    note = setup.check_made_under(obs, run.orientation, source, study, chosen)
    if note is None:
        return obs, ()
    if notify is not None:
        notify(note)
    return obs, (note,)


@dataclass(frozen=True, slots=True)
class _Arc:
    """The observations of a DC or EKF run: all of them, those of the arc, the Earth
    orientation's record over the arc, the brief's offset initial estimate (6,) and the
    observations' check notes."""

    every: Observations
    window: Observations
    used: dict
    x_start: np.ndarray
    notes: tuple[str, ...]


def _arc(run: RunSetup, arc: str | float, arc_s: float, stations: str | None,
         given: Observations | Path | str | None, seed: int | None, chosen: bool,
         notify: Notify | None) -> _Arc:
    """The observations (:func:`_observations`, ``seed`` checked as ``--seed``) cut to the
    arc (a bad one names ``--arc``), and the run's start."""
    every, notes = _observations(run, stations, given, check_seed("--seed", seed), chosen,
                                 notify)
    window = every.arc(arc_s, "--arc", got=arc)
    return _Arc(every, window, setup.orientation_record(run.orientation, window.t_s),
                setup.initial_estimate(run.x_true, offset(run.study)), notes)


def _short_arc(exc: TooFewMeasurementsError, data: Observations, arc: str | float
               ) -> InputError | TooFewMeasurementsError:
    """The error of an arc (``arc`` as given) of ``data`` holding fewer measurements than
    the estimator needs (``exc``): the option's, naming the time by which the data hold
    enough, when they do; else ``exc`` (the data are too few)."""
    if data.count < exc.need:
        return exc
    rows = math.ceil(exc.need / len(data.kinds))  # a row holds one value of each kind
    enough_s = float(np.sort(data.t_s)[rows - 1])
    return InputError("--arc", "value", f"an arc holding at least {exc.need} measurement"
                      f"{'s' if exc.need > 1 else ''} (it holds {exc.got}; these data hold "
                      f"them by t = {enough_s:.0f} s)", arc)


def _rate(run: RunSetup, data: Observations) -> PredictedRate | None:
    prop = run.propagator
    try:
        return predicted_rate(data, prop.state_model, prop.var_model, run.x_true,
                              run.orientation)
    except np.linalg.LinAlgError:
        return None


def run_dc(study: Study | Path | str, orbit: str, *, arc: str | float = "24h",
           truth: str = "J2", stm: str = "J2", stations: str | None = None,
           max_iter: int | None = None, seed: int | None = None,
           observations: Observations | Path | str | None = None,
           allow_subsurface: bool = False, earth_orientation: str | None = None,
           notify: Notify | None = None) -> FitRun:
    """Run a batch DC of ``orbit`` over ``arc`` from the brief's offset initial estimate
    (module docstring; the arguments are ``tapp dc``'s options).

    ``notify`` is called with the note of the observations' check, if any, as it is made.

    Raises
    ------
    InputError
        Bad input, naming the file and field or the option.
    IllConditionedFit
        The normal matrix of the first iteration is too ill-conditioned to iterate on.
    TooFewMeasurementsError
        Observations too few in all for the DC (6 measurements).
    """
    arc_s = duration_s(arc, "--arc")
    study = _read(study)
    settings = dc_settings(study, max_iter)
    orient = setup.orientation(study, earth_orientation)
    run = _run_setup(study, orbit, truth, stm, orient, allow_subsurface)
    a = _arc(run, arc, arc_s, stations, observations, seed, earth_orientation is not None,
             notify)
    try:
        result = differential_correction(a.window, run.propagator, a.x_start,
                                         orientation=orient, settings=settings)
    except TooFewMeasurementsError as exc:
        raise _short_arc(exc, a.every, arc) from None
    except IllConditionedError as exc:
        raise IllConditionedFit(exc, run, a.every, a.window, a.used) from None
    return FitRun(run, arc, arc_s, a.every, a.window, a.used, a.x_start, result,
                  _rate(run, a.window), a.notes)


def apriori_covariance(apriori: str, study: Study) -> np.ndarray:
    """The a priori covariance (6, 6) of ``apriori``: a label of the study's
    ``[ekf.apriori]`` (a bad one is the file's fault), or ``sx=..,sy=..,sz=..,svx=..,svy=..,
    svz=..`` (σ, km and km/s; a bad one names ``--apriori``)."""
    table = study.data.get("ekf", {}).get("apriori", {})
    if apriori in table:
        try:
            sig = np.asarray(table[apriori], dtype=float)
        except (TypeError, ValueError):
            sig = np.empty(0)
        if not _six_sigmas(sig):
            raise InputError(str(study.path), f"ekf.apriori.{apriori}",
                             "six standard deviations > 0 (km, km/s)", table[apriori])
    else:
        pairs = dict(item.partition("=")[::2] for item in apriori.split(","))
        if set(pairs) != set(APRIORI_KEYS):
            raise InputError("--apriori", "apriori", f"one of {', '.join(table) or 'none'} or "
                             f"{','.join(k + '=..' for k in APRIORI_KEYS)} (km, km/s)", apriori)
        try:
            sig = np.array([float(pairs[k]) for k in APRIORI_KEYS])
        except ValueError:
            raise InputError("--apriori", "apriori", "numbers", apriori) from None
        if not _six_sigmas(sig):
            raise InputError("--apriori", "apriori", "six standard deviations > 0", apriori)
    return np.diag(sig**2)


def _six_sigmas(sig: np.ndarray) -> bool:
    """Whether ``sig`` is six finite standard deviations > 0."""
    return sig.shape == (6,) and bool(np.all(np.isfinite(sig))) and not np.any(sig <= 0)


def run_ekf(study: Study | Path | str, orbit: str, *, arc: str | float = "18h",
            truth: str = "J2", stm: str = "J2", apriori: str = "1",
            stations: str | None = None, process_noise: float = 0.0, seed: int | None = None,
            observations: Observations | Path | str | None = None,
            allow_subsurface: bool = False, earth_orientation: str | None = None,
            notify: Notify | None = None) -> FilterRun:
    """Run the EKF of ``orbit`` over ``arc`` from the brief's offset initial estimate with
    the a priori ``apriori`` and the white-noise acceleration ``process_noise`` (q, km²/s³)
    (module docstring; the arguments are ``tapp ekf``'s options).

    Raises
    ------
    InputError
        Bad input, naming the file and field or the option.
    TooFewMeasurementsError
        No measurement in the observations at all.
    """
    arc_s = duration_s(arc, "--arc")
    study, orient = _study_and_orientation(study, earth_orientation)
    run = _run_setup(study, orbit, truth, stm, orient, allow_subsurface)
    p0 = apriori_covariance(apriori, study)
    q_km2_s3 = check_nonnegative("--process-noise", process_noise)
    a = _arc(run, arc, arc_s, stations, observations, seed, earth_orientation is not None,
             notify)
    try:
        result = extended_kalman_filter(a.window, run.propagator, a.x_start, p0,
                                        orientation=orient, q_km2_s3=q_km2_s3)
    except TooFewMeasurementsError as exc:
        raise _short_arc(exc, a.every, arc) from None
    return FilterRun(run, arc, arc_s, apriori, p0, q_km2_s3, a.every, a.window, a.used,
                     a.x_start, result, a.notes)


def run_rsig(study: Study | Path | str, orbit: str, *, truth: str = "J2", stm: str = "J2",
             span: str | float = "48h", step: str | float = "300s",
             allow_subsurface: bool = False, earth_orientation: str | None = None
             ) -> SignatureRun:
    """The error-growth signature R(t) of ``orbit`` under the (``truth``, ``stm``) pair on
    the grid 0, step, ..., span (:mod:`tapp.od.rsig`; the arguments are ``tapp rsig``'s
    options).

    Raises
    ------
    InputError
        Bad input (a grid of more than :data:`tapp.io.options.MAX_GRID_SAMPLES` samples, a
        span outside the EOP table, ...), naming the file and field or the option.
    """
    span_s = duration_s(span, "--span")
    step_s = duration_s(step, "--step")
    check_grid_size("--span/--step", grid_samples(span_s, step_s))
    study, orient = _study_and_orientation(study, earth_orientation)
    run = _run_setup(study, orbit, truth, stm, orient, allow_subsurface)
    t = np.arange(0.0, span_s + 0.5 * step_s, step_s)
    orient.check_covers(t[[0, -1]], "--span")
    sig = r_signature(run.propagator, run.x_true, t, orient)
    return SignatureRun(run, span_s, step_s, sig, setup.orientation_record(orient, t))

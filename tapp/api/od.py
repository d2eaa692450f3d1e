"""``fit``, ``ekf``, ``rsig``: the approximate-STM study's estimators on one orbit (a batch
DC, an extended Kalman filter, the error-growth signature R(t)), each result rendering what
``tapp dc``, ``tapp ekf`` and ``tapp rsig`` print and write with ``--json``.

The study is a :class:`~tapp.od.study_file.Study` or its file; given none, the shipped
``approx_stm.toml`` (:data:`tapp.examples.STUDY_FILE`), as the commands without
``--scenario``. The options are the commands' (:mod:`tapp.od.runs`), durations as text with
a unit (``"24h"``) or seconds. The run's internals are the results' fields: each DC
iteration's estimate, RMS, correction and covariance, and (recomputed on demand) its
trajectory, STMs, residuals and partials; each EKF row's residuals, states, covariances,
gains and process noise::

    import tapp
    dc = tapp.fit("SATORB1", arc="6h")
    dc.status, dc.iterations[-1].rms
    lin = dc.linearisation()        # the last iteration's: lin.stm (M, 6, 6), lin.partials
    kf = tapp.ekf("SATORB1", arc="3h", apriori="2")
    kf.result.gains                 # (M, 6, k)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from tapp.measurements.observations import Observations
from tapp.od.batch import DCIteration, DCResult, Linearisation, linearise
from tapp.od.ekf import EKFResult
from tapp.od.exits import exit_code
from tapp.od.rsig import RSignature
from tapp.od.runs import (
    FilterRun,
    FitRun,
    IllConditionedFit,
    Notify,
    SignatureRun,
    run_dc,
    run_ekf,
    run_rsig,
)
from tapp.od.study_file import Study, shipped_study
from tapp.report.figures import subplots
from tapp.report.od_runs import (
    Printout,
    dc_json,
    dc_printout,
    draw_dc_rms,
    draw_ekf_residuals,
    draw_rsig,
    ekf_json,
    ekf_printout,
    rsig_json,
    rsig_printout,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["FilterResult", "FitResult", "IllConditionedFit", "RSigResult", "ekf", "fit",
           "rsig"]

StudyInput = Study | Path | str | None


def _study(study: StudyInput) -> Study | Path | str:
    """The study given, or the shipped one (read once)."""
    return shipped_study() if study is None else study


def _own_axes(ax: Axes | None) -> Axes:
    if ax is None:
        _, ax = subplots(figsize=(6.4, 4.0))
    return ax


@dataclass(frozen=True, slots=True)
class FitResult:
    """A batch DC (:class:`tapp.od.runs.FitRun`: the set-up, the observations and the arc's
    window, the DC's iterations and outcome, the predicted rate)."""

    run: FitRun

    @property
    def result(self) -> DCResult:
        """The DC: iterations, final estimate (6,) and covariance (6, 6), outcome."""
        return self.run.result

    @property
    def status(self) -> str:
        """The outcome (:class:`tapp.od.batch.DCOutcome`)."""
        return self.run.result.status

    @property
    def exit_code(self) -> int:
        """``tapp dc``'s exit code of the outcome (:mod:`tapp.od.exits`)."""
        return exit_code(self.run.result.status)

    @property
    def iterations(self) -> tuple[DCIteration, ...]:
        """Each iteration's start x0 (6,), RMS, correction δx (6,), covariance (6, 6) and
        step |δx|_N."""
        return self.run.result.iterations

    def linearisation(self, iteration: int = -1) -> Linearisation:
        """The linearisation of one iteration (default the last, about the final estimate):
        the reference trajectory (M, 6), its STM Φ_M(t_i, t0) (M, 6, 6), the residuals
        (M, k) and the partials H̃ and H = H̃Φ (M, k, 6), recomputed from the iteration's start
        (:func:`tapp.od.batch.linearise`: the DC keeps none of them, the same numbers).

        Raises
        ------
        IndexError
            No such iteration.
        """
        x0 = self.run.result.iterations[iteration].x0
        s = self.run.setup
        return linearise(self.run.window, s.propagator, x0, s.orientation)

    def to_json(self) -> dict:
        """What ``tapp dc --json`` writes (:func:`tapp.report.od_runs.dc_json`)."""
        return dc_json(self.run)

    def printout(self) -> Printout:
        """What ``tapp dc`` prints, as renderables (:class:`tapp.report.od_runs.Printout`)."""
        return dc_printout(self.run)

    def text(self) -> str:
        """What ``tapp dc`` prints (to a file or a pipe)."""
        return self.printout().text()

    def plot(self, ax: Axes | None = None) -> Axes:
        """Draw the RMS of each iteration and the noise model's bound on ``ax`` or on a new
        figure's axes (:func:`tapp.report.figures.subplots`); return the axes."""
        ax = _own_axes(ax)
        draw_dc_rms(ax, self.run)
        return ax


@dataclass(frozen=True, slots=True)
class FilterResult:
    """An EKF run (:class:`tapp.od.runs.FilterRun`)."""

    run: FilterRun

    @property
    def result(self) -> EKFResult:
        """The filter: final estimate and covariance, and per measurement row the prefit
        residuals, states, covariances, gains and process noise."""
        return self.run.result

    def to_json(self) -> dict:
        """What ``tapp ekf --json`` writes (:func:`tapp.report.od_runs.ekf_json`)."""
        return ekf_json(self.run)

    def printout(self) -> Printout:
        """What ``tapp ekf`` prints, as renderables."""
        return ekf_printout(self.run)

    def text(self) -> str:
        """What ``tapp ekf`` prints (to a file or a pipe)."""
        return self.printout().text()

    def plot(self, ax: Axes | None = None) -> Axes:
        """Draw the prefit residuals (σ) of each kind against time on ``ax`` or on a new
        figure's axes; return the axes."""
        ax = _own_axes(ax)
        draw_ekf_residuals(ax, self.run)
        return ax


@dataclass(frozen=True, slots=True)
class RSigResult:
    """An R(t) run (:class:`tapp.od.runs.SignatureRun`)."""

    run: SignatureRun

    @property
    def signature(self) -> RSignature:
        """R(t): ``t_s`` (N,) s from the epoch, ``r`` (N,)."""
        return self.run.signature

    def to_json(self) -> dict:
        """What ``tapp rsig --json`` writes (:func:`tapp.report.od_runs.rsig_json`)."""
        return rsig_json(self.run)

    def printout(self) -> Printout:
        """What ``tapp rsig`` prints, as renderables."""
        return rsig_printout(self.run)

    def text(self) -> str:
        """What ``tapp rsig`` prints (to a file or a pipe)."""
        return self.printout().text()

    def plot(self, ax: Axes | None = None) -> Axes:
        """Draw R(t) on ``ax`` or on a new figure's axes; return the axes."""
        ax = _own_axes(ax)
        draw_rsig(ax, self.run)
        return ax


def fit(orbit: str, *, arc: str | float = "24h", truth: str = "J2", stm: str = "J2",
        stations: str | None = None, max_iter: int | None = None, seed: int | None = None,
        obs: Observations | Path | str | None = None, study: StudyInput = None,
        allow_subsurface: bool = False, earth_orientation: str | None = None,
        notify: Notify | None = None) -> FitResult:
    """Run a batch differential correction from the brief's offset initial estimate, as
    ``tapp dc`` does; return its iterations, outcome and renderings.

    Parameters
    ----------
    orbit : a name of the study's ``[orbits]`` or an element set
        (``a=..,e=..,i=..,raan=..,argp=..,M=..``, km and deg).
    arc : the arc from the epoch: text with a unit (``"24h"``) or seconds.
    truth, stm : the state model (of the data and the estimator) and the variational model.
    stations : a network or station of the study (default: its network for the orbit).
    max_iter : iteration limit, 2..10000 (default: the study's ``[dc_settings]``).
    seed : noise seed of the simulated data (default: the study's).
    obs : observations instead of simulated ones: a file (.h5, .csv, .tdm) or in memory.
    study : the study or its file (default: the shipped ``approx_stm.toml``).
    allow_subsurface : accept an orbit whose perigee is below the Earth's surface.
    earth_orientation : "iau2006" or "gmst", in place of the study file's model.
    notify : called with the note of the observations' check (a file that states no
        Earth orientation, or another than the one chosen), also kept in ``run.notes``.

    Raises
    ------
    InputError
        Bad input, as ``tapp dc`` reports it (exit 2).
    IllConditionedFit
        The normal matrix of the first iteration is too ill-conditioned (exit 4); it holds
        what the run used, for :func:`tapp.report.od_runs.ill_conditioned_json`.
    TooFewMeasurementsError
        Observations too few in all for a DC (exit 1).
    """
    return FitResult(run_dc(_study(study), orbit, arc=arc, truth=truth, stm=stm,
                            stations=stations, max_iter=max_iter, seed=seed, observations=obs,
                            allow_subsurface=allow_subsurface,
                            earth_orientation=earth_orientation, notify=notify))


def ekf(orbit: str, *, arc: str | float = "18h", truth: str = "J2", stm: str = "J2",
        apriori: str = "1", stations: str | None = None, process_noise: float = 0.0,
        seed: int | None = None, obs: Observations | Path | str | None = None,
        study: StudyInput = None, allow_subsurface: bool = False,
        earth_orientation: str | None = None, notify: Notify | None = None) -> FilterResult:
    """Run the extended Kalman filter from the brief's offset initial estimate, as ``tapp
    ekf`` does; return its residuals, gains and covariances and their renderings.

    Parameters
    ----------
    apriori : a label of the study's ``[ekf.apriori]`` ("1".."4" in the shipped one) or
        ``sx=..,sy=..,sz=..,svx=..,svy=..,svz=..`` (σ, km and km/s).
    process_noise : white-noise acceleration spectral density q, km²/s³.
    orbit, arc, truth, stm, stations, seed, obs, study, allow_subsurface, earth_orientation,
    notify : as :func:`fit`.

    Raises
    ------
    InputError
        Bad input, as ``tapp ekf`` reports it (exit 2).
    TooFewMeasurementsError
        No measurement in the observations at all (exit 1).
    """
    return FilterResult(run_ekf(_study(study), orbit, arc=arc, truth=truth, stm=stm,
                                apriori=apriori, stations=stations,
                                process_noise=process_noise, seed=seed, observations=obs,
                                allow_subsurface=allow_subsurface,
                                earth_orientation=earth_orientation, notify=notify))


def rsig(orbit: str, *, truth: str = "J2", stm: str = "J2", span: str | float = "48h",
         step: str | float = "300s", study: StudyInput = None, allow_subsurface: bool = False,
         earth_orientation: str | None = None) -> RSigResult:
    """The error-growth signature R(t) = sqrt(Σ_{i<=3, j<=6} φ_ij²) of the (``truth``,
    ``stm``) pair on the grid 0, step, ..., span (text with a unit, or seconds), as ``tapp
    rsig`` computes it; the other arguments as :func:`fit`.

    Raises
    ------
    InputError
        Bad input, as ``tapp rsig`` reports it (exit 2).
    """
    return RSigResult(run_rsig(_study(study), orbit, truth=truth, stm=stm, span=span,
                               step=step, allow_subsurface=allow_subsurface,
                               earth_orientation=earth_orientation))


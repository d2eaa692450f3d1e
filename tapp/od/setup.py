"""The approximate-STM study's set-up read from its scenario file.

Everything a DC, EKF or R(t) run needs besides the models: the true orbits, the station
networks, the tracking (data rate, span, noise, seed) and the brief's initial offset. The CLI
commands and the study runner share these functions so a single run and the full study use
the same data. The file is read and validated once, into a :class:`Study` value
(:func:`read_study`), and every function here takes that value; given none, they take the
shipped study's (:func:`shipped_study`, read once).

The study file (the shipped ``approx_stm.toml``, :data:`tapp.examples.STUDY_FILE`) is
validated as a whole against one schema, :class:`StudyFile` (``tapp.io.schema``: unknown keys
and sections are errors, booleans are not numbers, ...): ``epoch``, ``[orbits.NAME]``
(:class:`tapp.io.orbits.OrbitTable`), ``[stations.NAME]`` and ``[networks]``
(:mod:`tapp.io.stations_file`), ``[tracking]``, ``[noise.fit]`` (:mod:`tapp.io.noise_file`),
``[initial_offset]``, ``[dc_settings]``, ``[[dc]]``, ``[ekf]`` with ``[ekf.apriori]``,
``[rsig]``, ``[rate_vs_arc]`` and ``[rate_vs_inclination]`` (reference:
``docs/reference/study.md``). The runs name their models as every file does: ``gravity`` (the
state model, which simulates the data) and ``var_gravity`` (the variational models, one run
each); ``truth``, ``stm`` and ``[tracking]``'s σ keys are refused, naming the new key. Gravity
specs are checked by :func:`tapp.dynamics.parse_gravity`, orbit and station names against
their tables.

Earth orientation: top-level ``earth_orientation`` ("iau2006", the default, or "gmst"; see
:mod:`tapp.frames.orientation`) and ``eop`` ("iers", the default, "none" or a finals2000A file
path relative to the study file). One model serves everything a run computes: the stations of
the simulated data and of the estimator, and the geopotential of every force model built here
(:func:`force_model`). :func:`orientation` builds it once per study and model (a CLI's
``--earth-orientation`` passes its model in place of the file's) and checks that the EOP
table covers the epoch and the tracking span.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import Field, model_validator

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import ForceModel, Propagator, earth_model
from tapp.errors import InputError
from tapp.examples import STUDY_FILE
from tapp.frames.orientation import EarthOrientation, check_model
from tapp.frames.time import Epoch, parse_epoch
from tapp.io.eop_file import orientation_for
from tapp.io.models_file import GravityName
from tapp.io.noise_file import FitTable
from tapp.io.orbits import OrbitTable, parse_orbit
from tapp.io.schema import EarthOrientationName, EopSource, Invalid, Schema, UtcDate, validate
from tapp.io.stations_file import StationsSection, load_network
from tapp.io.tomlfile import read_toml
from tapp.measurements.observations import MadeUnder, Observations, simulate
from tapp.measurements.stations import Station
from tapp.od.batch import MAX_ITERATIONS
from tapp.orbit.elements import cartesian_to_elements, elements_to_cartesian

Positive = Annotated[float, Field(gt=0)]
#: The observable kinds of the study's tracking, in the order of ``Tracking.sigma``.
KINDS = ("range", "range_rate")


class StudyTracking(Schema):
    """``[tracking]``: the study's simulated tracking (its DATASIM): a file per orbit and
    gravity model, sampled while a station sees the spacecraft above its mask."""

    renamed_keys = {key: f"[noise.fit] {key}" for key in ("sigma_range_m",
                                                            "sigma_range_rate_mm_s")}

    data_interval_s: Positive = Field(description="Time between samples of each station.")
    span_days: Positive = Field(description="Span of each simulated observation file, from "
                                "the epoch; a run's arc is cut from it.")
    seed: Annotated[int, Field(ge=0)] = Field(0, description="Seed of the simulated noise "
                                              "(numpy SeedSequence).")
    equatorial_below_deg: Annotated[float, Field(gt=0, le=180)] = Field(
        description="Orbits inclined below this track from the network 'equatorial', the "
        "others from 'global', when a run names no network.")


class StudyNoise(Schema):
    """``[noise]``: the white noise of the simulated data, which every fit also assumes."""

    fit: FitTable = Field(description="σ of range and range rate (the study tracks no angles).")

    @model_validator(mode="after")
    def _range_and_range_rate(self) -> StudyNoise:
        for key in ("sigma_azimuth_deg", "sigma_elevation_deg"):
            if getattr(self.fit, key) is not None:
                raise Invalid("no angle σ (the study tracks range and range rate)",
                              getattr(self.fit, key), f"fit.{key}")
        for key in ("sigma_range_m", "sigma_range_rate_mm_s"):
            if getattr(self.fit, key) is None:
                raise Invalid("a value (the study tracks range and range rate)", None,
                              f"fit.{key}")
        return self


class InitialOffset(Schema):
    """``[initial_offset]``: the brief's initial estimate, an error added to the true
    elements of every orbit: Δa (m), Δe, Δi (deg).

    ``de`` is added to each orbit's e (the brief: e = 0.00012 for the circular orbits,
    0.10012 for SATORB7). ``e`` instead *sets* e for every orbit: the earlier reading of the
    brief, kept so that study files written for it still read; give one of the two.
    """

    da_m: float = Field(description="Error added to the semi-major axis.")
    de: float | None = Field(None, description="Error added to the eccentricity (or e).",
                             json_schema_extra={"unit": "1"})
    e: Annotated[float, Field(ge=0, lt=1)] | None = Field(
        None, description="The eccentricity every initial estimate starts from, in place of "
        "de (an earlier reading of the brief).", json_schema_extra={"unit": "1"})
    di_deg: float = Field(description="Error added to the inclination.")

    @model_validator(mode="after")
    def _one_e(self) -> InitialOffset:
        if (self.de is None) == (self.e is None):
            raise Invalid("either de (added to e) or e (replacing it), not both",
                          "both" if self.de is not None else "neither", "de")
        return self


class DCSettingsTable(Schema):
    """``[dc_settings]``: the iteration control of every DC run
    (:class:`tapp.od.batch.DCSettings`)."""

    max_iterations: Annotated[int, Field(ge=2, le=MAX_ITERATIONS)] = Field(
        15, description="Iterations at most; a DC still converging then ends as such.")
    rms_rel_tol: Positive = Field(1e-3, description="The weighted RMS has settled when it "
                                  "changes by less than this, relative.",
                                  json_schema_extra={"unit": "1"})
    divergence_ratio: Annotated[float, Field(gt=1)] = Field(
        10.0, description="Diverged when the RMS exceeds this times its smallest value so far.",
        json_schema_extra={"unit": "1"})
    rms_floor: Positive = Field(1e-6, description="Converged when the RMS falls below this "
                                "(a noise-free fit).", json_schema_extra={"unit": "1"})
    rms_fit_limit: Positive = Field(3.0, description="A settled RMS above this is a stall: "
                                    "the data are not fitted.", json_schema_extra={"unit": "1"})
    trend_window: Annotated[int, Field(ge=2)] = Field(
        10, description="Iterations over which the contraction factor is measured (at least).")
    max_condition: Annotated[float, Field(gt=1)] = Field(
        1e10, description="A normal matrix (scaled to a unit diagonal) of a larger condition "
        "number at the first iteration is diagnosed, not iterated on.",
        json_schema_extra={"unit": "1"})


class StudyModels(Schema):
    """The two models of a study run, named as in every other file (the study's own
    ``truth`` and ``stm`` are refused, naming the new key)."""

    renamed_keys = {"truth": "gravity", "stm": "var_gravity"}

    gravity: GravityName = Field(
        description="The Earth's gravity field of the state model: the data are simulated "
        "with it and every fit's trajectory moves under it.")
    var_gravity: Annotated[list[GravityName], Field(min_length=1)] = Field(
        description="The variational models, one run (or curve) each: the Earth field whose "
        "Jacobian drives the fit's STM (the truncated variational equations).")


class DCBlock(StudyModels):
    """One ``[[dc]]`` block: a batch DC for every orbit x variational model x arc."""

    title: str | None = Field(None, description="Heading of the block's table in the report.")
    orbits: Annotated[list[str], Field(min_length=1)] = Field(
        description="Names of [orbits.NAME] tables.")
    arcs_h: Annotated[list[Positive], Field(min_length=1)] = Field(
        description="Arc lengths, from the epoch.")


class EKFBlock(StudyModels):
    """``[ekf]``: an extended Kalman filter for one orbit, every variational model x a priori."""

    title: str = Field("EKF", description="Heading of the EKF table in the report.")
    orbit: str = Field(description="Name of an [orbits.NAME] table.")
    arc_h: Positive = Field(description="Arc length, from the epoch.")
    last_passes: Annotated[int, Field(ge=1)] = Field(
        6, description="Passes at the end of the arc whose largest |O-C| the report shows.")
    apriori: dict[str, Annotated[list[Positive], Field(min_length=6, max_length=6)]] = Field(
        {}, description="A priori σ by label: x, y, z (km), vx, vy, vz (km/s).",
        json_schema_extra={"unit": "km, km/s"})


class RSigBlock(Schema):
    """``[rsig]``: the error-growth signature R(t) of (state, variational) model pairs."""

    orbit: str = Field(description="Name of an [orbits.NAME] table.")
    hours: Positive = Field(description="Span of the curves, from the epoch.",
                            json_schema_extra={"unit": "h"})
    step_s: Positive = Field(description="Sampling of the curves.")
    cases: list[Annotated[list[GravityName], Field(min_length=2, max_length=2)]] = Field(
        description="[gravity, var_gravity] pairs, one curve each.")


class Grid(Schema):
    """A grid ``first``, ``first + step``, ... up to ``last`` (inclusive), in the field's
    units."""

    first: Annotated[float, Field(ge=0)] = Field(description="The first point.")
    last: Annotated[float, Field(ge=0)] = Field(description="The last point (inclusive).")
    step: Positive = Field(description="The spacing (at most 1000 points).")

    @model_validator(mode="after")
    def _ordered(self) -> Grid:
        if self.last < self.first:
            raise Invalid(f"last >= first ({self.first:g})", self.last, "last")
        if (self.last - self.first) / self.step > 1000:
            raise Invalid("at most 1000 grid points", (self.last - self.first) / self.step,
                          "step")
        return self

    def values(self) -> np.ndarray:
        """The grid points (n,)."""
        n = int(math.floor((self.last - self.first) / self.step + 1e-9))
        return self.first + self.step * np.arange(n + 1)


class RateVsArcBlock(StudyModels):
    """``[rate_vs_arc]``: the predicted DC rate ρ against arc length, for one orbit."""

    orbit: str = Field(description="Name of an [orbits.NAME] table.")
    arcs_h: Grid = Field(description="The arc lengths, as a grid {first, last, step} (h).")


class RateVsInclinationBlock(StudyModels):
    """``[rate_vs_inclination]``: ρ against inclination (deg) of ``orbit``'s elements over one
    arc, seen from one ``network`` (the same stations at every inclination)."""

    orbit: str = Field(description="Name of an [orbits.NAME] table given by elements.")
    arc_h: Positive = Field(description="Arc length, from the epoch.")
    network: str = Field(description="A network of [networks], or a station name.")
    inclinations_deg: Grid = Field(description="The inclinations, as a grid {first, last, "
                                   "step} within 0..180 (deg).")

    @model_validator(mode="after")
    def _range(self) -> RateVsInclinationBlock:
        if self.inclinations_deg.last > 180:
            raise Invalid("inclinations within 0..180 deg", self.inclinations_deg.last,
                          "inclinations_deg.last")
        return self


class StudyFile(StationsSection):
    """Schema of the study file."""

    epoch: UtcDate = Field(description="UTC at t = 0: the orbits' epoch and the "
                                     "start of the simulated tracking.")
    earth_orientation: EarthOrientationName = "iau2006"
    eop: EopSource = "iers"
    orbits: dict[str, OrbitTable] = Field({}, description="The true orbits, by name (--orbit "
                                          "NAME).")
    tracking: StudyTracking = Field(description="The simulated tracking.")
    noise: StudyNoise = Field(description="The noise of the simulated data.")
    initial_offset: InitialOffset = Field(description="The error of every initial estimate.")
    dc_settings: DCSettingsTable = Field(DCSettingsTable(), description="Iteration control "
                                         "of every DC.")
    dc: list[DCBlock] = Field([], description="Batch DC runs.")
    ekf: EKFBlock | None = Field(None, description="EKF runs.")
    rsig: RSigBlock | None = Field(None, description="R(t) curves.")
    rate_vs_arc: RateVsArcBlock | None = Field(None, description="ρ against arc length.")
    rate_vs_inclination: RateVsInclinationBlock | None = Field(
        None, description="ρ against inclination.")

    @model_validator(mode="after")
    def _names_exist(self) -> StudyFile:
        known = ", ".join(self.orbits) or "none"
        for i, block in enumerate(self.dc):
            for j, orbit in enumerate(block.orbits):
                if orbit not in self.orbits:
                    raise Invalid(f"an orbit of [orbits.*] ({known})", orbit,
                                  f"dc[{i}].orbits[{j}]")
        for key, block in (("ekf", self.ekf), ("rsig", self.rsig),
                           ("rate_vs_arc", self.rate_vs_arc),
                           ("rate_vs_inclination", self.rate_vs_inclination)):
            if block is not None and block.orbit not in self.orbits:
                raise Invalid(f"an orbit of [orbits.*] ({known})", block.orbit, f"{key}.orbit")
        inc = self.rate_vs_inclination
        if inc is not None and inc.network not in self.networks and inc.network not in \
                self.stations:
            raise Invalid(f"a network of [networks] ({', '.join(self.networks)}) or a station",
                          inc.network, "rate_vs_inclination.network")
        return self


@dataclass(frozen=True, slots=True)
class Tracking:
    """Simulated tracking: sampling (s), span (s), noise (km, km/s), seed, and the
    inclination (rad) below which the equatorial network is the default."""

    data_interval_s: float
    span_s: float
    sigma: np.ndarray
    seed: int
    equatorial_below_rad: float


@dataclass(frozen=True, slots=True)
class Offset:
    """The brief's initial estimate: Δa (km), Δe added (or e set, when ``e`` is given), Δi
    (rad)."""

    da_km: float
    de: float
    di_rad: float
    e: float | None = None


@dataclass(frozen=True, slots=True, eq=False)
class Study:
    """A study file, read and validated once (:func:`read_study`): what every function of this
    module takes.

    Compared and hashed by identity, so that :func:`orientation` builds the Earth orientation
    of one study once per model.

    Attributes
    ----------
    path : Path
        The file: errors name it, and an ``eop`` file path is taken from its folder.
    data : dict
        The parsed TOML (the tables :func:`tapp.io.stations_file.load_network` reads, the
        EKF's a priori).
    file : StudyFile
        The same, validated.
    """

    path: Path
    data: dict
    file: StudyFile


def read_study(path: Path = STUDY_FILE) -> Study:
    """Read and validate a study file; errors name the file and the field."""
    data = read_toml(path)
    return Study(Path(path), data, validate(StudyFile, data, str(path)))


@cache
def shipped_study() -> Study:
    """The shipped study file (:data:`tapp.examples.STUDY_FILE`), read once: the study of
    every function here that is given none."""
    return read_study()


def _or_shipped(study: Study | None) -> Study:
    return shipped_study() if study is None else study


def epoch(study: Study | None = None) -> Epoch:
    """Return the study's epoch (UTC), the t = 0 of its observations."""
    study = _or_shipped(study)
    text = study.file.epoch
    if isinstance(text, dt.datetime):
        text = text.isoformat().removesuffix("+00:00")
    return parse_epoch(text, source=str(study.path))


def tracking(study: Study | None = None) -> Tracking:
    """Return the ``[tracking]`` settings."""
    file = _or_shipped(study).file
    table, fit = file.tracking, file.noise.fit
    sigma = np.array([fit.sigma_range_m * 1e-3, fit.sigma_range_rate_mm_s * 1e-6])
    return Tracking(table.data_interval_s, table.span_days * 86400.0, sigma, table.seed,
                    math.radians(table.equatorial_below_deg))


def earth_orientation_name(study: Study | None = None, model: str | None = None) -> str:
    """Return the Earth orientation model of a run: ``model`` (a CLI override) or the file's."""
    if model is not None:
        return check_model(model, "--earth-orientation", "value")
    return _or_shipped(study).file.earth_orientation


@cache
def _orientation(study: Study, model: str) -> EarthOrientation:
    source = str(study.path)
    orient = orientation_for(model, epoch(study), study.file.eop, study.path.parent, source)
    # the simulated tracking span (observations read from a file are checked as they are used)
    orient.check_covers(np.array([0.0, tracking(study).span_s]), source)
    return orient


def orientation(study: Study | None = None, model: str | None = None) -> EarthOrientation:
    """Return the study's Earth orientation (cached per study and model; module docstring).

    ``model`` overrides the file's ``earth_orientation`` (the CLI's ``--earth-orientation``).

    Raises
    ------
    InputError
        An unknown model (naming ``--earth-orientation``), an unreadable EOP file, or an epoch
        or tracking span outside the EOP table (naming the file and the epoch).
    """
    model = earth_orientation_name(study, model)
    return _orientation(_or_shipped(study), model)


def orientation_record(orient: EarthOrientation, t_s: np.ndarray | None = None) -> dict:
    """The orientation for reports and JSON: ``model``, ``eop`` (its source, "" for gmst) and
    ``predicted_eop`` (True if any time t_s, s from the epoch, lies past the measured EOP)."""
    return {"model": orient.model, "eop": orient.eop_note,
            "predicted_eop": bool(t_s is not None and orient.uses_predicted_eop(t_s))}


def describe_orientation(record: dict) -> str:
    """One line for reports from an :func:`orientation_record`."""
    if record["model"] == "gmst":
        return "gmst (GMST IAU-82 + ω t, UT1 = UTC; no precession, nutation or polar motion)"
    predicted = "; predicted EOP used" if record["predicted_eop"] else ""
    return f"iau2006 (IAU 2006/2000A; EOP {record['eop']}{predicted})"


def _describe_made_under(made: MadeUnder) -> str:
    return f"{made.earth_orientation} (EOP {made.eop}, frame {made.frame})"


def check_made_under(obs: Observations, orient: EarthOrientation, source: str,
                     study: Study | None = None, chosen: bool = False) -> str | None:
    """Check observations read from ``source`` against the run's Earth orientation
    ``orient``; return a note for the user (one line) or None, or raise InputError.

    Where data meet a model: observations made under one Earth orientation and fitted under
    another are off by the difference of the station places (31.5 km at Goldstone between
    iau2006 and gmst on 2026-01-01), and a DC on them settles tens of km from the orbit
    (41.5 km for ``tapp simulate``'s TDM of ``leo_equatorial.toml`` fitted under
    the study's gmst). The file's record (``obs.made_under``, :mod:`tapp.io.obsfile`):

    - states the run's model, EOP source and frame: None;
    - states another, and the run's model is the study file's (``chosen`` False): refused,
      naming the file, the first field that differs, both values and ``--earth-orientation``
      (the option that sets the run's model);
    - states another, and ``--earth-orientation`` chose the run's model (``chosen``): the
      analyst asked for this fit; a note saying what the file states and what is used (a
      DC whose data its model does not explain then fails the noise-model test, exit 7);
    - states nothing: a note, and the data are taken as made under the run's model. Not
      refused, because files written by other tools (the CCSDS examples of
      ``tests/data/ccsds-tdm``, real tracking data) state no model: real data are made by
      the Earth itself, and the model that reduces them is the analyst's choice, which the
      study file or the option makes. Not assumed wrong either, which would be a silent
      answer of its own. A wrong choice still shows in the DC, whose residuals then fail
      the noise-model test (:func:`tapp.od.batch.rms_bound`, exit 7).

    Raises
    ------
    InputError
        A mismatch when not ``chosen`` (above).
    """
    run = MadeUnder.of(orient)
    made = obs.made_under
    if made is None:
        return (f"{source} states no Earth orientation its observations were made under "
                f"(earth_orientation, eop, frame); taken as the fit's, "
                f"{_describe_made_under(run)}")
    if made == run:
        return None
    if chosen:
        return (f"{source} states observations made under {_describe_made_under(made)}; "
                f"fitted under {_describe_made_under(run)} as --earth-orientation asks")
    model, path = run.earth_orientation, _or_shipped(study).path
    rows = (("earth_orientation", "Earth orientation model", f"{path}'s earth_orientation; "
             f"--earth-orientation {made.earth_orientation} fits them under theirs, "
             f"--earth-orientation {model} under {model} regardless"),
            ("eop", "EOP source", f"{path}'s eop; set it to theirs, or "
             f"--earth-orientation {model} fits them regardless"),
            ("frame", "inertial frame", f"that of {model}; --earth-orientation {model} fits "
             "them regardless"))
    # the first field that differs (made != run: there is one)
    key, what, how = next(row for row in rows if getattr(made, row[0]) != getattr(run, row[0]))
    raise InputError(source, key, f"observations made under the fit's {what} "
                     f"{getattr(run, key)} ({how})", getattr(made, key))


def force_model(spec: str, orient: EarthOrientation, source: str, field: str) -> ForceModel:
    """Return the Earth force model of a gravity spec under the run's Earth orientation (a bad
    spec names ``source`` and ``field``)."""
    return earth_model(spec, source=source, field=field, earth_orientation=orient.model)


def offset(study: Study | None = None) -> Offset:
    """Return the ``[initial_offset]`` of the brief."""
    table = _or_shipped(study).file.initial_offset
    return Offset(table.da_m * 1e-3, table.de or 0.0, math.radians(table.di_deg), table.e)


def initial_estimate(x_true: np.ndarray, off: Offset) -> np.ndarray:
    """Return the brief's initial estimate: the elements of x_true (6,) with a + Δa,
    e + Δe (or e := ``off.e`` when set), i + Δi, the other elements unchanged.

    Raises
    ------
    InputError
        The offset makes e negative or >= 1.
    """
    el = np.array(cartesian_to_elements(x_true, GM_EARTH_km3_s2), dtype=float)
    el[0] += off.da_km
    el[1] = el[1] + off.de if off.e is None else off.e
    el[2] += off.di_rad
    if not 0 <= el[1] < 1:
        raise InputError("initial_offset", "de", "an offset leaving 0 <= e < 1", el[1])
    return np.asarray(elements_to_cartesian(el, GM_EARTH_km3_s2), dtype=float)


def true_orbit(spec: str, study: Study | None = None, *, allow_subsurface: bool = False
               ) -> np.ndarray:
    """Return the true initial state of an orbit name (of the study's ``[orbits]``) or spec
    (see :mod:`tapp.io.orbits`).

    ``allow_subsurface`` accepts an orbit whose perigee is below the Earth's surface.
    """
    study = _or_shipped(study)
    return parse_orbit(spec, scenario=study.path, orbits=study.file.orbits,
                       allow_subsurface=allow_subsurface)


def network_for(x_true: np.ndarray, name: str | None, study: Study | None = None
                ) -> tuple[Station, ...]:
    """Return the named network/station, or the default for the orbit's inclination."""
    study = _or_shipped(study)
    if name is None:
        h = np.cross(x_true[:3], x_true[3:])
        inc = math.acos(abs(h[2]) / np.linalg.norm(h))
        name = "equatorial" if inc < tracking(study).equatorial_below_rad else "global"
    return load_network(study.data, str(study.path), name)


def simulated_observations(x_true: np.ndarray, truth_spec: str, stations: tuple[Station, ...],
                           study: Study | None = None, seed: int | None = None,
                           span_s: float | None = None, noise: bool = True,
                           orient: EarthOrientation | None = None) -> Observations:
    """Simulate the study's 5-day observation file for one orbit and truth model.

    ``span_s`` shortens the file (default: the scenario's span); ``noise=False`` gives the
    noise-free values (for a prediction that needs only the times and the stations);
    ``orient`` is the Earth orientation of the stations and of the truth's field (default: the
    file's, :func:`orientation`).
    """
    study = _or_shipped(study)
    orient = orientation(study) if orient is None else orient
    trk = tracking(study)
    span = trk.span_s if span_s is None else min(span_s, trk.span_s)
    t = np.arange(0.0, span + 0.5 * trk.data_interval_s, trk.data_interval_s)
    t = t[t <= span + 1e-9 * max(span, 1.0)]
    rng = np.random.default_rng(trk.seed if seed is None else seed) if noise else None
    truth = Propagator(force_model(truth_spec, orient, str(study.path), "truth"))
    return simulate(truth, x_true, stations, t, trk.sigma, rng, orient)

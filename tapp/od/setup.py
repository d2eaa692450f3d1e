"""The approximate-STM study's set-up read from its scenario file.

Everything a DC, EKF or R(t) run needs besides the models: the true orbits, the station
networks, the tracking (data rate, span, noise, seed) and the brief's initial offset. The CLI
commands and the study runner share these functions so a single run and the full study use
the same data.

The study file (``scenarios/approx_stm.toml``) is validated as a whole against one schema,
:class:`StudyFile` (``tapp.schema``: unknown keys and sections are errors, booleans are not
numbers, ...): ``epoch``, ``[orbits.NAME]`` (:class:`tapp.orbits.OrbitTable`),
``[stations.NAME]`` and ``[networks]`` (:mod:`tapp.stations_file`), ``[tracking]``,
``[initial_offset]``, ``[dc_settings]``, ``[[dc]]``, ``[ekf]`` with ``[ekf.apriori]`` and
``[rsig]``. Gravity specs are checked by :func:`tapp.dynamics.parse_gravity`, orbit and
station names against their tables.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import AfterValidator, Field, model_validator

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import Propagator, earth_model, parse_gravity
from tapp.errors import InputError
from tapp.frames.elements import cartesian_to_elements, elements_to_cartesian
from tapp.frames.time import parse_epoch
from tapp.measurements.stations import Station
from tapp.od.observations import Observations, simulate
from tapp.orbits import DEFAULT_SCENARIO, OrbitTable, parse_orbit
from tapp.schema import Invalid, Schema, validate
from tapp.stations_file import StationTable, load_network
from tapp.tomlfile import read_toml

Positive = Annotated[float, Field(gt=0)]


def _gravity(spec: str) -> str:
    try:
        parse_gravity(spec)
    except InputError as exc:
        raise Invalid(exc.expected) from None
    return spec


#: A gravity spec: J0, Jn or NxM (checked by ``tapp.dynamics.parse_gravity``).
GravityName = Annotated[str, AfterValidator(_gravity)]


class StudyTracking(Schema):
    """``[tracking]``: simulated tracking of the study (units in the names)."""

    data_interval_s: Positive
    span_days: Positive
    sigma_range_m: Positive
    sigma_range_rate_mm_s: Positive
    seed: Annotated[int, Field(ge=0)] = 0
    equatorial_below_deg: Annotated[float, Field(gt=0, le=180)]


class InitialOffset(Schema):
    """``[initial_offset]``: the brief's initial estimate (Δa m, e, Δi deg)."""

    da_m: float
    e: Annotated[float, Field(ge=0, lt=1)]
    di_deg: float


class DCSettingsTable(Schema):
    """``[dc_settings]``: fields of :class:`tapp.od.batch.DCSettings`."""

    max_iterations: Annotated[int, Field(ge=1)] = 15
    rms_rel_tol: Positive = 1e-3
    divergence_ratio: Annotated[float, Field(gt=1)] = 10.0
    rms_floor: Positive = 1e-6
    rms_fit_limit: Positive = 3.0


class DCBlock(Schema):
    """One ``[[dc]]`` block: orbits x STM models x arcs, one truth model."""

    title: str | None = None
    orbits: Annotated[list[str], Field(min_length=1)]
    truth: GravityName
    stm: Annotated[list[GravityName], Field(min_length=1)]
    arcs_h: Annotated[list[Positive], Field(min_length=1)]


class EKFBlock(Schema):
    """``[ekf]``: one orbit and truth, STM models x a priori σ (x, y, z km; vx, vy, vz km/s)."""

    title: str = "EKF"
    orbit: str
    truth: GravityName
    stm: Annotated[list[GravityName], Field(min_length=1)]
    arc_h: Positive
    last_passes: Annotated[int, Field(ge=1)] = 6
    apriori: dict[str, Annotated[list[Positive], Field(min_length=6, max_length=6)]] = {}


class RSigBlock(Schema):
    """``[rsig]``: R(t) curves of (truth, STM) pairs over ``hours`` sampled every ``step_s``."""

    orbit: str
    hours: Positive
    step_s: Positive
    cases: list[Annotated[list[GravityName], Field(min_length=2, max_length=2)]]


class StudyFile(Schema):
    """Schema of the study file (module docstring)."""

    epoch: str | dt.datetime
    orbits: dict[str, OrbitTable] = {}
    stations: dict[str, StationTable] = {}
    networks: dict[str, list[str]] = {}
    tracking: StudyTracking
    initial_offset: InitialOffset
    dc_settings: DCSettingsTable = DCSettingsTable()
    dc: list[DCBlock] = []
    ekf: EKFBlock | None = None
    rsig: RSigBlock | None = None

    @model_validator(mode="after")
    def _names_exist(self) -> StudyFile:
        known = ", ".join(self.orbits) or "none"
        for i, block in enumerate(self.dc):
            for j, orbit in enumerate(block.orbits):
                if orbit not in self.orbits:
                    raise Invalid(f"an orbit of [orbits.*] ({known})", orbit,
                                  f"dc[{i}].orbits[{j}]")
        for key, block in (("ekf", self.ekf), ("rsig", self.rsig)):
            if block is not None and block.orbit not in self.orbits:
                raise Invalid(f"an orbit of [orbits.*] ({known})", block.orbit, f"{key}.orbit")
        for network, names in self.networks.items():
            for i, name in enumerate(names):
                if name not in self.stations:
                    raise Invalid(f"names of [stations.*] tables ({', '.join(self.stations)})",
                                  name, f"networks.{network}[{i}]")
        return self


@dataclass(frozen=True, slots=True)
class Tracking:
    """Simulated tracking: sampling (s), span (s), noise (km, km/s), seed, and the Earth
    rotation angle at the scenario epoch (GMST, rad) shared by the data and the estimators."""

    data_interval_s: float
    span_s: float
    sigma: np.ndarray
    seed: int
    equatorial_below_rad: float
    theta0_rad: float


@dataclass(frozen=True, slots=True)
class Offset:
    """The brief's initial estimate: Δa (km), e replaced, Δi (rad)."""

    da_km: float
    e: float
    di_rad: float


@cache
def _study(path: Path) -> tuple[dict, StudyFile]:
    data = read_toml(path)
    return data, validate(StudyFile, data, str(path))


def study_file(path: Path = DEFAULT_SCENARIO) -> StudyFile:
    """Return the validated study file (cached); errors name the file and the field."""
    return _study(Path(path))[1]


def load_study(path: Path = DEFAULT_SCENARIO) -> dict:
    """Return the parsed study TOML (cached), validated against :class:`StudyFile` first."""
    return _study(Path(path))[0]


def tracking(path: Path = DEFAULT_SCENARIO) -> Tracking:
    """Return the ``[tracking]`` settings."""
    study = study_file(path)
    table = study.tracking
    src = str(path)
    epoch = study.epoch
    if isinstance(epoch, dt.datetime):
        epoch = epoch.isoformat().removesuffix("+00:00")
    sigma = np.array([table.sigma_range_m * 1e-3, table.sigma_range_rate_mm_s * 1e-6])
    return Tracking(table.data_interval_s, table.span_days * 86400.0, sigma, table.seed,
                    math.radians(table.equatorial_below_deg),
                    parse_epoch(epoch, source=src).gmst_rad())


def offset(path: Path = DEFAULT_SCENARIO) -> Offset:
    """Return the ``[initial_offset]`` of the brief."""
    table = study_file(path).initial_offset
    return Offset(table.da_m * 1e-3, table.e, math.radians(table.di_deg))


def initial_estimate(x_true: np.ndarray, off: Offset) -> np.ndarray:
    """Return the brief's initial estimate: elements of x_true with a + Δa, e := e0, i + Δi."""
    el = np.array(cartesian_to_elements(x_true, GM_EARTH_km3_s2), dtype=float)
    el[0] += off.da_km
    el[1] = off.e
    el[2] += off.di_rad
    return np.asarray(elements_to_cartesian(el, GM_EARTH_km3_s2), dtype=float)


def true_orbit(spec: str, path: Path = DEFAULT_SCENARIO, *, allow_subsurface: bool = False
               ) -> np.ndarray:
    """Return the true initial state of an orbit name or spec (see :mod:`tapp.orbits`).

    ``allow_subsurface`` accepts an orbit whose perigee is below the Earth's surface.
    """
    study_file(path)
    return parse_orbit(spec, scenario=path, allow_subsurface=allow_subsurface)


def network_for(x_true: np.ndarray, name: str | None, path: Path = DEFAULT_SCENARIO
                ) -> tuple[Station, ...]:
    """Return the named network/station, or the default for the orbit's inclination."""
    if name is None:
        h = np.cross(x_true[:3], x_true[3:])
        inc = math.acos(abs(h[2]) / np.linalg.norm(h))
        name = "equatorial" if inc < tracking(path).equatorial_below_rad else "global"
    return load_network(load_study(path), str(path), name)


def simulated_observations(x_true: np.ndarray, truth_spec: str, stations: tuple[Station, ...],
                           path: Path = DEFAULT_SCENARIO, seed: int | None = None
                           ) -> Observations:
    """Simulate the study's 5-day observation file for one orbit and truth model."""
    trk = tracking(path)
    t = np.arange(0.0, trk.span_s + 0.5 * trk.data_interval_s, trk.data_interval_s)
    rng = np.random.default_rng(trk.seed if seed is None else seed)
    truth = Propagator(earth_model(truth_spec, source=str(path), field="truth"))
    return simulate(truth, x_true, stations, t, trk.sigma, rng, theta0_rad=trk.theta0_rad)


def named_orbit_names(path: Path = DEFAULT_SCENARIO) -> list[str]:
    """Names of the orbits of the scenario file."""
    return list(study_file(path).orbits)

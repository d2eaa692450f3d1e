"""The approximate-STM study's set-up read from its scenario file.

Everything a DC, EKF or R(t) run needs besides the models: the true orbits, the station
networks, the tracking (data rate, span, noise, seed) and the brief's initial offset. The CLI
commands and the study runner share these functions so a single run and the full study use
the same data.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import Propagator, earth_model
from tapp.errors import InputError
from tapp.frames.elements import cartesian_to_elements, elements_to_cartesian
from tapp.frames.time import parse_epoch
from tapp.measurements.stations import Station
from tapp.od.observations import Observations, simulate
from tapp.orbits import DEFAULT_SCENARIO, named_orbits, parse_orbit
from tapp.stations_file import load_network
from tapp.tomlfile import finite_number, read_toml


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


def _positive(table: Mapping, key: str, source: str) -> float:
    return finite_number(table, key, source, f"tracking.{key}", positive=True)


@cache
def load_study(path: Path = DEFAULT_SCENARIO) -> dict:
    """Return the parsed scenario TOML (cached); errors name the file."""
    return read_toml(path)


def tracking(path: Path = DEFAULT_SCENARIO) -> Tracking:
    """Return the ``[tracking]`` settings."""
    table = load_study(path).get("tracking", {})
    src = str(path)
    sigma = np.array([_positive(table, "sigma_range_m", src) * 1e-3,
                      _positive(table, "sigma_range_rate_mm_s", src) * 1e-6])
    seed = table.get("seed", 0)
    if not isinstance(seed, int) or seed < 0:
        raise InputError(src, "tracking.seed", "an integer >= 0", seed)
    return Tracking(_positive(table, "data_interval_s", src),
                    _positive(table, "span_days", src) * 86400.0, sigma, seed,
                    math.radians(_positive(table, "equatorial_below_deg", src)),
                    parse_epoch(str(load_study(path).get("epoch", "")), source=src).gmst_rad())


def offset(path: Path = DEFAULT_SCENARIO) -> Offset:
    """Return the ``[initial_offset]`` of the brief."""
    table = load_study(path).get("initial_offset", {})
    src = str(path)
    return Offset(finite_number(table, "da_m", src, "initial_offset.da_m") * 1e-3,
                  finite_number(table, "e", src, "initial_offset.e"),
                  math.radians(finite_number(table, "di_deg", src, "initial_offset.di_deg")))


def initial_estimate(x_true: np.ndarray, off: Offset) -> np.ndarray:
    """Return the brief's initial estimate: elements of x_true with a + Δa, e := e0, i + Δi."""
    el = np.array(cartesian_to_elements(x_true, GM_EARTH_km3_s2), dtype=float)
    el[0] += off.da_km
    el[1] = off.e
    el[2] += off.di_rad
    return np.asarray(elements_to_cartesian(el, GM_EARTH_km3_s2), dtype=float)


def true_orbit(spec: str, path: Path = DEFAULT_SCENARIO) -> np.ndarray:
    """Return the true initial state of an orbit name or spec (see :mod:`tapp.orbits`)."""
    return parse_orbit(spec, scenario=path)


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
    return list(named_orbits(path))

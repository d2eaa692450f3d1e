"""Tracking scenarios (TOML) for TAPP I, read into frozen dataclasses; errors name file and field.

A scenario gives the trajectory (epoch, injection state, state and variational force models),
the parameter vector x = [p; q], the tracking stations and schedule, the fit-world and
real-world noise, the T13 times (input times and epoch times) and the miss parameters.
``scenarios/leo_equatorial.toml`` and ``scenarios/deep_space.toml`` are commented examples.

Tables and keys (units in the key names; times are seconds from the epoch, or UTC dates as
ISO strings or TOML dates)::

    title = "..."                   iden = "..."  (tape identification, default: file stem)
    epoch = "2026-01-01T00:00:00"   UTC of the injection, t = 0
    [injection]        r_km = [3], v_km_s = [3]   (EME2000, Earth-centred), or classical
                       elements a_km, e, i_deg, raan_deg, argp_deg and M_deg or nu_deg
    [model]            gravity (J0 | Jn | NxM), third_bodies, var_gravity, var_third_bodies
                       (the variational model: the seed's truncated variational equations;
                       default the state model), rtol, atol
    [parameters]       dynamic = ["GM", "GM_moon", "J2", "C22", ...] (tapp.dynamics.forces
                       names), station_location = "cylindrical" | "ecef" | "none",
                       station_biases = ["range", "range_rate"], [parameters.values] non-nominal
                       values of dynamic parameters
    [stations.NAME]    lat_deg, lon_deg, h_km, elev_mask_deg (tapp.stations_file)
    [tracking]         stations = [names], observables = ["range", "range_rate", "azimuth",
                       "elevation"], light_time = "none" | "one_way" | "two_way",
                       data_interval_s, start, end, min_pass_s, max_pass_s,
                       blackouts = [[start, end], ...]
    [tracking.station.NAME]  per-station observables, location, biases, range_bias_m,
                       range_rate_bias_mm_s (nominal bias values), blackouts, and fit / real
                       tables overriding [noise.fit] / [noise.real] keys
    [noise.fit]        sigma_range_m, sigma_range_rate_mm_s, sigma_azimuth_deg,
                       sigma_elevation_deg (white noise: W = diag(1/σ²))
    [noise.real]       sigma_<kind>_<unit> (white, default the fit σ), bias_<kind>_<unit>
                       (constant per pass), correlated_<kind>_<unit> with tau_<kind>_s
                       (exponentially correlated)
    [times]            input = [times] or input_step_s with end; epochs = [times] (epoch times
                       after t_0 = 0; re-epoching as in seed TAPP III §4.1)
    [miss]             kind = "bplane" (body, reference; b_dot_r_km, b_dot_t_km, ltof_s,
                       flight_time_s) | "equinoctial" (a_km, ex, ey, hx, hy, lambda_m_rad) |
                       "classical" (a_km, e, i_rad, raan_rad, argp_rad, M_rad); time;
                       quantities (default: all of the kind but flight_time_s)
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import numpy as np

from tapp.bplane import REFERENCE_POLES
from tapp.constants import SECONDS_PER_DAY, RADIUS_km
from tapp.dynamics import BODIES, ForceModel, Propagator, earth_model
from tapp.dynamics.forces import default_parameters
from tapp.errors import InputError
from tapp.frames.time import Epoch, parse_epoch
from tapp.measurements import BIAS_NAMES, STATION_PARAMETER_NAMES, Observable
from tapp.measurements.stations import Station
from tapp.orbits import state_from_elements
from tapp.stations_file import load_stations
from tapp.tomlfile import read_toml
from tapp.tracking.noise import EDGE_UNITS, FitNoise, RealNoise

#: Observable kinds, in the order of ``tapp.measurements.Observable``.
KINDS = tuple(o.value for o in Observable)
#: Kinds that can carry a station bias in q (names and units: ``BIAS_NAMES``).
BIAS_KINDS = ("range", "range_rate")
LOCATION_MODES = ("cylindrical", "ecef", "none")
LIGHT_TIME_MODES = ("none", "one_way", "two_way")
#: The p part of x: Cartesian state at the epoch, EME2000, Earth-centred.
ORBIT_PARAMETERS = (("x_km", "km"), ("y_km", "km"), ("z_km", "km"), ("vx_km_s", "km/s"),
                    ("vy_km_s", "km/s"), ("vz_km_s", "km/s"))
#: Miss quantities of each kind, with units.
MISS_QUANTITIES = {
    "bplane": (("b_dot_r_km", "km"), ("b_dot_t_km", "km"), ("ltof_s", "s"),
               ("flight_time_s", "s")),
    "equinoctial": (("a_km", "km"), ("ex", "1"), ("ey", "1"), ("hx", "1"), ("hy", "1"),
                    ("lambda_m_rad", "rad")),
    "classical": (("a_km", "km"), ("e", "1"), ("i_rad", "rad"), ("raan_rad", "rad"),
                  ("argp_rad", "rad"), ("M_rad", "rad")),
}

_TOP = {"title", "iden", "epoch", "injection", "model", "parameters", "stations", "networks",
        "tracking", "noise", "times", "miss"}
_ELEMENTS = ("a_km", "e", "i_deg", "raan_deg", "argp_deg")


@dataclass(frozen=True, slots=True)
class Parameter:
    """One TAPP I parameter: name (with unit), unit, kind, nominal value, station number.

    ``kind`` is "orbit", "dynamic", "location" or "bias"; ``station`` is the station number
    s (1-based) of a location or bias parameter, 0 otherwise.
    """

    name: str
    unit: str
    kind: str
    nominal: float
    station: int = 0


@dataclass(frozen=True, slots=True)
class TrackingStation:
    """A station as tracked in the scenario.

    Attributes
    ----------
    number : station number s on the tape, 1..n_ts.
    station : location and elevation mask.
    kinds : observable kinds it measures.
    fit, real : noise of each kind (same order as ``kinds``).
    location : location parameters in q: "cylindrical", "ecef" or "none".
    biases : kinds among ("range", "range_rate") whose bias is in q.
    range_bias_km, range_rate_bias_km_s : nominal bias values added to the observables.
    blackouts_s : ((start, end), ...) s, no data (the scenario's and the station's own).
    """

    number: int
    station: Station
    kinds: tuple[str, ...]
    fit: tuple[FitNoise, ...]
    real: tuple[RealNoise, ...]
    location: str
    biases: tuple[str, ...]
    range_bias_km: float
    range_rate_bias_km_s: float
    blackouts_s: tuple[tuple[float, float], ...]

    def parameters(self) -> tuple[Parameter, ...]:
        """Its parameters in q: location then biases, named ``<station>.<name>``."""
        out = []
        if self.location != "none":
            values = self.station.location(self.location)
            for pname, value in zip(STATION_PARAMETER_NAMES[self.location], values,
                                    strict=True):
                out.append(Parameter(f"{self.station.name}.{pname}", _unit_of(pname),
                                     "location", float(value), self.number))
        nominal = {"range": self.range_bias_km, "range_rate": self.range_rate_bias_km_s}
        for kind, bname in zip(BIAS_KINDS, BIAS_NAMES, strict=True):
            if kind in self.biases:
                out.append(Parameter(f"{self.station.name}.{bname}", _unit_of(bname), "bias",
                                     nominal[kind], self.number))
        return tuple(out)


@dataclass(frozen=True, slots=True)
class Schedule:
    """When observations are taken.

    Samples fall on t = start_s + i data_interval_s in (0, end_s] (and not after the last
    T13 time), where a station sees the spacecraft above its mask and outside its blackouts
    (:attr:`TrackingStation.blackouts_s`). ``light_time`` is "none", "one_way" or "two_way".
    A pass is a run of consecutive such samples; passes shorter than min_pass_s
    are dropped and longer ones cut after max_pass_s.
    """

    data_interval_s: float
    start_s: float
    end_s: float
    min_pass_s: float
    max_pass_s: float
    light_time: str


@dataclass(frozen=True, slots=True)
class TapeTimes:
    """Input times t̄ and epoch times t̂ (t̂_0 = 0, the injection), seconds, ascending."""

    input_s: tuple[float, ...]
    epochs_s: tuple[float, ...]

    @property
    def t13_s(self) -> np.ndarray:
        """The T13 times t_0 = 0 < t_1 < ... < t_n_it: all input and epoch times, (n_it+1,)."""
        return np.unique(np.array((*self.epochs_s, *self.input_s)))

    @property
    def is_epoch(self) -> np.ndarray:
        """Whether each T13 time is an epoch time, (n_it+1,) bool."""
        return np.isin(self.t13_s, self.epochs_s)

    @property
    def is_input(self) -> np.ndarray:
        """Whether each T13 time is an input time, (n_it+1,) bool."""
        return np.isin(self.t13_s, self.input_s)


@dataclass(frozen=True, slots=True)
class MissSpec:
    """Miss parameters: ``quantities`` of ``kind`` at time ``t_s`` (s from the epoch).

    For "bplane", ``body`` is the target (a third body of the state model) and ``reference``
    the B-plane reference plane (``tapp.bplane.REFERENCE_POLES``).
    """

    kind: str
    t_s: float
    quantities: tuple[str, ...]
    body: str = ""
    reference: str = "earth_equator"

    @property
    def units(self) -> tuple[str, ...]:
        """Unit of each quantity."""
        table = dict(MISS_QUANTITIES[self.kind])
        return tuple(table[q] for q in self.quantities)


@dataclass(frozen=True, slots=True)
class Scenario:
    """A validated TAPP I scenario (module docstring for the file format).

    Attributes
    ----------
    source : the file (for messages and provenance).
    title, iden : free text and tape identification.
    epoch : UTC of the injection, t = 0.
    x0 : (6,) injection state, km and km/s, EME2000, Earth-centred.
    state_model, var_model : force models of the trajectory and of the variational equations.
    rtol, atol : integrator tolerances.
    dynamic : names of the model parameters in q (``tapp.dynamics.forces``).
    dynamic_values : ((name, value), ...) values other than nominal.
    stations : tracking stations, numbered 1..n_ts.
    schedule, times, miss : see their classes.
    document_json : the scenario tables as JSON (tape provenance).
    """

    source: str
    title: str
    iden: str
    epoch: Epoch
    x0: np.ndarray
    state_model: ForceModel
    var_model: ForceModel
    rtol: float
    atol: float
    dynamic: tuple[str, ...]
    dynamic_values: tuple[tuple[str, float], ...]
    stations: tuple[TrackingStation, ...]
    schedule: Schedule
    times: TapeTimes
    miss: MissSpec
    document_json: str

    def propagator(self) -> Propagator:
        """The (state model, variational model, dynamic parameters) propagator."""
        return Propagator(self.state_model, self.var_model, self.dynamic, rtol=self.rtol,
                          atol=self.atol)

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """x = [p; q]: orbit state at the epoch, dynamic parameters, station parameters."""
        out = [Parameter(name, unit, "orbit", float(v))
               for (name, unit), v in zip(ORBIT_PARAMETERS, self.x0, strict=True)]
        values = default_parameters(self.state_model, self.dynamic)
        values.update(dict(self.dynamic_values))
        for name in self.dynamic:
            gm = name == "GM" or name.startswith("GM_")
            out.append(Parameter(f"{name}_km3_s2" if gm else name, "km^3/s^2" if gm else "1",
                                 "dynamic", values[name]))
        for st in self.stations:
            out.extend(st.parameters())
        return tuple(out)

    @property
    def n_p(self) -> int:
        """Number of orbit parameters (6)."""
        return len(ORBIT_PARAMETERS)

    @property
    def n_o(self) -> int:
        """Number of TAPP I parameters."""
        return len(self.parameters)


def _unit_of(name: str) -> str:
    for suffix, unit in (("_km_s", "km/s"), ("_km", "km"), ("_rad", "rad")):
        if name.endswith(suffix):
            return unit
    return "1"


# ---------------------------------------------------------------------------------------------
# Parsing
# ---------------------------------------------------------------------------------------------


class _Parser:
    """Validating accessors that name the file and the dotted field on failure."""

    def __init__(self, source: str, epoch: Epoch | None = None):
        self.source = source
        self.epoch = epoch

    def fail(self, field: str, expected: str, got: object = None) -> NoReturn:
        raise InputError(self.source, field, expected, got)

    def table(self, data: Mapping, key: str, where: str, allowed: set[str], *,
              required: bool = True) -> Mapping:
        value = data.get(key)
        if value is None and not required:
            return {}
        if not isinstance(value, Mapping):
            self.fail(where, "a table", value)
        unknown = sorted(set(value) - allowed)
        if unknown:
            self.fail(f"{where}.{unknown[0]}", f"one of {', '.join(sorted(allowed))}",
                      unknown[0])
        return value

    def number(self, table: Mapping, key: str, where: str, *, default: float | None = None,
               minimum: float | None = None, strict: bool = False) -> float:
        value = table.get(key, default)
        ok = (isinstance(value, int | float) and not isinstance(value, bool)
              and math.isfinite(value))
        if ok and minimum is not None:
            ok = value > minimum if strict else value >= minimum
        if not ok:
            bound = "" if minimum is None else f" {'>' if strict else '>='} {minimum:g}"
            self.fail(f"{where}.{key}" if where else key, f"a finite number{bound}", value)
        return float(value)

    def strings(self, table: Mapping, key: str, where: str, choices: tuple[str, ...] | None,
                default: list | None = None) -> tuple[str, ...]:
        value = table.get(key, default)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            self.fail(f"{where}.{key}", "a list of names", value)
        for v in value:
            if choices is not None and v not in choices:
                self.fail(f"{where}.{key}", f"names among {', '.join(choices)}", v)
        if len(set(value)) != len(value):
            self.fail(f"{where}.{key}", "each name once", value)
        return tuple(value)

    def choice(self, table: Mapping, key: str, where: str, choices: tuple[str, ...],
               default: str) -> str:
        value = table.get(key, default)
        if value not in choices:
            self.fail(f"{where}.{key}", f"one of {', '.join(choices)}", value)
        return value

    def time_s(self, value: object, field: str) -> float:
        """A time: seconds from the epoch (number) or a UTC date (ISO string, TOML date)."""
        if isinstance(value, int | float) and not isinstance(value, bool):
            if not math.isfinite(value):
                self.fail(field, "a finite time (s from the epoch) or a UTC date", value)
            return float(value)
        if isinstance(value, dt.datetime) and value.tzinfo not in (None, dt.UTC):
            self.fail(field, "a UTC date", value)
        if isinstance(value, dt.datetime | dt.date):
            value = value.isoformat().removesuffix("+00:00")
        if not isinstance(value, str):
            self.fail(field, "a time in s from the epoch or a UTC date string", value)
        try:
            when = parse_epoch(value, self.source)
        except InputError as exc:
            raise InputError(self.source, field, exc.expected, value) from None
        days = (when.jd_whole - self.epoch.jd_whole) + (when.jd_fraction - self.epoch.jd_fraction)
        return days * SECONDS_PER_DAY

    def times(self, table: Mapping, key: str, where: str) -> tuple[float, ...]:
        value = table.get(key, [])
        if not isinstance(value, list):
            self.fail(f"{where}.{key}", "a list of times", value)
        out = tuple(self.time_s(v, f"{where}.{key}[{i}]") for i, v in enumerate(value))
        if any(b <= a for a, b in zip(out, out[1:], strict=False)):
            self.fail(f"{where}.{key}", "times in strictly ascending order", list(out))
        return out

    def windows(self, table: Mapping, key: str, where: str) -> tuple[tuple[float, float], ...]:
        value = table.get(key, [])
        field = f"{where}.{key}"
        if not isinstance(value, list):
            self.fail(field, "a list of [start, end] windows", value)
        out = []
        for i, w in enumerate(value):
            if not isinstance(w, list) or len(w) != 2:
                self.fail(f"{field}[{i}]", "a [start, end] pair", w)
            start, end = (self.time_s(v, f"{field}[{i}]") for v in w)
            if end <= start:
                self.fail(f"{field}[{i}]", "start < end", w)
            out.append((start, end))
        return tuple(out)


def _epoch(p: _Parser, data: Mapping) -> Epoch:
    text = data.get("epoch")
    if isinstance(text, dt.datetime):
        text = text.isoformat().removesuffix("+00:00")
    if not isinstance(text, str):
        p.fail("epoch", "a UTC date (ISO 8601 string)", text)
    return parse_epoch(text, p.source)


def _injection(p: _Parser, data: Mapping) -> np.ndarray:
    inj = p.table(data, "injection", "injection",
                  {"r_km", "v_km_s", *_ELEMENTS, "M_deg", "nu_deg"})
    if "r_km" in inj or "v_km_s" in inj:
        if set(inj) != {"r_km", "v_km_s"}:
            p.fail("injection", "either r_km and v_km_s or classical elements", sorted(inj))
        vectors = []
        for key in ("r_km", "v_km_s"):
            value = inj[key]
            if (not isinstance(value, list) or len(value) != 3 or not all(
                    isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                    for v in value)):
                p.fail(f"injection.{key}", "a list of 3 finite numbers", value)
            vectors.extend(float(v) for v in value)
        x0 = np.array(vectors)
    else:
        anomaly = {"M_deg", "nu_deg"} & set(inj)
        if len(anomaly) != 1:
            p.fail("injection", "elements with exactly one of M_deg, nu_deg", sorted(inj))
        which = anomaly.pop()
        values = [p.number(inj, k, "injection") for k in (*_ELEMENTS, which)]
        x0 = state_from_elements(*values, true_anomaly=which == "nu_deg", source=p.source,
                                 field="injection")
    if np.linalg.norm(x0[:3]) <= RADIUS_km["earth"]:
        p.fail("injection", "a position above the Earth's surface", x0[:3].tolist())
    return x0


def _models(p: _Parser, data: Mapping) -> tuple[ForceModel, ForceModel, float, float]:
    mod = p.table(data, "model", "model", {"gravity", "third_bodies", "var_gravity",
                                           "var_third_bodies", "rtol", "atol"})
    bodies_allowed = tuple(b for b in BODIES if b != "earth")
    gravity = mod.get("gravity")
    if not isinstance(gravity, str):
        p.fail("model.gravity", "a gravity model J0, Jn or NxM", gravity)
    bodies = p.strings(mod, "third_bodies", "model", bodies_allowed, [])
    var_gravity = mod.get("var_gravity", gravity)
    if not isinstance(var_gravity, str):
        p.fail("model.var_gravity", "a gravity model J0, Jn or NxM", var_gravity)
    var_bodies = p.strings(mod, "var_third_bodies", "model", bodies_allowed, list(bodies))
    state = earth_model(gravity, bodies, source=p.source, field="model.gravity")
    var = earth_model(var_gravity, var_bodies, source=p.source, field="model.var_gravity")
    rtol = p.number(mod, "rtol", "model", default=1e-13, minimum=0.0, strict=True)
    atol = p.number(mod, "atol", "model", default=1e-13, minimum=0.0, strict=True)
    return state, var, rtol, atol


def _dynamic(p: _Parser, data: Mapping, state_model: ForceModel
             ) -> tuple[tuple[str, ...], tuple[tuple[str, float], ...], str, tuple[str, ...]]:
    par = p.table(data, "parameters", "parameters",
                  {"dynamic", "station_location", "station_biases", "values"}, required=False)
    dynamic = p.strings(par, "dynamic", "parameters", None, [])
    for name in dynamic:
        try:
            default_parameters(state_model, (name,))
        except InputError as exc:
            raise InputError(p.source, "parameters.dynamic", exc.expected, name) from None
    values = p.table(par, "values", "parameters.values", set(dynamic), required=False)
    chosen = tuple((name, p.number(values, name, "parameters.values")) for name in values)
    location = p.choice(par, "station_location", "parameters", LOCATION_MODES, "none")
    biases = p.strings(par, "station_biases", "parameters", BIAS_KINDS, [])
    return dynamic, chosen, location, biases


def _noise_key(prefix: str, kind: str) -> str:
    return f"{prefix}_{kind}_{EDGE_UNITS[kind][0]}"


def _noise(p: _Parser, kind: str, name: str, fit: Mapping, fit_own: Mapping, real: Mapping,
           real_own: Mapping) -> tuple[FitNoise, RealNoise]:
    """Fit and real noise of one kind at one station: station tables override the globals."""
    factor = EDGE_UNITS[kind][1]
    key = _noise_key("sigma", kind)
    own = f"tracking.station.{name}"
    if key in fit_own:
        sigma = p.number(fit_own, key, f"{own}.fit", minimum=0.0, strict=True)
    elif key in fit:
        sigma = p.number(fit, key, "noise.fit", minimum=0.0, strict=True)
    else:
        p.fail(f"noise.fit.{key}", f"the fit σ of every observable tracked ({kind} at {name})")
    values = {}
    for prefix, default in (("sigma", sigma), ("bias", 0.0), ("correlated", 0.0)):
        k = _noise_key(prefix, kind)
        table, where = (real_own, f"{own}.real") if k in real_own else (real, "noise.real")
        values[prefix] = p.number(table, k, where, default=default, minimum=0.0)
    tau_key = f"tau_{kind}_s"
    table, where = (real_own, f"{own}.real") if tau_key in real_own else (real, "noise.real")
    tau = math.inf
    if values["correlated"] > 0 or tau_key in table:
        tau = p.number(table, tau_key, where, minimum=0.0, strict=True)
    return (FitNoise(kind, sigma * factor),
            RealNoise(kind, values["sigma"] * factor, values["bias"] * factor,
                      values["correlated"] * factor, tau))


def _noise_keys() -> tuple[set[str], set[str]]:
    fit = {_noise_key("sigma", k) for k in KINDS}
    real = fit | {_noise_key(pre, k) for pre in ("bias", "correlated") for k in KINDS}
    return fit, real | {f"tau_{k}_s" for k in KINDS}


def _stations(p: _Parser, data: Mapping, location: str, biases: tuple[str, ...]
              ) -> tuple[tuple[TrackingStation, ...], Mapping]:
    known = load_stations(data, p.source)
    trk = p.table(data, "tracking", "tracking",
                  {"stations", "observables", "light_time", "data_interval_s", "start", "end",
                   "min_pass_s", "max_pass_s", "blackouts", "station"})
    names = p.strings(trk, "stations", "tracking", None)
    if not names:
        p.fail("tracking.stations", "at least one station")
    for name in names:
        if name not in known:
            p.fail("tracking.stations", "names of [stations.*] tables "
                   f"({', '.join(known) or 'none defined'})", name)
    kinds = p.strings(trk, "observables", "tracking", KINDS, ["range", "range_rate"])
    blackouts = p.windows(trk, "blackouts", "tracking")
    fit_keys, real_keys = _noise_keys()
    noise = p.table(data, "noise", "noise", {"fit", "real"})
    fit = p.table(noise, "fit", "noise.fit", fit_keys)
    real = p.table(noise, "real", "noise.real", real_keys, required=False)
    own_all = p.table(trk, "station", "tracking.station", set(names), required=False)
    out = []
    for number, name in enumerate(names, start=1):
        where = f"tracking.station.{name}"
        own = p.table(own_all, name, where,
                      {"observables", "location", "biases", "range_bias_m",
                       "range_rate_bias_mm_s", "blackouts", "fit", "real"}, required=False)
        st_kinds = p.strings(own, "observables", where, KINDS, list(kinds))
        if not st_kinds:
            p.fail(f"{where}.observables", "at least one observable")
        st_location = p.choice(own, "location", where, LOCATION_MODES, location)
        st_biases = p.strings(own, "biases", where, BIAS_KINDS, list(biases))
        for kind in st_biases:
            if kind not in st_kinds:
                p.fail(f"{where}.biases" if "biases" in own else "parameters.station_biases",
                       f"biases of observables that {name} measures ({', '.join(st_kinds)})",
                       kind)
        fit_own = p.table(own, "fit", f"{where}.fit", fit_keys, required=False)
        real_own = p.table(own, "real", f"{where}.real", real_keys, required=False)
        pairs = [_noise(p, kind, name, fit, fit_own, real, real_own) for kind in st_kinds]
        out.append(TrackingStation(
            number=number, station=known[name], kinds=st_kinds,
            fit=tuple(f for f, _ in pairs), real=tuple(r for _, r in pairs),
            location=st_location, biases=st_biases,
            range_bias_km=p.number(own, "range_bias_m", where, default=0.0) * 1e-3,
            range_rate_bias_km_s=p.number(own, "range_rate_bias_mm_s", where,
                                          default=0.0) * 1e-6,
            blackouts_s=blackouts + p.windows(own, "blackouts", where)))
    return tuple(out), trk


def _times(p: _Parser, data: Mapping) -> TapeTimes:
    tim = p.table(data, "times", "times", {"input", "input_step_s", "end", "epochs"})
    if "input" in tim:
        if "input_step_s" in tim:
            p.fail("times", "either input or input_step_s (with end), not both")
        inputs = p.times(tim, "input", "times")
    elif "input_step_s" in tim:
        step = p.number(tim, "input_step_s", "times", minimum=0.0, strict=True)
        if "end" not in tim:
            p.fail("times.end", "the last input time with input_step_s")
        end = p.time_s(tim["end"], "times.end")
        if end <= 0:
            p.fail("times.end", "a time after the injection (> 0 s)", end)
        grid = step * np.arange(1, int(math.floor(end / step * (1 + 1e-15))) + 1)
        inputs = tuple(float(t) for t in grid) + (() if grid.size and grid[-1] == end
                                                  else (end,))
    else:
        p.fail("times.input", "input times (a list), or input_step_s with end")
    if not inputs:
        p.fail("times.input", "at least one input time")
    if inputs[0] <= 0:
        p.fail("times.input", "input times after the injection (> 0 s)", inputs[0])
    epochs = p.times(tim, "epochs", "times")
    if epochs and epochs[0] <= 0:
        p.fail("times.epochs", "epoch times after the injection (> 0 s; t_0 = 0 is implicit)",
               epochs[0])
    if epochs and epochs[-1] > inputs[-1]:
        p.fail("times.epochs", f"epoch times up to the last input time {inputs[-1]:g} s",
               epochs[-1])
    return TapeTimes(inputs, (0.0, *epochs))


def _schedule(p: _Parser, trk: Mapping, last_s: float) -> Schedule:
    interval = p.number(trk, "data_interval_s", "tracking", minimum=0.0, strict=True)
    start = p.time_s(trk.get("start", 0.0), "tracking.start")
    end = p.time_s(trk.get("end", last_s), "tracking.end")
    if start < 0:
        p.fail("tracking.start", "a time at or after the injection (>= 0 s)", start)
    if end <= start:
        p.fail("tracking.end", f"a time after tracking.start = {start:g} s", end)
    light_time = p.choice(trk, "light_time", "tracking", LIGHT_TIME_MODES, "none")
    max_pass = math.inf
    if "max_pass_s" in trk:
        max_pass = p.number(trk, "max_pass_s", "tracking", minimum=0.0, strict=True)
    return Schedule(interval, start, end,
                    p.number(trk, "min_pass_s", "tracking", default=0.0, minimum=0.0),
                    max_pass, light_time)


def _miss(p: _Parser, data: Mapping, state_model: ForceModel, last_s: float) -> MissSpec:
    miss = p.table(data, "miss", "miss", {"kind", "time", "quantities", "body", "reference"})
    kind = p.choice(miss, "kind", "miss", tuple(MISS_QUANTITIES), "")
    names = tuple(n for n, _ in MISS_QUANTITIES[kind])
    default = [n for n in names if n != "flight_time_s"]
    quantities = p.strings(miss, "quantities", "miss", names, default)
    if not quantities:
        p.fail("miss.quantities", "at least one miss quantity")
    t_s = p.time_s(miss.get("time", last_s), "miss.time")
    if t_s <= 0:
        p.fail("miss.time", "a time after the injection (> 0 s)", t_s)
    if kind != "bplane":
        for key in ("body", "reference"):
            if key in miss:
                p.fail(f"miss.{key}", "no body or reference for orbit elements", miss[key])
        return MissSpec(kind, t_s, quantities)
    body = miss.get("body")
    if body not in state_model.third_bodies:
        p.fail("miss.body", f"one of model.third_bodies {list(state_model.third_bodies)}",
               body)
    reference = p.choice(miss, "reference", "miss", tuple(REFERENCE_POLES), "earth_equator")
    return MissSpec(kind, t_s, quantities, body, reference)


def parse_scenario(data: Mapping, source: str) -> Scenario:
    """Build a :class:`Scenario` from parsed TOML tables, validating everything.

    Raises
    ------
    InputError
        Naming ``source`` and the dotted field for any missing, unknown or invalid entry
        (unknown station, observable or parameter, σ <= 0, times not ascending, ...).
    """
    p = _Parser(source)
    unknown = sorted(set(data) - _TOP)
    if unknown:
        p.fail(unknown[0], f"one of {', '.join(sorted(_TOP))}", unknown[0])
    epoch = _epoch(p, data)
    p = _Parser(source, epoch)
    title = data.get("title", "")
    iden = data.get("iden", Path(source).name.split(".")[0])
    for key, value in (("title", title), ("iden", iden)):
        if not isinstance(value, str):
            p.fail(key, "text", value)
    x0 = _injection(p, data)
    state_model, var_model, rtol, atol = _models(p, data)
    dynamic, values, location, biases = _dynamic(p, data, state_model)
    stations, trk = _stations(p, data, location, biases)
    times = _times(p, data)
    last_s = float(times.t13_s[-1])
    schedule = _schedule(p, trk, last_s)
    miss = _miss(p, data, state_model, last_s)
    document = json.dumps(data, default=str, sort_keys=True)
    x0.setflags(write=False)
    return Scenario(source, title, iden, epoch, x0, state_model, var_model, rtol, atol, dynamic,
                    values, stations, schedule, times, miss, document)


def read_scenario(path: Path | str) -> Scenario:
    """Read and validate a scenario file (TOML); errors name the file and the field."""
    return parse_scenario(read_toml(path), str(Path(path)))

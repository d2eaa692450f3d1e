"""A :class:`~tapp.tracking.scenario.Scenario` from a tracking scenario file: read, validated
against :class:`~tapp.tracking.scenario_file.ScenarioFile`, then built table by table with the
rules between tables and the physics; every error names the file and the field.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import NoReturn

import numpy as np

from tapp.dynamics import ForceModel, Propagator
from tapp.dynamics.empirical import COMPONENTS
from tapp.dynamics.ephemeris import tdb_reader
from tapp.dynamics.ephemeris_offsets import offset_of
from tapp.dynamics.forces import check_parameter_value, default_parameters
from tapp.dynamics.manoeuvres import THRUST_NAMES, Burn
from tapp.dynamics.parameters import model_parameter
from tapp.errors import InputError
from tapp.estimation.gauss_markov import StochasticAccelerations
from tapp.frames.orientation import EarthOrientation, eop_parameters_of
from tapp.frames.time import Epoch, parse_epoch
from tapp.frames.timescales import seconds_after
from tapp.io.eop_file import orientation_for
from tapp.io.noise_file import FitTable, NoiseTable, RealTable
from tapp.io.schedule_file import read_schedule
from tapp.io.schema import validate
from tapp.io.tomlfile import read_toml
from tapp.io.trajectory_file import Reference
from tapp.measurements.bands import BANDS, DEFAULT_BAND
from tapp.measurements.doppler import DEFAULT_COUNT_TIME_s, range_rate_from_hz
from tapp.measurements.media import MediaModel, check_meteorology, day_of_year, standard_atmosphere
from tapp.measurements.noise import EDGE_UNITS, FitNoise, RealNoise
from tapp.measurements.stations import Station
from tapp.targeting.program import BPlaneSearch, check_reference
from tapp.targeting.searchfile import scenario_targeting
from tapp.tracking.ddor import tracking_baselines
from tapp.tracking.eop_days import EopDays, eop_days
from tapp.tracking.manoeuvres import scenario_manoeuvres
from tapp.tracking.scenario import (
    MISS_QUANTITIES,
    OPT_IN_MISS,
    MissSpec,
    Scenario,
    Schedule,
    TapeTimes,
    TrackingStation,
)
from tapp.tracking.scenario_file import (
    MAX_INPUT_TIMES,
    MAX_STOCHASTIC,
    MediaTable,
    MissTable,
    ParametersTable,
    ScenarioFile,
    StationTracking,
    StochasticTable,
    TimesTable,
    TrackingTable,
)


class _Parser:
    """Conversions that need the epoch, and failures that name the file and the field."""

    def __init__(self, source: str, epoch: Epoch | None = None):
        self.source = source
        self.epoch = epoch

    def fail(self, field: str, expected: str, got: object = None) -> NoReturn:
        raise InputError(self.source, field, expected, got)

    def time_s(self, value: object, field: str) -> float:
        """A time: seconds from the epoch (number) or a UTC date (ISO string, TOML date)."""
        if isinstance(value, int | float) and not isinstance(value, bool):
            return float(value)
        if isinstance(value, dt.datetime) and value.tzinfo not in (None, dt.UTC):
            self.fail(field, "a UTC date", value)
        if isinstance(value, dt.date):
            value = value.isoformat().removesuffix("+00:00")
        try:
            when = parse_epoch(str(value), self.source)
        except InputError as exc:
            raise InputError(self.source, field, exc.expected, value) from None
        return seconds_after(self.epoch, when, self.source)

    def times(self, values: list, field: str) -> tuple[float, ...]:
        out = tuple(self.time_s(v, f"{field}[{i}]") for i, v in enumerate(values))
        if any(b <= a for a, b in zip(out, out[1:], strict=False)):
            self.fail(field, "times in strictly ascending order", list(out))
        return out

    def windows(self, values: list, field: str) -> tuple[tuple[float, float], ...]:
        out = []
        for i, w in enumerate(values):
            start, end = (self.time_s(v, f"{field}[{i}]") for v in w)
            if end <= start:
                self.fail(f"{field}[{i}]", "start < end", w)
            out.append((start, end))
        return tuple(out)


def _epoch(p: _Parser, value: object) -> Epoch:
    if isinstance(value, dt.datetime):
        if value.tzinfo not in (None, dt.UTC):
            p.fail("epoch", "a UTC date", value)
        value = value.isoformat().removesuffix("+00:00")
    try:
        return parse_epoch(str(value), p.source)
    except InputError as exc:
        raise InputError(p.source, "epoch", exc.expected, value) from None


def _dynamic(p: _Parser, par: ParametersTable, state_model: ForceModel
             ) -> tuple[tuple[str, ...], tuple[tuple[str, float], ...]]:
    dynamic = _canonical_names(p, par.dynamic, "parameters.dynamic")
    for i, name in enumerate(dynamic):
        if name in THRUST_NAMES:
            p.fail(f"parameters.dynamic[{i}]", "a model parameter (a burn's thrust is set by "
                   "its [[manoeuvre]] table)", name)
        try:
            default_parameters(state_model, (name,))
        except InputError as exc:
            raise InputError(p.source, f"parameters.dynamic[{i}]", exc.expected, name) from None
        if (found := offset_of(name)) and found[0] in ("earth", state_model.center):
            p.fail(f"parameters.dynamic[{i}]", "the ephemeris offset of a third body other than "
                   "the Earth (the stations' frame) and the model's centre (the frame of every "
                   "state)", name)
    chosen = []
    for given, value in par.values.items():
        field = f"parameters.values.{given}"
        name = _canonical_names(p, [given], field, indexed=False)[0]
        if name not in dynamic:
            p.fail(field, f"a name of parameters.dynamic ({', '.join(dynamic) or 'none'})",
                   given)
        chosen.append((name, check_parameter_value(name, value, p.source, field)))
    return dynamic, tuple(chosen)


def _canonical_names(p: _Parser, names: list[str], field: str, indexed: bool = True
                     ) -> tuple[str, ...]:
    """``names`` in their one spelling (:mod:`tapp.dynamics.parameters`: an earlier one warns,
    naming ``field[i]``, or ``field`` if not ``indexed``); a name that is no model parameter's
    is left for the force model to refuse with what it expects."""
    out = []
    for i, name in enumerate(names):
        found = model_parameter(name, p.source, f"{field}[{i}]" if indexed else field)
        out.append(name if found is None else found.canonical)
    if len(set(out)) < len(out):
        p.fail(field, "each parameter once (in either spelling)", list(names))
    return tuple(out)


def _noise_key(prefix: str, kind: str) -> str:
    return f"{prefix}_{kind}_{EDGE_UNITS[kind][0]}"


def _noise(p: _Parser, kind: str, name: str, noise: NoiseTable, own: StationTracking,
           band: str = DEFAULT_BAND) -> tuple[FitNoise, RealNoise]:
    """Fit and real noise of one kind at one station: station tables override the globals.
    Doppler's keys may be given in Hz instead, converted at the station's ``band``."""
    factor = EDGE_UNITS[kind][1]
    key = _noise_key("sigma", kind)

    def lookup(table: FitTable | RealTable, prefix: str, where: str) -> float | None:
        value = getattr(table, _noise_key(prefix, kind))
        hz = getattr(table, f"{prefix}_{kind}_hz", None)
        if hz is None:
            return value
        if value is not None:
            p.fail(f"{where}.{prefix}_{kind}_hz",
                   f"one of {_noise_key(prefix, kind)} or {prefix}_{kind}_hz, not both", hz)
        return float(range_rate_from_hz(hz, BANDS[band])) / factor

    sigma = lookup(own.fit, "sigma", f"tracking.station.{name}.fit")
    if sigma is None:
        sigma = lookup(noise.fit, "sigma", "noise.fit")
    if sigma is None:
        p.fail(f"noise.fit.{key}", f"the fit σ of every observable tracked ({kind} at {name})")

    def real(prefix: str) -> float | None:
        value = lookup(own.real, prefix, f"tracking.station.{name}.real")
        return lookup(noise.real, prefix, "noise.real") if value is None else value

    values = {}
    for prefix, default in (("sigma", sigma), ("bias", 0.0), ("correlated", 0.0)):
        value = real(prefix)
        values[prefix] = default if value is None else value
    tau = getattr(own.real, f"tau_{kind}_s")
    where = f"tracking.station.{name}.real"
    if tau is None:
        tau, where = getattr(noise.real, f"tau_{kind}_s"), "noise.real"
    if values["correlated"] > 0 and tau is None:
        p.fail(f"{where}.tau_{kind}_s", f"the time constant of the correlated {kind} noise "
               "(a finite number > 0)")
    return (FitNoise(kind, sigma * factor),
            RealNoise(kind, values["sigma"] * factor, values["bias"] * factor,
                      values["correlated"] * factor, math.inf if tau is None else tau))


def _stations(p: _Parser, doc: ScenarioFile, par: ParametersTable
              ) -> tuple[TrackingStation, ...]:
    trk = doc.tracking
    known = {name: table.station(name) for name, table in doc.stations.items()}
    for i, name in enumerate(trk.stations):
        if name not in known:
            p.fail(f"tracking.stations[{i}]", "names of [stations.*] tables "
                   f"({', '.join(known) or 'none defined'})", name)
    for name in trk.station:
        if name not in trk.stations:
            p.fail(f"tracking.station.{name}",
                   f"a station of tracking.stations ({', '.join(trk.stations)})", name)
    blackouts = p.windows(trk.blackouts, "tracking.blackouts")
    out = []
    for number, name in enumerate(trk.stations, start=1):
        where = f"tracking.station.{name}"
        own = trk.station.get(name, StationTracking())
        kinds = tuple(trk.observables if own.observables is None else own.observables)
        if not kinds:
            p.fail("tracking.observables", "at least one observable")
        location = par.station_location if own.location is None else own.location
        biases = tuple(par.station_biases if own.biases is None else own.biases)
        for kind in biases:
            if kind not in kinds:
                p.fail(f"{where}.biases" if own.biases is not None
                       else "parameters.station_biases",
                       f"biases of observables that {name} measures ({', '.join(kinds)})",
                       kind)
        band = trk.band if own.band is None else own.band
        pairs = [_noise(p, kind, name, doc.noise, own, band) for kind in kinds]
        if ("doppler" in kinds or own.uplink is not None) and trk.light_time != "two_way":
            p.fail("tracking.light_time", f'"two_way" with the count-based doppler or a '
                   f"three-way uplink ({name})", trk.light_time)
        if own.uplink is not None and (own.uplink not in known or own.uplink == name):
            p.fail(f"{where}.uplink", "the name of another [stations.*] table (the station "
                   f"transmitting {name}'s up-leg: {', '.join(n for n in known if n != name)})",
                   own.uplink)
        out.append(TrackingStation(
            number=number, station=known[name], kinds=kinds,
            fit=tuple(f for f, _ in pairs), real=tuple(r for _, r in pairs),
            location=location, biases=biases,
            range_bias_km=own.range_bias_m * 1e-3,
            range_rate_bias_km_s=own.range_rate_bias_mm_s * 1e-6,
            blackouts_s=blackouts + p.windows(own.blackouts, f"{where}.blackouts"),
            band=band,
            media=_station_media(p, doc.media, own, known[name], band, where),
            media_parameters=tuple(par.media), media_per=par.media_per,
            uplink=None if own.uplink is None else known[own.uplink],
            uplink_media=None if own.uplink is None else _uplink_media(
                p, doc.media, trk, own.uplink, known[own.uplink]),
            doppler_bias_km_s=own.doppler_bias_mm_s * 1e-6))
    return tuple(out)


def _uplink_media(p: _Parser, media: MediaTable, trk: TrackingTable, name: str,
                  station: Station) -> MediaModel | None:
    """The :class:`MediaModel` of a three-way uplink station (:func:`_station_media`), from
    its own ``[tracking.station.NAME]`` table whether or not it tracks itself."""
    own = trk.station.get(name, StationTracking())
    return _station_media(p, media, own, station, trk.band if own.band is None else own.band,
                          f"tracking.station.{name}")


def _station_media(p: _Parser, media: MediaTable, own: StationTracking, station: Station,
                   band: str, where: str) -> MediaModel | None:
    """A station's :class:`MediaModel` (None with both effects off): its weather, else the
    standard atmosphere at its height; its zenith TEC, else the scenario's."""
    if not (media.troposphere or media.ionosphere):
        return None
    standard = standard_atmosphere(station.h_km)
    weather = tuple(s if v is None else float(v) for v, s in zip(
        (own.pressure_hpa, own.temperature_k, own.relative_humidity), standard, strict=True))
    check_meteorology(p.source, where, *weather)
    tec = media.zenith_tec_tecu if own.zenith_tec_tecu is None else own.zenith_tec_tecu
    return MediaModel.from_meteorology(
        station.lat_rad, station.h_km, day_of_year(p.epoch), *weather, zenith_tec_tecu=tec,
        band=band, troposphere=media.troposphere, ionosphere=media.ionosphere,
        shell_height_km=media.shell_height_km)


def _media_parameters(p: _Parser, doc: ScenarioFile) -> None:
    """Refuse zenith parameters in q of an effect that is off, and per-pass ones that would
    not exist (none asked for) or would not be modelled (a three-way up-leg's pass is its
    uplink station's, not its receiver's)."""
    if doc.parameters.media_per == "pass":
        if not doc.parameters.media:
            p.fail("parameters.media_per", 'zenith parameters to span passes (parameters.media '
                   'non-empty) or "station"', "pass")
        three_way = next((name for name, own in doc.tracking.station.items()
                          if own.uplink is not None), None)
        if three_way is not None:
            p.fail(f"tracking.station.{three_way}.uplink", 'no three-way uplink with '
                   'parameters.media_per = "pass" (the up-leg\'s pass is its uplink '
                   'station\'s: use "station")', doc.tracking.station[three_way].uplink)
    for i, effect in enumerate(doc.parameters.media):
        if not getattr(doc.media, effect):
            p.fail(f"parameters.media[{i}]", f"media.{effect} = true for the {effect}'s zenith "
                   "parameters", effect)


def _times(p: _Parser, tim: TimesTable) -> TapeTimes:
    if tim.input is not None:
        if tim.input_step_s is not None:
            p.fail("times", "either input or input_step_s (with end), not both")
        inputs = p.times(tim.input, "times.input")
    elif tim.input_step_s is not None:
        step = tim.input_step_s
        if tim.end is None:
            p.fail("times.end", "the last input time with input_step_s")
        end = p.time_s(tim.end, "times.end")
        if end <= 0:
            p.fail("times.end", "a time after the injection (> 0 s)", end)
        if end / step > MAX_INPUT_TIMES:
            p.fail("times.input_step_s", f"at most {MAX_INPUT_TIMES:,} input times (end / "
                   f"input_step_s = {end / step:.3g}; a larger input_step_s or an earlier end)",
                   step)
        grid = step * np.arange(1, int(math.floor(end / step * (1 + 1e-15))) + 1)
        inputs = tuple(float(t) for t in grid) + (() if grid.size and grid[-1] == end
                                                  else (end,))
    else:
        p.fail("times.input", "input times (a list), or input_step_s with end")
    if not inputs:
        p.fail("times.input", "at least one input time")
    if inputs[0] <= 0:
        p.fail("times.input", "input times after the injection (> 0 s)", inputs[0])
    epochs = p.times(tim.epochs, "times.epochs")
    if epochs and epochs[0] <= 0:
        p.fail("times.epochs", "epoch times after the injection (> 0 s; t_0 = 0 is implicit)",
               epochs[0])
    if epochs and epochs[-1] > inputs[-1]:
        p.fail("times.epochs", f"epoch times up to the last input time {inputs[-1]:g} s",
               epochs[-1])
    return TapeTimes(inputs, (0.0, *epochs))


def _schedule(p: _Parser, trk: TrackingTable, last_s: float,
              stations: tuple[TrackingStation, ...]) -> Schedule:
    start = p.time_s(trk.start, "tracking.start")
    end = p.time_s(last_s if trk.end is None else trk.end, "tracking.end")
    if start < 0:
        p.fail("tracking.start", "a time at or after the injection (>= 0 s)", start)
    if end <= start:
        p.fail("tracking.end", f"a time after tracking.start = {start:g} s", end)
    max_pass = math.inf if trk.max_pass_s is None else trk.max_pass_s
    use = trk.use or ("visibility" if trk.schedule is None else "schedule")
    passes = None
    if use != "visibility":
        if trk.schedule is None:
            p.fail("tracking.schedule", f'a pass schedule file with use = "{use}"')
        path = Path(trk.schedule)
        passes = read_schedule(path if path.is_absolute() else Path(p.source).parent / path,
                               epoch=p.epoch,
                               stations={ts.station.name: ts.kinds for ts in stations},
                               data_interval_s=trk.data_interval_s, clock_s=start,
                               uplinks={ts.station.name: ts.uplink.name for ts in stations
                                        if ts.uplink is not None})
    count_time = min(DEFAULT_COUNT_TIME_s, trk.data_interval_s)
    if trk.count_time_s is not None:
        if trk.count_time_s > trk.data_interval_s:
            p.fail("tracking.count_time_s", f"a count interval of at most data_interval_s = "
                   f"{trk.data_interval_s:g} s (consecutive counts do not overlap)",
                   trk.count_time_s)
        count_time = trk.count_time_s
    return Schedule(trk.data_interval_s, start, end, trk.min_pass_s, max_pass, trk.light_time,
                    use, passes, trk.allow_partial, trk.relativity, count_time)


def _miss(p: _Parser, miss: MissTable, state_model: ForceModel, last_s: float) -> MissSpec:
    kind = miss.kind
    names = tuple(n for n, _ in MISS_QUANTITIES[kind])
    quantities = tuple(n for n in names if n not in OPT_IN_MISS)
    if miss.quantities is not None:
        for i, q in enumerate(miss.quantities):
            if q not in names:
                p.fail(f"miss.quantities[{i}]", f"names among {', '.join(names)}", q)
        quantities = tuple(miss.quantities)
    at_periapsis = miss.time == "periapsis"
    if at_periapsis and kind != "bplane":
        p.fail("miss.time", 'a time (s or UTC date): "periapsis" is a B-plane\'s', miss.time)
    t_s = math.nan if at_periapsis else p.time_s(last_s if miss.time is None else miss.time,
                                                 "miss.time")
    if t_s <= 0:
        p.fail("miss.time", "a time after the injection (> 0 s)", t_s)
    if kind != "bplane":
        for key in ("body", "reference", "entry_radius_km"):
            if getattr(miss, key) is not None:
                p.fail(f"miss.{key}", "no body, reference or entry radius for orbit elements",
                       getattr(miss, key))
        return MissSpec(kind, t_s, quantities)
    if miss.body not in state_model.third_bodies:
        p.fail("miss.body", f"one of model.third_bodies {list(state_model.third_bodies)}",
               miss.body)
    reference = "earth_equator" if miss.reference is None else miss.reference
    check_reference(reference, miss.body, p.source, "miss.reference")
    entry = "entry_fpa_rad" in quantities
    if entry and miss.entry_radius_km is None:
        p.fail("miss.entry_radius_km", "the atmosphere interface radius (km from the body's "
               "centre) of the quantity entry_fpa_rad")
    if not entry and miss.entry_radius_km is not None:
        p.fail("miss.entry_radius_km", "no entry radius without entry_fpa_rad in "
               "miss.quantities", miss.entry_radius_km)
    return MissSpec(kind, t_s, quantities, miss.body, reference, at_periapsis,
                    math.nan if miss.entry_radius_km is None else float(miss.entry_radius_km))


def _stochastic(p: _Parser, table: StochasticTable | None, last_s: float
                ) -> StochasticAccelerations | None:
    """The stochastic accelerations of ``[stochastic]`` (None without one): intervals within
    [0, last T13 time], σ in km/s², finite τ."""
    if table is None:
        return None
    allowed = COMPONENTS[table.frame]
    components = tuple(allowed) if table.components is None else tuple(table.components)
    for i, c in enumerate(components):
        if c not in allowed:
            p.fail(f"stochastic.components[{i}]", f"components of the {table.frame} frame "
                   f"({', '.join(allowed)})", c)
    components = tuple(c for c in allowed if c in components)  # frame order
    if (table.sigma_km_s2 is None) == (table.sigma_m_s2 is None):
        p.fail("stochastic.sigma_km_s2", "exactly one of sigma_km_s2 or sigma_m_s2")
    sigma = table.sigma_km_s2 if table.sigma_m_s2 is None else table.sigma_m_s2 * 1e-3
    for key, value in (("sigma_km_s2", sigma), ("tau_s", table.tau_s)):
        if not math.isfinite(value):
            p.fail(f"stochastic.{key}", "a finite number > 0", value)
    if (table.interval_s is None) == (table.boundaries is None):
        p.fail("stochastic", "either interval_s (with start, end) or boundaries")
    if table.boundaries is not None:
        for key in ("start", "end"):
            if getattr(table, key) is not None:
                p.fail(f"stochastic.{key}", "no start or end with boundaries",
                       getattr(table, key))
        bounds = p.times(table.boundaries, "stochastic.boundaries")
        field = "stochastic.boundaries"
    else:
        start = p.time_s(0.0 if table.start is None else table.start, "stochastic.start")
        end = p.time_s(last_s if table.end is None else table.end, "stochastic.end")
        if end <= start:
            p.fail("stochastic.end", f"a time after stochastic.start = {start:g} s", end)
        n = math.ceil((end - start) / table.interval_s * (1 - 1e-12))
        if n > MAX_STOCHASTIC:
            p.fail("stochastic.interval_s", f"at most {MAX_STOCHASTIC} intervals", n)
        bounds = tuple(min(start + i * table.interval_s, end) for i in range(n)) + (end,)
        field = "stochastic.end" if bounds[0] >= 0 else "stochastic.start"
    if bounds[0] < 0 or bounds[-1] > last_s * (1 + 1e-15):
        p.fail(field, f"intervals within [0, {last_s:g}] s (the T13 times)",
               [bounds[0], bounds[-1]])
    n_par = (len(bounds) - 1) * len(components)
    if n_par > MAX_STOCHASTIC:
        p.fail("stochastic", f"at most {MAX_STOCHASTIC} parameters (intervals x components)",
               n_par)
    return StochasticAccelerations(table.frame, components, bounds, float(sigma),
                                   float(table.tau_s))


def _targeting(p: _Parser, doc: ScenarioFile, miss: MissSpec, values: tuple,
               x0: np.ndarray, propagator: Propagator, orientation: EarthOrientation
               ) -> BPlaneSearch | None:
    """The SEARCH problem of ``[targeting]`` (None without one), with the rules between it and
    the other tables: a B-plane miss at "periapsis" (the targeted encounter's time moves with
    the injection) and nominal model parameters (SEARCH's program flies the nominal model)."""
    if doc.targeting is None:
        return None
    if miss.kind != "bplane":
        p.fail("miss.kind", '"bplane" with [targeting] (the aim point is in the miss body\'s '
               "B-plane)", miss.kind)
    if not miss.at_periapsis:
        p.fail("miss.time", '"periapsis" with [targeting] (the targeted encounter\'s time moves '
               "with the injection)", doc.miss.time)
    if values:
        p.fail("parameters.values", "no values other than nominal with [targeting] (SEARCH's "
               "program flies the nominal model)", dict(values))
    return scenario_targeting(doc.targeting, p.source, epoch=p.epoch, state_km_km_s=x0,
                              propagator=propagator, body=miss.body, reference=miss.reference,
                              orientation=orientation)


#: Why burns are refused with a [targeting] table or a miss at the periapsis.
_NO_MANOEUVRES = ("no [[manoeuvre]] with [targeting] or miss.time = \"periapsis\" (SEARCH's "
                  "program, which finds the periapsis, flies no burn)")


#: Why a burn at t = 0 is refused with a [reference]: the fit of the first arc is the state
#: there.
_NOT_AT_START = ("a burn after t = 0 with [reference] (the first arc fits the state at t = 0, "
                 "which a burn there could not be told from)")


def _injection(p: _Parser, doc: ScenarioFile, orientation: EarthOrientation, last_s: float,
               burns: tuple[Burn, ...]) -> tuple[np.ndarray, Reference | None]:
    """The injection state, and the reference it comes from: ``[injection]``, or the state at
    t = 0 of ``[reference]``'s trajectory read over [0, last T13 time], at the arc boundaries
    t = 0 and the ``burns``' starts."""
    if (doc.injection is None) == (doc.reference is None):
        p.fail("injection", "either an [injection] table or a [reference] trajectory file")
    if doc.injection is not None:
        return doc.injection.state(p.source, "injection", center=doc.model.center,
                                   how_to_allow="injection.allow_subsurface = true",
                                   tdb=tdb_reader(p.epoch.jd, orientation.scales)), None
    if doc.model.center != "earth":
        p.fail("model.center", '"earth" with a [reference] trajectory (read Earth-centred)',
               doc.model.center)
    if doc.targeting is not None:
        p.fail("targeting", "no [targeting] with [reference] (the reference's trajectory is "
               "the mission's)")
    reference = doc.reference.read(p.source, epoch=p.epoch, orientation=orientation,
                                   span_s=(0.0, last_s),
                                   boundaries_s=(0.0, *(b.t_start_s for b in burns)))
    return reference.trajectory.state_at_boundary(0.0).copy(), reference


def parse_scenario(data: Mapping, source: str, earth_orientation: str | None = None
                   ) -> Scenario:
    """Build a :class:`Scenario` from parsed TOML tables, validating everything.

    The tables are first validated against :class:`ScenarioFile` (types, bounds, unknown
    keys); then the cross-table rules and the physics are checked while the scenario is built.
    ``earth_orientation`` overrides the file's model (the CLI's ``--earth-orientation``).

    Raises
    ------
    InputError
        Naming ``source`` and the dotted field for any missing, unknown or invalid entry
        (unknown station, observable or parameter, σ <= 0, times not ascending, an orbit
        below the surface, a tolerance outside its range, a station height out of its band,
        an epoch outside the EOP table).
    """
    doc = validate(ScenarioFile, data, source)
    p = _Parser(source)
    epoch = _epoch(p, doc.epoch)
    p = _Parser(source, epoch)
    model = doc.earth_orientation if earth_orientation is None else earth_orientation
    orientation = orientation_for(model, epoch, doc.eop, Path(source).parent, source)
    iden = Path(source).name.split(".")[0] if doc.iden is None else doc.iden
    state_model, var_model = doc.model.force_models(p.source, model)
    rtol, atol = doc.model.rtol, doc.model.atol
    dynamic, values = _dynamic(p, doc.parameters, state_model)
    _media_parameters(p, doc)
    stations = _stations(p, doc, doc.parameters)
    times = _times(p, doc.times)
    last_s = float(times.t13_s[-1])
    miss = _miss(p, doc.miss, state_model, last_s)
    manoeuvres = scenario_manoeuvres(
        source, doc.manoeuvre, time_s=p.time_s, last_s=last_s, method=doc.model.method,
        forbidden=_NO_MANOEUVRES if doc.targeting is not None or miss.at_periapsis else None,
        not_at_start=None if doc.reference is None else _NOT_AT_START)
    x0, reference = _injection(p, doc, orientation, last_s, manoeuvres)
    schedule = _schedule(p, doc.tracking, last_s, stations)
    stochastic = _stochastic(p, doc.stochastic, last_s)
    orientation.check_covers(np.array([0.0, last_s, schedule.end_s]), source)
    document = json.dumps(data, default=str, sort_keys=True)
    x0.setflags(write=False)
    eop = eop_parameters_of(orientation.model, doc.parameters.earth_orientation, source)
    # TAPP I's propagator, with every parameter TAPP I differentiates: a method its forces
    # refuse is the file's model.method, not found when the simulation starts
    changes = doc.model.propagator(
        source, state_model, var_model,
        dynamic + (() if stochastic is None else stochastic.model_parameters),
        p.time_s).centre_changes
    targeting = _targeting(p, doc, miss, values, x0,
                           doc.model.propagator(source, state_model, var_model, (), p.time_s),
                           orientation)
    baselines = tracking_baselines(source, doc.ddor, tuple(ts.station for ts in stations),
                                   schedule.data_interval_s)
    return Scenario(source, doc.title, iden, epoch, orientation, x0, state_model, var_model,
                    rtol, atol,
                    dynamic, values, stations, schedule, times, miss, document, targeting,
                    baselines, stochastic, doc.model.method, manoeuvres, reference,
                    eop=eop, eop_days=_eop_days(p, doc.parameters, eop, schedule, last_s),
                    centre_changes=changes)


def _eop_days(p: _Parser, par: ParametersTable, eop: tuple[str, ...], schedule: Schedule,
              last_s: float) -> EopDays | None:
    """The UTC days of per-day EOP offsets: those of the tracking window, from its start to
    its end or the last T13 time (None: offsets over the arc, or no offsets)."""
    if par.earth_orientation_per == "arc" or not eop:
        return None
    try:
        return eop_days(p.epoch, schedule.start_s, min(schedule.end_s, last_s))
    except ValueError as exc:
        p.fail("parameters.earth_orientation_per", f'"arc" for a tracking window of {exc}',
               "day")


def read_scenario(path: Path | str, earth_orientation: str | None = None) -> Scenario:
    """Read and validate a scenario file (TOML); errors name the file and the field.

    ``earth_orientation`` overrides the file's ``earth_orientation`` key.
    """
    return parse_scenario(read_toml(path), str(Path(path)), earth_orientation)

"""Tracking scenarios (TOML) for TAPP I, read into frozen dataclasses; errors name file and field.

A scenario gives the trajectory (epoch, injection state, state and variational force models),
the parameter vector x = [p; q], the tracking stations and schedule, the fit-world and
real-world noise, the T13 times (input times and epoch times) and the miss parameters.
The examples ``leo_equatorial.toml`` and ``deep_space.toml`` (``tapp examples``) are commented.
The file is validated against one declared schema, :class:`ScenarioFile` (``tapp.io.schema``):
unknown tables and keys are errors naming the allowed keys, booleans are not numbers, numbers
are not strings; the rules between tables and the physics are checked while it is built.

Tables and keys (units in the key names; times are seconds from the epoch, or UTC dates as
ISO strings or TOML dates)::

    title = "..."                   iden = "..."  (tape identification, default: file stem)
    epoch = "2026-01-01T00:00:00"   UTC of the injection, t = 0 (scenario time t is SI seconds
                                    from it: a date across a leap second counts it)
    earth_orientation = "iau2006"   or "gmst" (tapp.frames.orientation; stations, the field)
    eop = "iers"                    Earth orientation parameters: "iers" (the shipped IERS
                                    table), "none" (UT1 = UTC, no polar motion: a study
                                    beyond the predictions) or a finals2000A file path
    [injection]        r_km = [3], v_km_s = [3]   (EME2000, Earth-centred), or classical
                       elements a_km, e, i_deg, raan_deg, argp_deg and M_deg or nu_deg;
                       allow_subsurface = true accepts an orbit whose perigee is below the
                       Earth's surface (refused otherwise, ``tapp.io.orbits.check_perigee``)
    [reference]        instead of [injection]: the mission's trajectory, file = an SPK or
                       OEM (relative to this file), object, max_fit_error_m, fit_manoeuvres,
                       step_s; TAPP I flies its force model fitted to it over each arc
                       between the burns (tapp.tracking.reference)
    [model]            gravity (J0 | Jn | NxM), third_bodies (each once), var_gravity,
                       var_third_bodies (the variational model: the seed's truncated
                       variational equations; default the state model), rtol, atol (within
                       ``tapp.dynamics.propagate.TOLERANCE_RANGE``, 1e-15 to 1e-6), method
                       ("dop853" default, or "rkn12": ``tapp.dynamics.propagate``);
                       surface forces of a cannonball (tapp.io.models_file):
                       area_to_mass_m2_kg, c_r, c_d, srp / var_srp, shadows /
                       var_shadows, atmosphere / var_atmosphere ("none", "exponential",
                       "harris_priester")
    [parameters]       dynamic = ["GM", "GM_moon", "J2", "C22", "Cr", "Cd", "dr_mars_x", ...]
                       (tapp.dynamics.forces names; dr_<body>_x|y|z: a third body's
                       ephemeris offset, km, not the Earth's: tapp.dynamics.ephemeris_offsets),
                       station_location = "cylindrical" |
                       "ecef" | "none", station_biases = ["range", "range_rate",
                       "doppler"],
                       media = ["troposphere", "ionosphere"] (each station's zenith
                       parameters <STATION>.zenith_dry_km, .zenith_wet_km, kind
                       "troposphere", and .zenith_tec_tecu, kind "ionosphere"; needs
                       the effect on in [media]), media_per = "station" | "pass" (one
                       set per station, or one per pass: <STATION>.zenith_wet_km.p1, ...,
                       numbered in the station's pass order once the passes are known),
                       earth_orientation = true | ["ut1_s", "xp_rad", "yp_rad"] (constant
                       EOP offsets eop.*, kind "eop"; gmst: ut1_s only),
                       earth_orientation_per = "arc" | "day" (one offset over the arc, or
                       one per UTC day of the tracking window, eop.<name>.<YYYY-MM-DD>:
                       tapp.tracking.eop_days),
                       [parameters.values] non-nominal values of dynamic parameters
    [stations.NAME]    lat_deg, lon_deg, h_km (-0.5 to 10 km), elev_mask_deg
                       (tapp.io.stations_file)
    [tracking]         stations = [names], observables = ["range", "range_rate", "azimuth",
                       "elevation", "doppler"], light_time = "none" | "one_way" | "two_way",
                       band = "S" | "X" | "Ka" (tapp.measurements.bands), data_interval_s,
                       start, end, min_pass_s, max_pass_s,
                       blackouts = [[start, end], ...], schedule (a pass schedule, CSV:
                       tapp.io.schedule_file), use = "visibility" | "schedule" | "both",
                       allow_partial (tapp.tracking.schedule), relativity = "auto" | true |
                       false (tapp.measurements.relativity), count_time_s (doppler)
    [tracking.station.NAME]  per-station observables, location, biases, range_bias_m,
                       range_rate_bias_mm_s (nominal bias values), blackouts, uplink (the
                       station transmitting its three-way up-leg), and fit / real
                       tables overriding [noise.fit] / [noise.real] keys; the media's
                       pressure_hpa, temperature_k, relative_humidity (default: the
                       standard atmosphere at its height) and zenith_tec_tecu
    [media]            optional: troposphere = true, ionosphere = true (both default false)
                       add their delays to every station's range, range-rate and Doppler
                       (a three-way up-leg through its uplink station's; not to ΔDOR);
                       shell_height_km (350), zenith_tec_tecu (10) (tapp.measurements.media)
    [noise.fit]        sigma_range_m, sigma_range_rate_mm_s, sigma_azimuth_deg,
                       sigma_elevation_deg, sigma_doppler_mm_s or sigma_doppler_hz (white
                       noise: W = diag(1/σ²))
    [noise.real]       sigma_<kind>_<unit> (white, default the fit σ), bias_<kind>_<unit>
                       (constant per pass), correlated_<kind>_<unit> with tau_<kind>_s
                       (exponentially correlated)
    [ddor]             optional: ΔDOR on baselines of tracked stations (baselines, interval_s,
                       min_window_s, quasar_separation_deg, quasar_position_angle_deg,
                       quasar_position = true: A-B.quasar_ra_rad, .quasar_dec_rad in q;
                       [ddor.fit] sigma_ns or sigma_nrad, [ddor.real] sigma_*, bias_*;
                       tapp.tracking.ddor)
    [times]            input = [times] or input_step_s with end; epochs = [times] (epoch times
                       after t_0 = 0; re-epoching as in seed TAPP III §4.1)
    [miss]             kind = "bplane" (body, reference; b_dot_r_km, b_dot_t_km, ltof_s,
                       flight_time_s, entry_fpa_rad) | "equinoctial" (a_km, ex, ey, hx, hy,
                       lambda_m_rad) | "classical" (a_km, e, i_rad, raan_rad, argp_rad,
                       M_rad); time (a B-plane's may be "periapsis": the trajectory's first
                       periapsis at the body, found as SEARCH finds it); quantities (default:
                       all of the kind but flight_time_s and entry_fpa_rad). reference =
                       "earth_equator" (default, EME2000 xy) | "ecliptic" | "body_equator"
                       (the body's own equator, its IAU pole at the miss time; the Earth's
                       is EME2000 xy; bodies: tapp.dynamics.poles.EQUATOR_POLE_BODIES).
                       entry_fpa_rad: the flight-path angle (< 0) where the osculating
                       hyperbola at the miss time crosses entry_radius_km (required with
                       it, refused without; tapp.orbit.bplane.entry_flight_path_angle). A
                       B-plane miss must be an encounter (tapp.tracking.encounter), checked
                       before anything is written.
    [stochastic]       optional: piecewise-constant stochastic accelerations
                       (tapp.estimation.gauss_markov): frame = "ric" | "inertial",
                       components (default all three), interval_s with start, end (default
                       0 and the last T13 time; the last interval may be shorter) or
                       boundaries = [times], sigma_km_s2 or sigma_m_s2, tau_s (first-order
                       Gauss-Markov across the intervals); one parameter acc_<c>_<k> (km/s²,
                       kind "stochastic") per interval and component, appended to x
    [[manoeuvre]]      optional, one table per burn (tapp.tracking.manoeuvres): kind =
                       "impulsive" (time, dv_m_s or dv_km_s) or "finite" (start, duration_s,
                       thrust_N, direction, mass_kg, mass_flow_kg_s), axes = "inertial" |
                       "ric" | "vnb", Gates' four σ; one parameter <name>.<component> (kind
                       "execution") per error source with σ > 0, appended to x
    [targeting]        optional: retarget the injection velocity to a B-plane aim point of the
                       miss body by SEARCH before simulating
                       (tapp.targeting.searchfile.scenario_targeting: targets.b_dot_r_km,
                       targets.b_dot_t_km, targets.flight_time_s, vary, first_guess,
                       tolerances, increments, SEARCH's iteration control and scan); needs
                       miss.time = "periapsis" and nominal parameter values
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Annotated, Literal, NoReturn

import numpy as np
from pydantic import Field

from tapp.dynamics import ForceModel, Propagator
from tapp.dynamics.centres import CentreChange
from tapp.dynamics.empirical import COMPONENTS
from tapp.dynamics.ephemeris import tdb_reader
from tapp.dynamics.ephemeris_offsets import offset_of
from tapp.dynamics.forces import check_parameter_value, default_parameters
from tapp.dynamics.manoeuvres import KIND as EXECUTION
from tapp.dynamics.manoeuvres import THRUST_NAMES, Burn
from tapp.errors import InputError
from tapp.estimation.gauss_markov import FRAMES, KIND, UNIT, StochasticAccelerations
from tapp.frames.orientation import (
    EOP_KIND,
    EOP_PARAMETERS,
    EOP_UNITS,
    EarthOrientation,
    eop_parameters_of,
    orientation_for,
)
from tapp.frames.time import Epoch, parse_epoch
from tapp.frames.timescales import seconds_after
from tapp.io.models_file import ModelTable
from tapp.io.noise_file import FitTable, NoiseTable, NonNegative, Positive, RealTable
from tapp.io.orbits import OrbitTable
from tapp.io.schedule_file import PassSchedule, read_schedule
from tapp.io.schema import (
    EarthOrientationName,
    EopSource,
    Schema,
    Time,
    Unique,
    UtcDate,
    validate,
)
from tapp.io.stations_file import StationsSection
from tapp.io.tomlfile import read_toml
from tapp.io.trajectory_file import Reference, ReferenceTable
from tapp.measurements import BIAS_NAMES, STATION_PARAMETER_NAMES, Observable
from tapp.measurements.bands import BAND_NAMES, BANDS, DEFAULT_BAND
from tapp.measurements.doppler import DEFAULT_COUNT_TIME_s, range_rate_from_hz
from tapp.measurements.media import (
    MEDIA_KINDS,
    MEDIA_PARAMETER_NAMES,
    ZENITH_TEC_TECU,
    MediaModel,
    SHELL_HEIGHT_km,
    check_meteorology,
    day_of_year,
    standard_atmosphere,
)
from tapp.measurements.noise import EDGE_UNITS, FitNoise, RealNoise
from tapp.measurements.stations import Station
from tapp.orbit.bplane import REFERENCE_PLANES
from tapp.targeting.program import REFERENCE_HELP, BPlaneSearch, check_reference
from tapp.targeting.searchfile import TargetingTable, scenario_targeting
from tapp.tracking.ddor import QUASAR_KIND, DdorTable, TrackingBaseline, tracking_baselines
from tapp.tracking.eop_days import EopDays, eop_days
from tapp.tracking.manoeuvres import MAX_MANOEUVRES, ManoeuvreTable, scenario_manoeuvres

#: Observable kinds, in the order of ``tapp.measurements.Observable``.
KINDS = tuple(o.value for o in Observable)
#: Kinds that can carry a station bias in q (names and units: ``BIAS_NAMES``).
BIAS_KINDS = ("range", "range_rate", "doppler")
LOCATION_MODES = ("cylindrical", "ecef", "none")
#: The media whose zenith parameters may be in q ([parameters] media), and their units.
MEDIA_EFFECTS = ("troposphere", "ionosphere")
MEDIA_UNITS = ("km", "km", "TECU")
#: Most T13 input times a scenario may ask for (each is a tape record, held in memory).
MAX_INPUT_TIMES = 100_000
LIGHT_TIME_MODES = ("none", "one_way", "two_way")
#: Where the samples come from: [tracking] use (tapp.tracking.schedule).
USES = ("visibility", "schedule", "both")
#: The p part of x: Cartesian state at the epoch, EME2000, Earth-centred.
ORBIT_PARAMETERS = (("x_km", "km"), ("y_km", "km"), ("z_km", "km"), ("vx_km_s", "km/s"),
                    ("vy_km_s", "km/s"), ("vz_km_s", "km/s"))
#: Miss quantities of each kind, with units.
MISS_QUANTITIES = {
    "bplane": (("b_dot_r_km", "km"), ("b_dot_t_km", "km"), ("ltof_s", "s"),
               ("flight_time_s", "s"), ("entry_fpa_rad", "rad")),
    "equinoctial": (("a_km", "km"), ("ex", "1"), ("ey", "1"), ("hx", "1"), ("hy", "1"),
                    ("lambda_m_rad", "rad")),
    "classical": (("a_km", "km"), ("e", "1"), ("i_rad", "rad"), ("raan_rad", "rad"),
                  ("argp_rad", "rad"), ("M_rad", "rad")),
}
#: Miss quantities asked for by name only (the default is every other one of the kind).
OPT_IN_MISS = ("flight_time_s", "entry_fpa_rad")


@dataclass(frozen=True, slots=True)
class Parameter:
    """One TAPP I parameter: name (with unit), unit, kind, nominal value, station number.

    ``kind`` is "orbit", "dynamic", "location", "bias", "troposphere", "ionosphere",
    "stochastic" or "execution"; ``station`` is the station number s (1-based) of a location,
    bias or zenith (media) parameter, 0 otherwise.
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
    band : its radio band, "S", "X" or "Ka" (:mod:`tapp.measurements.bands`).
    media : the troposphere and ionosphere of its links (None: neither is on).
    media_parameters : effects among ("troposphere", "ionosphere") whose zenith parameters
        are in q.
    media_per : "station" (one set of zenith parameters) or "pass" (one per pass,
        ``<name>.p<i>``: :func:`pass_suffix`).
    media_passes : with ``media_per = "pass"``, its number of passes (set by TAPP I once it
        has found them: :func:`with_passes`; 0 before).
    uplink : the station transmitting its three-way up-leg; None: itself (two-way).
    uplink_media : the media of the uplink station, which its up-leg crosses (with media and
        an uplink; None otherwise).
    doppler_bias_km_s : nominal bias added to its count-based Doppler.
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
    band: str = DEFAULT_BAND
    media: MediaModel | None = None
    media_parameters: tuple[str, ...] = ()
    media_per: str = "station"
    media_passes: int = 0
    uplink: Station | None = None
    uplink_media: MediaModel | None = None
    doppler_bias_km_s: float = 0.0

    def parameters(self) -> tuple[Parameter, ...]:
        """Its parameters in q: location, biases, then zenith (media) parameters, named
        ``<station>.<name>``."""
        out = []
        if self.location != "none":
            values = self.station.location(self.location)
            for pname, value in zip(STATION_PARAMETER_NAMES[self.location], values,
                                    strict=True):
                out.append(Parameter(f"{self.station.name}.{pname}", _unit_of(pname),
                                     "location", float(value), self.number))
        nominal = {"range": self.range_bias_km, "range_rate": self.range_rate_bias_km_s,
                   "doppler": self.doppler_bias_km_s}
        for kind, bname in zip(BIAS_KINDS, BIAS_NAMES, strict=True):
            if kind in self.biases:
                out.append(Parameter(f"{self.station.name}.{bname}", _unit_of(bname), "bias",
                                     nominal[kind], self.number))
        suffixes = ([""] if self.media_per == "station"
                    else [pass_suffix(i) for i in range(self.media_passes)])
        if self.media_parameters:
            for suffix in suffixes:
                for zname, kind, unit, value in zip(MEDIA_PARAMETER_NAMES, MEDIA_KINDS,
                                                    MEDIA_UNITS, self.media.zenith, strict=True):
                    if kind in self.media_parameters:
                        out.append(Parameter(f"{self.station.name}.{zname}{suffix}", unit,
                                             kind, float(value), self.number))
        return tuple(out)


def pass_suffix(index: int) -> str:
    """The suffix of a station's zenith parameters of its pass ``index`` (0-based): ".p1",
    ".p2", ..."""
    return f".p{index + 1}"


@dataclass(frozen=True, slots=True)
class Schedule:
    """When observations are taken.

    Samples fall on t = start_s + i data_interval_s in (0, end_s] (and not after the last
    T13 time), where a station sees the spacecraft above its mask and outside its blackouts
    (:attr:`TrackingStation.blackouts_s`). ``light_time`` is "none", "one_way" or "two_way".
    A pass is a run of consecutive such samples; passes shorter than min_pass_s
    are dropped, and passes longer than max_pass_s split into consecutive passes of at most
    max_pass_s, every sample kept (each piece has its own per-pass bias in the real world).
    What each rule removes is counted (:data:`tapp.tracking.editing.EDITING_RULES`).

    ``use`` "schedule" or "both" takes the samples of the stations in ``passes`` from their
    passes instead (``allow_partial``: drop the samples a station cannot see instead of
    refusing them; :mod:`tapp.tracking.schedule`). ``relativity``: True, False or "auto"
    (:mod:`tapp.measurements.relativity`); ``count_time_s``: the doppler count interval.
    """

    data_interval_s: float
    start_s: float
    end_s: float
    min_pass_s: float
    max_pass_s: float
    light_time: str
    use: str = "visibility"
    passes: PassSchedule | None = None
    allow_partial: bool = False
    relativity: str | bool = "auto"
    count_time_s: float = DEFAULT_COUNT_TIME_s


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
    the B-plane reference plane (``tapp.orbit.bplane.REFERENCE_PLANES``; "body_equator" only
    for a body of ``tapp.dynamics.poles.EQUATOR_POLE_BODIES``). ``at_periapsis``: the time is
    the trajectory's periapsis at the body, NaN here until the simulator finds it
    (:func:`tapp.tracking.encounter.prepare_encounter`). ``entry_radius_km``: the atmosphere
    interface radius of ``entry_fpa_rad``, km (NaN without that quantity).
    """

    kind: str
    t_s: float
    quantities: tuple[str, ...]
    body: str = ""
    reference: str = "earth_equator"
    at_periapsis: bool = False
    entry_radius_km: float = math.nan

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
    orientation : the Earth orientation (model and EOP) of stations and field.
    x0 : (6,) injection state, km and km/s, inertial (GCRS; EME2000 with gmst), Earth-centred.
    state_model, var_model : force models of the trajectory and of the variational equations.
    rtol, atol : integrator tolerances.
    dynamic : names of the model parameters in q (``tapp.dynamics.forces``).
    dynamic_values : ((name, value), ...) values other than nominal.
    stations : tracking stations, numbered 1..n_ts.
    schedule, times, miss : see their classes.
    document_json : the scenario tables as JSON (tape provenance).
    targeting : the SEARCH problem of a ``[targeting]`` table, run before simulating; None
        without one (or once run: :func:`tapp.tracking.encounter.prepare_encounter`).
    baselines : the ΔDOR baselines of a ``[ddor]`` table, numbered after the stations.
    stochastic : the stochastic accelerations of a ``[stochastic]`` table, or None.
    method : the integration method of every propagation (``tapp.dynamics.propagate``).
    manoeuvres : the burns of the ``[[manoeuvre]]`` tables, ascending in time.
    reference : the mission's trajectory of a ``[reference]`` table, to which TAPP I fits its
        force model over each arc between the burns (:mod:`tapp.tracking.reference`); ``x0``
        is then its state at t = 0, and ``manoeuvres`` the tables', until the fit replaces
        them; None without one.
    eop : the Earth orientation parameters whose constant offsets are in q (parameters
        ``eop.<name>``, kind "eop": :func:`tapp.frames.orientation.eop_parameters_of`).
    eop_days : with per-day offsets, their UTC days (``eop.<name>.<YYYY-MM-DD>``:
        :mod:`tapp.tracking.eop_days`); None: one offset over the arc.
    centre_changes : the changes of integration centre of every propagation
        (:mod:`tapp.dynamics.centres`); states stay about the model's centre.
    """

    source: str
    title: str
    iden: str
    epoch: Epoch
    orientation: EarthOrientation
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
    targeting: BPlaneSearch | None = None
    baselines: tuple[TrackingBaseline, ...] = ()
    stochastic: StochasticAccelerations | None = None
    method: str = "dop853"
    manoeuvres: tuple[Burn, ...] = ()
    reference: Reference | None = None
    eop: tuple[str, ...] = ()
    eop_days: EopDays | None = None
    centre_changes: tuple[CentreChange, ...] = ()

    def propagator(self) -> Propagator:
        """The (state model, variational model, dynamic parameters) propagator, with the
        centre changes."""
        return Propagator(self.state_model, self.var_model, self.dynamic, rtol=self.rtol,
                          atol=self.atol, method=self.method,
                          centre_changes=self.centre_changes)

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """x = [p; q]: orbit state at the epoch, dynamic parameters, station parameters, EOP
        offsets, quasar positions, stochastic accelerations, execution errors of the
        manoeuvres (the segment parameters last)."""
        out = [Parameter(name, unit, "orbit", float(v))
               for (name, unit), v in zip(ORBIT_PARAMETERS, self.x0, strict=True)]
        values = default_parameters(self.state_model, self.dynamic)
        values.update(dict(self.dynamic_values))
        for name in self.dynamic:
            gm = name == "GM" or name.startswith("GM_")
            unit = "km^3/s^2" if gm else "km" if offset_of(name) else "1"
            suffix = {"km^3/s^2": "_km3_s2", "km": "_km", "1": ""}[unit]
            out.append(Parameter(f"{name}{suffix}", unit, "dynamic", values[name]))
        for st in self.stations:
            out.extend(st.parameters())
        out.extend(Parameter(name, EOP_UNITS[name.split(".")[1]], EOP_KIND, 0.0)
                   for name in self.eop_names())
        out.extend(Parameter(name, "rad", QUASAR_KIND, 0.0, bl.number)
                   for bl in self.baselines for name in bl.quasar_parameters)
        if self.stochastic is not None:
            out.extend(Parameter(name, UNIT, KIND, 0.0) for name in self.stochastic.names)
        out.extend(Parameter(name, unit, EXECUTION, 0.0) for burn in self.manoeuvres
                   for name, unit, _ in burn.parameters())
        return tuple(out)

    def eop_names(self) -> tuple[str, ...]:
        """The EOP offsets in q: ``eop.<name>``, or ``eop.<name>.<date>`` day after day."""
        if self.eop_days is None:
            return tuple(f"eop.{name}" for name in self.eop)
        return self.eop_days.names(self.eop)

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
# Schema: the file's tables and keys, their types and bounds (tapp.io.schema)
# ---------------------------------------------------------------------------------------------


Window = Annotated[list[Time], Field(min_length=2, max_length=2)]
Kind = Literal[KINDS]  # type: ignore[valid-type]
BiasKind = Literal[BIAS_KINDS]  # type: ignore[valid-type]
LocationMode = Literal[LOCATION_MODES]  # type: ignore[valid-type]
BandName = Literal[BAND_NAMES]  # type: ignore[valid-type]

_LOCATION = ("How station locations enter q: \"cylindrical\" (distance from the spin axis, "
             "longitude, height along the axis), \"ecef\" (x, y, z) or \"none\".")
_BIASES = "Observable kinds whose per-station bias is a parameter in q."
_BLACKOUTS = "Windows [start, end] without data"


class ParametersTable(Schema):
    """``[parameters]``: the parameters q of x = [p; q] beside the epoch state p."""

    dynamic: Annotated[list[str], Unique] = Field(
        [], description="Model parameters in q: \"GM\", \"GM_moon\" (a third body's), "
        "\"J2\", \"C22\", \"S22\", ... of the state model, \"Cr\" (with model.srp), "
        "\"Cd\" (with a model.atmosphere) and \"dr_mars_x\", \"dr_mars_y\", \"dr_mars_z\" "
        "(a third body's ephemeris offset, km, ICRF; not the Earth's).")
    station_location: LocationMode = Field("none", description=_LOCATION)
    station_biases: Annotated[list[BiasKind], Unique] = Field([], description=_BIASES)
    media: Annotated[list[Literal[MEDIA_EFFECTS]], Unique] = Field(  # type: ignore[valid-type]
        [], description="Media whose per-station zenith parameters are in q: "
        "\"troposphere\" (zenith_dry_km, zenith_wet_km), \"ionosphere\" (zenith_tec_tecu); "
        "each needs its effect on in [media].")
    media_per: Literal["station", "pass"] = Field(
        "station", description="The zenith parameters' span: one set per station over the arc "
        "(STATION.zenith_wet_km), or one per pass, its calibration's (STATION.zenith_wet_km.p1, "
        ".p2, ... in the station's pass order, named once TAPP I has found the passes).")
    values: dict[str, float] = Field(
        {}, description="Values other than nominal of dynamic parameters, by name (GM in "
        "km³/s²).")
    earth_orientation: bool | Annotated[list[Literal[EOP_PARAMETERS]],  # type: ignore[valid-type]
                                        Unique] = Field(
        False, description="Constant offsets of the Earth orientation parameters from the IERS "
        "values in q (eop.ut1_s, eop.xp_rad, eop.yp_rad): true for all (\"ut1_s\" alone under "
        "gmst), or a list of them.")
    earth_orientation_per: Literal["arc", "day"] = Field(
        "arc", description="The offsets' span: one over the whole arc (eop.<name>), or one per "
        "UTC day of the tracking window (eop.<name>.<YYYY-MM-DD>, each moving only its day's "
        "observations).")


class StationTracking(Schema):
    """``[tracking.station.NAME]``: what one station measures and how, overriding the
    scenario's defaults."""

    observables: Annotated[list[Kind], Field(min_length=1), Unique] | None = Field(
        None, description="What the station measures; default: tracking.observables.")
    location: LocationMode | None = Field(
        None, description="Its location parameters; default: parameters.station_location.")
    biases: Annotated[list[BiasKind], Unique] | None = Field(
        None, description="Its bias parameters; default: parameters.station_biases.")
    range_bias_m: float = Field(0.0, description="Nominal range bias added to its range.")
    range_rate_bias_mm_s: float = Field(0.0, description="Nominal range-rate bias added to "
                                        "its range rate.")
    blackouts: list[Window] = Field([], description=_BLACKOUTS + " at this station (beside "
                                    "tracking.blackouts).")
    band: BandName | None = Field(None, description="Its radio band; default: tracking.band.")
    doppler_bias_mm_s: float = Field(0.0, description="Nominal bias added to its count-based "
                                     "Doppler.")
    fit: FitTable = Field(FitTable(), description="Its fit-world σ, overriding [noise.fit].")
    real: RealTable = Field(RealTable(), description="Its real-world noise, overriding "
                            "[noise.real].")
    pressure_hpa: Positive | None = Field(
        None, description="Surface pressure for the zenith hydrostatic delay (300 to 1100 "
        "hPa); default: the standard atmosphere at its height.")
    temperature_k: Positive | None = Field(
        None, description="Surface temperature for the zenith wet delay (180 to 340 K); "
        "default: the standard atmosphere at its height.")
    relative_humidity: NonNegative | None = Field(
        None, description="Relative humidity, a fraction 0 to 1; default: 0.5.")
    zenith_tec_tecu: NonNegative | None = Field(
        None, description="Its nominal zenith TEC (TECU); default: media.zenith_tec_tecu.")
    uplink: str | None = Field(
        None, description="Three-way tracking: the [stations.NAME] station that transmits the "
        "up-leg this station receives (light_time = \"two_way\"; the up-leg's location "
        "partials go to its columns when it is tracked with location parameters); default: "
        "itself (two-way).")


class TrackingTable(Schema):
    """``[tracking]``: the stations, what they measure and when. Samples fall every
    ``data_interval_s`` from ``start`` to ``end`` while a station sees the spacecraft above
    its mask and outside blackouts; a pass is a run of such samples. A ``schedule`` gives the
    passes instead (``use``)."""

    stations: Annotated[list[str], Field(min_length=1), Unique] = Field(
        description="Names of [stations.NAME] tables, numbered 1, 2, ... on the tape.")
    observables: Annotated[list[Kind], Unique] = Field(
        ["range", "range_rate"], description="What every station measures.")
    light_time: Literal[LIGHT_TIME_MODES] = Field(  # type: ignore[valid-type]
        "none", description="Light-time correction of the observables.")
    band: BandName = Field(DEFAULT_BAND, description="The stations' radio band, \"S\", \"X\" "
                           "or \"Ka\": the carrier frequencies of their links (uplink, and "
                           "downlink by the DSN's turnaround ratio).")
    data_interval_s: Positive = Field(description="Time between samples of each station.")
    start: Time = Field(0.0, description="First sample time.")
    end: Time | None = Field(None, description="Last sample time; default: the last T13 time.")
    min_pass_s: NonNegative = Field(0.0, description="Passes shorter than this are dropped.")
    max_pass_s: Positive | None = Field(
        None, description="Passes longer than this are split (each piece its own per-pass "
        "bias); default: no limit.")
    blackouts: list[Window] = Field([], description=_BLACKOUTS + " at every station.")
    station: dict[str, StationTracking] = Field(
        {}, description="Per-station overrides, by station name.")
    schedule: str | None = Field(
        None, description="A pass schedule (CSV, relative to the scenario's folder): a header, "
        "then one row per pass: station, start, end (UTC dates or seconds from the epoch), "
        "data_types (observables separated by spaces; empty: the station's), data_interval_s "
        "(empty: tracking.data_interval_s), uplink_station (empty, the station itself, or its "
        "tracking.station.NAME.uplink for three-way); tapp.io.schedule_file.")
    use: Literal[USES] | None = Field(  # type: ignore[valid-type]
        None, description="Which samples: \"visibility\" (the grid, wherever a station sees "
        "the spacecraft), \"schedule\" (the schedule's passes only) or \"both\" (the stations "
        "with passes in the schedule in them, the others by visibility); default: "
        "\"schedule\" with a schedule, else \"visibility\".")
    allow_partial: bool = Field(
        False, description="Drop the samples of a scheduled pass that the station cannot see "
        "(counted under elevation_mask) instead of refusing the schedule.")
    relativity: Literal["auto"] | bool = Field(
        "auto", description="Relativistic light time (barycentric, TDB, Shapiro delays: "
        "tapp.measurements.relativity): true, false, or \"auto\": on with light_time = "
        "\"two_way\" when the spacecraft goes beyond the Moon's distance (384,400 km) in "
        "the tracking span.")
    count_time_s: Positive | None = Field(
        None, description="Count interval of the doppler observable (centred on each sample), "
        "s, at most data_interval_s; default: 60 s or data_interval_s if shorter.")


class MediaTable(Schema):
    """``[media]``: the troposphere and ionosphere on every station's range and range-rate
    (tapp.measurements.media; ΔDOR is left without them)."""

    troposphere: bool = Field(False, description="Saastamoinen-Davis zenith delays from each "
                              "station's weather, mapped by Niell (1996).")
    ionosphere: bool = Field(False, description="A thin-shell ionosphere: 40.3 TEC / f² at "
                             "each leg's carrier, a delay on range and an advance on "
                             "range-rate.")
    shell_height_km: Positive = Field(SHELL_HEIGHT_km, description="Height of the thin shell.")
    zenith_tec_tecu: NonNegative = Field(
        ZENITH_TEC_TECU, description="Every station's nominal zenith TEC, TECU (1e16 /m²); "
        "10 is Klobuchar's night-time floor, a mid-latitude day 20-50.")


class TimesTable(Schema):
    """``[times]``: the T13 times: input times (tape records) and epoch times (the state the
    information is referred to is re-epoched there; t = 0 is always one)."""

    input: list[Time] | None = Field(None, description="Input times, ascending, after 0 (or "
                                     "input_step_s with end).")
    input_step_s: Positive | None = Field(None, description="Input times every this many "
                                          "seconds up to end.")
    end: Time | None = Field(None, description="The last input time, with input_step_s.")
    epochs: list[Time] = Field([], description="Epoch times after t = 0, ascending, up to the "
                               "last input time.")


class MissTable(Schema):
    """``[miss]``: the miss parameters whose partials the tape carries. A B-plane miss must be
    an encounter: the spacecraft inside the body's sphere of attraction, on a hyperbola."""

    kind: Literal[tuple(MISS_QUANTITIES)] = Field(  # type: ignore[valid-type]
        description="\"bplane\" (b_dot_r_km, b_dot_t_km, ltof_s, flight_time_s, entry_fpa_rad), "
        "\"equinoctial\" (a_km, ex, ey, hx, hy, lambda_m_rad) or \"classical\" (a_km, e, "
        "i_rad, raan_rad, argp_rad, M_rad).")
    time: Time | None = Field(
        None, description="When the miss is evaluated; a B-plane's may be \"periapsis\" (the "
        "trajectory's first periapsis at the body); default: the last T13 time.")
    quantities: Annotated[list[str], Field(min_length=1), Unique] | None = Field(
        None, description="Which quantities of the kind; default: all but flight_time_s and "
        "entry_fpa_rad.")
    body: str | None = Field(None, description="The B-plane's body, a third body of the state "
                             "model.")
    reference: Literal[REFERENCE_PLANES] | None = Field(  # type: ignore[valid-type]
        None, description=f"The B-plane's reference plane (T axis): {REFERENCE_HELP}; "
        "default: \"earth_equator\".")
    entry_radius_km: Positive | None = Field(
        None, description="Atmosphere interface radius from the body's centre, km, where "
        "entry_fpa_rad is the flight-path angle of the incoming osculating hyperbola; "
        "required with entry_fpa_rad in quantities, refused without; below the distance at "
        "the miss time and at or above the hyperbola's periapsis radius.")


#: Most stochastic-acceleration parameters (intervals x components): each adds a column to
#: every factor on the tape (3 n_o² doubles per pair) and to the processor's matrices.
MAX_STOCHASTIC = 300


class StochasticTable(Schema):
    """``[stochastic]``: piecewise-constant accelerations, constant over each interval,
    correlated across intervals as a first-order Gauss-Markov process of their mid-times
    (tapp.estimation.gauss_markov); each (interval, component) is a parameter in q."""

    frame: Literal[FRAMES] = Field(  # type: ignore[valid-type]
        "ric", description="\"ric\": radial, in-track, cross-track of the trajectory; "
        "\"inertial\": x, y, z.")
    components: Annotated[list[str], Field(min_length=1), Unique] | None = Field(
        None, description="Components modelled (R, I, C or x, y, z); default: all three.")
    interval_s: Positive | None = Field(
        None, description="Interval length, from start to end (the last may be shorter); or "
        "boundaries.")
    start: Time | None = Field(None, description="Start of the first interval, with "
                               "interval_s; default: 0.")
    end: Time | None = Field(None, description="End of the last interval, with interval_s; "
                             "default: the last T13 time.")
    boundaries: Annotated[list[Time], Field(min_length=2)] | None = Field(
        None, description="Interval boundaries t_0 < ... < t_K, from 0 to the last T13 time.")
    sigma_km_s2: Positive | None = Field(None, description="Steady-state σ of each component "
                                         "(or sigma_m_s2).")
    sigma_m_s2: Positive | None = Field(None, description="The same σ in m/s².")
    tau_s: Positive = Field(description="Gauss-Markov time constant τ: consecutive intervals "
                            "correlate by exp(-Δt/τ) over their mid-times' distance Δt.")


class ScenarioFile(StationsSection):
    """Schema of a TAPP I tracking scenario (module docstring for the tables)."""

    title: str = Field("", description="Free text, kept on the tape.")
    iden: str | None = Field(None, description="Tape identification; default: the file name "
                             "up to its first dot.")
    epoch: UtcDate = Field(description="UTC of the injection, t = 0; scenario time is SI "
                           "seconds from it.")
    earth_orientation: EarthOrientationName = "iau2006"
    eop: EopSource = "iers"
    injection: OrbitTable | None = Field(
        None, description="The state at the epoch (GCRS; EME2000 with gmst); or [reference].")
    reference: ReferenceTable | None = Field(
        None, description="The mission's own trajectory, fitted by TAPP I's force model; or "
        "[injection].")
    model: ModelTable = Field(description="The state and variational force models.")
    parameters: ParametersTable = Field(ParametersTable(),
                                        description="The parameters q beside the state.")
    tracking: TrackingTable = Field(description="Who tracks, what and when.")
    noise: NoiseTable = Field(description="Fit-world and real-world measurement noise.")
    times: TimesTable = Field(description="The T13 times.")
    miss: MissTable = Field(description="The miss parameters.")
    targeting: TargetingTable | None = Field(
        None, description="Retarget the injection velocity by SEARCH before simulating.")
    ddor: DdorTable | None = Field(None, description="ΔDOR on baselines of tracked stations.")
    media: MediaTable = Field(MediaTable(), description="Troposphere and ionosphere on the "
                              "stations' range and range-rate.")
    stochastic: StochasticTable | None = Field(
        None, description="Stochastic accelerations, estimated or considered by TAPP III.")
    manoeuvre: Annotated[list[ManoeuvreTable], Field(max_length=MAX_MANOEUVRES)] = Field(
        [], description="Burns, impulsive or finite, with their execution errors "
        "(tapp.tracking.manoeuvres).")


# ---------------------------------------------------------------------------------------------
# Building the scenario from the validated tables
# ---------------------------------------------------------------------------------------------


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
    for i, name in enumerate(par.dynamic):
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
    for name, value in par.values.items():
        if name not in par.dynamic:
            p.fail(f"parameters.values.{name}",
                   f"a name of parameters.dynamic ({', '.join(par.dynamic) or 'none'})", name)
        chosen.append((name, check_parameter_value(name, value, p.source,
                                                   f"parameters.values.{name}")))
    return tuple(par.dynamic), tuple(chosen)


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


def with_passes(scenario: Scenario, passes: Sequence[int]) -> Scenario:
    """The scenario with each station's number of passes (in ``scenario.stations`` order),
    which names its per-pass zenith parameters (``media_per = "pass"``); unchanged without
    them."""
    if not any(ts.media_per == "pass" and ts.media_parameters for ts in scenario.stations):
        return scenario
    return replace(scenario, stations=tuple(replace(ts, media_passes=int(n)) for ts, n in zip(
        scenario.stations, passes, strict=True)))


def read_scenario(path: Path | str, earth_orientation: str | None = None) -> Scenario:
    """Read and validate a scenario file (TOML); errors name the file and the field.

    ``earth_orientation`` overrides the file's ``earth_orientation`` key.
    """
    return parse_scenario(read_toml(path), str(Path(path)), earth_orientation)

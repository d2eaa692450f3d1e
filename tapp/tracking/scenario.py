"""The tracking scenario of TAPP I as frozen dataclasses: :class:`Scenario` and its parts.

A scenario gives the trajectory (epoch, injection state, state and variational force models),
the parameter vector x = [p; q] (:attr:`Scenario.parameters`), the tracking stations and
schedule, the fit-world and real-world noise, the T13 times and the miss parameters. The file
it comes from: :mod:`tapp.tracking.scenario_file` (its tables and keys); reading and building
it: :mod:`tapp.tracking.scenario_build` (:func:`~tapp.tracking.scenario_build.read_scenario`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from tapp.dynamics import ForceModel, Propagator
from tapp.dynamics.centres import CentreChange
from tapp.dynamics.forces import default_parameters
from tapp.dynamics.manoeuvres import KIND as EXECUTION
from tapp.dynamics.manoeuvres import Burn
from tapp.dynamics.parameters import ORBIT_PARAMETERS, parse
from tapp.estimation.gauss_markov import KIND, UNIT, StochasticAccelerations
from tapp.frames.orientation import EOP_KIND, EOP_UNITS, EarthOrientation
from tapp.frames.time import Epoch
from tapp.io.schedule_file import PassSchedule
from tapp.io.trajectory_file import Reference
from tapp.measurements import BIAS_NAMES, STATION_PARAMETER_NAMES, Observable
from tapp.measurements.bands import DEFAULT_BAND
from tapp.measurements.doppler import DEFAULT_COUNT_TIME_s
from tapp.measurements.media import MEDIA_KINDS, MEDIA_PARAMETER_NAMES, MediaModel
from tapp.measurements.noise import FitNoise, RealNoise
from tapp.measurements.stations import Station
from tapp.targeting.program import BPlaneSearch
from tapp.tracking.ddor import QUASAR_KIND, TrackingBaseline
from tapp.tracking.eop_days import EopDays

#: Observable kinds, in the order of ``tapp.measurements.Observable``.
KINDS = tuple(o.value for o in Observable)
#: Kinds that can carry a station bias in q (names and units: ``BIAS_NAMES``).
BIAS_KINDS = ("range", "range_rate", "doppler")
LOCATION_MODES = ("cylindrical", "ecef", "none")
#: The media whose zenith parameters may be in q ([parameters] media).
MEDIA_EFFECTS = ("troposphere", "ionosphere")
LIGHT_TIME_MODES = ("none", "one_way", "two_way")
#: Where the samples come from: [tracking] use (tapp.tracking.schedule).
USES = ("visibility", "schedule", "both")
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
                name = f"{self.station.name}.{pname}"
                out.append(Parameter(name, parse(name).unit, "location", float(value),
                                     self.number))
        nominal = {"range": self.range_bias_km, "range_rate": self.range_rate_bias_km_s,
                   "doppler": self.doppler_bias_km_s}
        for kind, bname in zip(BIAS_KINDS, BIAS_NAMES, strict=True):
            if kind in self.biases:
                name = f"{self.station.name}.{bname}"
                out.append(Parameter(name, parse(name).unit, "bias", nominal[kind],
                                     self.number))
        suffixes = ([""] if self.media_per == "station"
                    else [pass_suffix(i) for i in range(self.media_passes)])
        if self.media_parameters:
            for suffix in suffixes:
                for zname, kind, value in zip(MEDIA_PARAMETER_NAMES, MEDIA_KINDS,
                                              self.media.zenith, strict=True):
                    if kind in self.media_parameters:
                        name = f"{self.station.name}.{zname}{suffix}"
                        out.append(Parameter(name, parse(name).unit, kind, float(value),
                                             self.number))
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
    """A validated TAPP I scenario (:mod:`tapp.tracking.scenario_file` for the file format).

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
            out.append(Parameter(name, parse(name).unit, "dynamic", values[name]))
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


def with_passes(scenario: Scenario, passes: Sequence[int]) -> Scenario:
    """The scenario with each station's number of passes (in ``scenario.stations`` order),
    which names its per-pass zenith parameters (``media_per = "pass"``); unchanged without
    them."""
    if not any(ts.media_per == "pass" and ts.media_parameters for ts in scenario.stations):
        return scenario
    return replace(scenario, stations=tuple(replace(ts, media_passes=int(n)) for ts, n in zip(
        scenario.stations, passes, strict=True)))


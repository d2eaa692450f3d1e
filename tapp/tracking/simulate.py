"""TAPP I: trajectory, observation partials and noise models -> the records of a T13 tape.

What is computed (seed TAPP III §1 and §4.1; notation n_o, n_p, j, k, U, ΔJ, ΔJ̃ of the seed):

1. **Trajectory and transition.** The injection state is propagated with the scenario's state
   model; Φ and the parameter sensitivities S come from its variational model (the truncated
   variational equations when the two differ). The integration restarts at every epoch time
   t̂_i from the state reached there, with Φ(t̂_i, t̂_i) = I and S = 0, so that every
   partial is *referred to its own epoch* directly: over (t̂_i, t̂_{i+1}]

   .. math::

       \\Psi(t, \\hat t_i) = \\frac{\\partial x(t)}{\\partial x(\\hat t_i)} =
       \\begin{pmatrix} \\Phi(t, \\hat t_i) & S_i(t) & 0 \\\\ 0 & I & 0 \\\\ 0 & 0 & I
       \\end{pmatrix},\\qquad x = [p; q_{dyn}; q_{stations}]

   (n_o x n_o, the parameter block of Φ extended by the sensitivities). Composing through t_0
   instead, Φ(t, t̂_i) = Φ(t, t_0) Φ(t̂_i, t_0)⁻¹, loses every digit after a lunar swing-by
   (cond Φ ~ 1e17 over 30 days): the restart keeps the full precision of the integrator.
   U of record k is the top n_p rows of Ψ(t_k, t_j). Stochastic accelerations (a
   ``[stochastic]`` table) and the execution errors of manoeuvres (``[[manoeuvre]]``) add the
   columns S(t) = ∂x(t)/∂s of their parameters referred to the same epoch; the integration
   then also restarts at their interval boundaries and at the burns, an impulsive burn
   jumping the state, Φ and S there (:mod:`tapp.tracking.pieces`), Φ and S being carried
   across them by forward products.

2. **Observations.** Samples fall on the schedule's grid (or in the passes of a pass
   schedule: :mod:`tapp.tracking.schedule`; the rules are :mod:`tapp.tracking.editing`'s);
   a station observes where the spacecraft is above its mask (geometric elevation) and
   outside its blackouts; runs of
   samples form passes (:func:`tapp.measurements.find_passes`, split at gaps); passes shorter
   than min_pass_s are removed, and passes longer than max_pass_s are split into consecutive
   passes of at most max_pass_s (each its own block of the real world's M: its own per-pass
   bias), none of their samples removed. Every scheduled observation is either kept or
   counted under the first of :data:`EDITING_RULES` that removed it (the tape's
   ``editing/``, :class:`tapp.io.tape.t13.TapeEditing`). Observables and their partials come from
   :class:`tapp.measurements.MeasurementModel` (state, station location, biases; light time
   optional, with the bounce state from the integrated trajectory; relativistic as
   :func:`relativity_choice` decides; a three-way station's up-leg partials go to its uplink
   station's location columns, and its samples need the uplink to see the spacecraft at
   transmission: :func:`_uplink_above`). A ΔDOR baseline
   (:mod:`tapp.tracking.ddor`) is an entry after the stations: its points fall on the same
   grid where both stations see the spacecraft (a mutual-visibility window is its pass), its
   rows come from :class:`tapp.measurements.ddor.DdorModel` (one-way legs; partials w.r.t.
   both stations' locations and, with ``quasar_position``, its quasar's position), the
   columns of constant EOP offsets (``[parameters] earth_orientation``) filled for every
   station and baseline, the reference quasar at its stated angle from the nominal
   geocentric direction of the spacecraft. One row of A per scalar observation, referred to
   the epoch t_j of its record:

   .. math::

       A = \\Big[\\, H\\,\\Phi(t, t_j),\\; H\\,S_j(t),\\; \\partial h/\\partial(\\text{location}),
       \\; \\partial h/\\partial(\\text{bias}),\\; \\partial h/\\partial(\\text{zenith}),
       \\; H\\,S_{s,j}(t) \\,\\Big].

   With a ``[media]`` table the stations' range, range-rate and Doppler carry the
   troposphere and ionosphere (:mod:`tapp.measurements.media`; ΔDOR does not), and their
   zenith parameters (``[parameters] media``) their columns ∂h/∂(zenith dry, wet km, TEC
   TECU); a three-way up-leg crosses its uplink station's atmosphere, whose partials go to
   that station's zenith columns when it tracks too (else its media are nominal only, as
   its location).

3. **Square-root information.** Per (record k, station s): upper-triangular factors R and R̃
   with RᵀR = ΔJ = AᵀWA and R̃ᵀR̃ = ΔJ̃ = AᵀWMWA over the observations in (t_{k-1}, t_k],
   from a Householder QR of the whitened rows (:func:`tapp.measurements.noise.pass_rows`: exact
   for the correlated real world, O(n) per pass), never from a formed normal matrix. The
   real world's M is block-diagonal over (station, observable kind, pass) *and record*: a
   pass that straddles a T13 time is split there, since the tape has no place for the cross
   terms of two records (and TAPP III treats the noise of new data as uncorrelated with what
   came before). R̃ is also kept split into the factors of its white, per-pass bias and
   correlated parts (``pairs/Rt_parts``), whose Grams sum to ΔJ̃: TAPP III's error budget
   reads them.

4. **Miss parameters.** m at the miss time from the state propagated from t_0 (B-plane of the
   osculating target-relative hyperbola, or orbit elements), and

   .. math:: B = \\frac{\\partial m}{\\partial x(t_0)} = G\\,[\\Phi(t_m, t_0),\\ S(t_m),\\ 0,
             \\ S_s(t_m)]
             + \\frac{\\partial m}{\\partial q}\\Big|_{\\text{direct}}

   with G = ∂m/∂x(t_m) by central differences of the closed-form m (steps 1e-6 of |r|,
   |v| of the state the formulas take, target-relative for a B-plane, and of GM: truncation
   ~1e-12, rounding ~1e-10 relative) and the direct terms: for the GM the formulas use (the
   target's GM for a B-plane, the Earth's for elements), and for a B-plane target's ephemeris
   offset dr_<body>_x|y|z (the state relative to the target is x − (s_B + δ_B): −G's position
   columns; :mod:`tapp.dynamics.ephemeris_offsets`). A B-plane's
   reference pole is that of the fixed miss time t_m (``"body_equator"``: the body's IAU
   pole at the TDB of t_m, :meth:`tapp.targeting.program.BPlaneProgram.reference_pole`), the
   same for every differenced state: G is a partial w.r.t. the state at the fixed time t_m
   and the pole depends on time only, so holding it is exact (for scale: the Moon's pole,
   the fastest, turns by < 1e-8 rad/s; a miss time that moves with x(t_0), as a
   "periapsis" one physically would, is not what B describes). The entry
   flight-path angle (``entry_fpa_rad``) is that of the osculating target-relative hyperbola
   at ``miss.entry_radius_km`` (:func:`tapp.orbit.bplane.entry_flight_path_angle`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from threadpoolctl import threadpool_limits

from tapp.constants import C_LIGHT_km_s
from tapp.dynamics import Propagator, Trajectory
from tapp.dynamics.ephemeris_offsets import offset_of, offset_values
from tapp.dynamics.events import Events
from tapp.dynamics.forces import default_parameters
from tapp.dynamics.parameters import gm_name
from tapp.errors import InputError
from tapp.estimation.factors import triangularize
from tapp.io.tape.t13 import (
    T13,
    TapeEditing,
    TapeMiss,
    TapePairs,
    TapeParameters,
    TapePasses,
    TapeRaw,
    TapeRecords,
    TapeStations,
)
from tapp.measurements import (
    BIAS_NAMES,
    STATION_PARAMETER_NAMES,
    LightTime,
    MeasurementModel,
    Station,
    is_visible,
    wrap_angle_rad,
)
from tapp.measurements.ddor import (
    DDOR_KIND,
    DdorModel,
    projected_baseline_km,
    quasar_direction,
)
from tapp.measurements.media import MEDIA_KINDS, MEDIA_PARAMETER_NAMES
from tapp.measurements.noise import PARTS, pass_rows
from tapp.measurements.relativity import (
    SHAPIRO_BODIES,
    AUTO_DISTANCE_km,
    Relativity,
)
from tapp.orbit.bplane import b_plane, entry_flight_path_angle
from tapp.orbit.elements import cartesian_to_elements
from tapp.orbit.equinoctial import equinoctial_elements
from tapp.targeting.program import BPlaneProgram
from tapp.tracking.centre import geocentric
from tapp.tracking.ddor import TrackingBaseline
from tapp.tracking.editing import (
    EDITING_RULES,
    Editing,
    edited_passes,
    outside_blackouts,
    removed_text,
)
from tapp.tracking.encounter import check_entry, prepare_encounter
from tapp.tracking.pieces import Forcing, SegmentPartials, fly, propagate_pieces
from tapp.tracking.reference import ReferenceFit, fitted
from tapp.tracking.scenario import (
    BIAS_KINDS,
    KINDS,
    MISS_QUANTITIES,
    Scenario,
    TrackingStation,
    pass_suffix,
    with_passes,
)
from tapp.tracking.schedule import (
    StationSamples,
    by_schedule,
    schedule_provenance,
    scheduled_passes,
    station_samples,
)

#: progress(stage, step, total): called as work advances (the CLI draws a bar with it).
ProgressCallback = Callable[[str, int, int], None]

#: Relative step of the central differences of the miss function (module docstring).
MISS_STEP = 1e-6
#: Classical elements are refused as miss parameters below this e or inclination (rad):
#: their angles are singular there (use equinoctial elements).
CLASSICAL_MIN_E = 1e-4
CLASSICAL_MIN_I_rad = 1e-4
#: Kind codes of the raw rows: the stations' observables, then ΔDOR (baselines).
RAW_KINDS = (*KINDS, DDOR_KIND)


@dataclass(frozen=True, slots=True)
class Simulation:
    """What :func:`simulate` returns: the T13 tape and the trajectory it was built on.

    Attributes
    ----------
    tape : T13
    t_s : (N,) trajectory times, s from the epoch (t_0 = 0, the samples and T13 times).
    states : (N, 6) states, km and km/s, Earth-centred, inertial: GCRS under the iau2006
        Earth orientation, EME2000 under gmst.
    scenario : the scenario simulated (its injection state is ``states[0]``).
    warnings : one line each, ``SOURCE: FIELD: what``: a station that yields no
        observation while others do (it never sees the spacecraft above its mask, outside its
        blackouts, for min_pass_s), with the samples each editing rule removed.
    events : the integration events of the trajectory from t = 0 to its end (shadow
        entries and exits, Harris-Priester table heights: :mod:`tapp.dynamics.events`).
    reference_fit : the fit of the force model to the scenario's ``[reference]``
        (:mod:`tapp.tracking.reference`), whose fitted trajectory was flown; None without one.
    """

    tape: T13
    t_s: np.ndarray
    states: np.ndarray
    scenario: Scenario
    warnings: tuple[str, ...] = ()
    events: Events = field(default_factory=Events.none)
    reference_fit: ReferenceFit | None = None


@dataclass(frozen=True, slots=True)
class _Arc:
    """Trajectory on the output times, partials referred to each time's epoch (those of the
    segment parameters, stochastic accelerations and execution errors, in ``batches``, None
    without them)."""

    t_s: np.ndarray
    states: np.ndarray
    phi: np.ndarray
    sens: np.ndarray
    batches: SegmentPartials | None = None
    #: The geocentric states the stations observe (:mod:`tapp.tracking.centre`; the states
    #: themselves about the Earth), set once the trajectory is flown.
    geo: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class _StationData:
    """Samples of one station (or ΔDOR baseline): rows A (n, m, n_o), values, records,
    passes, segments; ``scale`` (n,) the observable's unit per noise unit of each sample (a
    ΔDOR σ in nrad: its projected baseline, km), None: 1; ``taken`` (n, m) bool, the
    observables each sample measures (a scheduled pass's data types), None: all."""

    t_s: np.ndarray
    values: np.ndarray
    a: np.ndarray
    record: np.ndarray
    segment: np.ndarray
    passes: list[tuple[float, float, int]]
    scale: np.ndarray | None = None
    taken: np.ndarray | None = None


# ---------------------------------------------------------------------------------------------
# Trajectory
# ---------------------------------------------------------------------------------------------


def _n_samples(scenario: Scenario, end_s: float) -> int:
    """Number of sample times start + i Δt (i >= 0) up to ``end_s``."""
    sch = scenario.schedule
    return max(int(math.floor((end_s - sch.start_s) / sch.data_interval_s * (1 + 1e-14))) + 1,
               0)


def _grid(scenario: Scenario, last_s: float) -> np.ndarray:
    """Sample times start + i Δt in (0, min(end, last T13 time)], s."""
    sch = scenario.schedule
    end = min(sch.end_s, last_s)
    t = sch.start_s + sch.data_interval_s * np.arange(_n_samples(scenario, end))
    return t[(t > 0) & (t <= end)]


def _forcing(scenario: Scenario) -> Forcing:
    """What acts on pieces of the scenario's arc (:mod:`tapp.tracking.pieces`)."""
    return Forcing(scenario.stochastic, scenario.manoeuvres)


def _arc(scenario: Scenario, prop: Propagator, t13: np.ndarray, is_epoch: np.ndarray,
         grid: np.ndarray, progress: Callable[[str], None]) -> _Arc:
    """Propagate segment by segment from each epoch time (module docstring, item 1)."""
    epochs = t13[is_epoch]
    ends = np.append(epochs[1:], t13[-1])
    x_start = np.asarray(scenario.x0, dtype=float)
    values = dict(scenario.dynamic_values)
    parts: list[Trajectory] = []
    batches: list[SegmentPartials] = []
    forcing = _forcing(scenario)
    for a, b in zip(epochs, ends, strict=True):
        out = np.unique(np.concatenate([grid[(grid > a) & (grid <= b)],
                                        t13[(t13 > a) & (t13 <= b)]]))
        if not forcing:
            traj = prop.propagate(x_start, out, t0_s=float(a), stm=True, param_values=values,
                                  orientation=scenario.orientation,
                                  epoch_jd_utc=scenario.epoch.jd)
        else:
            arc = propagate_pieces(prop, forcing, x_start, out, t0_s=float(a),
                                   param_values=values, orientation=scenario.orientation,
                                   epoch_jd_utc=scenario.epoch.jd)
            traj = Trajectory(out, arc.states, arc.phi, arc.sens, prop.params, 0, 0)
            batches.append(arc.partials)
        parts.append(traj)
        x_start = traj.states[-1]
        progress("propagation")
    return _Arc(np.concatenate([p.t_s for p in parts]),
                np.concatenate([p.states for p in parts]),
                np.concatenate([p.stm for p in parts]),
                np.concatenate([p.sensitivity for p in parts]),
                SegmentPartials.join(batches) if batches else None)


# ---------------------------------------------------------------------------------------------
# Observations
# ---------------------------------------------------------------------------------------------


def _above(station: Station, scenario: Scenario, t: np.ndarray, states: np.ndarray
           ) -> np.ndarray:
    """Whether ``station`` sees the spacecraft strictly above its mask at t, (N,) bool."""
    geometric = MeasurementModel(station, scenario.orientation, ("elevation",))
    return is_visible(geometric.elevation_rad(t, states), station.elev_mask_rad)


def _light_time(scenario: Scenario, prop: Propagator, two_way: bool,
                relativity: Relativity | None = None) -> LightTime | None:
    """The scenario's light-time model (None: off), the bounce state from the integrated
    trajectory."""
    if scenario.schedule.light_time == "none":
        return None
    values = dict(scenario.dynamic_values)

    def state_at(t_s: np.ndarray) -> np.ndarray:  # geocentric (tapp.tracking.centre)
        states = fly(prop, scenario.manoeuvres, scenario.x0, t_s, param_values=values,
                     orientation=scenario.orientation, epoch_jd_utc=scenario.epoch.jd).states
        return geocentric(scenario.state_model.center, scenario.epoch, scenario.orientation,
                          t_s, states)

    return LightTime(two_way=two_way, state_at=state_at, relativity=relativity)


def relativity_choice(scenario: Scenario, t_s: np.ndarray, states: np.ndarray
                      ) -> tuple[Relativity | None, str]:
    """Return the scenario's relativistic light-time model (None: Newtonian) and a line
    saying which was used and why, for the tape's provenance and the run's output.

    ``[tracking] relativity``: True or False as given (True needs light time); "auto": on
    with two-way light time when the spacecraft's geocentric distance exceeds
    :data:`tapp.measurements.relativity.AUTO_DISTANCE_km` at a time ``t_s`` (N,) of
    ``states`` (N, 6) in the tracking span. The Shapiro bodies: Sun, Earth, Moon, and
    Jupiter when it is a third body of the state model.
    """
    sch = scenario.schedule
    mode = sch.relativity
    if sch.light_time == "none" or mode is False:
        return None, f"off (relativity = {str(mode).lower()}, light_time = {sch.light_time})"
    span = (t_s >= sch.start_s) & (t_s <= sch.end_s)
    reach = float(np.max(np.linalg.norm(states[span, :3], axis=-1), initial=0.0))
    if mode == "auto" and (sch.light_time != "two_way" or reach <= AUTO_DISTANCE_km):
        return None, (f"off (auto: light_time = {sch.light_time}, farthest "
                      f"{reach:,.0f} km, on beyond {AUTO_DISTANCE_km:,.0f} km two-way)")
    bodies = SHAPIRO_BODIES + (("jupiter",) if "jupiter" in scenario.state_model.third_bodies
                               else ())
    why = "relativity = true" if mode is True else f"auto: farthest {reach:,.0f} km"
    return (Relativity.at(scenario.epoch, bodies),
            f"on ({why}; barycentric TDB, Shapiro of {', '.join(bodies)})")


def _measurement_model(ts: TrackingStation, scenario: Scenario, prop: Propagator,
                       relativity: Relativity | None = None) -> MeasurementModel:
    light_time = _light_time(scenario, prop, scenario.schedule.light_time == "two_way",
                             relativity)
    return MeasurementModel(ts.station, scenario.orientation, ts.kinds, light_time,
                            ts.range_bias_km, ts.range_rate_bias_km_s, media=ts.media,
                            uplink=ts.uplink, uplink_media=ts.uplink_media,
                            count_time_s=scenario.schedule.count_time_s,
                            doppler_bias_km_s=ts.doppler_bias_km_s)


def _state_rows(h: np.ndarray, arc: _Arc, p: np.ndarray, scenario: Scenario,
                columns: dict[str, int]) -> np.ndarray:
    """Rows A (n, m, n_o) of the samples at arc positions ``p`` with the orbit, dynamic and
    segment-parameter columns [H Φ, H S, H S_s] filled."""
    a = np.zeros(h.shape[:2] + (len(columns),))
    sens = arc.sens[p]
    a[..., :6] = h @ arc.phi[p]
    a[..., 6:6 + sens.shape[-1]] = h @ sens
    if arc.batches is not None:
        names = _forcing(scenario).names
        first = columns[names[0]] if names else len(columns)
        a[..., first:first + len(names)] = arc.batches.rows(p, h)
    return a


def _segments(t: np.ndarray, label: np.ndarray, t13: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Record k of each sample and its segment (a pass split at the T13 times), (n,) int."""
    record = np.searchsorted(t13, t, side="left")
    change = np.ones(t.size, dtype=bool)
    change[1:] = (label[1:] != label[:-1]) | (record[1:] != record[:-1])
    return record, np.cumsum(change) - 1


@dataclass(frozen=True, slots=True)
class _StationPasses:
    """One station's passes: the candidate times (the grid, or its scheduled samples), their
    positions in the arc, the passes [start, end) into them, the observables each scheduled
    sample measures (None: all) and what the rules removed."""

    times: np.ndarray
    pos: np.ndarray
    passes: list[tuple[int, int]]
    taken: np.ndarray | None
    editing: Editing


def _station_passes(ts: TrackingStation, scenario: Scenario, arc: _Arc, grid: np.ndarray,
                    n_scheduled: int, samples: StationSamples | None = None
                    ) -> _StationPasses:
    """One station's passes (module docstring, item 2), and what the rules removed of its
    ``n_scheduled`` samples on the ``grid``, or of its scheduled ``samples``
    (:mod:`tapp.tracking.schedule`). A three-way station also needs its uplink station to
    see the spacecraft at transmission (:func:`_uplink_above`)."""
    sch = scenario.schedule
    times = grid if samples is None else samples.t_s
    pos = np.searchsorted(arc.t_s, times)
    above = (_above(ts.station, scenario, times, arc.geo[pos]) if times.size
             else np.zeros(0, dtype=bool))  # a station without a scheduled sample
    if ts.uplink is not None and times.size:
        above &= _uplink_above(ts.uplink, scenario, times, arc.geo[pos])
    taken = None
    if samples is None:
        passes, editing = edited_passes(above, ts.blackouts_s, sch.min_pass_s, sch.max_pass_s,
                                        sch.data_interval_s, grid, n_scheduled, len(ts.kinds))
    else:
        passes, taken, editing = scheduled_passes(samples, above, ts, sch, scenario.epoch)
    return _StationPasses(times, pos, passes, taken, editing)


def _station_data(ts: TrackingStation, scenario: Scenario, prop: Propagator, arc: _Arc,
                  found: _StationPasses, t13: np.ndarray, columns: dict[str, int],
                  relativity: Relativity | None = None) -> _StationData | None:
    """Rows of A for one station's passes (module docstring, item 2), or None without
    any."""
    times, pos, passes, taken = found.times, found.pos, found.passes, found.taken
    if not passes:
        return None
    take = np.concatenate([np.arange(a, b) for a, b in passes])
    label = np.concatenate([np.full(b - a, i) for i, (a, b) in enumerate(passes)])
    t, p = times[take], pos[take]
    x = arc.geo[p]
    model = _measurement_model(ts, scenario, prop, relativity)
    a = _state_rows(model.state_partials(t, x), arc, p, scenario, columns)
    name = ts.station.name
    if ts.location != "none":
        first = columns[f"{name}.{STATION_PARAMETER_NAMES[ts.location][0]}"]
        a[..., first:first + 3] = model.station_partials(t, x, ts.location)
    uplink = next((u for u in scenario.stations if ts.uplink is not None
                   and u.station.name == ts.uplink.name), None)
    if uplink is not None and uplink.location != "none":  # the up-leg's part goes to the
        # transmitter's location columns
        first = columns[f"{uplink.station.name}.{STATION_PARAMETER_NAMES[uplink.location][0]}"]
        a[..., first:first + 3] += model.uplink_station_partials(t, x, uplink.location)
    bias = model.bias_partials(t)
    for kind in ts.biases:
        i = BIAS_KINDS.index(kind)
        a[..., columns[f"{name}.{BIAS_NAMES[i]}"]] = bias[..., i]
    if ts.media_parameters:
        zenith = model.media_partials(t, x)
        if ts.media_per == "station":
            _zenith_columns(a, columns, name, ts.media_parameters, zenith)
        else:  # each pass's own
            for i in range(len(passes)):
                _zenith_columns(a, columns, name, ts.media_parameters, zenith, label == i,
                                pass_suffix(i))
        if uplink is not None and ts.uplink_media is not None:  # and the up-leg's media
            _zenith_columns(a, columns, uplink.station.name, uplink.media_parameters,
                            model.uplink_media_partials(t, x))
    _eop_rows(a, scenario, columns, t, lambda names: model.eop_partials(t, x, names))
    record, segment = _segments(t, label, t13)
    counts = np.full(times.size, len(ts.kinds)) if taken is None else taken.sum(axis=1)
    pass_list = [(float(times[a_]), float(times[b_ - 1]), int(counts[a_:b_].sum()))
                 for a_, b_ in passes]
    return _StationData(t, model.compute(t, x), a, record, segment, pass_list,
                        taken=None if taken is None else taken[take])


def _zenith_columns(a: np.ndarray, columns: dict[str, int], station: str,
                    effects: tuple[str, ...], zenith: np.ndarray,
                    rows: np.ndarray | slice = slice(None), suffix: str = "") -> None:
    """Add the partials w.r.t. a station's zenith parameters (N, m, 3) to its columns of A
    (those of ``effects`` in q; ``suffix``: a pass's, in that pass's ``rows``)."""
    for i, (zname, kind) in enumerate(zip(MEDIA_PARAMETER_NAMES, MEDIA_KINDS, strict=True)):
        if kind in effects:
            a[rows, ..., columns[f"{station}.{zname}{suffix}"]] += zenith[rows, ..., i]


def _uplink_above(uplink: Station, scenario: Scenario, t: np.ndarray, states: np.ndarray
                  ) -> np.ndarray:
    """Whether the three-way ``uplink`` station sees the spacecraft strictly above its mask
    at the transmit time t - 2 |r - r_uplink| / c, (N,) bool: the geometric elevation with
    the spacecraft at its receive-time position (its motion over the round trip turns the
    direction by < v tau / rho, 1e-4 rad). Samples it does not see are edited out under the
    elevation mask, as the receiver's are; a scheduled pass refuses them unless
    allow_partial (:mod:`tapp.tracking.schedule`)."""
    geometric = MeasurementModel(uplink, scenario.orientation, ("range",))
    transmit = t - 2.0 * geometric.compute(t, states)[:, 0] / C_LIGHT_km_s
    return _above(uplink, scenario, transmit, states)


def _ddor_points(bl: TrackingBaseline, windows: list[tuple[int, int]], grid: np.ndarray,
                 scenario: Scenario, n_scheduled: int) -> tuple[list[np.ndarray], np.ndarray, int]:
    """The ΔDOR points of each window (grid indices, empty windows left out), the mask of
    the grid samples the schedule asks for, and how many it asks for over the whole span:
    every ``interval_s`` on the tracking grid, or the middle sample of each window."""
    sch = scenario.schedule
    if bl.interval_s is None:
        picks = [np.array([(a + b - 1) // 2]) for a, b in windows]
        asked = np.zeros(grid.size, dtype=bool)
        asked[[int(p[0]) for p in picks]] = True
        return picks, asked, len(picks)
    k = round(bl.interval_s / sch.data_interval_s)
    asked = np.rint((grid - sch.start_s) / sch.data_interval_s).astype(np.int64) % k == 0
    picks = [np.flatnonzero(asked[a:b]) + a for a, b in windows]
    return [p for p in picks if p.size], asked, -(-n_scheduled // k)


def _baseline_data(bl: TrackingBaseline, scenario: Scenario, prop: Propagator, arc: _Arc,
                   grid: np.ndarray, t13: np.ndarray, columns: dict[str, int],
                   n_scheduled: int) -> tuple[_StationData | None, Editing]:
    """Rows of A of one ΔDOR baseline (:mod:`tapp.tracking.ddor`), or None without points,
    and what the rules removed of the points its schedule asks for (a window is a pass)."""
    sch = scenario.schedule
    pair = [scenario.stations[n - 1] for n in (bl.station_a, bl.station_b)]
    pos = np.searchsorted(arc.t_s, grid)
    above = np.logical_and(*(_above(ts.station, scenario, grid, arc.geo[pos])
                             for ts in pair))
    blackouts = pair[0].blackouts_s + pair[1].blackouts_s
    windows, win_editing = edited_passes(above, blackouts, bl.min_window_s, math.inf,
                                         sch.data_interval_s, grid, n_scheduled)
    picks, asked, n_asked = _ddor_points(bl, windows, grid, scenario, n_scheduled)
    visible = outside_blackouts(above, grid, blackouts)
    kept = np.zeros(grid.size, dtype=bool)
    for p in picks:
        kept[p] = True
    removed = (n_asked - int(np.count_nonzero(asked)), np.count_nonzero(asked & ~above),
               np.count_nonzero(asked & above & ~visible),
               np.count_nonzero(asked & visible & ~kept))
    editing = Editing(tuple(int(n) for n in removed), win_editing.removed_passes, 0, n_asked)
    if not picks:
        return None, editing
    take = np.concatenate(picks)
    t, p = grid[take], pos[take]
    x = arc.geo[p]
    model = DdorModel(pair[0].station, pair[1].station, scenario.orientation,
                      _light_time(scenario, prop, two_way=False))
    quasar = quasar_direction(x[:, :3], bl.separation_rad, bl.position_angle_rad)
    a = _state_rows(model.state_partials(t, x, quasar), arc, p, scenario, columns)
    for which, ts in enumerate(pair):
        if ts.location != "none":
            first = columns[f"{ts.station.name}.{STATION_PARAMETER_NAMES[ts.location][0]}"]
            a[..., first:first + 3] = model.station_partials(t, x, quasar, ts.location)[which]
    _eop_rows(a, scenario, columns, t, lambda names: model.eop_partials(t, x, quasar, names))
    if bl.quasar_position:
        first = columns[bl.quasar_parameters[0]]
        a[..., first:first + 2] = model.quasar_partials(t, x, quasar)
    scale = None
    if bl.per_nrad:
        r_a, r_b = (ts.station.state_eci(scenario.orientation, t)[:, :3] for ts in pair)
        scale = projected_baseline_km(r_b - r_a, x[:, :3])
    label = np.concatenate([np.full(q.size, i) for i, q in enumerate(picks)])
    record, segment = _segments(t, label, t13)
    pass_list = [(float(grid[q[0]]), float(grid[q[-1]]), int(q.size)) for q in picks]
    return (_StationData(t, model.compute(t, x, quasar), a, record, segment, pass_list, scale),
            editing)


def _accumulate(ts: TrackingStation | TrackingBaseline, data: _StationData, n_o: int
                ) -> dict[int, tuple[np.ndarray, np.ndarray, int, np.ndarray]]:
    """Per record k: the station's factors [R (n_o, n_o), R̃ (n_o, n_o), n_obs, the factors of
    R̃'s parts (3, n_o, n_o)] (module docstring, item 3): the rows of
    :func:`tapp.measurements.noise.pass_rows` of every segment and kind in the record,
    triangularised by Householder QR; R̃ is the QR of the three part factors stacked."""
    rows: dict[int, list] = {}
    bounds = np.flatnonzero(np.diff(data.segment, prepend=-1, append=data.segment[-1] + 1))
    for start, stop in zip(bounds[:-1], bounds[1:], strict=True):
        k = int(data.record[start])
        acc = rows.setdefault(k, [[], [[] for _ in PARTS], 0])
        t = data.t_s[start:stop]
        # Rows in the noise unit: A / scale with σ in that unit (the same AᵀWA, AᵀWMWA).
        scale = 1.0 if data.scale is None else data.scale[start:stop, None]
        for c, (fit, real) in enumerate(zip(ts.fit, ts.real, strict=True)):
            rows_c = (slice(None) if data.taken is None
                      else np.flatnonzero(data.taken[start:stop, c]))
            t_c = t[rows_c]
            if not t_c.size:  # a scheduled pass without this observable
                continue
            weights = np.full(t_c.size, fit.weight)
            pr = pass_rows((data.a[start:stop, c, :] / scale)[rows_c], t_c, weights, real)
            acc[0].append(pr.fit)
            for part, block in zip(acc[1], pr.parts, strict=True):
                part.append(block)
            acc[2] += t_c.size
    out = {}
    for k, (fit_rows, part_rows, count) in rows.items():
        parts = np.array([triangularize(*blocks, n=n_o) for blocks in part_rows])
        out[k] = (triangularize(*fit_rows, n=n_o), triangularize(*parts), count, parts)
    return out


def _raw(stations: tuple[TrackingStation | TrackingBaseline, ...],
         data: list[_StationData | None], n_o: int) -> TapeRaw:
    """One row per scalar observation, time-ordered within each station (and baseline: kind
    code ``RAW_KINDS.index("ddor")``), weights and variances in the observables' units."""
    cols: dict[str, list[np.ndarray]] = {}
    segment_offset = 0
    for ts, d in zip(stations, data, strict=True):
        if d is None:
            continue
        n, m = d.values.shape
        kind_code = np.array([RAW_KINDS.index(k) for k in ts.kinds])
        # Variance of each sample: σ² scale² (the noise unit to the observable's).
        scale2 = np.ones((n, 1)) if d.scale is None else d.scale[:, None] ** 2
        rows = {
            "t_s": np.repeat(d.t_s, m),
            "station": np.full(n * m, ts.number),
            "kind": np.tile(kind_code, n),
            "record": np.repeat(d.record, m),
            "segment": segment_offset + (d.segment[:, None] * m + np.arange(m)).ravel(),
            "value": d.values.ravel(),
            "A": d.a.reshape(n * m, n_o),
            "weight": (np.array([f.weight for f in ts.fit]) / scale2).ravel(),
            "m_white_var": (np.array([r.sigma_white**2 for r in ts.real]) * scale2).ravel(),
            "m_bias_var": (np.array([r.sigma_pass_bias**2 for r in ts.real]) * scale2).ravel(),
            "m_corr_var": (np.array([r.sigma_correlated**2 for r in ts.real]) * scale2).ravel(),
            "m_tau_s": np.tile([r.tau_s for r in ts.real], n),
        }
        segment_offset += (int(d.segment[-1]) + 1) * m
        taken = slice(None) if d.taken is None else d.taken.ravel()
        for key, value in rows.items():
            cols.setdefault(key, []).append(value[taken])
    joined = {key: np.concatenate(value) for key, value in cols.items()}
    return TapeRaw(RAW_KINDS, **joined)


# ---------------------------------------------------------------------------------------------
# Miss parameters
# ---------------------------------------------------------------------------------------------


def _miss_function(scenario: Scenario, gm_values: dict[str, float]
                   ) -> tuple[Callable[[np.ndarray, float], np.ndarray], str, float, np.ndarray]:
    """Return (m(state at t_m, gm), name of the GM it uses directly, that GM's value, the
    state the differencing steps scale with: relative to the target for a B-plane)."""
    miss = scenario.miss
    names = [n for n, _ in MISS_QUANTITIES[miss.kind]]
    index = [names.index(q) for q in miss.quantities]
    if miss.kind == "bplane":
        program = BPlaneProgram(scenario.epoch, scenario.x0[:3],
                                Propagator(scenario.state_model), target=miss.body,
                                reference=miss.reference, orientation=scenario.orientation)
        body = program.target_state(np.array([miss.t_s]))[0][0]
        body[:3] += offset_values(gm_values, miss.body)  # its ephemeris offset, nominal 0
        pole = program.reference_pole(np.array([miss.t_s]))[0]  # fixed at t_m (module doc)
        entry = "entry_fpa_rad" in miss.quantities

        def bplane(x: np.ndarray, gm: float) -> np.ndarray:
            z = x - body
            bp = b_plane(z[:3], z[3:], gm, reference=pole)
            fpa = (entry_flight_path_angle(z[:3], z[3:], gm, miss.entry_radius_km) if entry
                   else math.nan)
            all_values = (bp.b_dot_r_km, bp.b_dot_t_km, bp.ltof_s,
                          miss.t_s + bp.time_to_periapsis_s, fpa)
            return np.array([float(all_values[i]) for i in index])

        name = gm_name(miss.body)
        return bplane, name, gm_values[name], -body

    def elements(x: np.ndarray, gm: float) -> np.ndarray:
        if miss.kind == "equinoctial":
            return equinoctial_elements(x, gm)[index]
        return np.asarray(cartesian_to_elements(x, gm), dtype=float)[index]

    return elements, gm_name(), gm_values[gm_name()], np.zeros(6)


def _difference(f: Callable[[np.ndarray], np.ndarray], x: np.ndarray, steps: np.ndarray,
                angles: np.ndarray) -> np.ndarray:
    """Central differences of f at x with per-component steps; angle rows wrapped."""
    cols = []
    for i, h in enumerate(steps):
        e = np.zeros_like(x)
        e[i] = h
        diff = f(x + e) - f(x - e)
        diff[angles] = wrap_angle_rad(diff[angles])
        cols.append(diff / (2.0 * h))
    return np.stack(cols, axis=-1)


def miss_partials(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Return the nominal miss parameters (n_m,) and B = ∂m/∂x(t_0) (n_m, n_o).

    Equations in the module docstring (item 4). The miss time must be resolved (a
    ``"periapsis"`` one is found by :func:`tapp.tracking.encounter.prepare_encounter`, which
    :func:`simulate` runs first).

    Raises
    ------
    InputError
        Classical elements asked of a near-circular or near-equatorial orbit.
        An entry flight-path angle whose ``miss.entry_radius_km`` is not below the distance at
        the miss time, or below the hyperbola's periapsis radius
        (:func:`tapp.tracking.encounter.check_entry`).
    NotHyperbolicError
        A B-plane asked of a state that is not hyperbolic relative to the target.
    """
    miss = scenario.miss
    values = dict(scenario.dynamic_values)
    forcing = _forcing(scenario)
    if forcing:
        arc = propagate_pieces(scenario.propagator(), forcing, scenario.x0,
                               np.array([miss.t_s]), t0_s=0.0, param_values=values,
                               orientation=scenario.orientation, epoch_jd_utc=scenario.epoch.jd)
        x, phi, sens = arc.states[0], arc.phi[0], arc.sens[0]
    else:
        traj = scenario.propagator().propagate(
            scenario.x0, np.array([miss.t_s]), stm=True, param_values=values,
            orientation=scenario.orientation, epoch_jd_utc=scenario.epoch.jd)
        x, phi, sens = traj.states[0], traj.stm[0], traj.sensitivity[0]
    body_gm = gm_name(miss.body if miss.kind == "bplane" else "")
    gm_values = default_parameters(scenario.state_model, (body_gm,))
    gm_values.update(values)
    f, gm_param, gm, offset = _miss_function(scenario, gm_values)
    # Steps scale with the state the formulas see (target-relative for a B-plane: |z| of a
    # flyby is 1e-2 of the Earth-centred |x|, and G's position block needs the finer step).
    rel = x + offset
    check_entry(scenario, rel, gm)
    nominal = f(x, gm)
    if miss.kind == "classical":
        elements = np.asarray(cartesian_to_elements(x, gm), dtype=float)
        e, i = elements[1], min(elements[2], np.pi - elements[2])
        if e < CLASSICAL_MIN_E or i < CLASSICAL_MIN_I_rad:
            raise InputError(scenario.source, "miss.kind",
                             "equinoctial elements for a near-circular or near-equatorial "
                             "orbit (classical angles are singular there)",
                             f"e = {e:.3g}, i = {i:.3g} rad at the miss time")
    angles = np.array([u == "rad" for u in miss.units])
    steps = MISS_STEP * np.repeat([np.linalg.norm(rel[:3]), np.linalg.norm(rel[3:])], 3)
    g = _difference(lambda s: f(s, gm), x, steps, angles)
    big_b = np.zeros((len(nominal), scenario.n_o))
    big_b[:, :6] = g @ phi
    big_b[:, 6:6 + sens.shape[-1]] = g @ sens
    if gm_param in scenario.dynamic:
        column = 6 + scenario.dynamic.index(gm_param)
        big_b[:, column] += _difference(lambda q: f(x, float(q[0])), np.array([gm]),
                                        np.array([MISS_STEP * gm]), angles)[:, 0]
    if miss.kind == "bplane":  # z = x - (s_B + δ_B): the body's ephemeris offset, -G E
        for j, name in enumerate(scenario.dynamic):
            if (found := offset_of(name)) and found[0] == miss.body:
                big_b[:, 6 + j] -= g[:, found[1]]
    if forcing.names:
        first = scenario.n_o - len(forcing.names)  # the segment parameters come last
        big_b[:, first:] = arc.partials.rows(np.array([0]), g[None])[0]
    return nominal, big_b


# ---------------------------------------------------------------------------------------------
# The simulator
# ---------------------------------------------------------------------------------------------


def simulate(scenario: Scenario, *, raw: bool = False,
             progress: ProgressCallback | None = None,
             accept_poor_fit: bool = False) -> Simulation:
    """Run TAPP I on a scenario: return the T13 tape and the trajectory.

    A ``[reference]`` trajectory is first fitted by the force model over each arc between
    the burns, and the fitted trajectory (the injection state and the burns) is flown
    (:mod:`tapp.tracking.reference`).

    A B-plane miss is first checked for an encounter, after the ``[targeting]`` of the
    scenario has retargeted its injection (:func:`tapp.tracking.encounter.prepare_encounter`):
    the tape and the trajectory are those of the targeted injection.

    Parameters
    ----------
    scenario : Scenario
    raw : also keep the per-observation rows (``tape.raw``) for validation.
    progress : called with (stage, step, total) as the work advances.
    accept_poor_fit : fly a ``[reference]`` fit worse than its ``max_fit_error_m``
        (:func:`tapp.tracking.reference.fitted`; refused otherwise).

    Raises
    ------
    PoorFitError
        A ``[reference]`` fit worse than its limit, unless ``accept_poor_fit``.
    InputError
        A schedule that yields no observation (naming the scenario file and ``tracking``);
        classical miss elements at a singular orbit; a B-plane miss without an encounter
        (:class:`tapp.tracking.encounter.NoEncounterError`).
    TargetingError
        SEARCH did not reach the ``[targeting]`` aim point.
    PropagationError, NotHyperbolicError, DivergenceError
        From the integrator, the B-plane and the light-time iteration.
    """
    scenario, fit = fitted(scenario, accept_poor_fit=accept_poor_fit)
    scenario, encounter = prepare_encounter(scenario)
    times = scenario.times
    t13, is_epoch, is_input = times.t13_s, times.is_epoch, times.is_input
    n_it = t13.size - 1
    n_p = scenario.n_p
    prop = scenario.propagator()
    n_seg = int(np.count_nonzero(is_epoch))
    names = [ts.station.name for ts in scenario.stations] + [b.name for b in scenario.baselines]
    total = n_seg + 2 * len(names) + 1
    step = iter(range(1, total + 1))

    def tick(stage: str) -> None:
        done = next(step)
        if progress is not None:
            progress(stage, done, total)

    grid = _grid(scenario, float(t13[-1]))
    samples = {ts.number: station_samples(scenario.schedule, ts.station.name, float(t13[-1]))
               for ts in scenario.stations if by_schedule(scenario.schedule, ts.station.name)}
    on_grid = len(samples) < len(scenario.stations) or scenario.baselines
    arc = _arc(scenario, prop, t13, is_epoch, np.unique(np.concatenate(
        [grid if on_grid else grid[:0], *(s.t_s for s in samples.values())])), tick)

    n_scheduled = _n_samples(scenario, scenario.schedule.end_s)
    arc = replace(arc, geo=geocentric(scenario.state_model.center, scenario.epoch,
                                      scenario.orientation, arc.t_s, arc.states))
    relativity, relativity_note = relativity_choice(scenario, arc.t_s, arc.geo)
    found = [_station_passes(ts, scenario, arc, grid, n_scheduled, samples.get(ts.number))
             for ts in scenario.stations]
    # q is complete once the passes are known (per-pass zenith parameters)
    scenario = with_passes(scenario, [len(f.passes) for f in found])
    entries = (*scenario.stations, *scenario.baselines)  # the tape's stations
    params = scenario.parameters
    n_o = len(params)
    columns = {par.name: i for i, par in enumerate(params)}
    data: list[_StationData | None] = []
    editing: list[Editing] = [f.editing for f in found]
    for ts, passes in zip(scenario.stations, found, strict=True):
        data.append(_station_data(ts, scenario, prop, arc, passes, t13, columns, relativity))
        tick(f"observations {ts.station.name}")
    for i, bl in enumerate(scenario.baselines):
        d, e = _baseline_data(bl, scenario, prop, arc, grid, t13, columns, n_scheduled)
        if d is None:
            raise InputError(scenario.source, f"ddor.baselines[{i}]",
                             "a baseline whose stations both see the spacecraft above their "
                             "masks, outside their blackouts, at some ΔDOR point (check the "
                             "masks, min_window_s, interval_s)",
                             f"0 points on {bl.name} of {e.scheduled} asked for; removed: "
                             + removed_text(e.removed_obs))
        data.append(d)
        editing.append(e)
        tick(f"observations {bl.name}")
    if all(d is None for d in data):
        total = Editing.total(editing)
        raise InputError(scenario.source, "tracking",
                         "a schedule that yields at least one observation (check the stations, "
                         "their masks and blackouts, start/end, data_interval_s, min_pass_s)",
                         f"0 observations kept of the {total.scheduled} scheduled over the "
                         "stations; removed: " + removed_text(total.removed_obs))
    warnings = tuple(  # the stations' (the baselines' data and editing follow theirs)
        f"{scenario.source}: tracking.stations[{i}]: {ts.station.name} yields no observation "
        f"while other stations do ("
        + (f"0 of its {e.scheduled} scheduled observations kept; removed: "
           f"{removed_text(e.removed_obs)})" if e.scheduled else "no pass in the schedule)")
        for i, (ts, d, e) in enumerate(zip(
            scenario.stations, data, editing, strict=False)) if d is None)

    pair_rows = []
    with threadpool_limits(limits=1, user_api="blas"):  # many small QRs: threads only cost
        for ts, d, name in zip(entries, data, names, strict=True):
            if d is not None:
                for k, (r, rt, count, parts) in sorted(_accumulate(ts, d, n_o).items()):
                    pair_rows.append((k, ts.number, count, r, rt, parts))
            tick(f"square-root information {name}")
    pair_rows.sort(key=lambda row: (row[0], row[1]))

    nominal, big_b = miss_partials(scenario)
    tick("miss partials")

    at_k = np.searchsorted(arc.t_s, t13[1:])
    u = np.zeros((n_it, n_p, n_o))
    u[:, :, :6] = arc.phi[at_k]
    u[:, :, 6:6 + arc.sens.shape[-1]] = arc.sens[at_k]
    if arc.batches is not None and _forcing(scenario).names:
        first = columns[_forcing(scenario).names[0]]
        u[:, :, first:] = arc.batches.rows(at_k, np.broadcast_to(np.eye(n_p), (n_it, n_p, 6)))
    j = np.maximum.accumulate(np.where(is_epoch[:-1], np.arange(n_it), 0))
    # A baseline's entry carries the position and mask of its first station.
    located = [*(s.station for s in scenario.stations),
               *(scenario.stations[b.station_a - 1].station for b in scenario.baselines)]
    tape = T13(
        iden=scenario.iden,
        epoch=scenario.epoch,
        n_p=n_p,
        parameters=TapeParameters(tuple(p.name for p in params), tuple(p.unit for p in params),
                                  tuple(p.kind for p in params),
                                  np.array([p.station for p in params]),
                                  np.array([p.nominal for p in params])),
        stations=TapeStations(
            np.array([s.number for s in entries]), tuple(names),
            tuple(",".join(s.kinds) for s in entries),
            np.degrees([s.lat_rad for s in located]), np.degrees([s.lon_rad for s in located]),
            np.array([s.h_km for s in located]),
            np.degrees([s.elev_mask_rad for s in located])),
        miss=TapeMiss(scenario.miss.kind, scenario.miss.t_s, scenario.miss.quantities,
                      scenario.miss.units, nominal, big_b),
        records=TapeRecords(t13, is_epoch, is_input, j, np.arange(1, n_it + 1),
                            arc.states[at_k], u),
        pairs=TapePairs(np.array([r[0] for r in pair_rows]), np.array([r[1] for r in pair_rows]),
                        np.array([r[2] for r in pair_rows]),
                        np.array([r[3] for r in pair_rows]), np.array([r[4] for r in pair_rows]),
                        Rt_parts=np.array([r[5] for r in pair_rows])),
        passes=_pass_table(entries, data),
        editing=_editing_table(editing),
        raw=_raw(entries, data, n_o) if raw else None,
        stochastic=scenario.stochastic,
        manoeuvres=scenario.manoeuvres,
        provenance={"scenario": scenario.document_json, "scenario_source": scenario.source,
                    "earth_orientation": scenario.orientation.model,
                    "relativity": relativity_note,
                    "eop": scenario.orientation.eop_note + (
                        " (predicted values used)" if scenario.orientation.uses_predicted_eop(
                            t13) else ""), **encounter, **schedule_provenance(scenario.schedule)},
    )
    t_out = np.concatenate([[0.0], arc.t_s])
    states = np.concatenate([np.asarray(scenario.x0, dtype=float)[None, :], arc.states])
    events = fly(prop, scenario.manoeuvres, scenario.x0, t_out[-1:],
                 param_values=dict(scenario.dynamic_values), orientation=scenario.orientation,
                 epoch_jd_utc=scenario.epoch.jd).events
    return Simulation(tape, t_out, states, scenario, warnings, events, fit)


def _pass_table(stations: tuple[TrackingStation | TrackingBaseline, ...],
                data: list[_StationData | None]) -> TapePasses:
    rows = [(ts.number, *p) for ts, d in zip(stations, data, strict=True) if d is not None
            for p in d.passes]
    rows.sort(key=lambda r: (r[1], r[0]))
    return TapePasses(np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
                      np.array([r[2] for r in rows]), np.array([r[3] for r in rows]))


def _editing_table(editing: list[Editing]) -> TapeEditing:
    """The tape's ``editing/``: the counts of each station and baseline."""
    return TapeEditing(EDITING_RULES, np.array([e.scheduled for e in editing]),
                       np.array([e.removed_obs for e in editing]),
                       np.array([e.removed_passes for e in editing]),
                       np.array([e.added_passes for e in editing]))


def _eop_rows(a: np.ndarray, scenario: Scenario, columns: dict[str, int], t_s: np.ndarray,
              partials: Callable[[tuple[str, ...]], np.ndarray]) -> None:
    """Fill the EOP offsets' columns of rows A (n, m, n_o) at times ``t_s`` (n,) with
    ``partials(names)`` (n, m, k): a station's or a baseline's d h / d(EOP offsets), when
    the scenario has them; per-day offsets each in its day's rows."""
    if not scenario.eop:
        return
    names, k = scenario.eop_names(), len(scenario.eop)
    values = partials(scenario.eop)
    if scenario.eop_days is None:
        first = columns[names[0]]
        a[..., first:first + k] = values
        return
    day = scenario.eop_days.index(t_s)
    for d in np.unique(day):
        first = columns[names[d * k]]
        a[day == d, :, first:first + k] = values[day == d]

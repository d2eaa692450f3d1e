"""The states of TAPP I's trajectory for its CCSDS OEM (:mod:`tapp.io.ccsds.oem` writes them)
and its SPK (:mod:`tapp.io.spk`).

The trajectory is cut into smooth arcs at its burns (:func:`flight_arcs`): an impulsive burn
jumps the velocity, a finite burn's ignition and cut-off the acceleration, and an
interpolating polynomial follows neither (across a cut-off, a Hermite polynomial's velocity
misses by the acceleration's jump times the spacing of the states). Each arc is one OEM
segment and one SPK segment, from the state after the burn that starts it to the state before
the burn that ends it (the same state at ignition and cut-off, where the state is
continuous). Within an arc the states are placed where Lagrange interpolation of the degree
the OEM declares holds to the tolerances of :mod:`tapp.io.ccsds.oem` at every mid-point
between states. The SPK holds the same states (Hermite of degree
:data:`tapp.io.spk.SPK_DEGREE`, through half as many states); :func:`write_trajectory_spk`
reads it back through SPICE at every mid-point and refuses to keep it unless it too holds to
those tolerances. The burns are COMMENT lines (:func:`burn_comments`): kind, time, Δv (or
thrust) and axes, and what a ``[reference]`` fit made of them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tapp.dynamics import Trajectory
from tapp.dynamics.events import Events
from tapp.dynamics.manoeuvres import FiniteBurn, ImpulsiveBurn
from tapp.errors import TappError
from tapp.frames.file_frames import gcrs_from_scenario, to_scenario_frame
from tapp.frames.time import Epoch
from tapp.frames.timesystems import et_from_scenario, from_et, to_et
from tapp.io.ccsds.oem import (
    EPOCH_DECIMALS,
    INTERPOLATION_DEGREE,
    INTERPOLATION_TOL_KM,
    INTERPOLATION_TOL_KM_S,
    REF_FRAMES,
    OemTrajectory,
    event_comments,
    lagrange_interpolate,
)
from tapp.io.spk import NAIF_IDS, SPK_DEGREE, add_comments, spk_states, write_spk
from tapp.tracking.manoeuvres import describe, vector_text
from tapp.tracking.pieces import fly
from tapp.tracking.scenario import Scenario

if TYPE_CHECKING:
    from tapp.tracking.reference import ReferenceFit

#: Most states the OEM of a simulation may hold (the step is halved at most down to this).
MAX_STATES = 1_000_000


@dataclass(frozen=True, slots=True)
class FlightArc:
    """A smooth piece of the trajectory between burns (module docstring).

    Attributes
    ----------
    t_start_s, t_end_s : the arc, s from the epoch.
    x_start : (6,) the state at ``t_start_s`` after an impulsive burn there (km, km/s, the
        scenario's inertial frame); at t = 0, after a burn at the injection if there is one.
    thrust : the finite burn firing over the arc, or None (a coast arc).
    """

    t_start_s: float
    t_end_s: float
    x_start: np.ndarray
    thrust: FiniteBurn | None = None


def flight_arcs(scenario: Scenario, t_end_s: float) -> tuple[FlightArc, ...]:
    """Return the smooth arcs of the scenario's trajectory from t = 0 to ``t_end_s``: cut at
    every impulsive burn, ignition and cut-off strictly inside, each starting with the state
    after its impulsive burn."""
    burns = scenario.manoeuvres
    cuts = np.unique([t for b in burns for t in (b.t_start_s, b.t_end_s) if 0.0 < t < t_end_s])
    x0 = np.asarray(scenario.x0, dtype=float)
    starts = [x0]
    if cuts.size:
        starts += list(fly(scenario.propagator(), burns, x0, cuts,
                           param_values=dict(scenario.dynamic_values),
                           orientation=scenario.orientation,
                           epoch_jd_utc=scenario.epoch.jd).states)
    bounds = [0.0, *cuts.tolist(), float(t_end_s)]
    arcs = []
    for a, b, x in zip(bounds[:-1], bounds[1:], starts, strict=True):
        jump = next((u for u in burns if isinstance(u, ImpulsiveBurn) and u.t_s == a), None)
        thrust = next((u for u in burns if isinstance(u, FiniteBurn)
                       and u.t_start_s <= a < u.t_end_s), None)
        arcs.append(FlightArc(a, b, x if jump is None else jump.apply(x)[0], thrust))
    return tuple(arcs)


def fly_arc(scenario: Scenario, arc: FlightArc, t_s: np.ndarray) -> Trajectory:
    """The states (no partials) of ``arc`` at times ``t_s`` in it (its start: the state after
    its impulsive burn; its end: the state before the next), with its thrust."""
    burns = () if arc.thrust is None else (arc.thrust,)
    return fly(scenario.propagator(), burns, arc.x_start, t_s, t0_s=arc.t_start_s,
               param_values=dict(scenario.dynamic_values), orientation=scenario.orientation,
               epoch_jd_utc=scenario.epoch.jd)


def _uniform(t_end_s: float, step_s: float) -> np.ndarray:
    """0, step, 2 step, ..., then t_end, the last step from half to one and a half steps."""
    n = max(int(np.ceil(t_end_s / step_s - 0.5)), 1)
    return np.append(step_s * np.arange(n), t_end_s)


@dataclass(frozen=True, slots=True)
class _ArcStates:
    """The states of one arc where the interpolation holds, and what was found."""

    t_s: np.ndarray
    states: np.ndarray
    error: np.ndarray  # (2,) km, km/s
    events: Events


def _arc_states(scenario: Scenario, arc: FlightArc, most: int) -> _ArcStates | None:
    """States of ``arc`` where Lagrange interpolation holds at every mid-point (at most
    ``most`` of them; None when more would be needed)."""
    length = arc.t_end_s - arc.t_start_s
    reach = np.ones(2 * (INTERPOLATION_DEGREE // 2 + 1) + 1)
    t = arc.t_start_s + _uniform(length, min(scenario.schedule.data_interval_s,
                                             length / INTERPOLATION_DEGREE))
    t[-1] = arc.t_end_s
    while t.size <= most:
        mids = 0.5 * (t[1:] + t[:-1])
        traj = fly_arc(scenario, arc, np.sort(np.concatenate([t, mids])))
        both = traj.states
        states = both[0::2]
        err = np.abs(lagrange_interpolate(t, states, mids, INTERPOLATION_DEGREE) - both[1::2])
        bad = ((err[:, :3].max(axis=1) > INTERPOLATION_TOL_KM)
               | (err[:, 3:].max(axis=1) > INTERPOLATION_TOL_KM_S))
        if not bad.any():
            return _ArcStates(t, states, np.array([err[:, :3].max(), err[:, 3:].max()]),
                              traj.events)
        t = np.sort(np.concatenate([t, mids[np.convolve(bad, reach, mode="same") > 0]]))
    return None


def oem_trajectory(scenario: Scenario, t_end_s: float) -> OemTrajectory:
    """Return the scenario's trajectory from t = 0 to ``t_end_s`` for an OEM (module
    docstring): one segment per smooth arc (:func:`flight_arcs`), with states where Lagrange
    interpolation of degree :data:`INTERPOLATION_DEGREE` holds at every mid-point.

    In each arc the states start every data interval (at most the arc's length / degree, so
    that there are degree + 1 of them). Where the interpolation at a mid-point misses the
    propagated state by more than :data:`INTERPOLATION_TOL_KM` or
    :data:`INTERPOLATION_TOL_KM_S`, that interval and the degree // 2 + 1 on each side (the
    span of the windows that reach it) are halved, and all is checked again: the steps shrink
    only where the motion is fast (a low perigee, a swing-by). States come from the scenario's
    state model, propagated from the injection state with its burns (no variational
    equations).

    Raises
    ------
    TappError
        When more than :data:`MAX_STATES` states would be needed.
    PropagationError
        From the integrator.
    """
    parts: list[_ArcStates] = []
    for arc in flight_arcs(scenario, t_end_s):
        part = _arc_states(scenario, arc, MAX_STATES - sum(p.t_s.size for p in parts))
        if part is None:
            raise TappError(f"{scenario.source}: OEM: the trajectory needs more than "
                            f"{MAX_STATES:,} states for Lagrange interpolation of degree "
                            f"{INTERPOLATION_DEGREE} to {INTERPOLATION_TOL_KM * 1e6:g} mm and "
                            f"{INTERPOLATION_TOL_KM_S * 1e6:g} mm/s")
        parts.append(part)
    steps = np.concatenate([np.diff(p.t_s) for p in parts])
    error = np.max([p.error for p in parts], axis=0)
    return OemTrajectory(np.concatenate([p.t_s for p in parts]),
                         np.concatenate([p.states for p in parts]),
                         np.concatenate([np.full(p.t_s.size, k) for k, p in enumerate(parts)]),
                         REF_FRAMES[scenario.orientation.model], float(steps.min()),
                         float(steps.max()), float(error[0]), float(error[1]),
                         Events.join([p.events for p in parts]))


def burn_comments(epoch: Epoch, burns: Sequence, fit: ReferenceFit | None = None
                  ) -> tuple[str, ...]:
    """COMMENT lines of the burns flown: their number, then one line each,
    ``MANOEUVRE <name> <kind> ...`` (:func:`tapp.tracking.manoeuvres.describe`), with the
    scenario's own values beside those a ``[reference]`` fit replaced."""
    if not burns:
        return ()
    given = {} if fit is None else {b.name: b for b in fit.given_burns}
    fitted = set() if fit is None else {a.burn for a in fit.arcs if a.fitted}
    lines = [f"Manoeuvres flown ({len(burns)}; each burn, ignition and cut-off ends a segment "
             "and starts the next, an impulsive burn's with the state after it):"]
    for b in burns:
        text = f"MANOEUVRE {describe(b, epoch, EPOCH_DECIMALS)}"
        if b.name in fitted:
            text += f"; fitted to the reference (the scenario gives {vector_text(given[b.name])})"
        lines.append(text)
    return tuple(lines)


def segment_comments(traj: OemTrajectory, scenario: Scenario) -> tuple[tuple[str, ...], ...]:
    """COMMENT lines of each segment's metadata: which arc it is, and the integration events
    met in it (:func:`tapp.io.ccsds.oem.event_comments`)."""
    spans, epoch = traj.spans, scenario.epoch
    out = []
    for k, span in enumerate(spans):
        t_a, t_b = float(traj.t_s[span][0]), float(traj.t_s[span][-1])
        inside = (traj.events.t_s >= t_a) & (traj.events.t_s < t_b)
        events = Events(traj.events.t_s[inside],
                        tuple(n for n, i in zip(traj.events.name, inside, strict=True) if i),
                        traj.events.falling[inside])
        thrust = next((b.name for b in scenario.manoeuvres if isinstance(b, FiniteBurn)
                       and b.t_start_s <= t_a < b.t_end_s), None)
        arc = (f"Arc {k + 1} of {len(spans)} "
               f"({'coast' if thrust is None else f'thrust of {thrust}'}): "
               f"{epoch.iso_after(t_a, EPOCH_DECIMALS)} to "
               f"{epoch.iso_after(t_b, EPOCH_DECIMALS)} UTC.")
        out.append(((arc,) if len(spans) > 1 else ()) + event_comments(epoch, events))
    return tuple(out)


def write_trajectory_spk(path: Path, scenario: Scenario, traj: OemTrajectory, body: int,
                         comments: Sequence[str] = (), option: str = "--spk"
                         ) -> tuple[float, float]:
    """Write the OEM's states ``traj`` as an SPK (one type 13 segment of NAIF id ``body``
    about the integration centre per OEM segment, J2000 = the GCRS axes, a gmst scenario's
    states rotated there by the frame bias) at ``path``, check it, and return the largest
    interpolation errors SPICE makes at the mid-points between states (km, km/s).

    The states go in at ET of their scenario times, each moved by the sub-ulp remainder its
    rounded ET leaves out, velocities per TDB second (:func:`tapp.frames.timesystems.to_et`);
    SPICE's states at the mid-points, taken back (``from_et``), are compared with the
    scenario's propagation there (each segment's own: the mid-points are inside one).
    ``comments`` and a line stating those errors end up in the file's comment area.

    Raises
    ------
    TappError
        SPICE's interpolation misses a mid-point by more than the OEM's tolerances.
    InputError
        A path or segment SPICE refuses (naming ``option``).
    """
    epoch, orientation = scenario.epoch, scenario.orientation
    gcrs = gcrs_from_scenario(traj.states, orientation)
    center = NAIF_IDS[scenario.state_model.center]
    write_spk(path, body, [to_et(traj.t_s[s], gcrs[s], epoch) for s in traj.spans],
              option=option, center=center)
    arcs = flight_arcs(scenario, float(traj.t_s[-1]))
    mids = [0.5 * (traj.t_s[s][1:] + traj.t_s[s][:-1]) for s in traj.spans]
    truth = np.concatenate([fly_arc(scenario, arc, m).states
                            for arc, m in zip(arcs, mids, strict=True)])
    spice = [from_et(m, spk_states(path, body, et_from_scenario(m, epoch), option, str(path),
                                   center=center), epoch) for m in mids]
    got = to_scenario_frame("GCRF", np.concatenate(mids), np.concatenate(spice), orientation)
    err = np.abs(got - truth)
    error_km, error_km_s = float(err[:, :3].max()), float(err[:, 3:].max())
    if error_km > INTERPOLATION_TOL_KM or error_km_s > INTERPOLATION_TOL_KM_S:
        raise TappError(f"{scenario.source}: SPK: SPICE's type 13 interpolation of degree "
                        f"{SPK_DEGREE} misses the trajectory by {error_km * 1e6:.3g} mm and "
                        f"{error_km_s * 1e6:.3g} mm/s at the mid-points between states "
                        f"(required: {INTERPOLATION_TOL_KM * 1e6:g} mm, "
                        f"{INTERPOLATION_TOL_KM_S * 1e6:g} mm/s)")
    n = len(traj.spans)
    segments = ("one type 13 segment" if n == 1 else
                f"{n} type 13 segments, one per arc between burns,")
    add_comments(path, (*comments, f"SPK: {segments} (Hermite of degree {SPK_DEGREE}) of body "
                        f"{body} about the Earth (399) in J2000 (the GCRS axes); ET = TDB "
                        "seconds past J2000 of the scenario's UTC times. Read back by SPICE "
                        "at every mid-point between states, it reproduces the propagated "
                        f"trajectory to {error_km * 1e6:.2g} mm and {error_km_s * 1e6:.2g} "
                        f"mm/s (required: {INTERPOLATION_TOL_KM * 1e6:g} mm, "
                        f"{INTERPOLATION_TOL_KM_S * 1e6:g} mm/s)."), option)
    return error_km, error_km_s

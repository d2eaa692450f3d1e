"""The states of TAPP I's trajectory for its CCSDS OEM (:mod:`tapp.io.ccsds.oem` writes them)
and its SPK (:mod:`tapp.io.spk`).

The trajectory is sampled where Lagrange interpolation of the degree the OEM declares holds
to the tolerances of :mod:`tapp.io.ccsds.oem` at every mid-point between states. The SPK holds
the same states in one type 13 segment (Hermite of degree :data:`tapp.io.spk.SPK_DEGREE`,
through half as many states); :func:`write_trajectory_spk` reads it back through SPICE at
every mid-point and refuses to keep it unless it too holds to those tolerances.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from tapp.errors import InputError, TappError
from tapp.frames.file_frames import gcrs_from_scenario, to_scenario_frame
from tapp.frames.timesystems import et_from_scenario, from_et, to_et
from tapp.io.ccsds.oem import (
    INTERPOLATION_DEGREE,
    INTERPOLATION_TOL_KM,
    INTERPOLATION_TOL_KM_S,
    REF_FRAMES,
    OemTrajectory,
    lagrange_interpolate,
)
from tapp.io.spk import SPK_DEGREE, add_comments, spk_states, write_spk
from tapp.tracking.pieces import fly
from tapp.tracking.scenario import Scenario

#: Most states the OEM of a simulation may hold (the step is halved at most down to this).
MAX_STATES = 1_000_000


def _uniform(t_end_s: float, step_s: float) -> np.ndarray:
    """0, step, 2 step, ..., then t_end, the last step from half to one and a half steps."""
    n = max(int(np.ceil(t_end_s / step_s - 0.5)), 1)
    return np.append(step_s * np.arange(n), t_end_s)


def oem_trajectory(scenario: Scenario, t_end_s: float) -> OemTrajectory:
    """Return the scenario's trajectory from t = 0 to ``t_end_s`` for an OEM (module
    docstring), with states where Lagrange interpolation of degree
    :data:`INTERPOLATION_DEGREE` holds at every mid-point.

    The states start every data interval (at most ``t_end_s`` / degree, so that there are
    degree + 1 of them). Where the interpolation at a mid-point misses the propagated state by
    more than :data:`INTERPOLATION_TOL_KM` or :data:`INTERPOLATION_TOL_KM_S`, that interval
    and the degree // 2 + 1 on each side (the span of the windows that reach it) are halved,
    and all is checked again: the steps shrink only where the motion is fast (a low perigee,
    a swing-by, about a finite burn's ignition and cut-off). States come from the scenario's
    state model, propagated from the injection state with its finite burns (no variational
    equations).

    Raises
    ------
    InputError
        A scenario with impulsive burns (naming them).
    TappError
        When more than :data:`MAX_STATES` states would be needed.
    PropagationError
        From the integrator.
    """
    impulsive = [b.name for b in scenario.manoeuvres if b.kind == "impulsive"]
    if impulsive:
        raise InputError(scenario.source, "manoeuvre", "no impulsive burn with an OEM (the "
                         "velocity jumps there: Lagrange interpolation across it cannot hold, "
                         "and an OEM of one segment per coast arc is not written yet)",
                         impulsive)
    prop = scenario.propagator()
    values = dict(scenario.dynamic_values)
    reach = np.ones(2 * (INTERPOLATION_DEGREE // 2 + 1) + 1)
    t = _uniform(t_end_s, min(scenario.schedule.data_interval_s,
                              t_end_s / INTERPOLATION_DEGREE))
    while t.size <= MAX_STATES:
        mids = 0.5 * (t[1:] + t[:-1])
        traj = fly(prop, scenario.manoeuvres, scenario.x0, np.sort(np.concatenate([t, mids])),
                   param_values=values, orientation=scenario.orientation,
                   epoch_jd_utc=scenario.epoch.jd)
        both = traj.states
        states = both[0::2]
        err = np.abs(lagrange_interpolate(t, states, mids, INTERPOLATION_DEGREE) - both[1::2])
        bad = ((err[:, :3].max(axis=1) > INTERPOLATION_TOL_KM)
               | (err[:, 3:].max(axis=1) > INTERPOLATION_TOL_KM_S))
        if not bad.any():
            steps = np.diff(t)
            return OemTrajectory(t, states, REF_FRAMES[scenario.orientation.model],
                                 float(steps.min()), float(steps.max()),
                                 float(err[:, :3].max()), float(err[:, 3:].max()),
                                 traj.events)
        t = np.sort(np.concatenate([t, mids[np.convolve(bad, reach, mode="same") > 0]]))
    raise TappError(f"{scenario.source}: OEM: the trajectory needs more than {MAX_STATES:,} "
                    f"states for Lagrange interpolation of degree {INTERPOLATION_DEGREE} to "
                    f"{INTERPOLATION_TOL_KM * 1e6:g} mm and {INTERPOLATION_TOL_KM_S * 1e6:g} "
                    "mm/s")


def write_trajectory_spk(path: Path, scenario: Scenario, traj: OemTrajectory, body: int,
                         comments: Sequence[str] = (), option: str = "--spk"
                         ) -> tuple[float, float]:
    """Write the OEM's states ``traj`` as an SPK (one type 13 segment of NAIF id ``body``
    about the Earth, J2000 = the GCRS axes, a gmst scenario's states rotated there by the
    frame bias) at ``path``, check it, and return the largest interpolation errors SPICE
    makes at the mid-points between states (km, km/s).

    The states go in at ET of their scenario times, each moved by the sub-ulp remainder its
    rounded ET leaves out, velocities per TDB second (:func:`tapp.frames.timesystems.to_et`);
    SPICE's states at the mid-points, taken back (``from_et``), are compared with the
    scenario's propagation there. ``comments`` and a line stating those errors end up in the file's
    comment area.

    Raises
    ------
    TappError
        SPICE's interpolation misses a mid-point by more than the OEM's tolerances.
    InputError
        A path or segment SPICE refuses (naming ``option``).
    """
    epoch, orientation = scenario.epoch, scenario.orientation
    et, states = to_et(traj.t_s, gcrs_from_scenario(traj.states, orientation), epoch)
    write_spk(path, body, et, states, option=option)
    mids = 0.5 * (traj.t_s[1:] + traj.t_s[:-1])
    truth = scenario.propagator().propagate(
        scenario.x0, mids, stm=False, param_values=dict(scenario.dynamic_values),
        orientation=orientation, epoch_jd_utc=epoch.jd).states
    spice = spk_states(path, body, et_from_scenario(mids, epoch), option, str(path))
    got = to_scenario_frame("GCRF", mids, from_et(mids, spice, epoch), orientation)
    err = np.abs(got - truth)
    error_km, error_km_s = float(err[:, :3].max()), float(err[:, 3:].max())
    if error_km > INTERPOLATION_TOL_KM or error_km_s > INTERPOLATION_TOL_KM_S:
        raise TappError(f"{scenario.source}: SPK: SPICE's type 13 interpolation of degree "
                        f"{SPK_DEGREE} misses the trajectory by {error_km * 1e6:.3g} mm and "
                        f"{error_km_s * 1e6:.3g} mm/s at the mid-points between states "
                        f"(required: {INTERPOLATION_TOL_KM * 1e6:g} mm, "
                        f"{INTERPOLATION_TOL_KM_S * 1e6:g} mm/s)")
    add_comments(path, (*comments, f"SPK type 13 (Hermite of degree {SPK_DEGREE}) of body "
                        f"{body} about the Earth (399) in J2000 (the GCRS axes); ET = TDB "
                        "seconds past J2000 of the scenario's UTC times. Read back by SPICE "
                        "at every mid-point between states, it reproduces the propagated "
                        f"trajectory to {error_km * 1e6:.2g} mm and {error_km_s * 1e6:.2g} "
                        f"mm/s (required: {INTERPOLATION_TOL_KM * 1e6:g} mm, "
                        f"{INTERPOLATION_TOL_KM_S * 1e6:g} mm/s)."), option)
    return error_km, error_km_s

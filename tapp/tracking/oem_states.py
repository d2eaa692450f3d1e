"""The states of TAPP I's trajectory for its CCSDS OEM (:mod:`tapp.io.ccsds.oem` writes them).

The trajectory is sampled where Lagrange interpolation of the degree the OEM declares holds
to the tolerances of :mod:`tapp.io.ccsds.oem` at every mid-point between states.
"""

from __future__ import annotations

import numpy as np

from tapp.errors import InputError, TappError
from tapp.io.ccsds.oem import (
    INTERPOLATION_DEGREE,
    INTERPOLATION_TOL_KM,
    INTERPOLATION_TOL_KM_S,
    REF_FRAMES,
    OemTrajectory,
    lagrange_interpolate,
)
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

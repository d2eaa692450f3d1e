"""The integration centre seen from the Earth: what turns a trajectory integrated about the
Sun, the Moon or a planet (``[model] center``) into the geocentric states the tracking
stations observe.

The stations, their light time and their media live in the Earth's frame; the trajectory,
its transition matrices and its partials about the centre. The two differ by a translation,
the centre's state relative to the Earth from DE421 at TDB (:mod:`tapp.dynamics.ephemeris`;
TT under the gmst orientation, as the force model reads it), which depends on no parameter
of q: x_geo = x + X_centre(t), so ∂x_geo/∂x = I and every partial of an observable w.r.t.
the state holds as it is for the state about the centre.
"""

from __future__ import annotations

import numpy as np

from tapp.dynamics.ephemeris import relative_state, tdb_reader
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch


def centre_from_earth(center: str, epoch: Epoch, orientation: EarthOrientation,
                      t_s: np.ndarray) -> np.ndarray:
    """Return the state (N, 6) km, km/s of ``center`` relative to the Earth at t_s (N,) s
    from ``epoch``, ICRF axes (zeros for the Earth)."""
    t = np.asarray(t_s, dtype=float)
    if center == "earth":
        return np.zeros(t.shape + (6,))
    return relative_state(center, "earth", *tdb_reader(epoch.jd, orientation.scales)(t))


def geocentric(center: str, epoch: Epoch, orientation: EarthOrientation, t_s: np.ndarray,
               states: np.ndarray) -> np.ndarray:
    """Return ``states`` (N, 6) about ``center`` at t_s (N,) as geocentric states (the same
    array for an Earth centre)."""
    if center == "earth":
        return states
    return np.asarray(states, dtype=float) + centre_from_earth(center, epoch, orientation, t_s)

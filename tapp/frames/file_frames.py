"""The reference frames of trajectory files, turned into the scenario's inertial frame.

A trajectory file names the axes of its states (the OEM's ``REF_FRAME``, CCSDS SANA names);
the scenario's states are in the inertial frame of its Earth orientation model
(:data:`tapp.frames.orientation.INERTIAL_FRAME`: the GCRS under iau2006, EME2000 under gmst).
The frames read, and how (Earth-centred states; the centre is the reader's business):

- ``GCRF``, and ``ICRF`` for Earth-centred states: the GCRS, whose axes are the ICRS's.
- ``EME2000``, the mean equator and dynamical equinox of J2000.0: r_GCRS = Bᵀ r_EME2000 with B
  the constant frame-bias matrix of IAU 2006 (ERFA ``bp06``; IERS Conventions 2010 §5.5.1,
  eq. 5.21: ξ₀ = −16.617 mas, η₀ = −6.8192 mas, dα₀ = −14.6 mas, about 23 mas or 0.8 m at
  7000 km). A scenario under gmst takes EME2000 as its inertial frame, so the GCRS states are
  rotated by B for it.
- ``ITRF`` and its realisations (``ITRF-93``, ``ITRF-97``, ``ITRF2000``, ..., ``ITRF2020``):
  the Earth-fixed frame of the scenario's own Earth orientation model (iau2006 with its EOP,
  or gmst), r = Mᵀ r_ITRS and v = Mᵀ v_ITRS + ω ĉ × r (ĉ the rotation axis), as stations
  move (:mod:`tapp.frames.orientation`: the CIP's own motion, up to 6e-12 rad/s × |r|, 0.25
  mm/s at GEO, is left out of v). The realisations differ by centimetres and mm/yr, which
  is below what the scenario's own EOP interpolation keeps.

Frames of date (``TOD``, ``MOD``, ``TEME``) are not read: each rests on a precession-nutation
theory (TEME on IAU-76/FK5 and GMST82) that would have to be matched to the file's producer
to better than a metre.
"""

from __future__ import annotations

import re

import erfa
import numpy as np

from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import JD_J2000

#: Inertial frames read (their axes are the GCRS's or EME2000's).
INERTIAL_FRAMES = ("GCRF", "ICRF", "EME2000")
#: An Earth-fixed frame: the ITRF or one of its realisations.
_ITRF = re.compile(r"^ITRF(-?\d{2}|\d{4})?$")
#: What the error for an unknown frame says is read.
FRAMES_READ = "GCRF, ICRF, EME2000 or an ITRF (ITRF2014, ITRF-93, ...)"


def is_earth_fixed(frame: str) -> bool:
    """Return True if ``frame`` names the ITRF or one of its realisations."""
    return _ITRF.match(frame) is not None


def check_frame(frame: str, source: str, field: str = "REF_FRAME") -> str:
    """Return ``frame`` if :func:`to_scenario_frame` reads it, else raise InputError."""
    if frame not in INERTIAL_FRAMES and not is_earth_fixed(frame):
        raise InputError(source, field, f"a frame tapp reads ({FRAMES_READ})", frame)
    return frame


def frame_bias() -> np.ndarray:
    """Return B (3, 3): r_EME2000 = B r_GCRS, the IAU 2006 frame bias (ERFA ``bp06``)."""
    return erfa.bp06(JD_J2000, 0.0)[0]


def _rotate(matrix: np.ndarray, states: np.ndarray) -> np.ndarray:
    """Apply one constant rotation (3, 3) to positions and velocities (N, 6)."""
    return np.concatenate([states[:, :3] @ matrix.T, states[:, 3:] @ matrix.T], axis=1)


def to_scenario_frame(frame: str, t_s, states, orientation: EarthOrientation,
                      source: str = "trajectory", field: str = "REF_FRAME") -> np.ndarray:
    """Return Earth-centred states (N, 6) in ``frame`` as states in the scenario's inertial
    frame (``orientation.frame``), km and km/s.

    Parameters
    ----------
    frame : a name of :data:`INERTIAL_FRAMES` or an ITRF (module docstring).
    t_s : (N,) scenario times of the states, s (used by the Earth-fixed frames).
    states : (N, 6) position km, velocity km/s, Earth-centred, in ``frame``.
    orientation : the scenario's Earth orientation.
    source, field : where the frame was named (for the errors).

    Raises
    ------
    InputError
        An unknown frame; an Earth-fixed frame at a time outside the EOP table.
    """
    x = np.asarray(states, dtype=float)
    check_frame(frame, source, field)
    if is_earth_fixed(frame):
        att = orientation.attitude(np.asarray(t_s, dtype=float), source)
        m = att.gcrs_from_itrs
        r = np.einsum("nij,nj->ni", m, x[:, :3])
        v = np.einsum("nij,nj->ni", m, x[:, 3:]) + att.omega_rad_s * np.cross(att.spin_axis, r)
        return np.concatenate([r, v], axis=1)
    if (frame == "EME2000") == (orientation.frame == "EME2000"):
        return x.copy()
    bias = frame_bias()
    return _rotate(bias.T if frame == "EME2000" else bias, x)


def gcrs_from_scenario(states, orientation: EarthOrientation) -> np.ndarray:
    """Return states (N, 6) in the scenario's inertial frame as GCRS states: the inverse of
    :func:`to_scenario_frame` for ``"GCRF"`` (the frame bias Bᵀ under gmst)."""
    x = np.asarray(states, dtype=float)
    return _rotate(frame_bias().T, x) if orientation.frame == "EME2000" else x.copy()

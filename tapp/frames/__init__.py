"""Time, Earth rotation and geodesy: the reference-frame kernels of tapp.

Units are km, km/s, s and rad; time is SI seconds from the scenario epoch (a UTC calendar
date; :mod:`tapp.frames.timescales`). The Earth-fixed frame is reached from the inertial one by
the scenario's Earth orientation (:mod:`tapp.frames.orientation`): the IAU 2006/2000A GCRS ->
ITRS rotation with IERS EOP (the tables of :mod:`tapp.frames.eop`, the shipped IERS files read
by :mod:`tapp.frames.iers`), or the gmst model R3(GMST IAU-82 + omega t) with UT1 = UTC of
:mod:`tapp.frames.rotation`. :mod:`tapp.frames.ric` gives the radial / in-track / cross-track
axes of a state and rotates covariances into them. Trajectory files are brought into the
scenario's time and frame by :mod:`tapp.frames.timesystems` (CCSDS time systems, SPICE's ET)
and :mod:`tapp.frames.file_frames` (GCRF, ICRF, EME2000, the ITRF).
"""

from tapp.frames.geodesy import ecef_to_geodetic, enu_matrix, geodetic_to_ecef
from tapp.frames.rotation import (
    earth_rotation_angle_rad,
    ecef_to_eci_matrix,
    ecef_to_eci_matrix_dot,
    ecef_to_eci_state,
    eci_to_ecef_matrix,
    eci_to_ecef_matrix_dot,
    eci_to_ecef_state,
    r3,
    r3_derivative,
)
from tapp.frames.time import Epoch, calendar_to_jd, gmst_rad, jd_to_calendar, parse_epoch

__all__ = [
    "Epoch",
    "calendar_to_jd",
    "earth_rotation_angle_rad",
    "ecef_to_eci_matrix",
    "ecef_to_eci_matrix_dot",
    "ecef_to_eci_state",
    "ecef_to_geodetic",
    "eci_to_ecef_matrix",
    "eci_to_ecef_matrix_dot",
    "eci_to_ecef_state",
    "enu_matrix",
    "geodetic_to_ecef",
    "gmst_rad",
    "jd_to_calendar",
    "parse_epoch",
    "r3",
    "r3_derivative",
]

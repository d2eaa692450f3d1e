"""Time, Earth rotation, orbital elements and geodesy: the reference-frame kernels of tapp.

Units are km, km/s, s and rad; time is SI seconds from the scenario epoch (a UTC calendar
date; :mod:`tapp.frames.timescales`). The Earth-fixed frame is reached from the inertial one by
the scenario's Earth orientation (:mod:`tapp.frames.orientation`): the IAU 2006/2000A GCRS ->
ITRS rotation with IERS EOP, or the gmst model R3(GMST IAU-82 + omega t) with UT1 = UTC of
:mod:`tapp.frames.rotation`.
"""

from tapp.frames.elements import (
    E_CIRCULAR_TOL,
    I_EQUATORIAL_TOL,
    PARABOLIC_TOL,
    Elements,
    cartesian_to_elements,
    eccentric_to_mean_anomaly,
    eccentric_to_true_anomaly,
    elements_to_cartesian,
    hyperbolic_to_mean_anomaly,
    hyperbolic_to_true_anomaly,
    kepler_states,
    mean_to_eccentric_anomaly,
    mean_to_hyperbolic_anomaly,
    mean_to_true_anomaly,
    true_to_eccentric_anomaly,
    true_to_hyperbolic_anomaly,
    true_to_mean_anomaly,
)
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
    "E_CIRCULAR_TOL",
    "I_EQUATORIAL_TOL",
    "PARABOLIC_TOL",
    "Elements",
    "Epoch",
    "calendar_to_jd",
    "cartesian_to_elements",
    "earth_rotation_angle_rad",
    "eccentric_to_mean_anomaly",
    "eccentric_to_true_anomaly",
    "ecef_to_eci_matrix",
    "ecef_to_eci_matrix_dot",
    "ecef_to_eci_state",
    "ecef_to_geodetic",
    "eci_to_ecef_matrix",
    "eci_to_ecef_matrix_dot",
    "eci_to_ecef_state",
    "elements_to_cartesian",
    "enu_matrix",
    "geodetic_to_ecef",
    "gmst_rad",
    "hyperbolic_to_mean_anomaly",
    "hyperbolic_to_true_anomaly",
    "jd_to_calendar",
    "kepler_states",
    "mean_to_eccentric_anomaly",
    "mean_to_hyperbolic_anomaly",
    "mean_to_true_anomaly",
    "parse_epoch",
    "r3",
    "r3_derivative",
    "true_to_eccentric_anomaly",
    "true_to_hyperbolic_anomaly",
    "true_to_mean_anomaly",
]

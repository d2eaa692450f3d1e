"""Tracking measurements: stations, observables with partials (ΔDOR on a baseline:
:mod:`tapp.measurements.ddor`; troposphere and ionosphere: :mod:`tapp.measurements.media`),
visibility and passes; fit-world and real-world measurement noise and the per-pass
square-root information (:mod:`tapp.measurements.noise`, with the names of the real-world
noise parts).

Numerical kernels only (pure NumPy, no I/O), shared by the tracking simulator (TAPP I) and the
orbit-determination code. Conventions: km, km/s, s, rad; time-major arrays (N, ...); spacecraft
states in the inertial frame (GCRS); Earth orientation by :mod:`tapp.frames.orientation`.
"""

from tapp.measurements.ddor import DdorModel, projected_baseline_km, quasar_direction
from tapp.measurements.media import MEDIA_PARAMETER_NAMES, MediaModel
from tapp.measurements.observables import (
    BIAS_NAMES,
    OBSERVABLE_UNITS,
    LightTime,
    LightTimeSolution,
    MeasurementModel,
    Observable,
    azimuth_elevation_partials,
    azimuth_elevation_rad,
    light_time_range_km,
    light_time_range_rate_km_s,
    range_km,
    range_partials,
    range_rate_km_s,
    range_rate_partials,
    residual,
    solve_light_time,
    wrap_angle_rad,
)
from tapp.measurements.stations import (
    STATION_PARAMETER_NAMES,
    Station,
    station_state_eci,
    station_state_partials,
)
from tapp.measurements.visibility import find_passes, is_visible, pass_labels

__all__ = [
    "BIAS_NAMES",
    "MEDIA_PARAMETER_NAMES",
    "OBSERVABLE_UNITS",
    "STATION_PARAMETER_NAMES",
    "DdorModel",
    "LightTime",
    "LightTimeSolution",
    "MeasurementModel",
    "MediaModel",
    "Observable",
    "Station",
    "azimuth_elevation_partials",
    "azimuth_elevation_rad",
    "find_passes",
    "is_visible",
    "light_time_range_km",
    "light_time_range_rate_km_s",
    "pass_labels",
    "projected_baseline_km",
    "quasar_direction",
    "range_km",
    "range_partials",
    "range_rate_km_s",
    "range_rate_partials",
    "residual",
    "solve_light_time",
    "station_state_eci",
    "station_state_partials",
    "wrap_angle_rad",
]

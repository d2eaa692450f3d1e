"""Two-body orbit kernels (the ``orbit/`` floor of the layout in DESIGN.md): orbital elements
and Kepler's equation (:mod:`tapp.orbit.elements`), equinoctial elements
(:mod:`tapp.orbit.equinoctial`), Lambert's problem (:mod:`tapp.orbit.lambert`) and the B-plane of
a hyperbolic approach (:mod:`tapp.orbit.bplane`).

Plain float64 arrays in and out, km, km/s, s; no I/O.
"""

from tapp.orbit.elements import (
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
from tapp.orbit.equinoctial import equinoctial_elements
from tapp.orbit.lambert import lambert

__all__ = [
    "E_CIRCULAR_TOL",
    "Elements",
    "I_EQUATORIAL_TOL",
    "PARABOLIC_TOL",
    "cartesian_to_elements",
    "eccentric_to_mean_anomaly",
    "eccentric_to_true_anomaly",
    "elements_to_cartesian",
    "equinoctial_elements",
    "hyperbolic_to_mean_anomaly",
    "hyperbolic_to_true_anomaly",
    "kepler_states",
    "lambert",
    "mean_to_eccentric_anomaly",
    "mean_to_hyperbolic_anomaly",
    "mean_to_true_anomaly",
    "true_to_eccentric_anomaly",
    "true_to_hyperbolic_anomaly",
    "true_to_mean_anomaly",
]

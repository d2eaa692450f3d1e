"""The a priori covariance of station locations in the tape's parameters (TAPP III deck).

A deck's ``[fit.apriori.stations]`` / ``[real.apriori.stations]`` gives the covariance C of the
stations' Earth-fixed positions (m², each station in its own axes:
:mod:`tapp.io.station_covariance`) and optionally a common-frame error, a 7-parameter
Helmert transformation f = (T m, θ rad, s) shared by every station (the error of the terrestrial
frame the stations were surveyed in: it correlates the complexes):

.. math::

    \\delta\\mathbf r_i = R_i\\,\\boldsymbol\\epsilon_i + \\mathbf T
        + \\boldsymbol\\theta \\times \\mathbf r_i + s\\,\\mathbf r_i,
    \\qquad \\operatorname{cov}(\\delta\\mathbf r) = R C R^T + H \\Sigma_f H^T,
    \\quad H_i = [\\,I \\;\\; -[\\mathbf r_i\\times] \\;\\; \\mathbf r_i\\,]

(R_i the station's axes in ECEF, :func:`axes_rotation`; Σ_f diagonal, from the deck's σ's).
The tape's location parameters p_i (:data:`tapp.measurements.STATION_PARAMETER_NAMES`: (r_s km,
lon rad, z km) or (x, y, z km)) then get, to first order at the tape's nominal location,

.. math:: \\Lambda_p = G\\,\\operatorname{cov}(\\delta\\mathbf r)\\,G^T, \\qquad
    G_i = \\partial p_i/\\partial \\mathbf r_i = 10^{-3} J_i^{-1}\\ \\mathrm{(per\\ m)}

with J_i = ∂r_f/∂p_i (:func:`tapp.measurements.stations.location_jacobian`). The neglected
second-order terms of the cylindrical map are ~σ/r_s of σ (1e-8 for cm at the DSN's spin radii,
checked by a Monte Carlo of the exact map in tests/tapp/processor/test_station_covariance.py).
"""

from __future__ import annotations

import numpy as np

from tapp.frames.rotation import cross_matrix
from tapp.measurements.stations import location_jacobian

#: Metres per km.
M_PER_KM = 1000.0
#: Radians per milliarcsecond (the unit of the IERS's frame rotations).
RAD_PER_MAS = np.pi / (180.0 * 3600.0 * 1000.0)
#: The scale per part per billion.
PER_PPB = 1e-9


def axes_rotation(r_ecef_km, axes: str) -> np.ndarray:
    """Return R (3, 3), ECEF components of a station's axes (columns): the identity for
    "ecef"; for "cylindrical" (spin radius, east, z): ρ̂ = (cos λ, sin λ, 0),
    λ̂ = (−sin λ, cos λ, 0), ẑ at the station's longitude λ."""
    if axes == "ecef":
        return np.eye(3)
    lon = np.arctan2(r_ecef_km[1], r_ecef_km[0])
    c, s = np.cos(lon), np.sin(lon)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def frame_partials(r_ecef_km) -> np.ndarray:
    """Return H (3, 7) = ∂δr/∂(T, θ, s) of a station at r (km): δr (m) = T + θ × r + s r, T m,
    θ rad, s (a ratio)."""
    r_m = np.asarray(r_ecef_km, dtype=float) * M_PER_KM
    return np.hstack([np.eye(3), -cross_matrix(r_m), r_m[:, None]])


def position_km(values, parameters: str) -> np.ndarray:
    """Return the Earth-fixed position (3,), km, of a station's location parameters (3,) on
    the tape: (r_s cos lon, r_s sin lon, z) for "cylindrical", (x, y, z) for "ecef"."""
    v = np.asarray(values, dtype=float)
    if parameters == "cylindrical":
        return np.array([v[0] * np.cos(v[1]), v[0] * np.sin(v[1]), v[2]])
    return v.copy()


def parameter_jacobian(r_ecef_km, parameters: str) -> np.ndarray:
    """Return G (3, 3) = ∂p/∂r_f of the tape's location parameters p (km, rad) w.r.t. the
    Earth-fixed position in metres: 10⁻³ J⁻¹, J = ∂r_f/∂p (km per unit of p)."""
    return np.linalg.solve(location_jacobian(r_ecef_km, parameters), np.eye(3)) / M_PER_KM


def parameter_covariance(r_ecef_km: np.ndarray, parameters: tuple[str, ...],
                         axes: tuple[str, ...], covariance_m2: np.ndarray,
                         frame_sigma: np.ndarray) -> np.ndarray:
    """Return Λ_p (3N, 3N), the covariance of the N stations' location parameters (module
    docstring), in the tape's units squared, station-major.

    Parameters
    ----------
    r_ecef_km : (N, 3) nominal Earth-fixed positions, km (where the map is linearised).
    parameters : each station's parameterisation on the tape ("cylindrical", "ecef").
    axes : the axes of each station's rows of ``covariance_m2`` ("ecef", "cylindrical").
    covariance_m2 : (3N, 3N) C, m².
    frame_sigma : (7,) σ's of the common-frame error: T (m, 3), θ (rad, 3), s (1).
    """
    n = len(parameters)
    rot = np.zeros((3 * n, 3 * n))
    jac = np.zeros((3 * n, 3 * n))
    for i, (r, p, ax) in enumerate(zip(r_ecef_km, parameters, axes, strict=True)):
        at = slice(3 * i, 3 * i + 3)
        rot[at, at] = axes_rotation(r, ax)
        jac[at, at] = parameter_jacobian(r, p)
    h = np.vstack([frame_partials(r) for r in r_ecef_km])
    cart = rot @ covariance_m2 @ rot.T + (h * frame_sigma**2) @ h.T
    out = jac @ cart @ jac.T
    return 0.5 * (out + out.T)


__all__ = ["RAD_PER_MAS", "PER_PPB", "axes_rotation", "frame_partials", "parameter_covariance",
           "parameter_jacobian", "position_km"]

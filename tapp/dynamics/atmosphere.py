"""Atmospheric drag on a cannonball spacecraft: exponential and Harris-Priester densities.

The acceleration in an atmosphere co-rotating with the Earth (Montenbruck & Gill, *Satellite
Orbits*, 2000, §3.5.1):

.. math::
    \\mathbf a = -\\tfrac12 C_d \\frac{A}{m} \\rho\\, |\\mathbf v_r| \\mathbf v_r,\\qquad
    \\mathbf v_r = \\mathbf v - \\boldsymbol\\omega_\\oplus \\times \\mathbf r,

with ρ in kg/m³, A/m in m²/kg and v in km/s, so that a (km/s²) = −½ C_d (A/m) ρ |v_r| v_r
× 1e3 (m²/s² → km²/s², m/s² → km/s²). ω⊕ = 7.292115e-5 rad/s along the inertial z axis
(the true pole differs from the EME2000/GCRS z axis by under 0.3° until 2050: under
2.5 m/s, 3e-4 of v_r in LEO).

The height is the one above the WGS84 ellipsoid to first order in the flattening f,
h = |r| − a (1 − f sin²φ'), φ' the geocentric latitude from the inertial z axis: within
30 m of the geodetic height from 100 to 1000 km (checked in the tests).

Densities:

- ``"exponential"``: ρ = ρ0 exp(−(h − h0)/H), one layer
  (:class:`tapp.dynamics.spec.ExponentialLayer`), by default the 400-450 km band of Vallado
  (*Fundamentals of Astrodynamics and Applications*, 4th ed., 2013, Table 8-4, from CIRA-72):
  h0 = 400 km, ρ0 = 3.725e-12 kg/m³, H = 58.515 km, used at every height.
- ``"harris_priester"``: M&G §3.5.2, Table 3.8 (mean solar activity, 100 to 1000 km),
  ρ = ρ_m(h) + (ρ_M(h) − ρ_m(h)) cos^n(ψ/2), the antapex and apex densities ρ_m, ρ_M
  interpolated exponentially between table heights (ln ρ linear in h; beyond the table,
  the end bands' scale heights are extrapolated), cos^n(ψ/2) = ((1 + ê_r·ê_b)/2)^{n/2} with
  ê_b the Sun direction rotated by the bulge lag λ = 30° about the z axis, and n = 2 (M&G's
  value for low inclinations; 6 suits polar orbits).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from tapp.constants import WGS84_F, OMEGA_EARTH_rad_s, WGS84_A_km
from tapp.dynamics.spec import ExponentialLayer

#: Harris-Priester, mean solar activity (M&G Table 3.8): height (km), ρ_min and ρ_max
#: (g/km^3 = 1e-12 kg/m^3).
HP_HEIGHT_km = np.array([
    100.0, 120.0, 130.0, 140.0, 150.0, 160.0, 170.0, 180.0, 190.0, 200.0,
    210.0, 220.0, 230.0, 240.0, 250.0, 260.0, 270.0, 280.0, 290.0, 300.0,
    320.0, 340.0, 360.0, 380.0, 400.0, 420.0, 440.0, 460.0, 480.0, 500.0,
    520.0, 540.0, 560.0, 580.0, 600.0, 620.0, 640.0, 660.0, 680.0, 700.0,
    720.0, 740.0, 760.0, 780.0, 800.0, 840.0, 880.0, 920.0, 960.0, 1000.0])
HP_RHO_MIN_g_km3 = np.array([
    4.974e+05, 2.490e+04, 8.377e+03, 3.899e+03, 2.122e+03, 1.263e+03, 8.008e+02, 5.283e+02,
    3.617e+02, 2.557e+02, 1.839e+02, 1.341e+02, 9.949e+01, 7.488e+01, 5.709e+01, 4.403e+01,
    3.430e+01, 2.697e+01, 2.139e+01, 1.708e+01, 1.099e+01, 7.214e+00, 4.824e+00, 3.274e+00,
    2.249e+00, 1.558e+00, 1.091e+00, 7.701e-01, 5.474e-01, 3.916e-01, 2.819e-01, 2.042e-01,
    1.488e-01, 1.092e-01, 8.070e-02, 6.012e-02, 4.519e-02, 3.430e-02, 2.632e-02, 2.043e-02,
    1.607e-02, 1.281e-02, 1.036e-02, 8.496e-03, 7.069e-03, 4.680e-03, 3.200e-03, 2.210e-03,
    1.560e-03, 1.150e-03])
HP_RHO_MAX_g_km3 = np.array([
    4.974e+05, 2.490e+04, 8.710e+03, 4.059e+03, 2.215e+03, 1.344e+03, 8.758e+02, 6.010e+02,
    4.297e+02, 3.162e+02, 2.396e+02, 1.853e+02, 1.455e+02, 1.157e+02, 9.308e+01, 7.555e+01,
    6.182e+01, 5.095e+01, 4.226e+01, 3.526e+01, 2.511e+01, 1.819e+01, 1.337e+01, 9.955e+00,
    7.492e+00, 5.684e+00, 4.355e+00, 3.362e+00, 2.612e+00, 2.042e+00, 1.605e+00, 1.267e+00,
    1.005e+00, 7.997e-01, 6.390e-01, 5.123e-01, 4.121e-01, 3.325e-01, 2.691e-01, 2.185e-01,
    1.779e-01, 1.452e-01, 1.190e-01, 9.776e-02, 8.059e-02, 5.741e-02, 4.210e-02, 3.130e-02,
    2.360e-02, 1.810e-02])
#: Lag of the bulge apex behind the Sun in right ascension (rad) and the exponent n.
HP_LAG_rad = math.radians(30.0)
HP_EXPONENT = 2
_G_KM3_TO_KG_M3 = 1e-12


def height_km(r):
    """Return the height (km) above the WGS84 ellipsoid, first order in f (module doc)."""
    r_n = ca.norm_2(r)
    sin_lat = r[2] / r_n
    return r_n - WGS84_A_km * (1.0 - WGS84_F * sin_lat * sin_lat)


def _log_interp(h, table_g_km3: np.ndarray):
    """ρ (kg/m^3) with ln ρ piecewise linear in h through the Harris-Priester table."""
    log_rho = np.log(table_g_km3 * _G_KM3_TO_KG_M3)
    return ca.exp(ca.pw_lin(h, ca.DM(HP_HEIGHT_km), ca.DM(log_rho)))


def density_kg_m3(atmosphere: str, r, r_sun=None, layer: ExponentialLayer | None = None):
    """Return the density (kg/m^3) at inertial position r (km) of an Earth-centred orbit.

    ``r_sun`` (km, Earth-centred) orients the Harris-Priester bulge; ``layer`` is the
    exponential atmosphere's (default :class:`ExponentialLayer`'s defaults).
    """
    h = height_km(r)
    if atmosphere == "exponential":
        layer = ExponentialLayer() if layer is None else layer
        return layer.rho0_kg_m3 * ca.exp(-(h - layer.h0_km) / layer.scale_height_km)
    rho_min = _log_interp(h, HP_RHO_MIN_g_km3)
    rho_max = _log_interp(h, HP_RHO_MAX_g_km3)
    c, s = math.cos(HP_LAG_rad), math.sin(HP_LAG_rad)
    apex = ca.vertcat(c * r_sun[0] - s * r_sun[1], s * r_sun[0] + c * r_sun[1], r_sun[2])
    cos_psi = ca.dot(r, apex) / (ca.norm_2(r) * ca.norm_2(apex))
    bulge = ((1.0 + cos_psi) / 2.0) ** (HP_EXPONENT / 2)
    return rho_min + (rho_max - rho_min) * bulge


def drag_acceleration(r, v, rho_kg_m3, c_d, area_to_mass_m2_kg: float):
    """Return the drag acceleration (km/s^2, SX (3,)) in a co-rotating atmosphere.

    Parameters
    ----------
    r, v : SX (3,) inertial position (km) and velocity (km/s), Earth-centred.
    rho_kg_m3 : density at r, kg/m^3.
    c_d : drag coefficient (a number or a symbol).
    area_to_mass_m2_kg : A/m, m^2/kg.
    """
    v_rel = v - ca.vertcat(-OMEGA_EARTH_rad_s * r[1], OMEGA_EARTH_rad_s * r[0], 0.0)
    return -0.5e3 * c_d * area_to_mass_m2_kg * rho_kg_m3 * ca.norm_2(v_rel) * v_rel

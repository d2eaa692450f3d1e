"""Solar radiation pressure on a cannonball spacecraft, with conical shadows (the Earth's, the
Moon's and the centre's: :attr:`tapp.dynamics.spec.ForceModel.occulters`).

The acceleration (Montenbruck & Gill, *Satellite Orbits*, 2000, §3.4.1, for a
sphere) pushes away from the Sun:

.. math::
    \\mathbf a = \\nu\\, P_\\odot\\, C_r \\frac{A}{m}
        \\left(\\frac{\\mathrm{AU}}{|\\mathbf r - \\mathbf r_\\odot|}\\right)^2
        \\frac{\\mathbf r - \\mathbf r_\\odot}{|\\mathbf r - \\mathbf r_\\odot|},

with P☉ = 4.56e-6 N/m² at 1 AU (:data:`tapp.constants.SOLAR_PRESSURE_1AU_N_m2`), A/m in
m²/kg, converted to km/s² (× 1e-3). The shadow function ν ∈ [0, 1] is the visible fraction of
the solar disc (M&G §3.4.2): with the apparent radii a = asin(R☉/|s|) of the
Sun and b = asin(R_B/|d|) of the occulting body B, and their apparent separation
c = ∠(s, d) (s, d: spacecraft → Sun and → body; taken by atan2, accurate near 0 and π),

- c ≥ a + b: no occultation, ν = 1;
- c ≤ b − a: total (umbra), ν = 0;
- c ≤ a − b: annular, ν = 1 − b²/a²;
- otherwise partial (penumbra): ν = 1 − A/(π a²), A = a² acos(x/a) + b² acos((c − x)/b) − c y,
  x = (c² + a² − b²)/(2c), y = √(a² − x²).

The angles are taken as atan2(y, x) and atan2(y, c − x), with c² − b² = (c − b)(c + b) and
a² − x² = (a − x)(a + x): acos near 1 (the thin segment of the large Earth disc in LEO)
would lose half the digits, 1e-10 of ν.

The discs overlap as plane circles (M&G's model): the boundaries c = a + b and c = b − a are
exact cones, the partial area is approximate where the Earth's disc is large (LEO). The
bodies' factors are multiplied: a simultaneous occultation by two (rare) is then not exact.
Each body's radius is its equatorial one (no oblateness in the shadow).
Positions are relative to the integration centre, in km, from DE421.
"""

from __future__ import annotations

import math

import casadi as ca

from tapp.constants import AU_km, RADIUS_km, SOLAR_PRESSURE_1AU_N_m2


def _clip(x, lo: float, hi: float):
    return ca.fmin(ca.fmax(x, lo), hi)


def disc_geometry(r, r_sun, r_body, radius_body_km: float):
    """Return (a, b, c), rad: the apparent radii of the Sun and of the occulting body seen from
    the spacecraft and their apparent separation (module docstring).

    The arguments of asin are clipped to its domain, so no NaN reaches a branch of
    :func:`shadow_factor` that is not taken.

    Parameters
    ----------
    r, r_sun, r_body : SX (3,) positions of the spacecraft, the Sun and the occulting body
        relative to a common origin, km, same axes.
    radius_body_km : radius of the occulting body, km.
    """
    s = r_sun - r
    d = r_body - r
    s_n, d_n = ca.norm_2(s), ca.norm_2(d)
    a = ca.asin(_clip(RADIUS_km["sun"] / s_n, 0.0, 1.0))
    b = ca.asin(_clip(radius_body_km / d_n, 0.0, 1.0))
    c = ca.atan2(ca.norm_2(ca.cross(s, d)), ca.dot(s, d))  # exact at small c, unlike acos
    return a, b, c


def shadow_factor(r, r_sun, r_body, radius_body_km: float):
    """Return the visible fraction ν ∈ [0, 1] of the solar disc (module docstring).

    Arguments as in :func:`disc_geometry`. Every branch is evaluated (CasADi ``if_else``), so
    the argument of sqrt is clipped to its domain too.
    """
    a, b, c = disc_geometry(r, r_sun, r_body, radius_body_km)
    x = ((c - b) * (c + b) + a * a) / (2.0 * ca.fmax(c, 1e-300))
    y = ca.sqrt(ca.fmax((a - x) * (a + x), 0.0))
    area = a * a * ca.atan2(y, x) + b * b * ca.atan2(y, c - x) - c * y
    partial = 1.0 - area / (math.pi * a * a)
    return ca.if_else(c >= a + b, 1.0,
                      ca.if_else(c <= b - a, 0.0,
                                 ca.if_else(c <= a - b, 1.0 - (b * b) / (a * a), partial)))


#: The boundaries between the branches of :func:`shadow_factor`, as functions of (a, b, c)
#: that change sign there, negative on the shadow side: ν is continuous across each but its
#: derivatives are not (integration events, :mod:`tapp.dynamics.events`).
SHADOW_BOUNDARIES = {
    "penumbra": lambda a, b, c: c - (a + b),
    "umbra": lambda a, b, c: c - (b - a),
    "annular": lambda a, b, c: c - (a - b),
}


def srp_acceleration(r, r_sun, occulters, c_r, area_to_mass_m2_kg: float):
    """Return the SRP acceleration (km/s^2, SX (3,)) of a cannonball (module docstring).

    Parameters
    ----------
    r, r_sun : SX (3,) spacecraft and Sun positions relative to the centre, km.
    occulters : mapping of body name (:attr:`tapp.dynamics.spec.ForceModel.occulters`) to
        its position relative to the centre (km, SX (3,)); empty for no shadows (ν = 1: a
        conservative force).
    c_r : radiation pressure coefficient (a number or a symbol).
    area_to_mass_m2_kg : A/m, m^2/kg.
    """
    nu = 1.0
    for body, r_body in occulters.items():
        nu = nu * shadow_factor(r, r_sun, r_body, RADIUS_km[body])
    u = r - r_sun
    dist = ca.norm_2(u)
    p_km_s2 = SOLAR_PRESSURE_1AU_N_m2 * area_to_mass_m2_kg * 1e-3  # N/kg = m/s^2 -> km/s^2
    return nu * p_km_s2 * c_r * (AU_km / dist) ** 2 * u / dist

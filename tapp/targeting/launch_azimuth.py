"""A cheap body for the seed's ITER examples: direct ascent from a launch site at an azimuth.

The seed (section VI, CASES 1 and 2) iterates JPL's Near-Earth Conic program NECON over
launch azimuths and launch days. :func:`launch_azimuth_case` stands in for it with the
closed-form geometry of a direct ascent to a circular orbit from a spherical, rotating Earth:
the orbit plane contains the launch site and the launch direction. It costs microseconds, so
the examples exercise ITER rather than the physics. It is not validated against NECON.

It lives in ``tapp``, not in the generic engine ``iter``, so that it takes the Earth's
constants from :mod:`tapp.constants`.
"""

from __future__ import annotations

import math

from tapp.constants import GM_EARTH_km3_s2, OMEGA_EARTH_rad_s, R_EARTH_km

# Greenwich mean sidereal angle at J2000.0 and its rate, deg and deg/day of UT1
# (Meeus, Astronomical Algorithms, 2nd ed., eq. 12.4, without the T^2 and T^3 terms).
GMST_J2000_deg = 280.46061837
GMST_RATE_deg_day = 360.98564736629


def launch_azimuth_case(launch_day: float, azimuth_deg: float, *, latitude_deg: float,
                        east_longitude_deg: float, altitude_km: float) -> dict[str, float]:
    """Return inclination, node (deg) and Δv (km/s) of a direct ascent at ``azimuth_deg``.

    Parameters
    ----------
    launch_day : float
        Launch instant, days of UT1 past J2000.0 (2000-01-01 12:00 UT1).
    azimuth_deg : float
        Launch azimuth, deg, clockwise from north (90 = due east).
    latitude_deg, east_longitude_deg : float
        Launch site, geocentric, deg.
    altitude_km : float
        Altitude of the circular target orbit above the equatorial radius, km.

    Returns
    -------
    dict
        ``inclination_deg`` in [0, 180]; ``raan_deg``, the right ascension of the ascending
        node in [0, 360) (for an equatorial orbit, where the node is undefined, the site's
        right ascension); ``circular_speed_km_s``; ``delta_v_km_s``, the ideal speed to add to
        the launch pad's (no gravity or drag loss); ``rotation_gain_km_s``, what the Earth's
        rotation saves, circular speed minus Δv.

    Notes
    -----
    With site latitude φ, azimuth A, pad speed :math:`v_e = \\omega_E R_E \\cos\\phi` due east
    and circular speed :math:`v_c = \\sqrt{\\mu / (R_E + h)}` along A:

    .. math::

        \\cos i = \\cos\\phi \\sin A, \\qquad
        \\Delta v = \\sqrt{v_c^2 + v_e^2 - 2 v_c v_e \\sin A}, \\qquad
        \\Omega = \\alpha_{site} - \\operatorname{atan2}(\\cos i \\sin\\phi, \\cos A \\cos\\phi).

    Δv by the law of cosines on the two velocities; i and Ω by Napier's rules on the right
    spherical triangle formed by the ascending node, the site, and the foot of the site's
    meridian on the equator, with
    :math:`\\alpha_{site} = \\theta_{GMST} + \\lambda_E`.

    Examples
    --------
    Due east from the equator, the orbit is equatorial and the pad's 0.465 km/s is saved:

    >>> out = launch_azimuth_case(0.0, 90.0, latitude_deg=0.0, east_longitude_deg=0.0,
    ...                           altitude_km=185.0)
    >>> round(out["inclination_deg"], 9), round(out["rotation_gain_km_s"], 6)
    (0.0, 0.465101)
    """
    phi_rad = math.radians(latitude_deg)
    a_rad = math.radians(azimuth_deg)
    cos_i = math.cos(phi_rad) * math.sin(a_rad)
    i_rad = math.acos(max(-1.0, min(1.0, cos_i)))
    v_c_km_s = math.sqrt(GM_EARTH_km3_s2 / (R_EARTH_km + altitude_km))
    v_e_km_s = OMEGA_EARTH_rad_s * R_EARTH_km * math.cos(phi_rad)
    delta_v_km_s = math.sqrt(v_c_km_s**2 + v_e_km_s**2
                             - 2.0 * v_c_km_s * v_e_km_s * math.sin(a_rad))
    site_ra_deg = GMST_J2000_deg + GMST_RATE_deg_day * launch_day + east_longitude_deg
    node_to_site_rad = math.atan2(cos_i * math.sin(phi_rad), math.cos(a_rad) * math.cos(phi_rad))
    raan_deg = (site_ra_deg - math.degrees(node_to_site_rad)) % 360.0
    return {
        "inclination_deg": math.degrees(i_rad),
        "raan_deg": raan_deg,
        "circular_speed_km_s": v_c_km_s,
        "delta_v_km_s": delta_v_km_s,
        "rotation_gain_km_s": v_c_km_s - delta_v_km_s,
    }

"""Physical constants, in km, s and rad, each with its source.

Gravity field: EGM96 (Lemoine et al. 1998, NASA/TP-1998-206861), fully normalised C_nm, S_nm
to degree and order 8, shipped in ``tapp/data/egm96_deg8.txt``. GM and radius of the Earth are
those of EGM96 so the field is used with the constants it was fitted with.
GM of the other bodies: JPL DE430 (Folkner et al. 2014, IPN Progress Report 42-196, Table 8).

Zonal J2 of the other centres that have one here (:data:`J2_CENTRE`, :data:`J2_RADIUS_km`),
unnormalised, J2 = -sqrt(5) \\bar C_{20}, each with the reference radius of its field:

- Mars: J2 = 1.95545e-3, R = 3396.0 km, MRO120D (Konopliv et al. 2016, Icarus 274, 253);
  GMM-3 (Genova et al. 2016, Icarus 272, 228) has \\bar C_{20} = -8.7450e-4, i.e.
  J2 = 1.95544e-3, the same to 5e-6. The fields' GM of Mars alone (42828.374 km^3/s^2) differs
  from DE430's Mars-system GM (42828.375214, with Phobos and Deimos) by ~2e-8 relative, far
  below J2's effect (1e-3): the DE430 value is used.
- Moon: \\bar C_{20} = -9.0880e-5, R = 1738.0 km, GRAIL GL0660B (Konopliv et al. 2013, JGR
  Planets 118, 1415), so J2 = sqrt(5) * 9.0880e-5 = 2.03214e-4 (not 2.0330e-4: that value does
  not follow from this C20). The field's GM (4902.80007) is DE430's to 1e-9.
- Venus: J2 = 4.458e-6, R = 6051.8 km, MGNP180U (Konopliv, Banerdt & Sjogren 1999, Icarus
  139, 3). DE430's GM is used.

Each J2 acts about the body's IAU rotation pole (:mod:`tapp.dynamics.poles`).
"""

from __future__ import annotations

from functools import cache
from importlib.resources import files

import numpy as np

# Earth, EGM96 (NASA/TP-1998-206861)
GM_EARTH_km3_s2 = 398600.4415
R_EARTH_km = 6378.1363
# Nominal mean angular velocity of the Earth, IERS Conventions (2010) Table 1.1.
OMEGA_EARTH_rad_s = 7.292115e-5
# WGS 84 ellipsoid for geodetic station coordinates (NIMA TR8350.2, 3rd ed., Table 3.1).
WGS84_A_km = 6378.137
WGS84_F = 1.0 / 298.257223563

# Speed of light (SI definition).
C_LIGHT_km_s = 299792.458
AU_km = 149597870.700  # IAU 2012 Resolution B2
SECONDS_PER_DAY = 86400.0
# Solar radiation pressure on an absorbing surface at 1 AU, P = Φ/c with the solar flux
# Φ ≈ 1367 W/m^2 (Montenbruck & Gill, Satellite Orbits, 2000, §3.4.1), N/m^2.
SOLAR_PRESSURE_1AU_N_m2 = 4.56e-6

# GM of Sun, Moon and planet systems, DE430 (Folkner et al. 2014, Table 8), km^3/s^2.
GM_km3_s2 = {
    "sun": 132712440041.939400,
    "mercury": 22031.780000,
    "venus": 324858.592000,
    "earth": GM_EARTH_km3_s2,
    "moon": 4902.800066,
    "mars": 42828.375214,
    "jupiter": 126712764.800000,
    "saturn": 37940585.200000,
    "uranus": 5794548.600000,
    "neptune": 6836527.100580,
}
# Mean equatorial radii (IAU WGCCRE 2015, Archinal et al. 2018), km: for B-plane impact checks.
RADIUS_km = {
    "sun": 695700.0,
    "mercury": 2440.53,
    "venus": 6051.8,
    "earth": R_EARTH_km,
    "moon": 1737.4,
    "mars": 3396.19,
    "jupiter": 71492.0,
    "saturn": 60268.0,
    "uranus": 25559.0,
    "neptune": 24764.0,
}

# Zonal J2 (unnormalised, dimensionless) and the reference radius of its field (km) of the
# centres other than the Earth that have one (module docstring for the sources).
J2_CENTRE = {
    "mars": 1.95545e-3,                      # MRO120D
    "moon": float(np.sqrt(5.0)) * 9.0880e-5,  # GL0660B, -sqrt(5) C20
    "venus": 4.458e-6,                       # MGNP180U
}
J2_RADIUS_km = {"mars": 3396.0, "moon": 1738.0, "venus": 6051.8}
#: Highest degree of the shipped gravity field.
MAX_DEGREE = 8


@cache
def egm96_coefficients() -> tuple[np.ndarray, np.ndarray]:
    """Return fully normalised EGM96 (C, S), each (MAX_DEGREE+1, MAX_DEGREE+1), C[0,0] = 1.

    Entries C[n, m] hold \\bar C_{nm}; degree 1 and S[n, 0] are zero. Read-only arrays.
    """
    text = files("tapp").joinpath("data/egm96_deg8.txt").read_text()
    c = np.zeros((MAX_DEGREE + 1, MAX_DEGREE + 1))
    s = np.zeros_like(c)
    c[0, 0] = 1.0
    for line in text.splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        n, m, cnm, snm = line.split()
        c[int(n), int(m)] = float(cnm)
        s[int(n), int(m)] = float(snm)
    c.setflags(write=False)
    s.setflags(write=False)
    return c, s


def unnormalised_zonal_j(n: int) -> float:
    """Return the classical zonal J_n = -sqrt(2n+1) * \\bar C_{n0} (dimensionless)."""
    c, _ = egm96_coefficients()
    return float(-np.sqrt(2 * n + 1) * c[n, 0])

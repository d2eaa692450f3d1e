"""Ground stations: Earth-fixed location, inertial state, and partials w.r.t. location.

A station is fixed in the Earth-fixed frame of :mod:`tapp.frames.rotation`; its inertial
(EME2000) state at scenario time t is

.. math::

    \\mathbf r(t) = R_3(-\\theta(t))\\,\\mathbf r_f,\\qquad
    \\mathbf v(t) = \\boldsymbol\\omega \\times \\mathbf r(t),\\qquad
    \\theta(t) = \\theta_0 + \\omega_\\oplus t

(:func:`tapp.frames.earth_rotation_angle_rad`, the same model the dynamics use).

Two location parameterisations are offered for estimation and consider analysis:

- ``"cylindrical"``: (r_s km, lon rad, z km), distance from the spin axis, longitude, and
  height along the spin axis: the classic DSN station-location set, in which r_s and lon are
  well determined by range-rate and z poorly (Hamilton & Melbourne 1966, JPL SPS 37-39);
- ``"ecef"``: Earth-fixed (x, y, z) km.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from tapp.constants import OMEGA_EARTH_rad_s
from tapp.errors import InputError
from tapp.frames.geodesy import ecef_to_geodetic, enu_matrix, geodetic_to_ecef
from tapp.frames.rotation import earth_rotation_angle_rad, eci_to_ecef_matrix, r3

StationParameters = Literal["cylindrical", "ecef"]
_PARAMETER_CHOICES = '"cylindrical" or "ecef"'
#: Names and units of the location parameters, in the order of the partials' last axis.
STATION_PARAMETER_NAMES = {
    "cylindrical": ("spin_radius_km", "lon_rad", "z_km"),
    "ecef": ("x_km", "y_km", "z_km"),
}


#: Plausible heights of a ground station above the WGS84 ellipsoid, km, inclusive: the lowest
#: land (Dead Sea shore, -0.43 km) to above the highest summit (Everest, 8.85 km). A height
#: outside is a unit slip (m for km) or a typo, and would silently see nothing (or everything).
HEIGHT_RANGE_km = (-0.5, 10.0)


def station_state_eci(r_ecef_km, theta_rad, omega_rad_s: float = OMEGA_EARTH_rad_s):
    """Return the inertial state [r km, v km/s] of an Earth-fixed point, shape (..., 6).

    Parameters
    ----------
    r_ecef_km : array_like, shape (3,) or (..., 3)
        Earth-fixed position, km.
    theta_rad : array_like, shape (...)
        Earth rotation angle at each time, rad.
    omega_rad_s : float
        Earth rotation rate, rad/s.

    Notes
    -----
    r = R3(-theta) r_f and v = omega z_hat x r = omega (-r_y, r_x, 0).
    """
    r = np.einsum("...ij,...j->...i", r3(-np.asarray(theta_rad, float)), np.asarray(r_ecef_km))
    v = omega_rad_s * np.stack([-r[..., 1], r[..., 0], np.zeros_like(r[..., 0])], -1)
    return np.concatenate([r, v], axis=-1)


def station_state_partials(
    r_ecef_km,
    theta_rad,
    parameters: StationParameters = "cylindrical",
    omega_rad_s: float = OMEGA_EARTH_rad_s,
):
    """Return d[r_eci, v_eci]/d(location parameters), shape (..., 6, 3).

    Parameters
    ----------
    r_ecef_km : array_like, shape (3,)
        Earth-fixed position, km (the point where the partials are taken).
    theta_rad : array_like, shape (...)
        Earth rotation angle at each time, rad.
    parameters : {"cylindrical", "ecef"}
        ``"cylindrical"``: columns d/d(r_s km, lon rad, z km); ``"ecef"``: d/d(x, y, z km).
    omega_rad_s : float
        Earth rotation rate, rad/s.

    Notes
    -----
    Cylindrical: with alpha = lon + theta, r_eci = (r_s cos alpha, r_s sin alpha, z) and
    v_eci = omega (-r_s sin alpha, r_s cos alpha, 0), so

    .. math::

        \\frac{\\partial \\mathbf r}{\\partial (r_s, \\lambda, z)} =
        \\begin{pmatrix} \\cos\\alpha & -r_s\\sin\\alpha & 0 \\\\
        \\sin\\alpha & r_s\\cos\\alpha & 0 \\\\ 0 & 0 & 1 \\end{pmatrix},\\quad
        \\frac{\\partial \\mathbf v}{\\partial (r_s, \\lambda, z)} = \\omega
        \\begin{pmatrix} -\\sin\\alpha & -r_s\\cos\\alpha & 0 \\\\
        \\cos\\alpha & -r_s\\sin\\alpha & 0 \\\\ 0 & 0 & 0 \\end{pmatrix}.

    ECEF: dr/dr_f = R3(-theta), dv/dr_f = [omega z_hat x] R3(-theta).
    """
    theta = np.asarray(theta_rad, dtype=float)
    r_f = np.asarray(r_ecef_km, dtype=float)
    out = np.zeros(theta.shape + (6, 3))
    if parameters == "cylindrical":
        spin_radius = np.hypot(r_f[0], r_f[1])
        alpha = np.arctan2(r_f[1], r_f[0]) + theta
        ca, sa = np.cos(alpha), np.sin(alpha)
        out[..., 0, 0], out[..., 1, 0] = ca, sa
        out[..., 0, 1], out[..., 1, 1] = -spin_radius * sa, spin_radius * ca
        out[..., 2, 2] = 1.0
        out[..., 3, 0], out[..., 4, 0] = -omega_rad_s * sa, omega_rad_s * ca
        out[..., 3, 1] = -omega_rad_s * spin_radius * ca
        out[..., 4, 1] = -omega_rad_s * spin_radius * sa
    elif parameters == "ecef":
        rot = r3(-theta)
        out[..., :3, :] = rot
        out[..., 3, :] = -omega_rad_s * rot[..., 1, :]
        out[..., 4, :] = omega_rad_s * rot[..., 0, :]
    else:
        raise InputError("station_state_partials", "parameters", _PARAMETER_CHOICES, parameters)
    return out


@dataclass(frozen=True, slots=True)
class Station:
    """A ground station on the WGS84 ellipsoid, fixed in the Earth-fixed frame.

    Attributes
    ----------
    name : str
        Station name.
    lat_rad, lon_rad : float
        Geodetic latitude and east longitude, rad.
    h_km : float
        Height above the WGS84 ellipsoid, km, within :data:`HEIGHT_RANGE_km` (-0.5 to 10 km).
    elev_mask_rad : float
        Elevation mask: the station sees a spacecraft strictly above it, rad.
    r_ecef_km : numpy.ndarray, shape (3,)
        Earth-fixed position, km (derived, read-only).

    Notes
    -----
    The topocentric East-North-Up frame (``enu_from_ecef``) is that of the nominal geodetic
    latitude and longitude: partials w.r.t. the location parameters move the station, not the
    axes its angles are measured in (the antenna mount does not tilt with a survey error).
    """

    name: str
    lat_rad: float
    lon_rad: float
    h_km: float
    elev_mask_rad: float = 0.0
    r_ecef_km: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not -0.5 * np.pi <= self.lat_rad <= 0.5 * np.pi:
            raise InputError(f"station {self.name}", "lat_rad", "[-pi/2, pi/2]", self.lat_rad)
        lo, hi = HEIGHT_RANGE_km
        if not lo <= self.h_km <= hi:
            raise InputError(f"station {self.name}", "h_km", f"a ground-station height in "
                             f"[{lo:g}, {hi:g}] km above the WGS84 ellipsoid", self.h_km)
        if not np.isfinite(self.lon_rad):
            raise InputError(f"station {self.name}", "lon_rad", "a finite longitude",
                             self.lon_rad)
        r = geodetic_to_ecef(self.lat_rad, self.lon_rad, self.h_km)
        r.setflags(write=False)
        object.__setattr__(self, "r_ecef_km", r)

    @classmethod
    def from_degrees(
        cls, name: str, lat_deg: float, lon_deg: float, h_km: float, elev_mask_deg: float = 0.0
    ) -> Station:
        """Build from geodetic latitude/longitude and mask in degrees (the edge form)."""
        lat, lon, mask = np.radians([lat_deg, lon_deg, elev_mask_deg])
        return cls(name, float(lat), float(lon), float(h_km), float(mask))

    @classmethod
    def from_ecef(cls, name: str, r_ecef_km, elev_mask_rad: float = 0.0) -> Station:
        """Build from an Earth-fixed position (3,) km (geodetic coordinates by Bowring)."""
        lat, lon, h = ecef_to_geodetic(np.asarray(r_ecef_km, dtype=float))
        return cls(name, float(lat), float(lon), float(h), float(elev_mask_rad))

    @classmethod
    def from_cylindrical(
        cls,
        name: str,
        spin_radius_km: float,
        lon_rad: float,
        z_km: float,
        elev_mask_rad: float = 0.0,
    ) -> Station:
        """Build from (distance off the spin axis km, longitude rad, z km)."""
        r = [spin_radius_km * np.cos(lon_rad), spin_radius_km * np.sin(lon_rad), z_km]
        return cls.from_ecef(name, r, elev_mask_rad)

    @property
    def spin_radius_km(self) -> float:
        """Distance from the spin axis, km."""
        return float(np.hypot(self.r_ecef_km[0], self.r_ecef_km[1]))

    @property
    def z_km(self) -> float:
        """Height above the equatorial plane (along the spin axis), km."""
        return float(self.r_ecef_km[2])

    def location(self, parameters: StationParameters = "cylindrical") -> np.ndarray:
        """Return the location parameters, shape (3,), named by ``STATION_PARAMETER_NAMES``."""
        if parameters == "cylindrical":
            return np.array([self.spin_radius_km, self.lon_rad, self.z_km])
        if parameters == "ecef":
            return self.r_ecef_km.copy()
        raise InputError(f"station {self.name}", "parameters", _PARAMETER_CHOICES, parameters)

    @property
    def enu_from_ecef(self) -> np.ndarray:
        """Rotation Earth-fixed -> local East-North-Up, shape (3, 3)."""
        return enu_matrix(self.lat_rad, self.lon_rad)

    def enu_from_eci(self, theta_rad) -> np.ndarray:
        """Rotation inertial -> local East-North-Up at rotation angles theta, shape (..., 3, 3)."""
        return self.enu_from_ecef @ eci_to_ecef_matrix(theta_rad)

    def state_eci(self, theta0_rad: float, t_s, omega_rad_s: float = OMEGA_EARTH_rad_s):
        """Return the inertial state [r km, v km/s] at times t_s (N,) s, shape (N, 6).

        theta0_rad is the GMST at the scenario epoch (see :func:`station_state_eci`).
        """
        theta = earth_rotation_angle_rad(theta0_rad, t_s, omega_rad_s)
        return station_state_eci(self.r_ecef_km, theta, omega_rad_s)

    def state_partials(
        self,
        theta0_rad: float,
        t_s,
        parameters: StationParameters = "cylindrical",
        omega_rad_s: float = OMEGA_EARTH_rad_s,
    ):
        """Return d[r_eci, v_eci]/d(location), shape (N, 6, 3) (see station_state_partials)."""
        theta = earth_rotation_angle_rad(theta0_rad, t_s, omega_rad_s)
        return station_state_partials(self.r_ecef_km, theta, parameters, omega_rad_s)

"""Ground stations: Earth-fixed location, inertial state, and partials w.r.t. location.

A station is fixed in the Earth-fixed frame (ITRS); its inertial (GCRS) state at scenario
time t is

.. math::

    \\mathbf r(t) = M(t)^T\\,\\mathbf r_f,\\qquad
    \\mathbf v(t) = \\omega\\,\\hat{\\mathbf c}(t) \\times \\mathbf r(t)

with M the inertial → Earth-fixed rotation and ĉ the spin axis of the scenario's Earth
orientation model (:mod:`tapp.frames.orientation`, the same model the dynamics use).

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

from tapp.errors import InputError
from tapp.frames.geodesy import ecef_to_geodetic, enu_matrix, geodetic_to_ecef
from tapp.frames.orientation import (
    EOP_PARAMETERS,
    EarthAttitude,
    EarthOrientation,
    as_orientation,
    eop_generators,
)

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


def station_state_eci(r_ecef_km, attitude: EarthAttitude):
    """Return the inertial state [r km, v km/s] of an Earth-fixed point, shape (N, 6).

    Parameters
    ----------
    r_ecef_km : array_like, shape (3,)
        Earth-fixed (ITRS) position, km.
    attitude : EarthAttitude
        The Earth's orientation at the N times (:meth:`EarthOrientation.attitude`).

    Notes
    -----
    r = Mᵀ r_f with M the inertial → Earth-fixed rotation, and v = ω ĉ × r, ĉ the spin axis
    (the CIP; z for gmst): a rigid rotation (see :mod:`tapp.frames.orientation` for what the
    velocity leaves out).
    """
    r = np.einsum("...ij,j->...i", attitude.gcrs_from_itrs, np.asarray(r_ecef_km, dtype=float))
    v = attitude.omega_rad_s * np.cross(attitude.spin_axis, r)
    return np.concatenate([r, v], axis=-1)


def location_jacobian(r_ecef_km, parameters: StationParameters = "cylindrical") -> np.ndarray:
    """Return d r_f / d(location parameters), shape (3, 3), at an Earth-fixed position (km).

    Cylindrical (r_s, lon, z): r_f = (r_s cos lon, r_s sin lon, z), so the columns are
    (cos lon, sin lon, 0), (-r_s sin lon, r_s cos lon, 0), (0, 0, 1); ECEF: the identity.
    """
    r_f = np.asarray(r_ecef_km, dtype=float)
    if parameters == "ecef":
        return np.eye(3)
    if parameters != "cylindrical":
        raise InputError("station_state_partials", "parameters", _PARAMETER_CHOICES, parameters)
    spin_radius = np.hypot(r_f[0], r_f[1])
    lon = np.arctan2(r_f[1], r_f[0])
    c, s = np.cos(lon), np.sin(lon)
    return np.array([[c, -spin_radius * s, 0.0], [s, spin_radius * c, 0.0], [0.0, 0.0, 1.0]])


def station_state_partials(r_ecef_km, attitude: EarthAttitude,
                           parameters: StationParameters = "cylindrical"):
    """Return d[r_eci, v_eci]/d(location parameters), shape (N, 6, 3).

    Parameters
    ----------
    r_ecef_km : array_like, shape (3,)
        Earth-fixed position, km (the point where the partials are taken).
    attitude : EarthAttitude
        The Earth's orientation at the N times.
    parameters : {"cylindrical", "ecef"}
        ``"cylindrical"``: columns d/d(r_s km, lon rad, z km); ``"ecef"``: d/d(x, y, z km).

    Notes
    -----
    With J = d r_f / dp (:func:`location_jacobian`): dr/dp = Mᵀ J and dv/dp = ω [ĉ×] Mᵀ J,
    the derivatives of :func:`station_state_eci`.
    """
    dr = attitude.gcrs_from_itrs @ location_jacobian(r_ecef_km, parameters)
    dv = attitude.omega_rad_s * np.cross(attitude.spin_axis[..., :, None], dr, axis=-2)
    return np.concatenate([dr, dv], axis=-2)


def station_eop_partials(r_ecef_km, attitude: EarthAttitude, names=EOP_PARAMETERS):
    """Return d[r_eci, v_eci]/d(constant EOP offsets), shape (N, 6, k).

    Parameters
    ----------
    r_ecef_km : array_like, shape (3,)
        Earth-fixed position, km.
    attitude : EarthAttitude
        The Earth's orientation at the N times.
    names : sequence of str
        Columns among ("ut1_s", "xp_rad", "yp_rad"): km/s (UT1 − UTC offset in s) and km/rad
        (pole coordinates); check them against the model with
        :func:`tapp.frames.orientation.check_eop_parameters` first.

    Notes
    -----
    dr/dp = g_p × r with g_p the inertial rotation vector of the offset
    (:func:`tapp.frames.orientation.eop_generators`, IERS Conventions 2010 ch. 5), and
    dv/dp = ω ĉ × dr/dp (ĉ, the CIP, does not depend on UT1 or the pole coordinates): the
    derivatives of :func:`station_state_eci`. dr/dUT1 is the station's velocity, 0.465 m per
    ms of UT1 at the equator.
    """
    r = station_state_eci(r_ecef_km, attitude)[..., None, :3]
    dr = np.cross(eop_generators(attitude, names), r)  # (N, k, 3)
    dv = attitude.omega_rad_s * np.cross(attitude.spin_axis[..., None, :], dr)
    return np.swapaxes(np.concatenate([dr, dv], axis=-1), -1, -2)


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

    def enu_from_eci(self, attitude: EarthAttitude) -> np.ndarray:
        """Rotation inertial -> local East-North-Up at the attitude's times, shape (N, 3, 3)."""
        return self.enu_from_ecef @ attitude.itrs_from_gcrs

    def state_eci(self, orientation: EarthOrientation | float, t_s):
        """Return the inertial state [r km, v km/s] at times t_s (N,) s, shape (N, 6).

        ``orientation`` is the scenario's Earth orientation (a float: the gmst model's angle at
        the epoch, rad).
        """
        return station_state_eci(self.r_ecef_km, as_orientation(orientation).attitude(t_s))

    def state_partials(self, orientation: EarthOrientation | float, t_s,
                       parameters: StationParameters = "cylindrical"):
        """Return d[r_eci, v_eci]/d(location), shape (N, 6, 3) (see station_state_partials)."""
        return station_state_partials(self.r_ecef_km, as_orientation(orientation).attitude(t_s),
                                      parameters)

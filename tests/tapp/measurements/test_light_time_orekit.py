"""tapp's Newtonian two-way light time against Orekit's ``Range``, ``RangeRate`` and
``ShapiroRangeModifier`` (Orekit 13.1, tests/orekit_session.py's world: the same time scales,
EOP rows and WGS84 stations, GCRF).

Orekit solves the two-way light time in the GCRF from the state at the reception date,
moved along its Keplerian orbit; tapp from the same state by its third-order two-body Taylor
expansion with the same GM (both exact to < 1e-9 km over the 1.3 s and 1000 s light times
here). Geometries: a DSN pass of the lunar scenario (deep_space.toml's Goldstone, a
spacecraft 380,000 km away near its zenith) and a Mars-distance one (1.5 AU), five days
after the world's epoch. What remains different: Orekit interpolates the daily EOP with a
cubic Hermite polynomial where tapp interpolates linearly, and its station velocity includes
the motion of the CIP where tapp's is a rigid rotation about it (tapp.frames.orientation).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tapp.constants import C_LIGHT_km_s, GM_EARTH_km3_s2
from tapp.measurements import LightTime, MeasurementModel, Station
from tapp.measurements.observables import range_rate_km_s
from tapp.measurements.relativity import shapiro_delay_s
from tests import orekit_session

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

ONE_MM_km = 1e-6
HUNDREDTH_MM_S_km_s = 1e-8
GOLDSTONE = Station("GOLDSTONE", math.radians(35.4267), math.radians(-116.89), 1.0,
                    math.radians(10.0))
T_S = 5 * 86400.0 + 3600.0


def _state(distance_km: float) -> np.ndarray:
    """A spacecraft ``distance_km`` from the geocentre, 20 deg off the station's zenith,
    moving at 1 km/s across the line of sight and 0.4 km/s along it."""
    model = MeasurementModel(GOLDSTONE, orekit_session.orientation(), ("range",))
    up = model.station_eci(np.array([T_S]))[0, :3]
    up /= np.linalg.norm(up)
    side = np.cross(up, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    u = math.cos(math.radians(20.0)) * up + math.sin(math.radians(20.0)) * side
    return np.r_[distance_km * u, 0.4 * u + 1.0 * np.cross(u, side)]


def _orekit(x: np.ndarray, two_way: bool = True, shapiro: bool = False):
    """Orekit's range (km), range-rate (km/s) and the station's GCRF positions (km) at
    reception and transmission, of state x (GCRF) at T_S."""
    w = orekit_session.world()  # starts the JVM: Orekit's classes import after it
    from jpype import JArray
    from org.hipparchus.geometry.euclidean.threed import Vector3D
    from org.orekit.bodies import GeodeticPoint
    from org.orekit.estimation.measurements import (
        GroundStation,
        ObservableSatellite,
        Range,
        RangeRate,
    )
    from org.orekit.estimation.measurements.modifiers import ShapiroRangeModifier
    from org.orekit.frames import TopocentricFrame
    from org.orekit.orbits import CartesianOrbit
    from org.orekit.propagation import SpacecraftState
    from org.orekit.utils import PVCoordinates

    date = w.epoch.shiftedBy(T_S)
    site = GroundStation(TopocentricFrame(w.earth, GeodeticPoint(
        GOLDSTONE.lat_rad, GOLDSTONE.lon_rad, GOLDSTONE.h_km * 1e3), GOLDSTONE.name))
    mu = GM_EARTH_km3_s2 * 1e9
    orbit = CartesianOrbit(PVCoordinates(Vector3D(*(float(v) * 1e3 for v in x[:3])),
                                         Vector3D(*(float(v) * 1e3 for v in x[3:]))),
                           w.gcrf, date, mu)
    states = JArray(SpacecraftState)([SpacecraftState(orbit)])
    satellite = ObservableSatellite(0)
    ranging = Range(site, two_way, date, 0.0, 1.0, 1.0, satellite)
    if shapiro:
        ranging.addModifier(ShapiroRangeModifier(mu))
    rate = RangeRate(site, date, 0.0, 1.0, 1.0, two_way, satellite)
    for measurement in (ranging, rate):  # the station's (zero) EOP and clock offsets
        for driver in measurement.getParametersDrivers():
            driver.setReferenceDate(date)
    estimated = ranging.estimateWithoutDerivatives(states)
    rate_value = rate.estimateWithoutDerivatives(states).getEstimatedValue()[0]
    stations = [1e-3 * np.array(list(p.getPosition().toArray()))
                for p in estimated.getParticipants()]
    return (estimated.getEstimatedValue()[0] * 1e-3, rate_value * 1e-3, stations[-1],
            stations[0])


def _tapp(two_way: bool = True) -> MeasurementModel:
    return MeasurementModel(GOLDSTONE, orekit_session.orientation(), ("range", "range_rate"),
                            LightTime(two_way, None, GM_EARTH_km3_s2))


def _station_offset_km(model: MeasurementModel, x, receive_km, transmit_km, two_way):
    """The range that the two frames' station positions make differ, km: the projection
    of Orekit's minus tapp's station position on each leg (d range = -rho_hat . d r_st)."""
    sol = model._geometry(np.array([T_S]), x[None]).solution
    sc = sol.spacecraft_eci[0, :3]

    def leg(station, orekit_km):
        direction = (sc - station[0, :3]) / np.linalg.norm(sc - station[0, :3])
        return -direction @ (orekit_km - station[0, :3])

    down = leg(sol.station_receive_eci, receive_km)
    return 0.5 * (down + leg(sol.station_transmit_eci, transmit_km)) if two_way else down


@pytest.mark.parametrize(("distance_km", "two_way"), [
    (380000.0, True), (380000.0, False), (1.5 * 149597870.7, False)])
def test_range_and_range_rate_match_orekit(distance_km, two_way):
    """Range within 1 mm once the stations' 11 mm position difference (the two realizations
    of the ITRF-GCRF transformation, EOP interpolated linearly vs by Hermite) is projected
    out (measured 1e-4 mm two-way and 0 one-way at 380,000 km, 0.03 mm one-way at 1.5 AU);
    the legs' line-of-sight rates within 0.01 mm/s (measured 0.0025 mm/s). At 1.5 AU only
    one-way: Orekit moves the station to the transmit time of a two-way signal by a Taylor
    expansion of its motion, 1.1 km off after 1494 s (181 m in range: see the next test),
    where tapp rotates it."""
    x = _state(distance_km)
    model = _tapp(two_way)
    assert model.elevation_rad(np.array([T_S]), x[None])[0] > GOLDSTONE.elev_mask_rad
    tapp_range, tapp_rate = model.compute(np.array([T_S]), x[None])[0]
    orekit_range, orekit_rate, receive, transmit = _orekit(x, two_way)
    stations = model.station_eci(np.array([T_S]))[0, :3]
    assert np.linalg.norm(receive - stations) < 0.02e-3  # km: 11 mm measured
    offset = _station_offset_km(model, x, receive, transmit, two_way)
    assert abs(tapp_range + offset - orekit_range) < ONE_MM_km
    # Orekit's RangeRate is the mean of the legs' line-of-sight rates at the solved
    # geometry; tapp's range_rate the time derivative of the light-time range, which
    # differs by O(rho_dot v / c) (1e-6 km/s here): compare the legs' rates at tapp's solution.
    sol = model._geometry(np.array([T_S]), x[None]).solution
    legs = [range_rate_km_s(sol.spacecraft_eci, sol.station_receive_eci)[0],
            range_rate_km_s(sol.spacecraft_eci, sol.station_transmit_eci)[0]]
    geometric = 0.5 * (legs[0] + legs[1]) if two_way else legs[0]
    assert abs(geometric - orekit_rate) < HUNDREDTH_MM_S_km_s
    assert 1e-7 < abs(tapp_rate - geometric) < 1e-5


def test_orekits_two_way_station_at_transmission_is_a_taylor_expansion():
    """At 1.5 AU Orekit's two-way transmit station is ~1.1 km from the rotated one: the
    third-order term ω³ ρ_s T³ / 6 of a second-order expansion over T = 1494 s (ρ_s the
    distance from the spin axis). tapp's is the rotation: its own transmit station is where
    the Earth orientation puts the station at t - T."""
    x = _state(1.5 * 149597870.7)
    model = _tapp()
    sol = model._geometry(np.array([T_S]), x[None]).solution
    _, _, _, transmit = _orekit(x)
    round_trip = sol.tau_down_s[0] + sol.tau_up_s[0]
    spin_km = float(np.hypot(*GOLDSTONE.r_ecef_km[:2]))
    predicted = spin_km * (7.2921e-5 * round_trip) ** 3 / 6.0
    assert np.linalg.norm(transmit - sol.station_transmit_eci[0, :3]) == pytest.approx(
        predicted, rel=0.1)
    assert np.allclose(sol.station_transmit_eci[0, :3],
                       model.station_eci(np.array([T_S - round_trip]))[0, :3], atol=1e-9)


@pytest.mark.parametrize("distance_km", [380000.0, 1.5 * 149597870.7])
def test_earth_shapiro_term_matches_orekit(distance_km):
    """Orekit's ShapiroRangeModifier adds the mean of the legs' Earth terms
    2 μ / c² ln((r1 + r2 + r12) / (r1 + r2 - r12)) (GCRF); tapp's Earth term
    (tapp.measurements.relativity.shapiro_delay_s, Moyer eq. 8-38) at tapp's solution."""
    x = _state(distance_km)
    model = _tapp()
    sol = model._geometry(np.array([T_S]), x[None]).solution
    zero = np.zeros((1, 3))
    legs = [shapiro_delay_s(a[:, :3], b[:, :3], zero, zero, GM_EARTH_km3_s2)
            for a, b in ((sol.station_transmit_eci, sol.spacecraft_eci),
                         (sol.spacecraft_eci, sol.station_receive_eci))]
    tapp_term = 0.5 * C_LIGHT_km_s * (legs[0] + legs[1])[0]
    orekit_term = _orekit(x, shapiro=True)[0] - _orekit(x)[0]
    assert tapp_term > 0.03e-3  # km: tens of mm
    assert abs(tapp_term - orekit_term) < ONE_MM_km

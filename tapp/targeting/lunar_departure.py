"""Trans-lunar injection on a given departure day: a first guess and a SEARCH to a B-plane point.

The body of the departure-day sweep (the example ``iter_lunar_departure.toml``): for each day,
the first guess is the perigee of a transfer ellipse from the circular parking orbit
(radius r_p) to 1.1 times the Earth-Moon distance at arrival, in the plane of the Moon's
orbit, with perigee opposite the Moon's arrival position (a Hohmann-like half ellipse,
vis-viva speed v_p = sqrt(2 μ r_a / (r_p (r_p + r_a)))). SEARCH then moves the injection
velocity to a B-plane point of magnitude |B| along the first guess's own B direction (the
natural approach geometry of the day; a fixed (B·R, B·T) in Earth-equator axes would ask a
different out-of-plane correction every day) and to the first guess's flight time plus θ,
through the integrator with the Sun, Earth (J2) and Moon (:mod:`tapp.targeting.program`). The
injection ΔV is measured from the circular parking-orbit velocity at the injection point.
"""

from __future__ import annotations

import math

import numpy as np

from tapp.constants import SECONDS_PER_DAY, GM_EARTH_km3_s2, R_EARTH_km
from tapp.dynamics import Propagator, earth_model
from tapp.dynamics.ephemeris import position_km, utc_to_tdb_jd
from tapp.frames.time import Epoch, parse_epoch
from tapp.io.eop_file import orientation_for
from tapp.targeting.program import BPlaneProgram, BPlaneSearch, run_search

#: Time step of the Moon-velocity central difference, days (1 min).
_DT_DAYS = 60.0 / SECONDS_PER_DAY


def shifted_epoch(base: Epoch, days: float) -> Epoch:
    """Return ``base`` + ``days`` (UTC days) keeping the whole/fraction split."""
    whole, frac = divmod(base.jd_fraction + days, 1.0)
    return Epoch(base.jd_whole + whole, frac)


def first_guess(epoch: Epoch, parking_radius_km: float, flight_days: float = 4.0,
                apogee_factor: float = 1.1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return (r0 km, v0 km/s, ŝ) of the transfer-ellipse first guess (module docstring).

    ŝ is the unit vector of the parking-orbit velocity at the injection point.
    """
    jd = utc_to_tdb_jd(epoch.jd)
    days = flight_days + np.array([-_DT_DAYS, 0.0, _DT_DAYS])
    moon = position_km("moon", "earth", jd, days)
    r_moon, v_moon = moon[1], (moon[2] - moon[0]) / (2 * _DT_DAYS * SECONDS_PER_DAY)
    h_hat = np.cross(r_moon, v_moon)
    h_hat /= np.linalg.norm(h_hat)
    p_hat = -r_moon / np.linalg.norm(r_moon)
    s_hat = np.cross(h_hat, p_hat)
    r_p, r_a = parking_radius_km, apogee_factor * np.linalg.norm(r_moon)
    v_p = math.sqrt(2 * GM_EARTH_km3_s2 * r_a / (r_p * (r_p + r_a)))
    return r_p * p_hat, v_p * s_hat, s_hat


def lunar_departure_case(departure_day: float, base_epoch: str = "2026-03-10T12:00:00",
                         b_mag_km: float = 5600.0, arrive_later_s: float = 3600.0,
                         parking_altitude_km: float = 185.0, analytic_partials: bool = True,
                         earth_orientation: str = "iau2006") -> dict[str, float]:
    """Target the injection of ``departure_day`` days after ``base_epoch``; return its outputs.

    ``earth_orientation`` orients the Earth's J2 field (:mod:`tapp.frames.orientation`).

    Outputs: injection velocity (km/s, GCRS), ΔV from the parking orbit (km/s), flight
    time (s), achieved B·R, B·T (km), periapsis altitude (km), SEARCH's cases, and its status
    as a number (1 converged, 2 diverged, 3 singular: the seed's FLAG).
    """
    epoch = shifted_epoch(parse_epoch(base_epoch, source="base_epoch"), departure_day)
    r_park = R_EARTH_km + parking_altitude_km
    r0, v_guess, s_hat = first_guess(epoch, r_park)
    orientation = orientation_for(earth_orientation, epoch, source="earth_orientation")
    model = earth_model("J2", ("sun", "moon"), earth_orientation=orientation.model)
    program = BPlaneProgram(epoch, r0, Propagator(model), orientation=orientation)
    y0 = program(v_guess)
    b_target = y0[:2] * (b_mag_km / np.hypot(y0[0], y0[1]))
    problem = BPlaneSearch(program, v_guess, targets=np.array([*b_target, y0[2]]),
                           target_increments=np.array([0.0, 0.0, arrive_later_s]),
                           tolerances=np.array([1.0, 1.0, 1.0]),
                           increments=np.full(3, 1e-5), analytic_partials=analytic_partials)
    run = run_search(problem)
    v0 = run.result.x
    enc = run.encounter
    return {
        "flag": float(run.result.flag),
        "vx_km_s": float(v0[0]), "vy_km_s": float(v0[1]), "vz_km_s": float(v0[2]),
        "dv_km_s": float(np.linalg.norm(v0 - math.sqrt(GM_EARTH_km3_s2 / r_park) * s_hat)),
        "flight_time_s": float(enc.y[2]), "b_dot_r_km": float(enc.y[0]),
        "b_dot_t_km": float(enc.y[1]),
        "periapsis_altitude_km": float(enc.b_plane.periapsis_radius_km - 1737.4),
        "cases": float(run.result.n_cases),
    }

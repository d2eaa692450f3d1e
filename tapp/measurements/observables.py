"""Ground-station observables (range, range-rate, azimuth, elevation) and their partials.

Shapes are time-major: N observation times, spacecraft states (N, 6) = [r km, v km/s] in
EME2000 at the receive times, observables (N, m), partials (N, m, 6) w.r.t. the spacecraft
state, (N, m, 3) w.r.t. the station location, (N, m, 3) w.r.t. the biases. Kernels are pure
NumPy and noise-free.

Observables (biases are added: observed = model + bias)

- ``range``: km. Without light time the instantaneous distance |r - r_st|. With light time,
  the two-way (round trip) range c (tau_up + tau_down) / 2, or the one-way down-leg c tau_down.
- ``range_rate``: km/s, the time derivative of the range above (with light time, half the
  rate of change of the round-trip light time: instantaneous two-way Doppler; a count-averaged
  Doppler, a range difference over a count interval, is not modelled here).
- ``azimuth``: rad in [0, 2 pi), from north towards east, and ``elevation``: rad in
  [-pi/2, pi/2], in the station's topocentric East-North-Up frame (geodetic normal "up").
  With light time they are taken along the down-leg, from the station at reception to the
  spacecraft at transmission (no aberration, no refraction).
- ``doppler``: km/s, count-based two-/three-way Doppler as an equivalent range-rate: the
  change of the two-way range over a count interval centred on the sample time, divided by
  it (:mod:`tapp.measurements.doppler`: the equations, the sign, Hz). Needs a two-way light
  time model. Partials: the difference of the range partials at the ends of the interval,
  mapped to the centre by :func:`tapp.measurements.doppler.local_transition`.

Light time (:class:`LightTime`), following the iterative light-time solution of Moyer (2003),
Formulation for Observed and Computed Values of DSN Data Types, JPL DESCANSO Monograph 2,
ch. 8, with all times in one uniform time scale (no relativistic terms):

.. math::

    c\\,\\tau_d = |\\mathbf r(t - \\tau_d) - \\mathbf r_{st}(t)|,\\qquad
    c\\,\\tau_u = |\\mathbf r(t - \\tau_d) - \\mathbf r_{st}(t - \\tau_d - \\tau_u)|.

The spacecraft state at the bounce time t - tau_d comes from a callback (an interpolating
ephemeris) or, without one, from the third-order Taylor expansion about the receive-time
state with the two-body acceleration a = -mu r / r^3 and its rate j = da/dt:
r(t - tau) ~ r - tau v + tau^2 a / 2 - tau^3 j / 6, v(t - tau) ~ v - tau a + tau^2 j / 2
(truncation: tau^4 |d2a/dt2| / 24 < 1e-12 km and tau^3 |d2a/dt2| / 6 < 1e-12 km/s for
tau < 0.15 s, LEO to GEO). Perturbing accelerations a_p are not in the expansion: they move
the bounce state by tau^2 a_p / 2 and tau a_p (J2 in LEO: < 1e-8 km and < 1e-6 km/s); pass a
callback where that matters. Station positions at every time are exact (rotation).

Partials are analytic. Without light time they are exact. With light time they are those of
the first-order light-time model: the partials of each leg, taken at the solved geometry
(spacecraft at the bounce, station at reception and, for the up-leg, at transmission) and
weighted as in the observable, then chained through x(t - tau_d) ~ x(t) - tau_d [v, 0]
(d/dv picks up -tau_d d/dr). The range's keep the light times' dependence on the geometry
(:func:`light_time_range_leg_partials`: exact to first order). The range-rate's and the
angles' neglect it, the terms (dh/dt)(d tau/dx) with d tau/dx ~ rho_hat / c: a relative
O(v / c) ~ 3e-5 per block, at most |rho_ddot| / c (< 3e-7 1/s in LEO) per km in range-rate.
That only slows Gauss-Newton convergence and does not bias an estimate. Count-based Doppler
differences the range's partials (:mod:`tapp.measurements.doppler`).

Media (``MeasurementModel.media``, :mod:`tapp.measurements.media`; a three-way up-leg's from
``uplink_media``; Doppler differences its phase ranges'): the troposphere and the
ionosphere add to range and range-rate, each leg at its own elevation and carrier (the range's
legs weighted as in the range). Their partials w.r.t. the spacecraft state go through the
leg's ENU vector p and its rate (exact for the media model); w.r.t. the station location they
are minus those (the station moves; its ENU axes and the latitude and height of the mapping
functions stay: the tilt of the zenith with a survey error, Z m'(E) / R per km, up to 5e-5
km/km at 5 deg and 5e-7 at 45 deg against the geometric 1 km/km, is left out);
``media_partials`` gives those w.r.t. the zenith parameters.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from enum import StrEnum
from typing import TYPE_CHECKING

import numpy as np

from tapp.constants import C_LIGHT_km_s, GM_EARTH_km3_s2
from tapp.errors import DivergenceError, InputError
from tapp.frames.orientation import (
    EOP_PARAMETERS,
    EarthAttitude,
    EarthOrientation,
    as_orientation,
    check_eop_parameters,
    eop_generators,
)
from tapp.frames.rotation import cross_matrix
from tapp.measurements.doppler import DEFAULT_COUNT_TIME_s, local_transition
from tapp.measurements.media import LegMedia, MediaModel
from tapp.measurements.stations import (
    Station,
    StationParameters,
    location_jacobian,
    station_eop_partials,
    station_state_eci,
    station_state_partials,
)
from tapp.measurements.visibility import is_visible

if TYPE_CHECKING:
    from tapp.measurements.relativity import Relativity

#: Light-time iterations stop when the change is below this fraction of tau (the contraction
#: factor is v/c ~ 3e-5, so 3 to 4 iterations reach it).
LIGHT_TIME_REL_TOL = 4.0 * np.finfo(float).eps
LIGHT_TIME_MAX_ITERATIONS = 10


class Observable(StrEnum):
    """The observable kinds; plain strings ("range", ...) are accepted wherever these are."""

    RANGE = "range"
    RANGE_RATE = "range_rate"
    AZIMUTH = "azimuth"
    ELEVATION = "elevation"
    DOPPLER = "doppler"


#: Units of each observable, for tapes and reports.
OBSERVABLE_UNITS = {
    Observable.RANGE: "km",
    Observable.RANGE_RATE: "km/s",
    Observable.AZIMUTH: "rad",
    Observable.ELEVATION: "rad",
    Observable.DOPPLER: "km/s",
}
#: Names and units of the bias parameters, in the order of ``bias_partials``' last axis.
BIAS_NAMES = ("range_bias_km", "range_rate_bias_km_s", "doppler_bias_km_s")
#: The kinds those biases add to, in the same order.
BIASED_KINDS = (Observable.RANGE, Observable.RANGE_RATE, Observable.DOPPLER)


def wrap_angle_rad(angle_rad):
    """Return the angle wrapped to (-pi, pi], rad, same shape."""
    return np.pi - np.mod(np.pi - np.asarray(angle_rad, dtype=float), 2.0 * np.pi)


def residual(observed, computed, kinds: Sequence[str]):
    """Return observed - computed, shape (N, m), azimuth columns wrapped to (-pi, pi].

    The residual function to inject into estimators (filterpy's ``residual=`` hook): an azimuth
    of 359.9 deg against 0.1 deg is a -0.2 deg residual, not 359.8 deg.

    Parameters
    ----------
    observed, computed : array_like, shape (N, m)
        Observables in the units of ``OBSERVABLE_UNITS``, columns in ``kinds`` order.
    kinds : sequence of str
        The m observable kinds.
    """
    res = np.asarray(observed, dtype=float) - np.asarray(computed, dtype=float)
    azimuth = np.array([Observable(k) is Observable.AZIMUTH for k in kinds])
    if azimuth.any():
        res = res.copy()
        res[..., azimuth] = wrap_angle_rad(res[..., azimuth])
    return res


# ---------------------------------------------------------------------------------------------
# Geometric (instantaneous) observables and partials
# ---------------------------------------------------------------------------------------------


def range_km(state_eci, station_eci):
    """Return |r - r_st|, km, shape (N,).

    Parameters
    ----------
    state_eci, station_eci : array_like, shape (N, 6)
        Spacecraft and station inertial states [km, km/s] at the same times.
    """
    rel = np.asarray(state_eci, float)[..., :3] - np.asarray(station_eci, float)[..., :3]
    return np.linalg.norm(rel, axis=-1)


def range_rate_km_s(state_eci, station_eci):
    """Return the range-rate (r - r_st).(v - v_st) / |r - r_st|, km/s, shape (N,)."""
    rel = np.asarray(state_eci, float) - np.asarray(station_eci, float)
    return np.sum(rel[..., :3] * rel[..., 3:], -1) / np.linalg.norm(rel[..., :3], axis=-1)


def azimuth_elevation_rad(rho_enu_km):
    """Return (azimuth in [0, 2 pi), elevation in [-pi/2, pi/2]), rad, from an ENU vector.

    .. math:: A = \\operatorname{atan2}(E, N),\\qquad
              El = \\operatorname{atan2}(U, \\sqrt{E^2 + N^2})

    Parameters
    ----------
    rho_enu_km : array_like, shape (..., 3)
        Station-to-spacecraft vector in the station's East-North-Up frame, km.

    Notes
    -----
    Vallado, Fundamentals of Astrodynamics and Applications, Algorithm 27, in ENU instead of
    SEZ axes (E = E, N = -S, U = Z). At the zenith the azimuth is undefined and returned as 0.
    """
    rho = np.asarray(rho_enu_km, dtype=float)
    east, north, up = rho[..., 0], rho[..., 1], rho[..., 2]
    azimuth = np.mod(np.arctan2(east, north), 2.0 * np.pi)
    return azimuth, np.arctan2(up, np.hypot(east, north))


def range_partials(state_eci, station_eci):
    """Return d range / d spacecraft state, shape (N, 1, 6): [rho_hat^T, 0].

    The partial w.r.t. the station inertial state is its negative.
    """
    rel = np.asarray(state_eci, float)[..., :3] - np.asarray(station_eci, float)[..., :3]
    out = np.zeros(rel.shape[:-1] + (1, 6))
    out[..., 0, :3] = rel / np.linalg.norm(rel, axis=-1)[..., None]
    return out


def range_rate_partials(state_eci, station_eci):
    """Return d range-rate / d spacecraft state, shape (N, 1, 6).

    .. math::

        \\frac{\\partial\\dot\\rho}{\\partial\\mathbf r} =
        \\frac{(\\Delta\\mathbf v - \\dot\\rho\\,\\hat{\\boldsymbol\\rho})^T}{\\rho},\\qquad
        \\frac{\\partial\\dot\\rho}{\\partial\\mathbf v} = \\hat{\\boldsymbol\\rho}^T

    (Tapley, Schutz & Born, Statistical Orbit Determination, 2004, ch. 3 and 4). The partial
    w.r.t. the station inertial state is its negative.
    """
    rel = np.asarray(state_eci, float) - np.asarray(station_eci, float)
    rho = np.linalg.norm(rel[..., :3], axis=-1)[..., None]
    rho_hat = rel[..., :3] / rho
    rho_dot = np.sum(rho_hat * rel[..., 3:], -1)[..., None]
    out = np.zeros(rel.shape[:-1] + (1, 6))
    out[..., 0, :3] = (rel[..., 3:] - rho_dot * rho_hat) / rho
    out[..., 0, 3:] = rho_hat
    return out


def azimuth_elevation_partials(rho_enu_km, enu_from_eci):
    """Return d(azimuth, elevation) / d spacecraft state, rad per km, shape (N, 2, 6).

    .. math::

        \\frac{\\partial A}{\\partial(E,N,U)} = \\frac{(N, -E, 0)}{E^2 + N^2},\\qquad
        \\frac{\\partial El}{\\partial(E,N,U)} =
        \\frac{(-E U, -N U, E^2 + N^2)}{\\rho^2\\sqrt{E^2 + N^2}},

    chained with d(ENU)/d r = ``enu_from_eci``; the angles do not depend on velocity. The
    partial w.r.t. the station inertial position is the negative (axes held fixed).

    Parameters
    ----------
    rho_enu_km : array_like, shape (N, 3)
        Station-to-spacecraft vector in ENU, km.
    enu_from_eci : array_like, shape (N, 3, 3)
        Rotation inertial -> ENU at each time.

    Notes
    -----
    Not finite at the zenith (E = N = 0), where the azimuth is undefined.
    """
    rho = np.asarray(rho_enu_km, dtype=float)
    east, north, up = rho[..., 0], rho[..., 1], rho[..., 2]
    horiz2 = east * east + north * north
    horiz = np.sqrt(horiz2)
    range2 = horiz2 + up * up
    d_enu = np.zeros(rho.shape[:-1] + (2, 3))
    with np.errstate(divide="ignore", invalid="ignore"):
        d_enu[..., 0, 0] = north / horiz2
        d_enu[..., 0, 1] = -east / horiz2
        d_enu[..., 1, 0] = -east * up / (range2 * horiz)
        d_enu[..., 1, 1] = -north * up / (range2 * horiz)
        d_enu[..., 1, 2] = horiz / range2
    out = np.zeros(rho.shape[:-1] + (2, 6))
    out[..., :3] = d_enu @ np.asarray(enu_from_eci, dtype=float)
    return out


# ---------------------------------------------------------------------------------------------
# Light time
# ---------------------------------------------------------------------------------------------

StateCallback = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True, slots=True)
class LightTime:
    """Light-time model of the observables (module docstring for the equations).

    Attributes
    ----------
    two_way : bool
        True: round trip station -> spacecraft -> same station, range = c (tau_u + tau_d) / 2.
        False: down-leg only, range = c tau_d.
    state_at : callable or None
        ``state_at(t_s (N,)) -> (N, 6)`` spacecraft inertial states [km, km/s] at scenario
        times, e.g. an interpolating ephemeris; None: third-order two-body Taylor expansion
        about the receive-time state.
    mu_km3_s2 : float
        Gravitational parameter of the Taylor expansion, km^3/s^2.
    relativity : Relativity or None
        None: the Newtonian solution above (geocentric, one time scale). Otherwise the
        barycentric TDB solution with the Shapiro delays (:mod:`tapp.measurements.relativity`).
    """

    two_way: bool = True
    state_at: StateCallback | None = None
    mu_km3_s2: float = GM_EARTH_km3_s2
    relativity: Relativity | None = None

    def spacecraft_state(self, t_s, state_eci, tau_s):
        """Return the spacecraft state at t_s - tau_s, shape (N, 6)."""
        t = np.asarray(t_s, dtype=float)
        tau = np.asarray(tau_s, dtype=float)
        if self.state_at is not None:
            return np.asarray(self.state_at(t - tau), dtype=float)
        x = np.asarray(state_eci, dtype=float)
        r, v = x[..., :3], x[..., 3:]
        r_norm = np.linalg.norm(r, axis=-1)[..., None]
        # Two-body acceleration and jerk: a = -mu r / r^3, da/dt = -mu (v / r^3 - 3 (r.v) r / r^5).
        acc = -self.mu_km3_s2 * r / r_norm**3
        r_dot_v = np.sum(r * v, axis=-1)[..., None]
        jerk = -self.mu_km3_s2 * (v / r_norm**3 - 3.0 * r_dot_v * r / r_norm**5)
        dt = -tau[..., None]
        position = r + dt * (v + dt * (0.5 * acc + dt * jerk / 6.0))
        velocity = v + dt * (acc + 0.5 * dt * jerk)
        return np.concatenate([position, velocity], axis=-1)


@dataclass(frozen=True, slots=True)
class LightTimeSolution:
    """Solved light-time geometry at N receive times.

    Attributes
    ----------
    tau_down_s, tau_up_s : numpy.ndarray, shape (N,)
        Down-leg and up-leg light times, s (tau_up_s is zero for a one-way model).
    spacecraft_eci : numpy.ndarray, shape (N, 6)
        Spacecraft state at the bounce (transmit) time t - tau_down.
    station_receive_eci, station_transmit_eci : numpy.ndarray, shape (N, 6)
        Station state at reception t and at transmission t - tau_down - tau_up.
    """

    tau_down_s: np.ndarray
    tau_up_s: np.ndarray
    spacecraft_eci: np.ndarray
    station_receive_eci: np.ndarray
    station_transmit_eci: np.ndarray


def iterate_light_time(distance_km, tau0_s, what: str, floor_s=0.0):
    """Return the fixed point tau = distance_km(tau) / c, s, shape (N,), from tau0_s.

    The iteration contracts by v / c (~3e-5); it stops when every change is below
    :data:`LIGHT_TIME_REL_TOL` of tau or below ``floor_s`` (s, scalar or (N,)): the rounding
    of the distance itself, below which the iterates only wander (barycentric positions of
    1.5e8 km carry 3e-8 km each), and raises DivergenceError (naming ``what``) after
    :data:`LIGHT_TIME_MAX_ITERATIONS`.
    """
    tau = tau0_s
    for _ in range(LIGHT_TIME_MAX_ITERATIONS):
        new = distance_km(tau) / C_LIGHT_km_s
        done = np.abs(new - tau) <= np.maximum(LIGHT_TIME_REL_TOL * new, floor_s)
        tau = new
        if done.all():
            return tau
    raise DivergenceError(f"light time ({what}) not converged", LIGHT_TIME_MAX_ITERATIONS)


def solve_light_time(
    t_s,
    state_eci,
    r_station_ecef_km,
    orientation: EarthOrientation | float,
    light_time: LightTime,
    r_transmit_ecef_km=None,
) -> LightTimeSolution:
    """Return the light-time geometry for receive times t_s (N,) at a station.

    Parameters
    ----------
    t_s : array_like, shape (N,)
        Receive times, s from the scenario epoch.
    state_eci : array_like, shape (N, 6)
        Spacecraft inertial states at t_s, [km, km/s].
    r_station_ecef_km : array_like, shape (3,)
        Station Earth-fixed position, km.
    orientation : EarthOrientation or float
        The scenario's Earth orientation (a float: the gmst model's angle at the epoch, rad).
    light_time : LightTime
        The model (with ``relativity``: :meth:`tapp.measurements.relativity.Relativity.solve`).
    r_transmit_ecef_km : array_like, shape (3,), or None
        Earth-fixed position of the station transmitting the up-leg (three-way), km; None:
        the receiving station (two-way).

    Raises
    ------
    DivergenceError
        If the fixed-point iteration (contraction v/c) fails to converge in 10 iterations.
    """
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(state_eci, dtype=float)
    orientation = as_orientation(orientation)
    r_tx = r_station_ecef_km if r_transmit_ecef_km is None else r_transmit_ecef_km
    if light_time.relativity is not None:
        return light_time.relativity.solve(t, x, light_time, r_station_ecef_km, r_tx,
                                           orientation)
    station_rx = station_state_eci(r_station_ecef_km, orientation.attitude(t))

    def down_distance(tau):
        bounce = light_time.spacecraft_state(t, x, tau)
        return np.linalg.norm(bounce[..., :3] - station_rx[..., :3], axis=-1)

    tau_d = iterate_light_time(down_distance, range_km(x, station_rx) / C_LIGHT_km_s, "down")
    bounce = light_time.spacecraft_state(t, x, tau_d)
    if not light_time.two_way:
        return LightTimeSolution(tau_d, np.zeros_like(tau_d), bounce, station_rx, station_rx)

    def station_at(tau_u):
        return station_state_eci(r_tx, orientation.attitude(t - tau_d - tau_u))

    def up_distance(tau_u):
        return np.linalg.norm(bounce[..., :3] - station_at(tau_u)[..., :3], axis=-1)

    tau_u = iterate_light_time(up_distance, tau_d, "up")
    return LightTimeSolution(tau_d, tau_u, bounce, station_rx, station_at(tau_u))


def light_time_range_km(solution: LightTimeSolution, two_way: bool = True):
    """Return c (tau_u + tau_d) / 2 (two-way) or c tau_d (one-way), km, shape (N,)."""
    if two_way:
        return 0.5 * C_LIGHT_km_s * (solution.tau_up_s + solution.tau_down_s)
    return C_LIGHT_km_s * solution.tau_down_s


def light_time_range_rate_km_s(solution: LightTimeSolution, two_way: bool = True):
    """Return the time derivative of :func:`light_time_range_km`, km/s, shape (N,).

    .. math::

        \\dot\\tau_d = \\frac{\\hat{\\mathbf d}_d\\cdot(\\mathbf v_B - \\mathbf v_{st}(t))}
                          {c + \\hat{\\mathbf d}_d\\cdot\\mathbf v_B},\\qquad
        \\dot\\tau_u = (1 - \\dot\\tau_d)\\,
            \\frac{\\hat{\\mathbf d}_u\\cdot(\\mathbf v_B - \\mathbf v_{st}(t_T))}
                  {c - \\hat{\\mathbf d}_u\\cdot\\mathbf v_{st}(t_T)}

    from differentiating the two light-time equations in t (d_d, d_u the down- and up-leg
    vectors from station to spacecraft, v_B the spacecraft velocity at the bounce, t_T the
    transmit time). Exact for the light-time model: the 1/c terms (~ rho_dot v / c, up to
    1e-4 km/s in LEO) are kept.
    """
    sc = solution.spacecraft_eci
    d_down = sc[..., :3] - solution.station_receive_eci[..., :3]
    d_down_hat = d_down / np.linalg.norm(d_down, axis=-1)[..., None]
    v_b = sc[..., 3:]
    tau_d_dot = np.sum(d_down_hat * (v_b - solution.station_receive_eci[..., 3:]), -1) / (
        C_LIGHT_km_s + np.sum(d_down_hat * v_b, -1)
    )
    if not two_way:
        return C_LIGHT_km_s * tau_d_dot
    d_up = sc[..., :3] - solution.station_transmit_eci[..., :3]
    d_up_hat = d_up / np.linalg.norm(d_up, axis=-1)[..., None]
    v_st_t = solution.station_transmit_eci[..., 3:]
    tau_u_dot = (1.0 - tau_d_dot) * np.sum(d_up_hat * (v_b - v_st_t), -1) / (
        C_LIGHT_km_s - np.sum(d_up_hat * v_st_t, -1)
    )
    return 0.5 * C_LIGHT_km_s * (tau_u_dot + tau_d_dot)


def light_time_range_leg_partials(solution: LightTimeSolution, two_way: bool = True):
    """Return the range's partials w.r.t. the bounce position carried by each leg, (N, 3) each.

    The light times' own dependence on the geometry is kept (first order in the solved
    geometry; Shapiro's and TDB's gradients, < 2e-6 relative at 1.5 deg from the Sun, left
    out). With V_2 the spacecraft's velocity at the bounce and V_1 the transmitter's at
    transmission (in the solution's frame), g_d = rho_hat_d / (1 + rho_hat_d . V_2 / c),
    k = rho_hat_u . (V_2 - V_1) / c, D_u = 1 - rho_hat_u . V_1 / c:

    .. math::

        d\\rho_d = g_d\\cdot(d\\mathbf r_2 - d\\mathbf r_3),\\qquad
        d\\rho_u = \\frac{\\hat\\rho_u\\cdot(d\\mathbf r_2 - d\\mathbf r_1) - k\\,d\\rho_d}{D_u},

    from differentiating c tau_d = |r_2(t - tau_d) - r_3(t)| and
    c tau_u = |r_2 - r_1(t - tau_d - tau_u)|. Returns (leg 0: -d range / d r_3, leg 1:
    -d range / d r_1): their sum is d range / d r_2 (a translation moves nothing), each the
    negative of its station's partial. One-way: (g_d,).
    """
    sc = solution.spacecraft_eci
    d_down = sc[..., :3] - solution.station_receive_eci[..., :3]
    rho_d = d_down / np.linalg.norm(d_down, axis=-1)[..., None]
    v2 = sc[..., 3:]
    g_d = rho_d / (1.0 + np.sum(rho_d * v2, -1) / C_LIGHT_km_s)[..., None]
    if not two_way:
        return (g_d,)
    d_up = sc[..., :3] - solution.station_transmit_eci[..., :3]
    rho_u = d_up / np.linalg.norm(d_up, axis=-1)[..., None]
    v1 = solution.station_transmit_eci[..., 3:]
    d_u = (1.0 - np.sum(rho_u * v1, -1) / C_LIGHT_km_s)[..., None]
    k = np.sum(rho_u * (v2 - v1), -1)[..., None] / C_LIGHT_km_s
    return (0.5 * (1.0 - k / d_u) * g_d, 0.5 * rho_u / d_u)


# ---------------------------------------------------------------------------------------------
# The measurement model: one station, a list of observable kinds
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Geometry:
    """Spacecraft at the bounce, tau_down, and the legs (weight, station state, attitude)."""

    spacecraft: np.ndarray
    tau_down_s: np.ndarray
    attitude_rx: EarthAttitude
    solution: LightTimeSolution | None
    legs: tuple[tuple[float, np.ndarray, EarthAttitude], ...]
    t_s: np.ndarray | None = None

    def enu(self, station: Station):
        """Down-leg station-to-spacecraft vector in the station's ENU axes at reception, km."""
        relative = self.spacecraft[..., :3] - self.legs[0][1][..., :3]
        return np.einsum("...ij,...j->...i", station.enu_from_eci(self.attitude_rx), relative)


@dataclass(frozen=True, slots=True)
class MeasurementModel:
    """Observables of kinds ``kinds`` of a spacecraft from one station, with their partials.

    The interface TAPP I and the orbit-determination code share: ``compute`` gives h(x) (N, m),
    ``state_partials`` H = dh/dx (N, m, 6), ``station_partials`` dh/d(location) (N, m, 3),
    ``bias_partials`` dh/d(range, range-rate, Doppler bias) (N, m, 3), ``residual`` the
    angle-wrapping observed - computed, and ``visible`` the mask test (N,). Columns follow
    ``kinds``; pass the visible samples, grouped by :func:`find_passes`, to the estimator.

    Attributes
    ----------
    station : Station
        The tracking station.
    orientation : EarthOrientation
        The scenario's Earth orientation (:mod:`tapp.frames.orientation`); a float given here is
        taken as the gmst model's angle at the epoch, rad (``Epoch.gmst_rad()``).
    kinds : tuple of str
        Observable kinds, a subset of ("range", "range_rate", "azimuth", "elevation").
    light_time : LightTime or None
        None: instantaneous geometry (observation and signal at the receive time).
    range_bias_km, range_rate_bias_km_s : float
        Constant biases added to range and range-rate.
    media : MediaModel or None
        The troposphere and ionosphere of the station's links (:mod:`tapp.measurements.media`),
        added to range and range-rate; None: none. Each leg takes its own elevation and
        carrier: with two-way light time, the down-leg (f_R) at reception and the up-leg (f_T)
        at transmission, half each; one-way, the down-leg; without light time, one leg at the
        mean of the two carriers' 1 / f². Angles are left without refraction.
    uplink : Station or None
        Three-way tracking: the station that transmits the up-leg (``station`` receives);
        needs a two-way light-time model. None: ``station`` transmits too.
    uplink_media : MediaModel or None
        Three-way tracking with media: the troposphere and ionosphere of the uplink station,
        which the up-leg crosses (its weather, latitude and band); required with ``media``
        and an ``uplink``, refused otherwise.
    count_time_s : float
        Count interval T_c of the ``doppler`` kind, s.
    doppler_bias_km_s : float
        Constant bias added to the count-based Doppler.

    Examples
    --------
    >>> import numpy as np
    >>> model = MeasurementModel(Station("EQ", 0.0, 0.0, 0.0), 0.0, ("range", "elevation"))
    >>> overhead = np.array([[7000.0, 0.0, 0.0, 0.0, 7.5, 0.0]])
    >>> np.round(model.compute(np.array([0.0]), overhead), 6)
    array([[621.863   ,   1.570796]])
    """

    station: Station
    orientation: EarthOrientation
    kinds: tuple[str, ...] = ("range", "range_rate")
    light_time: LightTime | None = None
    range_bias_km: float = 0.0
    range_rate_bias_km_s: float = 0.0
    media: MediaModel | None = None
    uplink: Station | None = None
    uplink_media: MediaModel | None = None
    count_time_s: float = DEFAULT_COUNT_TIME_s
    doppler_bias_km_s: float = 0.0

    def __post_init__(self) -> None:
        try:
            kinds = tuple(Observable(k) for k in self.kinds)
        except ValueError as err:
            raise InputError(
                "MeasurementModel", "kinds", f"a subset of {[o.value for o in Observable]}",
                self.kinds,
            ) from err
        object.__setattr__(self, "kinds", kinds)
        object.__setattr__(self, "orientation", as_orientation(self.orientation))
        if self.uplink is not None and (self.light_time is None or not self.light_time.two_way):
            raise InputError("MeasurementModel", "uplink",
                             "a two-way light-time model with an uplink station (three-way)",
                             self.light_time)
        if Observable.DOPPLER in kinds:
            if self.light_time is None or not self.light_time.two_way:
                raise InputError("MeasurementModel", "kinds",
                                 "a two-way light-time model with doppler (count-based "
                                 "two-/three-way Doppler)", self.light_time)
            if not self.count_time_s > 0.0:
                raise InputError("MeasurementModel", "count_time_s", "a count time > 0 s",
                                 self.count_time_s)
        # The up-leg crosses the uplink station's atmosphere, not the receiver's.
        if (self.uplink_media is not None) != (self.media is not None
                                               and self.uplink is not None):
            raise InputError("MeasurementModel", "uplink_media",
                             "the uplink station's MediaModel exactly when there are media "
                             "and a three-way uplink", self.uplink_media)

    def station_eci(self, t_s):
        """Return the station inertial state at t_s (N,), shape (N, 6)."""
        return station_state_eci(self.station.r_ecef_km, self.orientation.attitude(t_s))

    def _geometry(self, t_s, state_eci) -> _Geometry:
        t = np.asarray(t_s, dtype=float)
        x = np.asarray(state_eci, dtype=float)
        attitude_rx = self.orientation.attitude(t)
        if self.light_time is None:
            station = station_state_eci(self.station.r_ecef_km, attitude_rx)
            return _Geometry(x, np.zeros(t.shape), attitude_rx, None,
                             ((1.0, station, attitude_rx),), t)
        sol = solve_light_time(t, x, self.station.r_ecef_km, self.orientation, self.light_time,
                               None if self.uplink is None else self.uplink.r_ecef_km)
        legs = ((1.0, sol.station_receive_eci, attitude_rx),)
        if self.light_time.two_way:
            attitude_tx = self.orientation.attitude(t - sol.tau_down_s - sol.tau_up_s)
            legs = ((0.5, sol.station_receive_eci, attitude_rx),
                    (0.5, sol.station_transmit_eci, attitude_tx))
        return _Geometry(sol.spacecraft_eci, sol.tau_down_s, attitude_rx, sol, legs, t)

    def _observables(self, t_s, state_eci, kinds):
        """Return {kind: values (N,)} without biases, solving the light time once."""
        geo = self._geometry(t_s, state_eci)
        out = {}
        if geo.solution is None:
            station = geo.legs[0][1]
            if Observable.RANGE in kinds:
                out[Observable.RANGE] = range_km(geo.spacecraft, station)
            if Observable.RANGE_RATE in kinds:
                out[Observable.RANGE_RATE] = range_rate_km_s(geo.spacecraft, station)
        else:
            two_way = self.light_time.two_way
            if Observable.RANGE in kinds:
                out[Observable.RANGE] = light_time_range_km(geo.solution, two_way)
            if Observable.RANGE_RATE in kinds:
                out[Observable.RANGE_RATE] = (light_time_range_rate_km_s(geo.solution, two_way)
                                              + self._clock_rate_km_s(t_s, geo.solution))
        if Observable.AZIMUTH in kinds or Observable.ELEVATION in kinds:
            out[Observable.AZIMUTH], out[Observable.ELEVATION] = azimuth_elevation_rad(
                geo.enu(self.station)
            )
        if Observable.DOPPLER in kinds:
            (t_s_, x_s), (t_e, x_e) = self._count_ends(t_s, state_eci)
            ranges = self._ranging()
            out[Observable.DOPPLER] = (ranges.compute(t_e, x_e)[..., 0]
                                       - ranges.compute(t_s_, x_s)[..., 0]) / self.count_time_s
        if self.media is not None:
            for kind, value in self._media_terms(geo, kinds).items():
                out[kind] = out[kind] + value
        return out

    def _media_terms(self, geo: _Geometry, kinds) -> dict[Observable, np.ndarray]:
        """Return {kind: the media's share (N,)} of the range and range-rate among ``kinds``."""
        out = {k: np.zeros(geo.tau_down_s.shape) for k in kinds
               if k in (Observable.RANGE, Observable.RANGE_RATE)}
        if out:
            for weight, leg, _ in self._media_legs(geo):
                if Observable.RANGE in out:
                    out[Observable.RANGE] += weight * leg.range_km
                if Observable.RANGE_RATE in out:
                    out[Observable.RANGE_RATE] += weight * leg.rate_km_s
        return out

    def media_corrections(self, t_s, state_eci):
        """Return the media's share of the observables, shape (N, m), units of
        OBSERVABLE_UNITS (zero in the angle columns; all zero without media)."""
        if self.media is None:
            return np.zeros(np.shape(t_s) + (len(self.kinds),))
        terms = self._media_terms(self._geometry(t_s, state_eci), self.kinds)
        if Observable.DOPPLER in self.kinds:
            terms[Observable.DOPPLER] = self._count_difference(
                t_s, state_eci, lambda m, t, x: m.media_corrections(t, x)[..., None])[..., 0]
        zero = np.zeros(np.shape(t_s))
        return np.stack([terms.get(k, zero) for k in self.kinds], axis=-1)

    def _media_legs(self, geo: _Geometry) -> list[tuple[float, LegMedia, np.ndarray]]:
        """Per leg: (weight, its media terms, the partials of (p, ṗ) w.r.t. the spacecraft
        state (N, 6, 6)), p the station-to-spacecraft vector in the station's ENU axes at the
        leg's time and ṗ = M_enu [Δv - ω ĉ × Δr] its rate seen from the rotating Earth
        (:mod:`tapp.measurements.media`); a three-way up-leg in the uplink station's axes,
        with its media."""
        if geo.solution is None:
            links = ("two_way",)
        else:
            links = ("down", "up") if self.light_time.two_way else ("down",)
        out = []
        for number, ((weight, station, attitude), link) in enumerate(
                zip(geo.legs, links, strict=True)):
            site, media = ((self.uplink, self.uplink_media) if number == 1 and self.uplink
                           else (self.station, self.media))
            rot = site.enu_from_eci(attitude)
            rel = geo.spacecraft - station
            spin = attitude.omega_rad_s * attitude.spin_axis
            w = rel[..., 3:] - np.cross(spin, rel[..., :3])
            p = np.einsum("...ij,...j->...i", rot, rel[..., :3])
            p_dot = np.einsum("...ij,...j->...i", rot, w)
            # d(p, ṗ)/d(r, v): [[M, 0], [-M [ω ĉ ×], M]]
            jac = np.zeros(rot.shape[:-2] + (6, 6))
            jac[..., :3, :3] = rot
            jac[..., 3:, 3:] = rot
            jac[..., 3:, :3] = -rot @ cross_matrix(spin)
            out.append((weight, media.leg(geo.t_s, p, p_dot, link), jac))
        return out

    def _media_rows(self, leg: LegMedia, jac: np.ndarray) -> np.ndarray:
        """Return a leg's d(media terms)/d(spacecraft state), (N, m, 6), zero but in the
        range and range-rate rows."""
        rows = np.zeros(jac.shape[:-2] + (len(self.kinds), 6))
        for row, kind in enumerate(self.kinds):
            if kind is Observable.RANGE:
                rows[..., row, :] = np.einsum("...i,...ij->...j", leg.range_p, jac[..., :3, :])
            elif kind is Observable.RANGE_RATE:
                grad = np.concatenate([leg.rate_p, leg.rate_pdot], axis=-1)
                rows[..., row, :] = np.einsum("...i,...ij->...j", grad, jac)
        return rows

    def media_partials(self, t_s, state_eci):
        """Return d observables / d the station's zenith parameters (dry km, wet km, TEC
        TECU), shape (N, m, 3), columns named by
        :data:`tapp.measurements.media.MEDIA_PARAMETER_NAMES`: the legs through its own
        atmosphere (three-way: the down-leg; :meth:`uplink_media_partials` the up-leg's).
        Doppler's row differences its phase ranges' (ionosphere negative) over the count.

        Raises
        ------
        InputError
            The model has no media.
        """
        return self._zenith_partials(t_s, state_eci, uplink=False)

    def uplink_media_partials(self, t_s, state_eci):
        """Return d observables / d the uplink station's zenith parameters (three-way),
        shape (N, m, 3): the up-leg's part of :meth:`media_partials`' sum.

        Raises
        ------
        InputError
            The model has no uplink station with media.
        """
        if self.uplink_media is None:
            raise InputError("MeasurementModel", "uplink_media",
                             "a three-way uplink with media for the uplink's media partials")
        return self._zenith_partials(t_s, state_eci, uplink=True)

    def _zenith_partials(self, t_s, state_eci, uplink: bool):
        if self.media is None:
            raise InputError("MeasurementModel", "media", "a MediaModel for media partials")
        geo = self._geometry(t_s, state_eci)
        out = np.zeros(geo.tau_down_s.shape + (len(self.kinds), 3))
        for number, (weight, leg, _) in enumerate(self._media_legs(geo)):
            if (self.uplink is not None and number == 1) != uplink:
                continue
            for row, kind in enumerate(self.kinds):
                if kind is Observable.RANGE:
                    out[..., row, :] += weight * leg.range_zenith
                elif kind is Observable.RANGE_RATE:
                    out[..., row, :] += weight * leg.rate_zenith
        self._put_doppler(out, t_s, state_eci,
                          lambda m, t, x: m._zenith_partials(t, x, uplink))
        return out

    def _clock_rate_km_s(self, t_s, solution: LightTimeSolution):
        """Return the range-rate from the clocks' TDB - TT rates (relativistic light time;
        0 otherwise), km/s, (N,): the light times are solved in TDB and read on TT clocks,
        so d(t_3 - t_1)/dt_3 = (dET_1/dET_3 geometric) + dΔ_tx(t_1)/dt - dΔ_rx(t_3)/dt to
        first order (one-way: the spacecraft's geocentric Δ at t_2 for the transmitter's):
        up to (c / 2) |v_E| ω R_E / c² = 2e-5 km/s between two stations (three-way)."""
        relativity = None if self.light_time is None else self.light_time.relativity
        if relativity is None:
            return 0.0
        t = np.asarray(t_s, dtype=float)
        receive = relativity.tdb_rate(t, self.station.r_ecef_km)
        if not self.light_time.two_way:
            return C_LIGHT_km_s * (relativity.tdb_rate(t - solution.tau_down_s) - receive)
        transmitter = self.station if self.uplink is None else self.uplink
        t1 = t - solution.tau_down_s - solution.tau_up_s
        return 0.5 * C_LIGHT_km_s * (relativity.tdb_rate(t1, transmitter.r_ecef_km) - receive)

    def _ranging(self) -> MeasurementModel:
        """This model measuring the two-/three-way range of the carrier's phase only (no
        bias; the ionosphere a phase advance): Doppler's ends."""
        def phase(media: MediaModel | None) -> MediaModel | None:
            return None if media is None else replace(media, phase=True)

        return replace(self, kinds=(Observable.RANGE,), range_bias_km=0.0,
                       media=phase(self.media), uplink_media=phase(self.uplink_media))

    def _count_ends(self, t_s, state_eci):
        """Return ((t_s, states), (t_e, states)) at the ends t -/+ T_c / 2 of the count
        intervals: the states from the light-time model's trajectory (its ``state_at``, or
        its Taylor expansion about the state at t)."""
        t = np.asarray(t_s, dtype=float)
        x = np.asarray(state_eci, dtype=float)
        half = 0.5 * self.count_time_s
        return tuple((t + sign * half, self.light_time.spacecraft_state(t, x, -sign * half))
                     for sign in (-1.0, 1.0))

    def _count_difference(self, t_s, state_eci, of: Callable, state: bool = False):
        """Doppler's share of ``of(ranging model, t, x)`` (N, 1, k) (values or partials of
        the phase range, :meth:`_ranging`), (N, k): (at t_e - at t_s) / T_c; ``state``: the
        state partials, mapped to the centre by the local transition
        (:mod:`tapp.measurements.doppler`)."""
        ranges = self._ranging()
        x = np.asarray(state_eci, dtype=float)
        out = 0.0
        for sign, (t_end, x_end) in zip((-1.0, 1.0), self._count_ends(t_s, x), strict=True):
            rows = of(ranges, t_end, x_end)[..., 0, :]
            if state:
                rows = np.einsum("...i,...ij->...j", rows, local_transition(
                    x, sign * 0.5 * self.count_time_s, self.light_time.mu_km3_s2))
            out = out + sign * rows
        return out / self.count_time_s

    def azimuth_elevation(self, t_s, state_eci):
        """Return (azimuth, elevation), rad, each (N,), along the down-leg if light time is on."""
        obs = self._observables(t_s, state_eci, (Observable.AZIMUTH,))
        return obs[Observable.AZIMUTH], obs[Observable.ELEVATION]

    def compute(self, t_s, state_eci):
        """Return the observables (biases included), shape (N, m), units of OBSERVABLE_UNITS.

        Parameters
        ----------
        t_s : array_like, shape (N,)
            Receive times, s from the scenario epoch.
        state_eci : array_like, shape (N, 6)
            Spacecraft inertial states at t_s, [km, km/s].
        """
        obs = self._observables(t_s, state_eci, self.kinds)
        bias = dict(zip(BIASED_KINDS, (self.range_bias_km, self.range_rate_bias_km_s,
                                       self.doppler_bias_km_s), strict=True))
        return np.stack([obs[k] + bias.get(k, 0.0) for k in self.kinds], axis=-1)

    def _leg_partials(self, geo: _Geometry):
        """Return per leg (attitude, weighted dh/d bounce state (N, m, 6)).

        Range and range-rate rows carry the leg's weight; the angle rows are whole on the
        down-leg (leg 0) and zero on the up-leg.
        """
        angles = None
        if Observable.AZIMUTH in self.kinds or Observable.ELEVATION in self.kinds:
            rot = self.station.enu_from_eci(geo.attitude_rx)
            angles = azimuth_elevation_partials(geo.enu(self.station), rot)
        ranges = (None if geo.solution is None
                  else light_time_range_leg_partials(geo.solution, self.light_time.two_way))
        out = []
        for number, (weight, station, attitude) in enumerate(geo.legs):
            rows = np.zeros(geo.tau_down_s.shape + (len(self.kinds), 6))
            for row, kind in enumerate(self.kinds):
                if kind is Observable.RANGE and ranges is not None:
                    rows[..., row, :3] = ranges[number]
                elif kind is Observable.RANGE:
                    rows[..., row, :] = weight * range_partials(geo.spacecraft, station)[..., 0, :]
                elif kind is Observable.RANGE_RATE:
                    rows[..., row, :] = (
                        weight * range_rate_partials(geo.spacecraft, station)[..., 0, :]
                    )
                elif number == 0 and kind is not Observable.DOPPLER:
                    rows[..., row, :] = angles[..., 0 if kind is Observable.AZIMUTH else 1, :]
            out.append((attitude, rows))
        if self.media is not None:
            for (_, rows), (weight, leg, jac) in zip(out, self._media_legs(geo), strict=True):
                rows += weight * self._media_rows(leg, jac)
        return out

    def state_partials(self, t_s, state_eci):
        """Return H = d observables / d spacecraft state [r, v] at t_s, shape (N, m, 6).

        Exact without light time; first-order light-time model otherwise (module docstring).
        """
        geo = self._geometry(t_s, state_eci)
        h_bounce = sum(rows for _, rows in self._leg_partials(geo))
        # x(t - tau) ~ x(t) - tau [v, 0]: d/dv = d/dv_B - tau d/dr_B.
        h = h_bounce.copy()
        h[..., 3:] -= geo.tau_down_s[..., None, None] * h_bounce[..., :3]
        self._put_doppler(h, t_s, state_eci, MeasurementModel.state_partials, state=True)
        return h

    def _put_doppler(self, out, t_s, state_eci, of: Callable, state: bool = False) -> None:
        """Fill the doppler row of ``out`` (N, m, n) in place with the count difference of
        the phase range's partials ``of(model, t, x)`` (:meth:`_count_difference`)."""
        if Observable.DOPPLER in self.kinds:
            row = self.kinds.index(Observable.DOPPLER)
            out[..., row, :] = self._count_difference(t_s, state_eci, of, state)

    def station_partials(self, t_s, state_eci, parameters: StationParameters = "cylindrical"):
        """Return d observables / d station location, shape (N, m, 3).

        Columns named by ``STATION_PARAMETER_NAMES[parameters]``: (r_s km, lon rad, z km) or
        Earth-fixed (x, y, z) km. Chain rule per leg: dh/dp = (dh/d station state at the leg's
        time) (d station state / dp at that time's attitude), with dh/d station state =
        -dh/d spacecraft state for every kind (angles: axes held fixed). Three-way (an
        ``uplink`` station): the down-leg part only (:meth:`uplink_station_partials`).
        """
        legs = self._leg_partials(self._geometry(t_s, state_eci))
        if self.uplink is not None:
            legs = legs[:1]
        r_ecef = self.station.r_ecef_km
        out = -sum(
            rows @ station_state_partials(r_ecef, attitude, parameters)
            for attitude, rows in legs
        )
        self._put_clock(out, t_s, state_eci, "receiver", parameters)
        if self.uplink is None:
            self._put_clock(out, t_s, state_eci, "transmitter", parameters)
        self._put_doppler(out, t_s, state_eci,
                          lambda m, t, x: m.station_partials(t, x, parameters))
        return out

    def _put_clock(self, out, t_s, state_eci, end: str, parameters: StationParameters) -> None:
        """Add to the range rows of ``out`` (N, m, 3) the part through the station's own
        TDB - TT (relativistic light time only): the receiver's clock term moves every event
        by d(TDB)/dp and the range by -c w d(TDB)/dp (w = 1/2 two-/three-way, 1 one-way); the
        transmitter's moves t_1 and the range by +c/2 d(TDB)/dp
        (:meth:`tapp.measurements.relativity.Relativity.tdb_site_gradient_s_km`)."""
        if (self.light_time is None or self.light_time.relativity is None
                or Observable.RANGE not in self.kinds):
            return
        t = np.asarray(t_s, dtype=float)
        two_way = self.light_time.two_way
        if end == "receiver":
            station, when, factor = self.station, t, -(0.5 if two_way else 1.0)
        else:
            sol = self._geometry(t, state_eci).solution
            station = self.station if self.uplink is None else self.uplink
            when, factor = t - sol.tau_down_s - sol.tau_up_s, 0.5
        gradient = self.light_time.relativity.tdb_site_gradient_s_km(when, station.r_ecef_km)
        row = self.kinds.index(Observable.RANGE)
        out[..., row, :] += factor * C_LIGHT_km_s * gradient @ location_jacobian(
            station.r_ecef_km, parameters)

    def uplink_station_partials(self, t_s, state_eci,
                                parameters: StationParameters = "cylindrical"):
        """Return d observables / d uplink station location (three-way), shape (N, m, 3).

        The up-leg part of :meth:`station_partials`' chain rule, at the transmit attitude.
        """
        attitude, rows = self._leg_partials(self._geometry(t_s, state_eci))[1]
        out = -rows @ station_state_partials(self.uplink.r_ecef_km, attitude, parameters)
        self._put_clock(out, t_s, state_eci, "transmitter", parameters)
        self._put_doppler(out, t_s, state_eci,
                          lambda m, t, x: m.uplink_station_partials(t, x, parameters))
        return out

    def uplink_elevation_rad(self, t_s, state_eci):
        """Return the elevation (N,), rad, of the spacecraft at the bounce seen from the
        transmitting station (``uplink``, or ``station``) at transmission, along the up-leg."""
        geo = self._geometry(t_s, state_eci)
        _, station, attitude = geo.legs[-1]
        transmitter = self.station if self.uplink is None else self.uplink
        relative = geo.spacecraft[..., :3] - station[..., :3]
        enu = np.einsum("...ij,...j->...i", transmitter.enu_from_eci(attitude), relative)
        return azimuth_elevation_rad(enu)[1]

    def bias_partials(self, t_s):
        """Return d observables / d (the biases of :data:`BIAS_NAMES`), shape (N, m, 3)."""
        t = np.asarray(t_s, dtype=float)
        out = np.zeros(t.shape + (len(self.kinds), len(BIAS_NAMES)))
        for row, kind in enumerate(self.kinds):
            if kind in BIASED_KINDS:
                out[..., row, BIASED_KINDS.index(kind)] = 1.0
        return out

    def residual(self, observed, computed):
        """Return observed - computed, shape (N, m), azimuth wrapped to (-pi, pi]."""
        return residual(observed, computed, self.kinds)

    def elevation_rad(self, t_s, state_eci):
        """Return the elevation, rad, shape (N,)."""
        return self.azimuth_elevation(t_s, state_eci)[1]

    def visible(self, t_s, state_eci):
        """Return True where the elevation is strictly above the station's mask, (N,) bool."""
        return is_visible(self.elevation_rad(t_s, state_eci), self.station.elev_mask_rad)

    def eop_partials(self, t_s, state_eci, names=EOP_PARAMETERS):
        """Return d observables / d constant EOP offsets, shape (N, m, k).

        Columns ``names`` among ("ut1_s", "xp_rad", "yp_rad") (:data:`EOP_PARAMETERS`; only
        "ut1_s" under gmst): per s of UT1 − UTC and per rad of pole coordinate.

        Range and range-rate: the chain rule per leg as :meth:`station_partials`, with the
        station's state partials of :func:`station_eop_partials` at the leg's attitude.
        Angles: the ENU vector E M (r − r_st) changes only through M (the ENU axes turn with
        the Earth), d(ENU)/dp = −E M (g_p × r) (:func:`eop_generators`), i.e. the angle
        rows of :meth:`state_partials` at the bounce times (−g_p × r). Exact without light
        time; with light time the neglected dτ/dp is relative O(v/c), as for the station
        partials. With media, their rows follow the range's (station moved, ENU axes held):
        the turn of the elevation with the Earth, δE ~ 7e-8 rad per ms of UT1, changes a
        10-degree troposphere by ~5 μm, 2e-5 of the geometric 0.3 m, and is left out.

        Raises
        ------
        InputError
            A name that is not an EOP parameter of the orientation model.
        """
        names = check_eop_parameters(self.orientation.model, names, "MeasurementModel", "eop")
        geo = self._geometry(t_s, state_eci)
        r_ecef = self.station.r_ecef_km
        angle = np.array([k in (Observable.AZIMUTH, Observable.ELEVATION) for k in self.kinds])
        out = 0.0
        for number, (attitude, rows) in enumerate(self._leg_partials(geo)):
            out = out - np.where(angle[:, None], 0.0,
                                 rows @ station_eop_partials(r_ecef, attitude, names))
            if number == 0 and angle.any():
                moved = -np.cross(eop_generators(attitude, names), geo.spacecraft[..., None, :3])
                out = out + np.where(angle[:, None], rows[..., :3] @ np.swapaxes(moved, -1, -2),
                                     0.0)
        self._put_doppler(out, t_s, state_eci, lambda m, t, x: m.eop_partials(t, x, names))
        return out

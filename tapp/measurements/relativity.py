"""Relativistic light time in the solar-system barycentric frame, TDB (Moyer 2003, ch. 8).

Moyer, Formulation for Observed and Computed Values of Deep Space Network Data Types for
Navigation, JPL DESCANSO Monograph 2 (2003). The down-leg (receive time t_3 at the receiving
station, bounce t_2 at the spacecraft) and the up-leg (transmit time t_1 at the transmitting
station, the same one for two-way, another for three-way) are solved in barycentric
coordinate time TDB (ET in Moyer's notation), §8.3:

.. math::

    ET_3 - ET_2 = \\frac{r_{23}}{c} + RLT_{23},\\qquad
    ET_2 - ET_1 = \\frac{r_{12}}{c} + RLT_{12},

with r_ij the barycentric distance between the end points, each at its own time, and the
Shapiro delay of each body B of ``bodies`` (Moyer eq. 8-38; γ = 1, the Sun's term with the
(1 + γ) μ_S / c² correction inside the logarithm, the other bodies without it):

.. math::

    RLT_{ij} = \\sum_B \\frac{(1+\\gamma)\\,\\mu_B}{c^3}
    \\ln\\frac{r_i^B + r_j^B + r_{ij}^B + \\epsilon_B}{r_i^B + r_j^B - r_{ij}^B + \\epsilon_B},
    \\qquad \\epsilon_S = \\frac{(1+\\gamma)\\mu_S}{c^2},\\ \\epsilon_{B\\neq S} = 0,

r_i^B = |r_i(t_i) - r_B(t_i)| (the body at each end's own time) and r_ij^B = |(r_j - r_B)(t_j)
- (r_i - r_B)(t_i)|.

Positions. The barycentric position of a station is the Earth's barycentric position (DE421,
:func:`tapp.dynamics.ephemeris.barycentric_state`) at the station's TDB plus its geocentric
position (IAU 2006 / gmst rotation of its Earth-fixed position); the spacecraft's is the
Earth's plus the integrated geocentric position at its TDB. Approximation: the geocentric
vectors are added as they are, without the GCRS -> BCRS transformation's Lorentz term
-(v_E . r) v_E / (2 c²) (< 5e-9 r) and scale term L_C r (L_C = 1.48e-8): together < 2e-8 of
the geocentric distance, 0.1 mm for a station, 8 m at the Moon's distance, 4 km at 1.5 AU.
That is the usual approximation of an Earth-centred integration, whose Newtonian geocentric
positions are taken as differences of barycentric positions: the solution is consistent with
the dynamics, not with a GCRS reading of the coordinates. (The Sun's Shapiro term over a
geocentric distance r, ~ 2 μ_S r / (c² AU) = 2e-8 r, is of the same order: it is what L_C
absorbs in a GCRS formulation, so near the Earth the two formulations differ by metres.)

Times. Scenario time t is elapsed TT (TAI) seconds; a station's clock reads it. TDB at a
station is TT + (TDB - TT)(TT, station) from ERFA's ``dtdb`` (Fairhead & Bretagnon 1990) with
the station's longitude, distance from the spin axis and from the equator (the topocentric
terms, up to 2.1 us, instead of Moyer's eq. 2-23 approximation); at the spacecraft the
geocentric value (its own location terms, v_E . r / c², are the Lorentz term above). The
solved light times are differences of scenario (station clock) times, so the round-trip
light time is the observable ρ = t_3 - t_1 of Moyer ch. 11, and the range c ρ / 2.

Sizes (measured in tests/tapp/measurements/test_relativity.py, two-way range from
Goldstone): the Earth's Shapiro term 37 mm at 380,000 km and 0.1 m at 1.5 AU; the Sun's 7.5 m
at 380,000 km (see the approximation above), 4.2 km at 1.5 AU and 27 km (90 us one way) with
the spacecraft beyond the Sun 1.5 deg from it; relativistic minus Newtonian range 10.7 m,
5.6 km and 24 km there. TDB - TT's rate, up to 3.3e-10, changes a 1000 s light time by
0.3 us (100 m).

The instantaneous range-rate (:func:`tapp.measurements.observables.light_time_range_rate_km_s`
at this solution, plus the clocks' TDB - TT rates: up to 2e-5 km/s between two stations in
three-way) leaves out the rates of the Shapiro delays: it differs from the derivative of the
round-trip light time by < 0.03 mm/s at 380,000 km (the reference's resolution), 0.5 mm/s at
1.5 AU and 42 mm/s 1.5 deg from the Sun. The count-based ``doppler``, a difference of two
solutions, has them all.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from tapp.constants import SECONDS_PER_DAY, C_LIGHT_km_s, GM_km3_s2
from tapp.dynamics.ephemeris import barycentric_state, tai_minus_utc_s
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tapp.frames.timescales import (
    TT_MINUS_TAI_s,
    geocentric_tdb_minus_tt_s,
    topocentric_tdb_minus_tt_s,
)
from tapp.measurements.observables import (
    LIGHT_TIME_REL_TOL,
    LightTime,
    LightTimeSolution,
    iterate_light_time,
    range_km,
)
from tapp.measurements.stations import station_state_eci

#: PPN γ of general relativity.
GAMMA_PPN = 1.0
#: Bodies whose Shapiro delay is always modelled; "jupiter" joins when it is a third body.
SHAPIRO_BODIES = ("sun", "earth", "moon")
#: Geocentric distance (km) beyond which relativity = "auto" turns the model on: the Moon's
#: mean distance.
AUTO_DISTANCE_km = 384400.0


#: Node spacing (s) of the barycentric body tables DE421 is interpolated from (cubic Hermite
#: on positions and velocities), and nodes per cached block (one day). Error h⁴ |r⁗| / 384:
#: the Moon's barycentric 384,400 km at 2.66e-6 rad/s gives 7e-9 km at 600 s.
BODY_STEP_s = 600.0
BODY_BLOCK = 144


@functools.lru_cache(maxsize=4096)
def _body_block(body: str, tt0_whole: float, tt0_fraction: float, block: int) -> np.ndarray:
    """DE421's barycentric state (km, km/s) of ``body`` at TDB seconds (block B + i) h past
    the TT Julian date ``tt0``, shape (BODY_BLOCK, 6)."""
    t = (block * BODY_BLOCK + np.arange(BODY_BLOCK)) * BODY_STEP_s
    return barycentric_state(body, tt0_whole, tt0_fraction + t / SECONDS_PER_DAY)


def shapiro_delay_s(r_i_km, r_j_km, body_i_km, body_j_km, mu_km3_s2: float,
                    gamma: float = GAMMA_PPN, sun: bool = False):
    """Return one body's Shapiro delay RLT_ij, s, shape (N,) (Moyer eq. 8-38, module docstring).

    Parameters
    ----------
    r_i_km, r_j_km : array_like, shape (N, 3)
        Barycentric positions of the two ends, each at its own time, km.
    body_i_km, body_j_km : array_like, shape (N, 3)
        Barycentric positions of the body at those two times, km.
    mu_km3_s2 : float
        The body's GM.
    sun : bool
        Add (1 + γ) μ / c² inside the logarithm (the Sun's term).
    """
    a = np.asarray(r_i_km, float) - np.asarray(body_i_km, float)
    b = np.asarray(r_j_km, float) - np.asarray(body_j_km, float)
    r_i, r_j = np.linalg.norm(a, axis=-1), np.linalg.norm(b, axis=-1)
    r_ij = np.linalg.norm(b - a, axis=-1)
    scale = (1.0 + gamma) * mu_km3_s2 / C_LIGHT_km_s**2
    eps = scale if sun else 0.0
    return scale / C_LIGHT_km_s * np.log((r_i + r_j + r_ij + eps) / (r_i + r_j - r_ij + eps))


@dataclass(frozen=True, slots=True)
class _Nodes:
    """Joined day tables of one body: the first day's index and the (n, 6) nodes."""

    first: int
    table: np.ndarray


@dataclass(frozen=True, slots=True)
class Relativity:
    """The relativistic light-time model of one scenario (module docstring).

    Attributes
    ----------
    tt0_jd : (float, float)
        TT Julian date of scenario time 0, split (whole at 0h, fraction), days.
    ut_minus_tt_s : float
        UTC - TT at the epoch, s: the diurnal argument of the topocentric TDB terms (UT1 - UTC,
        < 0.9 s, neglected: 6e-5 rad of a 2 us term).
    bodies : tuple of str
        Bodies whose Shapiro delay is summed.
    gamma : float
        PPN γ.
    """

    tt0_jd: tuple[float, float]
    ut_minus_tt_s: float
    bodies: tuple[str, ...] = SHAPIRO_BODIES
    gamma: float = GAMMA_PPN
    #: Per body, the last span of day tables joined (:meth:`_body_nodes`): a cache.
    _spans: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def at(cls, epoch: Epoch, bodies: tuple[str, ...] = SHAPIRO_BODIES) -> Relativity:
        """The model for a scenario whose t = 0 is the UTC ``epoch``."""
        tt_minus_utc = tai_minus_utc_s(epoch.jd) + TT_MINUS_TAI_s
        return cls((epoch.jd_whole, epoch.jd_fraction + tt_minus_utc / SECONDS_PER_DAY),
                   -tt_minus_utc, bodies)

    def tdb_minus_tt_s(self, t_s, r_ecef_km=None):
        """Return TDB - TT at scenario times t_s (N,), s: at the geocentre, or at the site
        ``r_ecef_km`` (3,) km with ERFA's topocentric terms (ERFA's series through
        :meth:`dtdb`)."""
        if r_ecef_km is None:
            return self.dtdb(t_s, (0.0, 0.0, 0.0))
        x, y, z = (float(c) for c in r_ecef_km)
        return self.dtdb(t_s, (math.atan2(y, x), math.hypot(x, y), z))

    def dtdb(self, t_s, site: tuple[float, float, float]):
        """Return ERFA's TDB - TT (``erfa.dtdb``: Fairhead & Bretagnon 1990 with Moyer's
        topocentric terms) at scenario times t_s, s, same shape, at ``site`` (east longitude
        rad, distance from the spin axis km, from the equator km): the geocentric series
        interpolated from cached day tables
        (:func:`tapp.frames.timescales.geocentric_tdb_minus_tt_s`) plus the site's terms in
        closed form (:meth:`topocentric`)."""
        geocentre = geocentric_tdb_minus_tt_s(self.tt0_jd, t_s)
        if site[1] == 0.0 and site[2] == 0.0:  # the topocentric terms all scale with u or v
            return geocentre
        return geocentre + self.topocentric(t_s, site)

    def topocentric(self, t_s, site: tuple[float, float, float]):
        """Return the topocentric terms of TDB - TT at ``site`` (as :meth:`dtdb`), s, at
        scenario times t_s (:func:`tapp.frames.timescales.topocentric_tdb_minus_tt_s`; the
        solar time from UTC, :attr:`ut_minus_tt_s`)."""
        fraction = self.tt0_jd[1] + np.asarray(t_s, dtype=float) / SECONDS_PER_DAY
        ut = self.tt0_jd[0] - 0.5 + fraction + self.ut_minus_tt_s / SECONDS_PER_DAY
        return topocentric_tdb_minus_tt_s((self.tt0_jd[0], fraction), ut, site)

    def tdb_rate(self, t_s, r_ecef_km=None):
        """Return d(TDB - TT)/dt at t_s (N,), dimensionless: central difference, 1 s steps
        (truncation h² |d³Δ/dt³| / 6 < 1e-19), at the geocentre or the site ``r_ecef_km``."""
        t = np.asarray(t_s, dtype=float)
        return 0.5 * (self.tdb_minus_tt_s(t + 1.0, r_ecef_km)
                      - self.tdb_minus_tt_s(t - 1.0, r_ecef_km))

    def tdb_site_gradient_s_km(self, t_s, r_ecef_km):
        """Return d(TDB - TT)/d(Earth-fixed site position) at t_s (N,), s/km, shape (N, 3).

        ERFA's topocentric terms are linear in the distances u (from the spin axis) and v
        (from the equator) and periodic in the longitude: the u and v slopes are differences
        at unit distance (exact), the longitude slope a central difference (step 1e-3 rad,
        truncation 2e-7 relative); then chained through u = hypot(x, y), lon = atan2(y, x),
        v = z. Size ~ |v_E| / c² = 3.3e-10 s/km: the receiver's and transmitter's clocks
        move the range by c / 2 times it, 5e-5 of a station partial in three-way.
        """
        x, y, _ = (float(c) for c in r_ecef_km)
        u, lon = math.hypot(x, y), math.atan2(y, x)

        def topo(lon_rad, u_km, v_km):
            return self.topocentric(t_s, (lon_rad, u_km, v_km))

        step = 1e-3
        d_u, d_v = topo(lon, 1.0, 0.0), topo(lon, 0.0, 1.0)
        d_lon = u * (topo(lon + step, 1.0, 0.0) - topo(lon - step, 1.0, 0.0)) / (2.0 * step)
        c, s_ = math.cos(lon), math.sin(lon)
        # du/d(x, y) = (cos lon, sin lon), dlon/d(x, y) = (-sin lon, cos lon) / u.
        return np.stack([d_u * c - d_lon * s_ / u, d_u * s_ + d_lon * c / u,
                         d_v * np.ones_like(d_u)], axis=-1)

    def body_state(self, body: str, t_s, tdb_minus_tt_s, *, velocity: bool = True):
        """Return the barycentric state (N, 6) of ``body`` at TDB = TT(t_s) + tdb_minus_tt_s
        (its position (N, 3) alone with ``velocity=False``): DE421 (jplephem) interpolated
        by cubic Hermite polynomials on its positions and velocities every
        :data:`BODY_STEP_s`, tables computed once per day and body (the light-time solution
        asks for the bodies' positions ~10 times per sample)."""
        x = (np.asarray(t_s, dtype=float) + tdb_minus_tt_s) / BODY_STEP_s
        x = np.atleast_1d(x)
        n = np.floor(x).astype(np.int64)
        nodes = self._body_nodes(body, int(n.min()) // BODY_BLOCK,
                                 (int(n.max()) + 1) // BODY_BLOCK)
        i = n - nodes.first * BODY_BLOCK
        s = (x - n)[:, None]
        h = BODY_STEP_s
        a, b = nodes.table[i], nodes.table[i + 1]
        p0, m0, m1 = a[:, :3], h * a[:, 3:], h * b[:, 3:]
        s2 = s * s
        s3 = s2 * s
        step = b[:, :3] - p0  # exact for neighbouring nodes: one rounding of p0's size in all
        position = p0 + ((3 * s2 - 2 * s3) * step + (s3 - 2 * s2 + s) * m0 + (s3 - s2) * m1)
        if not velocity:
            return position
        rate = ((6 * s - 6 * s2) * step + (3 * s2 - 4 * s + 1) * m0 + (3 * s2 - 2 * s) * m1) / h
        return np.concatenate([position, rate], axis=-1)

    def _body_nodes(self, body: str, first: int, last: int) -> _Nodes:
        """The nodes of ``body``'s day tables ``first`` ... ``last``, joined once per span
        (the last span asked is kept: the light-time iterations ask for the same one)."""
        key = (body, first, last)
        cached = self._spans.get(body)
        if cached is None or cached[0] != key:
            table = np.concatenate([_body_block(body, *self.tt0_jd, b)
                                    for b in range(first, last + 1)])
            cached = (key, _Nodes(first, table))
            self._spans[body] = cached
        return cached[1]

    def bodies_at(self, t_s, tdb_minus_tt_s) -> tuple[np.ndarray, ...]:
        """The barycentric positions (N, 3) of :attr:`bodies` at scenario times t_s (the
        ends of a leg, for :meth:`delay_s`)."""
        return tuple(self.body_state(body, t_s, tdb_minus_tt_s, velocity=False)
                     for body in self.bodies)

    def delay_s(self, r_i_km, bodies_i, r_j_km, bodies_j):
        """Return RLT_ij summed over :attr:`bodies`, s, (N,): ends r_i, r_j with the bodies'
        positions at each end's time (:meth:`bodies_at`)."""
        total = 0.0
        for body, b_i, b_j in zip(self.bodies, bodies_i, bodies_j, strict=True):
            total = total + shapiro_delay_s(r_i_km, r_j_km, b_i, b_j, GM_km3_s2[body],
                                            self.gamma, sun=body == "sun")
        return total

    def solve(self, t_s, state_eci, light_time: LightTime, r_receive_ecef_km,
              r_transmit_ecef_km, orientation: EarthOrientation) -> LightTimeSolution:
        """Return the light-time geometry at receive times t_s (N,) (module docstring).

        The returned states are barycentric, translated by the Earth's barycentric position
        at the bounce TDB (no velocity boost): the spacecraft's position is its geocentric
        position at the bounce, its velocity the barycentric one; the stations' positions
        are r_E(ET_st) - r_E(ET_2) + their geocentric positions. Differences of positions
        (the legs) and all velocities are barycentric, as the light-time equations and
        :func:`tapp.measurements.observables.light_time_range_rate_km_s` take them; the
        light times tau_down = t_3 - t_2 and tau_up = t_2 - t_1 are station-clock (scenario)
        time differences.

        Parameters
        ----------
        t_s : array_like, shape (N,)
            Receive times, s from the scenario epoch.
        state_eci : array_like, shape (N, 6)
            Spacecraft geocentric states at t_s, [km, km/s].
        light_time : LightTime
            The spacecraft's state at other times (``spacecraft_state``) and two_way.
        r_receive_ecef_km, r_transmit_ecef_km : array_like, shape (3,)
            Earth-fixed positions of the receiving and the transmitting station, km.
        orientation : EarthOrientation
        """
        t3 = np.asarray(t_s, dtype=float)
        x = np.asarray(state_eci, dtype=float)
        dt3 = self.tdb_minus_tt_s(t3, r_receive_ecef_km)
        station3 = station_state_eci(r_receive_ecef_km, orientation.attitude(t3))
        earth3 = self.body_state("earth", t3, dt3)
        r3 = earth3[..., :3] + station3[..., :3]
        bodies3 = self.bodies_at(t3, dt3)  # the receive end: fixed while tau_down is sought

        def bounce(tau, velocity=True):
            t2 = t3 - tau
            dt2 = self.tdb_minus_tt_s(t2)
            earth2 = self.body_state("earth", t2, dt2, velocity=velocity)
            return t2, dt2, earth2, light_time.spacecraft_state(t3, x, tau)

        def down(tau):
            t2, dt2, earth2, sc = bounce(tau, velocity=False)
            r2 = earth2 + sc[..., :3]
            return (np.linalg.norm(r2 - r3, axis=-1) + C_LIGHT_km_s * (
                self.delay_s(r2, self.bodies_at(t2, dt2), r3, bodies3) + dt2 - dt3))

        # The barycentric positions' rounding, below which the iterates only wander.
        floor_s = LIGHT_TIME_REL_TOL * np.linalg.norm(r3, axis=-1) / C_LIGHT_km_s
        tau_d = iterate_light_time(down, range_km(x, station3) / C_LIGHT_km_s, "down", floor_s)
        t2, dt2, earth2, sc = bounce(tau_d)
        r2 = earth2[..., :3] + sc[..., :3]
        spacecraft = np.concatenate([sc[..., :3], sc[..., 3:] + earth2[..., 3:]], axis=-1)

        def translated(station, earth):
            return np.concatenate([station[..., :3] + earth[..., :3] - earth2[..., :3],
                                   station[..., 3:] + earth[..., 3:]], axis=-1)

        receive = translated(station3, earth3)
        if not light_time.two_way:
            return LightTimeSolution(tau_d, np.zeros_like(tau_d), spacecraft, receive, receive)

        bodies2 = self.bodies_at(t2, dt2)  # the bounce: fixed while tau_up is sought

        def transmit(tau_u, velocity=True):
            t1 = t2 - tau_u
            dt1 = self.tdb_minus_tt_s(t1, r_transmit_ecef_km)
            station1 = station_state_eci(r_transmit_ecef_km, orientation.attitude(t1))
            return t1, dt1, station1, self.body_state("earth", t1, dt1, velocity=velocity)

        def up(tau_u):
            t1, dt1, station1, earth1 = transmit(tau_u, velocity=False)
            r1 = earth1 + station1[..., :3]
            return (np.linalg.norm(r2 - r1, axis=-1) + C_LIGHT_km_s * (
                self.delay_s(r1, self.bodies_at(t1, dt1), r2, bodies2) + dt1 - dt2))

        tau_u = iterate_light_time(up, tau_d, "up", floor_s)
        _, _, station1, earth1 = transmit(tau_u)
        return LightTimeSolution(tau_d, tau_u, spacecraft, receive, translated(station1, earth1))

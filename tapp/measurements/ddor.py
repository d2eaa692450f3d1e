"""ΔDOR (delta-differenced one-way range) of a spacecraft on a baseline, and its partials.

A baseline is an ordered pair of stations (A, B). The spacecraft's differenced one-way range
is the difference of the arrival times at B and at A of the same wavefront (Moyer 2003,
Formulation for Observed and Computed Values of DSN Data Types, JPL DESCANSO Monograph 2,
its VLBI time-delay observables), as a range (km): with t the reception time at A,

.. math::

    c\\,\\tau_A = |\\mathbf r(t_e) - \\mathbf r_A(t)|,\\quad t_e = t - \\tau_A,\\qquad
    c\\,(t_B - t_e) = |\\mathbf r(t_e) - \\mathbf r_B(t_B)|,\\qquad
    \\Delta\\rho_{sc} = c\\,(t_B - t)

(the down-leg to A solved as the one-way range of :mod:`tapp.measurements.observables`, the
leg to B forward from the same transmission t_e). The reference quasar is a plane wave from
the inertial direction ŝ_q; its wavefront reaches B after A by

.. math::

    c\\,\\Delta t_q = -\\hat{\\mathbf s}_q\\cdot
        (\\mathbf r_B(t + \\Delta t_q) - \\mathbf r_A(t)),

and the observable is the range-equivalent delay difference (Thornton & Border 2003,
Radiometric Tracking Techniques for Deep-Space Navigation, JPL DESCANSO Monograph 1, ch. 7:
the far-field delay τ ≈ -b·ŝ/c of each source, differenced)

.. math:: \\mathrm{ddor} = \\Delta\\rho_{sc} - c\\,\\Delta t_q\\quad\\text{(km)}.

Without light time everything is instantaneous at t: Δρ_sc = |r - r_B(t)| - |r - r_A(t)|
and c Δt_q = -ŝ_q·(r_B(t) - r_A(t)).

The quasar is a fixed inertial direction per observation (a catalogue source does not move
with the spacecraft): :func:`quasar_direction` places it at a stated angular separation from
the nominal geocentric direction of the spacecraft, and it enters the model as data, not as
a function of the state. Both sources are taken at the same reception time t (the real
session alternates them minutes apart and interpolates).

Partials. State: d̂_B - d̂_A (unit vectors from each station to the spacecraft at t_e),
chained to the receive-time state through x(t_e) ~ x(t) - τ_A [v, 0] as the one-way range
(exact without light time; with light time they neglect dτ_A/dx and dt_B/dx, relative
O(v/c) as the observables of :mod:`tapp.measurements.observables`). Station locations
(through :func:`tapp.measurements.stations.station_state_partials`, position rows):

.. math::

    \\frac{\\partial\\,\\mathrm{ddor}}{\\partial p_A} = (\\hat{\\mathbf d}_A - \\hat{\\mathbf s}_q)
        \\cdot\\frac{\\partial\\mathbf r_A(t)}{\\partial p_A},\\qquad
    \\frac{\\partial\\,\\mathrm{ddor}}{\\partial p_B} =
        \\hat{\\mathbf s}_q\\cdot\\frac{\\partial\\mathbf r_B(t + \\Delta t_q)}{\\partial p_B}
        - \\hat{\\mathbf d}_B\\cdot\\frac{\\partial\\mathbf r_B(t_B)}{\\partial p_B}:

the quasar cancels all but the (ŝ_q - ŝ_sc) part of a station error (neglected: the shift of
t_B and Δt_q with the station, relative v_station / c ~ 1.5e-6).

Neglected in the model: troposphere, ionosphere and solar plasma (they are the noise),
station clock offsets (removed by the quasar), relativistic light-time terms, the quasar's
structure and the spacecraft-quasar switching time; the Earth orientation is the scenario's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.constants import C_LIGHT_km_s
from tapp.errors import DivergenceError, InputError
from tapp.frames.orientation import (
    EOP_PARAMETERS,
    EarthOrientation,
    as_orientation,
    check_eop_parameters,
)
from tapp.measurements.observables import (
    LIGHT_TIME_MAX_ITERATIONS,
    LightTime,
    iterate_light_time,
    solve_light_time,
)
from tapp.measurements.stations import (
    Station,
    StationParameters,
    station_eop_partials,
    station_state_eci,
    station_state_partials,
)

#: The observable's kind code and unit (a range-equivalent delay).
DDOR_KIND = "ddor"
DDOR_UNIT = "km"
#: Names and units of the quasar position offsets, in the order of ``quasar_partials``' last
#: axis: Δα cos δ and Δδ, rad.
QUASAR_PARAMETER_NAMES = ("quasar_ra_rad", "quasar_dec_rad")
#: The quasar's delay iteration stops when a change is below this many seconds (1e-18 s is
#: 3e-13 km: rounding of a 1e4 km baseline); it contracts by |v_B| / c ~ 1.5e-6.
_QUASAR_DELAY_TOL_s = 1e-18


def _unit(v):
    return v / np.linalg.norm(v, axis=-1)[..., None]


def quasar_direction(direction_eci, separation_rad: float, position_angle_rad: float = 0.0):
    """Return a unit inertial direction at ``separation_rad`` from ``direction_eci``, (N, 3).

    .. math:: \\hat{\\mathbf s}_q = \\cos\\theta\\,\\hat{\\mathbf s}
              + \\sin\\theta\\,(\\cos\\phi\\,\\hat{\\mathbf n} + \\sin\\phi\\,\\hat{\\mathbf e})

    with ê = ẑ × ŝ / |ẑ × ŝ| (east, increasing right ascension) and n̂ = ŝ × ê (north):
    θ the separation and φ the position angle from north through east, the astronomer's
    convention. At the celestial poles (|ẑ × ŝ| < 1e-12) east is taken as ŷ.

    Parameters
    ----------
    direction_eci : array_like, shape (N, 3)
        Direction of the spacecraft (any length), inertial.
    separation_rad, position_angle_rad : float
        θ and φ, rad.
    """
    s = _unit(np.asarray(direction_eci, dtype=float))
    east = np.cross([0.0, 0.0, 1.0], s)
    size = np.linalg.norm(east, axis=-1)[..., None]
    east = np.where(size > 1e-12, east / np.maximum(size, 1e-300), [0.0, 1.0, 0.0])
    north = np.cross(s, east)
    offset = np.cos(position_angle_rad) * north + np.sin(position_angle_rad) * east
    return np.cos(separation_rad) * s + np.sin(separation_rad) * offset


def projected_baseline_km(baseline_eci_km, direction_eci):
    """Return |b - (b·ŝ) ŝ|, the baseline length seen from the source, km, shape (N,).

    The length that turns an angle (rad) into a delay (km): δ(c τ) = |b_proj| δθ in the
    plane of b and ŝ (Thornton & Border 2003, ch. 7).
    """
    b = np.asarray(baseline_eci_km, dtype=float)
    s = _unit(np.asarray(direction_eci, dtype=float))
    return np.linalg.norm(b - np.sum(b * s, axis=-1)[..., None] * s, axis=-1)


@dataclass(frozen=True, slots=True, eq=False)
class DdorGeometry:
    """Solved geometry of N ΔDOR observations (module docstring for the symbols).

    Attributes
    ----------
    spacecraft : (N, 6) spacecraft state at transmission t_e (at t without light time).
    tau_a_s : (N,) τ_A = t - t_e, s (0 without light time).
    station_a : (N, 6) station A at t.
    station_b : (N, 6) station B at t_B (spacecraft signal).
    station_b_quasar : (N, 6) station B at t + Δt_q (quasar wavefront).
    t_b_s, t_b_quasar_s : (N,) those times, s.
    sc_km, quasar_km : (N,) Δρ_sc and c Δt_q, km.
    """

    spacecraft: np.ndarray
    tau_a_s: np.ndarray
    station_a: np.ndarray
    station_b: np.ndarray
    station_b_quasar: np.ndarray
    t_b_s: np.ndarray
    t_b_quasar_s: np.ndarray
    sc_km: np.ndarray
    quasar_km: np.ndarray


@dataclass(frozen=True, slots=True)
class DdorModel:
    """The ΔDOR observable of a baseline (station_a, station_b), with its partials.

    Interface as :class:`tapp.measurements.MeasurementModel` with one observable (m = 1):
    ``compute`` (N, 1) km, ``state_partials`` (N, 1, 6), ``station_partials`` a pair
    ((N, 1, 3) for A, (N, 1, 3) for B); each takes the quasar directions (N, 3).

    Attributes
    ----------
    station_a, station_b : Station
        The baseline b = r_B - r_A (two different stations).
    orientation : EarthOrientation
        The scenario's Earth orientation (a float: the gmst model's angle at the epoch).
    light_time : LightTime or None
        A one-way model (its ``state_at`` gives the spacecraft at transmission); None:
        instantaneous geometry.
    """

    station_a: Station
    station_b: Station
    orientation: EarthOrientation
    light_time: LightTime | None = None

    def __post_init__(self) -> None:
        if np.array_equal(self.station_a.r_ecef_km, self.station_b.r_ecef_km):
            raise InputError("DdorModel", "station_b", "a station other than station_a",
                             self.station_b.name)
        if self.light_time is not None and self.light_time.two_way:
            raise InputError("DdorModel", "light_time", "a one-way light-time model (ΔDOR "
                             "is one-way)", "two_way")
        object.__setattr__(self, "orientation", as_orientation(self.orientation))

    def _b_at(self, t_s):
        return station_state_eci(self.station_b.r_ecef_km, self.orientation.attitude(t_s))

    def _quasar_delay_s(self, t, r_a, s_q):
        """Δt_q of the module docstring by fixed-point iteration, s, (N,)."""
        dt = np.zeros_like(t)
        for _ in range(LIGHT_TIME_MAX_ITERATIONS):
            new = -np.sum(s_q * (self._b_at(t + dt)[..., :3] - r_a), -1) / C_LIGHT_km_s
            done = np.abs(new - dt) <= _QUASAR_DELAY_TOL_s
            dt = new
            if done.all():
                return dt
        raise DivergenceError("quasar delay not converged", LIGHT_TIME_MAX_ITERATIONS)

    def geometry(self, t_s, state_eci, quasar_eci) -> DdorGeometry:
        """Return the solved geometry at receive times t_s (N,) for states (N, 6) at t_s."""
        t = np.asarray(t_s, dtype=float)
        x = np.asarray(state_eci, dtype=float)
        s_q = _unit(np.asarray(quasar_eci, dtype=float))
        station_a = station_state_eci(self.station_a.r_ecef_km, self.orientation.attitude(t))
        if self.light_time is None:
            station_b = self._b_at(t)
            sc_km = (np.linalg.norm(x[..., :3] - station_b[..., :3], axis=-1)
                     - np.linalg.norm(x[..., :3] - station_a[..., :3], axis=-1))
            quasar_km = -np.sum(s_q * (station_b[..., :3] - station_a[..., :3]), -1)
            return DdorGeometry(x, np.zeros_like(t), station_a, station_b, station_b, t, t,
                                sc_km, quasar_km)
        sol = solve_light_time(t, x, self.station_a.r_ecef_km, self.orientation,
                               self.light_time)
        t_e = t - sol.tau_down_s
        sc = sol.spacecraft_eci

        def b_distance(tau_b):
            return np.linalg.norm(sc[..., :3] - self._b_at(t_e + tau_b)[..., :3], axis=-1)

        tau_b = iterate_light_time(b_distance, sol.tau_down_s, "ddor, leg to station B")
        dt_q = self._quasar_delay_s(t, station_a[..., :3], s_q)
        return DdorGeometry(sc, sol.tau_down_s, station_a, self._b_at(t_e + tau_b),
                            self._b_at(t + dt_q), t_e + tau_b, t + dt_q,
                            C_LIGHT_km_s * (tau_b - sol.tau_down_s), C_LIGHT_km_s * dt_q)

    def compute(self, t_s, state_eci, quasar_eci):
        """Return ddor = Δρ_sc - c Δt_q, km, shape (N, 1).

        Parameters
        ----------
        t_s : array_like, shape (N,)
            Reception times at station A, s from the scenario epoch.
        state_eci : array_like, shape (N, 6)
            Spacecraft inertial states at t_s, [km, km/s].
        quasar_eci : array_like, shape (N, 3)
            Inertial directions of the reference quasars (:func:`quasar_direction`).
        """
        geo = self.geometry(t_s, state_eci, quasar_eci)
        return (geo.sc_km - geo.quasar_km)[..., None]

    @staticmethod
    def _lines_of_sight(geo: DdorGeometry):
        return (_unit(geo.spacecraft[..., :3] - geo.station_a[..., :3]),
                _unit(geo.spacecraft[..., :3] - geo.station_b[..., :3]))

    def state_partials(self, t_s, state_eci, quasar_eci):
        """Return d ddor / d spacecraft state [r, v] at t_s, shape (N, 1, 6) (module docstring)."""
        geo = self.geometry(t_s, state_eci, quasar_eci)
        d_a, d_b = self._lines_of_sight(geo)
        h = np.zeros(geo.tau_a_s.shape + (1, 6))
        h[..., 0, :3] = d_b - d_a
        # x(t - tau_A) ~ x(t) - tau_A [v, 0]: d/dv = -tau_A d/dr.
        h[..., 0, 3:] = -geo.tau_a_s[..., None] * h[..., 0, :3]
        return h

    def station_partials(self, t_s, state_eci, quasar_eci,
                         parameters: StationParameters = "cylindrical"):
        """Return (d ddor / d location of A, d ddor / d location of B), each (N, 1, 3).

        Columns named by ``STATION_PARAMETER_NAMES[parameters]`` (module docstring for the
        equations: the quasar term is in both).
        """
        t = np.asarray(t_s, dtype=float)
        geo = self.geometry(t, state_eci, quasar_eci)
        s_q = _unit(np.asarray(quasar_eci, dtype=float))
        d_a, d_b = self._lines_of_sight(geo)

        def dr(station, times):
            return station_state_partials(station.r_ecef_km, self.orientation.attitude(times),
                                          parameters)[..., :3, :]

        wrt_a = np.einsum("...i,...ij->...j", d_a - s_q, dr(self.station_a, t))
        wrt_b = (np.einsum("...i,...ij->...j", s_q, dr(self.station_b, geo.t_b_quasar_s))
                 - np.einsum("...i,...ij->...j", d_b, dr(self.station_b, geo.t_b_s)))
        return wrt_a[..., None, :], wrt_b[..., None, :]

    def eop_partials(self, t_s, state_eci, quasar_eci, names=EOP_PARAMETERS):
        """Return d ddor / d constant EOP offsets, shape (N, 1, k).

        Columns ``names`` among ("ut1_s", "xp_rad", "yp_rad") (only "ut1_s" under gmst), km
        per s and km per rad. The chain rule of :meth:`station_partials` with both stations
        moved by the same rotation (:func:`tapp.measurements.stations.station_eop_partials`):

        .. math::

            \\frac{\\partial\\,\\mathrm{ddor}}{\\partial p} =
            (\\hat{\\mathbf d}_A - \\hat{\\mathbf s}_q)\\cdot\\mathbf g_p\\times\\mathbf r_A(t)
            + \\hat{\\mathbf s}_q\\cdot\\mathbf g_p\\times\\mathbf r_B(t + \\Delta t_q)
            - \\hat{\\mathbf d}_B\\cdot\\mathbf g_p\\times\\mathbf r_B(t_B),

        to first order (ŝ_sc − ŝ_q)·(g_p × b): an EOP error is a baseline orientation error,
        which the quasar removes but for the separation (Thornton & Border 2003, ch. 7).

        Raises
        ------
        InputError
            A name that is not an EOP parameter of the orientation model.
        """
        names = check_eop_parameters(self.orientation.model, names, "DdorModel", "eop")
        t = np.asarray(t_s, dtype=float)
        geo = self.geometry(t, state_eci, quasar_eci)
        s_q = _unit(np.asarray(quasar_eci, dtype=float))
        d_a, d_b = self._lines_of_sight(geo)

        def dr(station, times):
            return station_eop_partials(station.r_ecef_km, self.orientation.attitude(times),
                                        names)[..., :3, :]

        out = (np.einsum("...i,...ij->...j", d_a - s_q, dr(self.station_a, t))
               + np.einsum("...i,...ij->...j", s_q, dr(self.station_b, geo.t_b_quasar_s))
               - np.einsum("...i,...ij->...j", d_b, dr(self.station_b, geo.t_b_s)))
        return out[..., None, :]

    def quasar_partials(self, t_s, state_eci, quasar_eci):
        """Return d ddor / d(Δα cos δ, Δδ) of the quasar, km/rad, shape (N, 1, 2).

        Offsets of the quasar's right ascension (times cos δ) and declination in the inertial
        frame (:data:`QUASAR_PARAMETER_NAMES`): ŝ_q moves by ê (east, ẑ × ŝ_q normalised)
        and n̂ = ŝ_q × ê (north). From c Δt_q = −ŝ_q · (r_B(t + Δt_q) − r_A(t)):

        .. math::

            \\frac{\\partial\\,\\mathrm{ddor}}{\\partial\\hat{\\mathbf s}_q} =
            \\frac{c\\,\\mathbf b_q}{c + \\hat{\\mathbf s}_q\\cdot\\mathbf v_B},
            \\qquad \\mathbf b_q = \\mathbf r_B(t + \\Delta t_q) - \\mathbf r_A(t)

        (exact for the model; without light time Δt_q = 0, so v_B drops out). A quasar error
        of δθ is a delay error of |b_proj| δθ, 1 nrad on an 8,000 km baseline 8 mm
        (Thornton & Border 2003, ch. 7). Undefined at the celestial poles, where east is.
        """
        geo = self.geometry(t_s, state_eci, quasar_eci)
        s_q = _unit(np.asarray(quasar_eci, dtype=float))
        east = _unit(np.cross([0.0, 0.0, 1.0], s_q))
        north = np.cross(s_q, east)
        b_q = geo.station_b_quasar[..., :3] - geo.station_a[..., :3]
        if self.light_time is None:
            grad = b_q
        else:
            v_b = geo.station_b_quasar[..., 3:]
            grad = C_LIGHT_km_s * b_q / (C_LIGHT_km_s + np.sum(s_q * v_b, -1))[..., None]
        return np.stack([np.sum(grad * east, -1), np.sum(grad * north, -1)], -1)[..., None, :]

r"""B-plane targeting: the astrodynamic program that SEARCH drives.

SEARCH (:mod:`search`) knows nothing of orbits; it drives a plain ``f(x) -> y``. This module
supplies that ``f`` for the seed's "typical search over a trajectory" (TM 33-203, section II):
x = the injection velocity (vx, vy, vz) in km/s, EME2000, Earth-centred; y = (B·R km, B·T km,
flight time s) at a target body, computed through the numerical integrator with the Sun, the
Moon (and any target) from DE421. Optionally it supplies the analytic partials
:math:`\partial y/\partial x` from the variational equations.

The evaluation of one case (:meth:`BPlaneProgram.evaluate`):

1. **Scan.** Propagate the state alone from the injection (t = 0, the scenario epoch) to the
   horizon ``max_flight_time_s`` on a grid of ``scan_step_s``, and form the target-relative
   state :math:`\mathbf z = \mathbf x - \mathbf x_b(t)` on it (target ephemeris from DE421).
   The encounter is the first grid interval where :math:`h = \mathbf r\cdot\mathbf v` of
   :math:`\mathbf z` changes sign from - to + (a closest approach) with the target within its
   sphere of influence :math:`r_{SOI} = D\,(\mu_b/\mu_c)^{2/5}` (Laplace; D the centre-target
   distance at that time). No such interval: :class:`TargetMissedError`.
2. **Periapsis.** The evaluation time :math:`t_e` is the periapsis of the *integrated*
   trajectory relative to the target, the root of :math:`h(t) = 0`. It is found by Newton's
   method with the two-body step :math:`t \leftarrow t + t_p(\mathbf z(t))` (:math:`t_p` the
   osculating hyperbola's time to periapsis, :func:`tapp.orbit.bplane.b_plane`), starting at the
   grid point of the bracket nearer the target, until :math:`|t_p| \le`
   ``periapsis_time_tol_s``; each step is one propagation from t = 0 (with the STM when
   partials are wanted). The step converges at the rate of the non-Keplerian part of the
   motion (the Earth's tidal acceleration against the Moon's attraction): from a grid point
   up to ``scan_step_s``/2 away, the first step leaves milliseconds on a close flyby (a
   fraction of a second on a distant one), so one or two steps follow the scan. An
   osculating orbit that is not hyperbolic there: :class:`TargetMissedError`.
3. **Values.** :math:`y = (B\cdot R, B\cdot T)` of the osculating target-relative hyperbola at
   :math:`t_e`, and the flight time :math:`t_f = t_e + t_p(\mathbf z(t_e))`, the time of
   periapsis passage measured from the injection (the :math:`t_p` term is the last Newton
   correction, below ``periapsis_time_tol_s``). LTOF is *not* used: it is a far-field proxy
   that differs from the periapsis time by :math:`(\mu/v_\infty^3)(e^F/e - 1 - F)` (see
   :func:`tapp.orbit.bplane.b_plane`), and at periapsis it is not zero.

Analytic partials (consistent with that choice of :math:`t_e`). With
:math:`\Phi_v = \Phi(t_e, 0)[:, 3{:}6]` (6x3, from the variational equations),
:math:`\dot{\mathbf z} = (\mathbf v - \mathbf v_b,\ \mathbf a(\mathbf x) - \mathbf a_b)` and
:math:`\nabla h = (\mathbf v_z, \mathbf r_z)` the gradient of :math:`h = \mathbf r\cdot\mathbf v`:

.. math::

    \frac{\partial t_e}{\partial \mathbf v_0} =
        -\frac{\nabla h\,\Phi_v}{\nabla h\cdot\dot{\mathbf z}}, \qquad
    \frac{\partial \mathbf z(t_e)}{\partial \mathbf v_0} =
        \Phi_v + \dot{\mathbf z}\,\frac{\partial t_e}{\partial \mathbf v_0},

    \frac{\partial (B\cdot R, B\cdot T)}{\partial \mathbf v_0} =
        G\,\frac{\partial \mathbf z(t_e)}{\partial \mathbf v_0}
        + \frac{\partial (B\cdot R, B\cdot T)}{\partial t}\Big|_{\mathbf z}
          \frac{\partial t_e}{\partial \mathbf v_0}, \qquad
    \frac{\partial t_f}{\partial \mathbf v_0} = \frac{\partial t_e}{\partial \mathbf v_0}

(implicit differentiation of :math:`h(\mathbf z(t_e)) = 0`; the :math:`t_p` term of
:math:`t_f` has zero derivative because :math:`t_p(\mathbf z(t_e)) \equiv 0`).
:math:`G = \partial(B\cdot R, B\cdot T)/\partial\mathbf z` (2x6) is the B-plane Jacobian: its
velocity block is :attr:`tapp.orbit.bplane.BPlane.jacobian_v` (complex step), its position block is
taken here by central differences of :func:`tapp.orbit.bplane.b_plane` (cheap: two-body formulas
only). The time derivative at fixed z is that of the reference pole, non-zero only for
``reference = "body_equator"`` (the body's pole at the moving t_e; a central difference over
600 s): the Moon's pole turns by up to ~3e-9 rad/s, which moves a 7,000 km B by ~2e-5 km/s;
times :math:`\partial t_e/\partial \mathbf v_0` (~2e6 s per km/s on a lunar transfer) that is
5 s, 1e-4 of the B·R row of the shipped lunar search (measured; tested).
:math:`\mathbf a(\mathbf x)` is the state model's acceleration (its CasADi function); the
target's velocity and acceleration are central differences of the DE421 position. The
expensive part, the trajectory's sensitivity, comes from the STM alone. With a variational
model other than the state model (:class:`tapp.dynamics.Propagator` ``var_model``) the
partials are those of the approximate STM, as the (J_N, J_M) study intends.

Failures. A case whose trajectory misses the target's sphere of influence, or whose
target-relative orbit is not hyperbolic, raises :class:`TargetMissedError` (a
:class:`~tapp.errors.NotHyperbolicError`). :func:`search.solve` lets exceptions of ``f``
propagate unchanged (only non-finite or mis-shaped outputs become its own
``SearchInputError``), which is what we want: a Newton step that throws the trajectory off
the target has no meaningful y, and inventing one (NaN, a penalty) would either stop SEARCH
with a less clear message or corrupt its partials. :func:`run_search` therefore lets the
search stop there and re-raises the failure as :class:`FailedCaseError`, naming the case
number (as in SEARCH's history and report), its x and the reason; the CLI turns it into one
line on stderr and exit code 1.

References
----------
N. S. Newhall, "A Users' Guide for SEARCH and ITER", JPL TM 33-203 (1965), section II (the
3x3 search of B·T, B·R, t_f over the injection velocity).
W. Kizner, Planetary and Space Science 7 (1961) 125-131 (the B-plane).
R. H. Battin, *An Introduction to the Mathematics and Methods of Astrodynamics*, rev. ed.
(1999), section 9.6 (sphere of influence, :math:`r_{SOI} = D (m/M)^{2/5}`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from search import SearchResult, solve
from tapp.constants import SECONDS_PER_DAY, GM_km3_s2
from tapp.dynamics import PropagationError, Propagator
from tapp.dynamics.ephemeris import position_km, tdb_reader
from tapp.dynamics.poles import EQUATOR_POLE_BODIES, equator_pole, pole_unit
from tapp.errors import DivergenceError, InputError, NotHyperbolicError, TappError
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tapp.orbit import lambert
from tapp.orbit.bplane import BODY_EQUATOR, REFERENCE_PLANES, REFERENCE_POLES, BPlane, b_plane

#: Names of the independent variables x (injection velocity, EME2000) and dependent ones y.
X_NAMES = ("vx_km_s", "vy_km_s", "vz_km_s")
Y_NAMES = ("b_dot_r_km", "b_dot_t_km", "flight_time_s")

#: Newton steps allowed on the periapsis time before giving up (one usually suffices).
MAX_PERIAPSIS_ITERATIONS = 6
#: Most closest-approach scan steps (max_flight_time_s / scan_step_s), checked before the
#: scan grid is allocated (a horizon of 1e308 s would otherwise exhaust memory).
MAX_SCAN_STEPS = 1_000_000
#: Times of the grid that refines a closest approach over two scan steps (1 s for 600 s steps).
CLOSEST_APPROACH_SAMPLES = 1201

# Central-difference step for the target's velocity and acceleration from DE421 positions:
# a 4th-order stencil with h = 60 s has truncation ~1e-17 km/s for the Moon, round-off
# ~1e-12 km/s (positions good to ~4e-11 km).
_EPHEMERIS_STEP_s = 60.0
# Relative step of the central differences of the B-plane in position: truncation
# ~(1e-6)^2, round-off ~1e-16 |B| / (1e-6 |r|), both far below 1e-8 of the partials.
_B_PLANE_POSITION_STEP = 1e-6
# Time step of the central difference of the B-plane in its moving reference pole: the
# fastest pole term (the Moon's E6, 13.6 days) leaves a truncation (omega h)^2 / 6 ~ 2e-6 of
# a term that is itself ~1e-4 of the partials; round-off 1e-16 / (3e-9 rad/s x h) ~ 6e-11 of it.
_POLE_TIME_STEP_s = 600.0

#: What a file's B-plane ``reference`` may be (the schemas' field descriptions).
REFERENCE_HELP = (
    "\"earth_equator\" (the EME2000 xy-plane), \"ecliptic\" (of J2000) or \"body_equator\" "
    "(the body's own equator, its pole from the IAU WGCCRE model at the time of the B-plane; "
    f"the Earth's is the EME2000 xy-plane; bodies with a pole: {', '.join(EQUATOR_POLE_BODIES)})")


def check_reference(reference: str, body: str, source: str, field: str) -> None:
    """Raise :class:`~tapp.errors.InputError` naming ``source`` and ``field`` unless
    ``reference`` is one of :data:`tapp.orbit.bplane.REFERENCE_PLANES` and, for
    ``"body_equator"``, ``body`` has an equator pole
    (:data:`tapp.dynamics.poles.EQUATOR_POLE_BODIES`)."""
    if reference not in REFERENCE_PLANES:
        raise InputError(source, field, f"one of {list(REFERENCE_PLANES)}", reference)
    if reference == BODY_EQUATOR and body not in EQUATOR_POLE_BODIES:
        raise InputError(source, field, f"a body with a pole model for \"{BODY_EQUATOR}\" "
                         f"({', '.join(EQUATOR_POLE_BODIES)}), or \"earth_equator\" or "
                         f"\"ecliptic\"", f"{reference} of the {body}")


class TargetMissedError(NotHyperbolicError):
    """No hyperbolic encounter: the trajectory misses the target's sphere of influence within
    the horizon, or its target-relative orbit at closest approach is not hyperbolic. The
    message gives the closest approach (km), its time (s) and the sphere of influence (km),
    or the eccentricity and energy."""


class FailedCaseError(TappError):
    """A SEARCH case could not be evaluated; names the case number, its x and the reason.

    Attributes
    ----------
    case : int
        1-based case number, as in ``SearchResult.history.cases`` and the report.
    x : numpy.ndarray, shape (3,)
        Injection velocity of the case, km/s.
    """

    def __init__(self, case: int, x: np.ndarray, reason: Exception):
        self.case = case
        self.x = np.array(x, dtype=float)
        values = ", ".join(f"{v:.9f}" for v in self.x)
        super().__init__(f"search case {case} at v0 = [{values}] km/s failed: {reason}")


@dataclass(frozen=True, slots=True)
class ClosestApproach:
    """The closest approach of a trajectory to the target (:meth:`BPlaneProgram.closest_approach`).

    Attributes
    ----------
    t_s : float
        Time, s from the injection (the scenario epoch).
    distance_km : float
        Distance between the spacecraft and the target's centre, km.
    soi_km : float
        The target's sphere of influence at that time (:meth:`BPlaneProgram.soi_radius_km`), km.
    """

    t_s: float
    distance_km: float
    soi_km: float


@dataclass(frozen=True, slots=True)
class Encounter:
    """One evaluation of the program: y, the target-relative state at periapsis, partials.

    Attributes
    ----------
    v0_km_s : numpy.ndarray, shape (3,)
        The injection velocity evaluated (x), km/s, EME2000.
    y : numpy.ndarray, shape (3,)
        (B·R km, B·T km, flight time s) in the order of :data:`Y_NAMES`.
    t_periapsis_s : float
        Evaluation time t_e, s from the injection: periapsis of the integrated trajectory.
    state_rel : numpy.ndarray, shape (6,)
        Target-relative position (km) and velocity (km/s) at t_e, EME2000 axes.
    b_plane : BPlane
        B-plane parameters of the osculating hyperbola at t_e (its ``periapsis_radius_km``
        tells an impacting case).
    partials : numpy.ndarray of shape (3, 3), or None
        dy/dv0, rows as ``y``, columns vx, vy, vz: (s, s, s^2/km); None unless asked for.
    propagations : int
        Numerical integrations run for this case (scan + Newton steps on t_e).
    """

    v0_km_s: np.ndarray
    y: np.ndarray
    t_periapsis_s: float
    state_rel: np.ndarray
    b_plane: BPlane
    partials: np.ndarray | None
    propagations: int


def frozen_array(a: ArrayLike) -> np.ndarray:
    """Return a read-only float64 copy of ``a`` (the arrays of the frozen values here)."""
    out = np.array(a, dtype=np.float64, copy=True)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, slots=True)
class BPlaneProgram:
    r"""The trajectory program of a B-plane search: injection velocity -> (B·R, B·T, t_f).

    Call it as ``program(v0_km_s) -> y`` (what :func:`search.solve` drives), or use
    :meth:`evaluate` for the whole :class:`Encounter` and :meth:`partials` for the analytic
    dy/dv0. The module docstring gives the definitions and the equations.

    Parameters
    ----------
    epoch : Epoch
        UTC instant of the injection, t = 0.
    r0_km : array_like, shape (3,)
        Injection position, km, EME2000, relative to the propagator's centre.
    propagator : Propagator
        State and variational models (the target must be one of the state model's third
        bodies), tolerances. No model parameters (``params == ()``).
    target : str, optional
        Target body, one of :data:`tapp.dynamics.BODIES` (default ``"moon"``).
    reference : str, optional
        B-plane reference plane (:meth:`reference_pole`): ``"earth_equator"`` (default),
        ``"ecliptic"`` or ``"body_equator"`` (the target's own equator; its pole from the IAU
        model at the evaluation time, for a target of
        :data:`tapp.dynamics.poles.EQUATOR_POLE_BODIES`).
    max_flight_time_s : float, optional
        Horizon of the scan, s (default 8 days).
    scan_step_s : float, optional
        Output step of the scan for the closest approach, s (default 600).
    periapsis_time_tol_s : float, optional
        Stop the Newton iteration on t_e when the osculating time to periapsis is below this,
        s (default 1e-3: B moves ~3e-7 km and t_f ~1e-8 s in that time near the Moon).
    orientation : EarthOrientation, optional
        The Earth orientation of the models (default: gmst at the epoch, with the ephemeris at
        TT); with iau2006 the ephemeris is read at its TDB.
    """

    epoch: Epoch
    r0_km: np.ndarray
    propagator: Propagator
    target: str = "moon"
    reference: str = "earth_equator"
    max_flight_time_s: float = 8.0 * SECONDS_PER_DAY
    scan_step_s: float = 600.0
    periapsis_time_tol_s: float = 1e-3
    orientation: EarthOrientation | None = None
    #: TDB of scenario times (:func:`tapp.dynamics.ephemeris.tdb_reader`).
    _tdb: Callable[[np.ndarray], tuple] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        r0 = np.asarray(self.r0_km, dtype=np.float64)
        if r0.shape != (3,) or not np.all(np.isfinite(r0)) or not np.any(r0):
            raise InputError("targeting", "r0_km", "3 finite numbers, not all zero (km)",
                             r0.tolist())
        object.__setattr__(self, "r0_km", frozen_array(r0))
        model = self.propagator.state_model
        if self.target not in model.third_bodies:
            raise InputError("targeting", "target",
                             f"one of the state model's third bodies {model.third_bodies}",
                             self.target)
        if self.propagator.params:
            raise InputError("targeting", "propagator.params", "no model parameters",
                             self.propagator.params)
        check_reference(self.reference, self.target, "targeting", "reference")
        for name in ("max_flight_time_s", "scan_step_s", "periapsis_time_tol_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError("targeting", name, "a finite number > 0 (s)", value)
        if self.scan_step_s >= self.max_flight_time_s:
            raise InputError("targeting", "scan_step_s", "a step shorter than "
                             f"max_flight_time_s = {self.max_flight_time_s} s", self.scan_step_s)
        if self.max_flight_time_s / self.scan_step_s > MAX_SCAN_STEPS:
            raise InputError("targeting", "max_flight_time_s", f"at most {MAX_SCAN_STEPS:,} "
                             f"scan steps of {self.scan_step_s:g} s", self.max_flight_time_s)
        if self.orientation is None:
            object.__setattr__(self, "orientation", EarthOrientation.gmst(self.epoch))
        object.__setattr__(self, "_tdb", tdb_reader(self.epoch.jd, self.orientation.scales))

    @property
    def gm_target_km3_s2(self) -> float:
        """GM of the target body, km^3/s^2 (DE430 value, :data:`tapp.constants.GM_km3_s2`)."""
        return GM_km3_s2[self.target]

    # --- ephemeris and dynamics -----------------------------------------------------------

    def target_state(self, t_s: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Return the target's state (N, 6) (km, km/s) and acceleration (N, 3) (km/s^2)
        relative to the centre at ``t_s`` (N,) seconds from the epoch (DE421).

        Velocity and acceleration are the 4th-order central differences
        :math:`(8(p_{+1} - p_{-1}) - (p_{+2} - p_{-2}))/12h` and
        :math:`(-p_{+2} + 16 p_{+1} - 30 p_0 + 16 p_{-1} - p_{-2})/12h^2`, h = 60 s.
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        h = _EPHEMERIS_STEP_s
        offsets = np.array([-2.0, -1.0, 0.0, 1.0, 2.0]) * h
        p = self.body_position_km(self.target, (t[:, None] + offsets[None, :]).ravel())
        p = p.reshape(t.size, 5, 3)
        vel = (8.0 * (p[:, 3] - p[:, 1]) - (p[:, 4] - p[:, 0])) / (12.0 * h)
        acc = (-p[:, 4] + 16.0 * p[:, 3] - 30.0 * p[:, 2] + 16.0 * p[:, 1] - p[:, 0]) / (
            12.0 * h * h)
        return np.concatenate([p[:, 2], vel], axis=1), acc

    def acceleration_km_s2(self, t_s: float, state: np.ndarray) -> np.ndarray:
        """Return the state model's acceleration (3,), km/s^2, at one time and state (6,)."""
        eqs, _ = self.propagator.compiled()
        t = np.array([t_s], dtype=np.float64)
        rb = [self.body_position_km(body, t)[0] for body in eqs.bodies]
        if eqs.oriented == "body_pole":
            rb.append(pole_unit(self.propagator.state_model.center, *self._tdb(t)).ravel())
        elif eqs.oriented:
            rb.append((self.orientation.slow_terms(t) if eqs.oriented == "full"
                       else self.orientation.pole(t)).ravel())
        xdot = eqs.f_state(t_s, state, np.zeros(0), [self.orientation.theta0_rad],
                           np.concatenate([np.zeros(0), *rb]))
        return np.asarray(xdot, dtype=np.float64).ravel()[3:6]

    def body_position_km(self, body: str, t_s: np.ndarray) -> np.ndarray:
        """Position (N, 3) km of ``body`` relative to the centre, at TDB (TT with gmst)."""
        return position_km(body, self.propagator.state_model.center, *self._tdb(t_s))

    def soi_radius_km(self, distance_km: ArrayLike) -> np.ndarray:
        r"""Return Laplace's sphere-of-influence radius :math:`D(\mu_b/\mu_c)^{2/5}`, km."""
        ratio = self.gm_target_km3_s2 / self.propagator.state_model.gm_center_km3_s2
        return np.asarray(distance_km, dtype=np.float64) * ratio**0.4

    def _propagate(self, v0: np.ndarray, t_s: np.ndarray, stm: bool):
        try:
            return self.propagator.propagate(
                np.concatenate([self.r0_km, v0]), t_s, stm=stm,
                orientation=self.orientation, epoch_jd_utc=self.epoch.jd)
        except PropagationError as exc:
            raise PropagationError(f"{exc} (injection velocity {v0.tolist()} km/s)") from exc

    def reference_pole(self, t_s: ArrayLike) -> np.ndarray:
        """Return the pole (N, 3) of the B-plane's reference plane, EME2000 axes, at ``t_s``
        (N,) s from the epoch: the fixed pole of :data:`tapp.orbit.bplane.REFERENCE_POLES`,
        or for ``"body_equator"`` the target's equator pole
        (:func:`tapp.dynamics.poles.equator_pole`: the IAU WGCCRE model at the TDB of t_s,
        :func:`tapp.dynamics.ephemeris.tdb_reader`; for the Earth the EME2000 z axis, the
        same plane as ``"earth_equator"``)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        if self.reference == BODY_EQUATOR:
            return equator_pole(self.target, *self._tdb(t))
        return np.broadcast_to(REFERENCE_POLES[self.reference], t.shape + (3,))

    def _b_plane(self, z: np.ndarray, t_s: float) -> BPlane:
        """The B-plane of target-relative states z (..., 6) at one time t_s (its pole)."""
        return b_plane(z[..., :3], z[..., 3:], self.gm_target_km3_s2,
                       reference=self.reference_pole(t_s)[0])

    # --- the program ----------------------------------------------------------------------

    def _relative_states(self, v0: np.ndarray, t_s: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
        """Target-relative states (N, 6) and the target's states (N, 6) at t_s (N,), s."""
        body, _ = self.target_state(t_s)
        return self._propagate(v0, t_s, stm=False).states - body, body

    def _scan_grid(self) -> np.ndarray:
        """The scan's times scan_step_s, 2 scan_step_s, ..., max_flight_time_s, s."""
        n = int(math.ceil(self.max_flight_time_s / self.scan_step_s))
        return np.minimum(self.scan_step_s * np.arange(1, n + 1), self.max_flight_time_s)

    def closest_approach(self, v0_km_s: ArrayLike) -> ClosestApproach:
        """Return the trajectory's closest approach to the target within the horizon.

        The smallest distance on the scan grid (``scan_step_s`` over ``max_flight_time_s``,
        inside the sphere of influence or not), refined on a grid of
        :data:`CLOSEST_APPROACH_SAMPLES` times over the two scan steps around it (time to
        ``2 scan_step_s / (CLOSEST_APPROACH_SAMPLES - 1)``, 1 s by default): two state-only
        propagations from the injection. The sphere of influence is reported at that time.
        """
        v0 = np.asarray(v0_km_s, dtype=np.float64)
        t = self._scan_grid()
        k = int(np.argmin(np.linalg.norm(self._relative_states(v0, t)[0][:, :3], axis=1)))
        fine = np.linspace(t[k - 1] if k else 0.0, t[min(k + 1, t.size - 1)],
                           CLOSEST_APPROACH_SAMPLES)
        z, body = self._relative_states(v0, fine)
        dist = np.linalg.norm(z[:, :3], axis=1)
        j = int(np.argmin(dist))
        return ClosestApproach(
            t_s=float(fine[j]), distance_km=float(dist[j]),
            soi_km=float(self.soi_radius_km(np.linalg.norm(body[j, :3]))))

    def _closest_approach_time(self, v0: np.ndarray) -> float:
        """Scan for the first closest approach inside the SOI; return the Newton start (s)."""
        t = self._scan_grid()
        z, body = self._relative_states(v0, t)
        dist = np.linalg.norm(z[:, :3], axis=1)
        rdotv = np.sum(z[:, :3] * z[:, 3:], axis=1)
        soi = self.soi_radius_km(np.linalg.norm(body[:, :3], axis=1))
        bracket = (rdotv[:-1] < 0.0) & (rdotv[1:] >= 0.0)
        bracket &= np.minimum(dist[:-1], dist[1:]) < np.minimum(soi[:-1], soi[1:])
        hits = np.flatnonzero(bracket)
        if hits.size == 0:
            k = int(np.argmin(dist))
            raise TargetMissedError(
                f"the trajectory does not reach the {self.target}'s sphere of influence within "
                f"{self.max_flight_time_s:.0f} s: closest approach on the {self.scan_step_s:g} s "
                f"grid {dist[k]:.1f} km at t = {t[k]:.0f} s (sphere of influence "
                f"{soi[k]:.1f} km)")
        k = int(hits[0])
        k = k if dist[k] <= dist[k + 1] else k + 1
        try:
            t_p = float(self._b_plane(z[k], t[k]).time_to_periapsis_s)
        except NotHyperbolicError as exc:
            raise TargetMissedError(
                f"the {self.target}-relative orbit at closest approach (t = {t[k]:.0f} s, "
                f"{dist[k]:.1f} km) is not hyperbolic: {exc}") from exc
        return float(t[k]) + t_p

    def evaluate(self, v0_km_s: ArrayLike, *, partials: bool = False) -> Encounter:
        """Run one case: propagate from the injection, find periapsis, return the encounter.

        Parameters
        ----------
        v0_km_s : array_like, shape (3,)
            Injection velocity, km/s, EME2000.
        partials : bool, optional
            Also integrate the STM and return the analytic dy/dv0.

        Raises
        ------
        TargetMissedError
            No closest approach inside the sphere of influence within the horizon, or a
            target-relative orbit that is not hyperbolic there.
        PropagationError
            The integrator stopped (message names the injection velocity).
        DivergenceError
            The Newton iteration on the periapsis time did not reach ``periapsis_time_tol_s``
            in :data:`MAX_PERIAPSIS_ITERATIONS` steps.
        InputError
            A velocity that is not 3 finite numbers.
        """
        v0 = np.asarray(v0_km_s, dtype=np.float64)
        if v0.shape != (3,) or not np.all(np.isfinite(v0)):
            raise InputError("targeting", "v0_km_s", "3 finite numbers (km/s)", v0.tolist())
        t_e = self._closest_approach_time(v0)
        steps = 0
        while True:
            if not 0.0 < t_e <= self.max_flight_time_s:
                raise TargetMissedError(
                    f"periapsis time {t_e:.3f} s outside the horizon (0, "
                    f"{self.max_flight_time_s:.0f}] s")
            traj = self._propagate(v0, np.array([t_e]), stm=partials)
            steps += 1
            body, body_acc = self.target_state(t_e)
            z = traj.states[0] - body[0]
            try:
                bp = self._b_plane(z, t_e)
            except NotHyperbolicError as exc:
                raise TargetMissedError(
                    f"the {self.target}-relative orbit at t = {t_e:.3f} s is not hyperbolic: "
                    f"{exc}") from exc
            t_p = float(bp.time_to_periapsis_s)
            if abs(t_p) <= self.periapsis_time_tol_s:
                break
            if steps == MAX_PERIAPSIS_ITERATIONS:
                raise DivergenceError(
                    f"periapsis time not found to {self.periapsis_time_tol_s:g} s (last step "
                    f"{t_p:.3e} s)", steps)
            t_e += t_p
        y = np.array([float(bp.b_dot_r_km), float(bp.b_dot_t_km), t_e + t_p])
        jac = None
        if partials:
            jac = self._partials(t_e, traj.states[0], traj.stm[0], z, body_acc[0], bp)
        return Encounter(
            v0_km_s=frozen_array(v0),
            y=frozen_array(y),
            t_periapsis_s=t_e,
            state_rel=frozen_array(z),
            b_plane=bp,
            partials=None if jac is None else frozen_array(jac),
            propagations=1 + steps,
        )

    def _partials(self, t_e: float, state: np.ndarray, phi: np.ndarray, z: np.ndarray,
                  body_acc: np.ndarray, bp: BPlane) -> np.ndarray:
        """dy/dv0 (3, 3) at periapsis; equations in the module docstring."""
        r, v = z[:3], z[3:]
        # G = d(B.R, B.T)/dz (2, 6): position block by central differences of b_plane,
        # velocity block from its complex-step Jacobian (rows B.R, B.T, LTOF).
        step_km = _B_PLANE_POSITION_STEP * float(np.linalg.norm(r))
        dr = step_km * np.eye(3)
        plus = self._b_plane(np.concatenate([r + dr, np.broadcast_to(v, (3, 3))], axis=1), t_e)
        minus = self._b_plane(np.concatenate([r - dr, np.broadcast_to(v, (3, 3))], axis=1), t_e)
        g_r = np.stack([plus.b_dot_r_km - minus.b_dot_r_km,
                        plus.b_dot_t_km - minus.b_dot_t_km]) / (2.0 * step_km)
        g = np.concatenate([g_r, bp.jacobian_v[:2]], axis=1)
        # d(B.R, B.T)/dt at fixed z through the reference pole (zero for a fixed plane).
        later = self._b_plane(z, t_e + _POLE_TIME_STEP_s)
        earlier = self._b_plane(z, t_e - _POLE_TIME_STEP_s)
        g_t = np.array([later.b_dot_r_km - earlier.b_dot_r_km,
                        later.b_dot_t_km - earlier.b_dot_t_km]) / (2.0 * _POLE_TIME_STEP_s)
        # zdot = (v_rel, a - a_b); grad h of h = r.v is (v, r).
        zdot = np.concatenate([v, self.acceleration_km_s2(t_e, state) - body_acc])
        grad_h = np.concatenate([v, r])
        phi_v = phi[:, 3:6]
        dte_dv0 = -(grad_h @ phi_v) / (grad_h @ zdot)
        dz_dv0 = phi_v + np.outer(zdot, dte_dv0)
        return np.vstack([g @ dz_dv0 + np.outer(g_t, dte_dv0), dte_dv0])

    def partials(self, v0_km_s: ArrayLike) -> np.ndarray:
        """Return the analytic dy/dv0 (3, 3) (s, s, s^2/km) from the variational equations."""
        return np.array(self.evaluate(v0_km_s, partials=True).partials)

    def __call__(self, v0_km_s: ArrayLike) -> np.ndarray:
        """Return y = (B·R km, B·T km, flight time s) for an injection velocity (km/s)."""
        return np.array(self.evaluate(v0_km_s).y)


#: How the first nominal case of a search is chosen (:attr:`BPlaneSearch.first_guess`).
FIRST_GUESSES = ("injection", "conic")


@dataclass(frozen=True, slots=True)
class BPlaneSearch:
    """A complete B-plane targeting problem: the program, the start and SEARCH's inputs.

    Arrays have shape (3,), in the order of :data:`X_NAMES` (km/s) and :data:`Y_NAMES`
    (km, km, s). ``target_increments`` are SEARCH's theta (y_T = y_0 + theta where != 0).
    The search is n by n over ``vary`` (indices into :data:`X_NAMES`: the velocity components
    SEARCH moves; the others keep their value of ``v0_km_s``) and ``targeted`` (indices into
    :data:`Y_NAMES`); the entries of the arrays outside them are not used. ``first_guess`` is
    "injection" (the first nominal case is ``v0_km_s``, as in the seed) or "conic" (the
    patched-conic velocity of :func:`patched_conic_guess`, with ``v0_km_s`` giving only the
    direction of motion).
    """

    program: BPlaneProgram
    v0_km_s: np.ndarray
    targets: np.ndarray
    target_increments: np.ndarray
    tolerances: np.ndarray
    increments: np.ndarray
    iterations_per_partials: int = 3
    partial_sets: int = 3
    analytic_partials: bool = False
    broyden: bool = False
    step_halving: bool = False
    vary: tuple[int, ...] = (0, 1, 2)
    targeted: tuple[int, ...] = (0, 1, 2)
    first_guess: str = "injection"

    def __post_init__(self) -> None:
        for name, values in (("vary", self.vary), ("targeted", self.targeted)):
            if len(set(values)) != len(values) or not set(values) <= {0, 1, 2}:
                raise InputError("targeting", name, "distinct indices among 0, 1, 2", values)
        if len(self.vary) != len(self.targeted):
            raise InputError("targeting", "vary", f"one varied component per targeted quantity "
                             f"({len(self.targeted)})", self.vary)
        if self.first_guess not in FIRST_GUESSES:
            raise InputError("targeting", "first_guess", f"one of {FIRST_GUESSES}",
                             self.first_guess)
        if self.first_guess == "conic" and np.any(self.target_increments[list(self.targeted)]):
            raise InputError("targeting", "target_increments", "none with a conic first guess "
                             "(theta is relative to the first case, which the conic sets)",
                             self.target_increments)

    @property
    def x_names(self) -> tuple[str, ...]:
        """Names of the independent variables searched."""
        return tuple(X_NAMES[i] for i in self.vary)

    @property
    def y_names(self) -> tuple[str, ...]:
        """Names of the dependent variables targeted."""
        return tuple(Y_NAMES[i] for i in self.targeted)

    def start_km_s(self) -> np.ndarray:
        """The injection velocity (3,) of the first nominal case, km/s (``first_guess``)."""
        if self.first_guess == "injection":
            return np.array(self.v0_km_s, dtype=np.float64)
        arrival_s = (float(self.targets[2]) if 2 in self.targeted
                     else self.program.closest_approach(self.v0_km_s).t_s)
        return patched_conic_guess(self.program, float(self.targets[0]),
                                   float(self.targets[1]), arrival_s,
                                   np.cross(self.program.r0_km, self.v0_km_s))


class FirstGuessError(TappError):
    """The patched-conic first guess cannot be formed (the geometry is degenerate)."""


def patched_conic_guess(program: BPlaneProgram, b_dot_r_km: float, b_dot_t_km: float,
                        arrival_s: float, pole: ArrayLike) -> np.ndarray:
    r"""Return the injection velocity (3,), km/s, of the patched conic through the aim point.

    The central body's two-body conic (:func:`tapp.orbit.lambert`, prograde about ``pole``)
    from the injection position to the target's centre at ``arrival_s`` gives the arrival
    velocity relative to the target, taken as the incoming asymptote :math:`\hat S`; the
    B-plane axes :math:`\hat T, \hat R` follow from it and the program's reference plane
    (:func:`tapp.orbit.bplane.b_plane`). A second conic to the aim point
    :math:`\mathbf r_b + (B\cdot T)\,\hat T + (B\cdot R)\,\hat R` gives the velocity
    returned: the patched-conic B vector is the miss of the asymptote, which the target's
    gravity then bends into the hyperbola whose B-plane point this is (seed TM 33-203,
    section II: the first partials or initial values may come from "a conic").

    Raises
    ------
    FirstGuessError
        The target at arrival is collinear with the injection position (a transfer of half a
        revolution has no plane): start from the injection instead.
    """
    r0, gm = program.r0_km, program.propagator.state_model.gm_center_km3_s2
    body = program.target_state(np.array([arrival_s]))[0][0]
    try:
        arrival = lambert(r0, body[:3], arrival_s, gm, pole=pole)[1]
        s_hat = (arrival - body[3:]) / np.linalg.norm(arrival - body[3:])
        t_hat = np.cross(s_hat, program.reference_pole(arrival_s)[0])
        t_hat /= np.linalg.norm(t_hat)
        aim = body[:3] + b_dot_t_km * t_hat + b_dot_r_km * np.cross(s_hat, t_hat)
        return lambert(r0, aim, arrival_s, gm, pole=pole)[0]
    except InputError as exc:
        raise FirstGuessError(
            f"no patched-conic first guess to the {program.target} at t = {arrival_s:.0f} s: "
            f"{exc.field}: expected {exc.expected} (got {exc.got}); start from the injection "
            "(first_guess = \"injection\")") from exc


@dataclass(frozen=True, slots=True)
class TargetingRun:
    """What :func:`run_search` returns.

    Attributes
    ----------
    result : SearchResult
        SEARCH's outcome and history.
    encounter : Encounter
        The evaluation at ``result.x`` (periapsis radius, v_inf, ...).
    propagations : int
        Numerical integrations run by all cases (scan + periapsis steps; analytic partials
        ride on the cases' own integrations).
    start_km_s : numpy.ndarray, shape (3,)
        The injection velocity of the first nominal case (:meth:`BPlaneSearch.start_km_s`).
    """

    result: SearchResult
    encounter: Encounter
    propagations: int
    start_km_s: np.ndarray

    @property
    def trajectories(self) -> int:
        """Trajectories flown (cases run by SEARCH, one trajectory each)."""
        return self.result.n_cases


def run_search(problem: BPlaneSearch, *, analytic_partials: bool | None = None) -> TargetingRun:
    """Target the injection velocity to (B·R, B·T, t_f) with SEARCH.

    Parameters
    ----------
    problem : BPlaneSearch
        Program, start and SEARCH inputs.
    analytic_partials : bool, optional
        Override ``problem.analytic_partials``. When on, every case integrates the STM and
        every set of partials is the analytic dy/dv0 at its nominal point (no perturbed case).

    Returns
    -------
    TargetingRun

    Raises
    ------
    FailedCaseError
        A case missed the target, was not hyperbolic there, or could not be integrated (see
        the module docstring for why the search stops there).
    FirstGuessError
        A conic first guess that cannot be formed (:func:`patched_conic_guess`).
    """
    program = problem.program
    analytic = problem.analytic_partials if analytic_partials is None else analytic_partials
    start = problem.start_km_s()
    cols, rows = list(problem.vary), list(problem.targeted)
    encounters: dict[bytes, Encounter] = {}
    counts = {"cases": 0, "propagations": 0}

    def evaluate(x: np.ndarray, case: int) -> Encounter:
        v0 = start.copy()
        v0[cols] = x
        key = v0.tobytes()
        if key not in encounters:
            try:
                encounters[key] = program.evaluate(v0, partials=analytic)
            except (NotHyperbolicError, PropagationError, DivergenceError) as exc:
                raise FailedCaseError(case, v0, exc) from exc
            counts["propagations"] += encounters[key].propagations
        return encounters[key]

    def f(x: np.ndarray) -> np.ndarray:
        counts["cases"] += 1  # search.solve runs f exactly once per case, in case order
        return np.array(evaluate(x, counts["cases"]).y[rows])

    def partials(x: np.ndarray) -> np.ndarray:
        # The nominal of a set has always just been run at this very x: a cache hit.
        return np.array(evaluate(x, counts["cases"]).partials[np.ix_(rows, cols)])

    result = solve(
        f,
        start[cols],
        problem.targets[rows],
        tolerances=problem.tolerances[rows],
        increments=problem.increments[cols],
        iterations_per_partials=problem.iterations_per_partials,
        partial_sets=problem.partial_sets,
        target_increments=problem.target_increments[rows],
        partials=partials if analytic else None,
        broyden=problem.broyden,
        step_halving=problem.step_halving,
    )
    final = evaluate(result.x, result.n_cases)
    return TargetingRun(result=result, encounter=final, propagations=counts["propagations"],
                        start_km_s=frozen_array(start))

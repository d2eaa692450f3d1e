"""Propagation of a state with its STM and parameter sensitivities on a time grid.

The caller names two force models: ``state_model`` moves the trajectory, ``var_model``
drives Φ(t, t0) and S(t) = ∂x(t)/∂q (see :mod:`tapp.dynamics.equations`). Integration runs
in compiled code (CasADi-generated C under a driver, :mod:`tapp.dynamics.compiled`), never a
Python callback per step. Two methods (:data:`METHODS`):

- ``"dop853"`` (default): Dormand-Prince 8(5,3) on x' = f(t, x), with its 7th-order dense
  output; any force model.
- ``"rkn12"``: the Runge-Kutta-Nyström 12(10) pair of Dormand, El-Mikkawy & Prince (1987) on
  the second-order form r'' = a(t, r) and Φ_r'' = (∂a/∂r) Φ_r, with outputs from the
  Hermite polynomial through (r, v, a) at six step ends (eight with Φ). On a LEO day at
  1e-12, 4x fewer right-hand-side evaluations than DOP853 (about 2900 accelerations against
  12000 derivatives with the dense-output stages), each on half the components. Only for
  models without velocity-dependent forces
  (:func:`tapp.dynamics.equations.velocity_dependent`); others are refused.

Either way the grid does not constrain the step size, and no step straddles a boundary where
the force model is not smooth (a shadow's edge, a Harris-Priester table height): both drivers
locate these integration events and restart there (:mod:`tapp.dynamics.events`); the
trajectory lists the events it met.

With centre changes (:mod:`tapp.dynamics.centres`) the propagator integrates each interval
between them about that interval's body, and translates the state at each change and every
output back to the model's centre: the caller sees one trajectory about the model's centre.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache

import numpy as np

from tapp.dynamics.centres import (
    CentreChange,
    centre_at,
    check_centre_changes,
    model_about,
    names_about,
)
from tapp.dynamics.compiled import METHODS, STATUS, CompiledPropagator, compiled_propagator
from tapp.dynamics.ephemeris_offsets import offset_values, selector
from tapp.dynamics.equations import (
    Equations,
    build_equations,
    from_second_order,
    initial_augmented,
    second_order,
    split_augmented,
    to_second_order,
    velocity_dependent,
)
from tapp.dynamics.events import Events
from tapp.dynamics.forces import check_parameter_value, default_parameters
from tapp.dynamics.parameters import model_parameter
from tapp.dynamics.poles import pole_table
from tapp.dynamics.spec import ForceModel
from tapp.errors import InputError, TappError
from tapp.estimation.factors import accurate_stacked
from tapp.frames.chebyshev import ChebyshevTable
from tapp.frames.orientation import EarthOrientation


class PropagationError(TappError):
    """The integrator stopped early; the message gives the status and the time reached."""


#: Accepted integrator tolerances (rtol and atol, km and km/s), inclusive. Above 1e-6 the
#: answer is no longer an orbit: a day of a 7000 km, e = 0.01 two-body orbit drifts 0.7 km at
#: 1e-6, 11 km at 1e-5 and 2.4e6 km at 1 (against 1e-14). Below 1e-15 the request is under
#: five units in the last place of a double (2.2e-16) and cannot be met by step control.
TOLERANCE_RANGE = (1e-15, 1e-6)


def check_tolerance(value: float, source: str = "propagator", field: str = "rtol") -> float:
    """Return ``value`` as a float if it lies in :data:`TOLERANCE_RANGE`, else raise.

    Raises
    ------
    InputError
        Naming ``source`` and ``field``, the value and the range (a non-number, NaN or
        infinity included).
    """
    lo, hi = TOLERANCE_RANGE
    ok = (isinstance(value, int | float | np.floating) and not isinstance(value, bool)
          and lo <= value <= hi)
    if not ok:
        raise InputError(source, field, f"an integrator tolerance in [{lo:g}, {hi:g}] (looser "
                         "than 1e-6 drifts by km per day; tighter than 1e-15 is below double "
                         "precision)", value)
    return float(value)


@dataclass(frozen=True, slots=True)
class Trajectory:
    """States and partials on a time grid (time-major arrays).

    Attributes
    ----------
    t_s : (N,) seconds from the epoch.
    states : (N, 6) position (km) and velocity (km/s), inertial axes, relative to the centre.
    stm : (N, 6, 6) or None, Φ(t_k, t0).
    sensitivity : (N, 6, n_q) or None, ∂x(t_k)/∂q for the parameters ``params``.
    params : names of q, in column order of ``sensitivity``.
    steps : accepted integration steps; ``rhs_evaluations`` : right-hand-side calls.
    events : the integration events met from t0 to the last output (shadow boundaries, table
        heights), in the order met.
    """

    t_s: np.ndarray
    states: np.ndarray
    stm: np.ndarray | None
    sensitivity: np.ndarray | None
    params: tuple[str, ...]
    steps: int
    rhs_evaluations: int
    events: Events = field(default_factory=Events.none)


@cache
def _equations(state_model: ForceModel, var_model: ForceModel, params: tuple[str, ...]
               ) -> Equations:
    return build_equations(state_model, var_model, params)


@cache
def _velocity_dependent(state_model: ForceModel, var_model: ForceModel,
                        params: tuple[str, ...]) -> bool:
    return velocity_dependent(_equations(state_model, var_model, params))


@cache
def _compiled(state_model: ForceModel, var_model: ForceModel, params: tuple[str, ...],
              method: str) -> tuple[Equations, CompiledPropagator]:
    eqs = _equations(state_model, var_model, params)
    driven = second_order(eqs) if method == "rkn12" else eqs
    return eqs, compiled_propagator(driven.f_state, driven.f_var, driven.f_event, method)


@dataclass(frozen=True, slots=True)
class Propagator:
    """A (state model, variational model, parameters) triple with integrator settings.

    Parameters
    ----------
    state_model, var_model : ForceModel
        ``var_model`` defaults to ``state_model`` (exact variational equations).
    params : names of the model parameters whose sensitivities are wanted (see
        :mod:`tapp.dynamics.forces`), held in their one spelling
        (:mod:`tapp.dynamics.parameters`; an earlier one is read with a warning).
    rtol, atol : relative and absolute (km, km/s) local error tolerances, each within
        :data:`TOLERANCE_RANGE` = [1e-15, 1e-6]. The default
        1e-13 keeps a day of an e = 0.3 orbit within 1 mm of the Kepler solution (1e-12
        gives 8 mm there; a tolerance is no proof of accuracy, see the tests).
    error_control : ``"state"`` controls the step on the 6 state components only;
        ``"all"`` includes Φ and S.
    max_steps : cap on integration steps per call.
    method : ``"dop853"`` (default) or ``"rkn12"`` (see the module docstring); ``"rkn12"``
        refuses a model whose acceleration depends on velocity.
    centre_changes : changes of the integration centre, ascending in time
        (:func:`tapp.dynamics.centres.check_centre_changes`); every input and output stays
        about the models' centre.
    """

    state_model: ForceModel
    var_model: ForceModel | None = None
    params: tuple[str, ...] = ()
    rtol: float = 1e-13
    atol: float = 1e-13
    error_control: str = "state"
    max_steps: int = 10_000_000
    method: str = "dop853"
    centre_changes: tuple[CentreChange, ...] = ()
    _nominal: dict[str, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.var_model is None:
            object.__setattr__(self, "var_model", self.state_model)
        for name in ("rtol", "atol"):
            check_tolerance(getattr(self, name), "propagator", name)
        if self.error_control not in ("state", "all"):
            raise InputError("propagator", "error_control", "'state' or 'all'",
                             self.error_control)
        if self.method not in METHODS:
            raise InputError("propagator", "method", f"one of {', '.join(METHODS)}",
                             self.method)
        nominal = default_parameters(self.state_model, tuple(
            getattr(model_parameter(name, "propagator", f"params[{i}]"), "canonical", name)
            for i, name in enumerate(self.params)))
        if len(nominal) != len(self.params):
            raise InputError("propagator", "params", "each parameter once", self.params)
        object.__setattr__(self, "params", tuple(nominal))
        object.__setattr__(self, "_nominal", nominal)
        if self.method == "rkn12" and _velocity_dependent(self.state_model, self.var_model,
                                                          self.params):
            raise InputError("propagator", "method", "'dop853' for a model with velocity-"
                             "dependent forces ('rkn12' integrates r'' = a(t, r) only)",
                             self.method)
        object.__setattr__(self, "centre_changes", check_centre_changes(
            self.centre_changes, self.state_model, self.var_model, self.params))

    def compiled(self) -> tuple[Equations, CompiledPropagator]:
        """Build (or fetch from the cache) the equations and the compiled library."""
        return _compiled(self.state_model, self.var_model, self.params, self.method)

    def propagate(self, x0: np.ndarray, t_s: np.ndarray, *, t0_s: float = 0.0,
                  stm: bool = True, param_values: Mapping[str, float] | None = None,
                  theta0_rad: float = 0.0, epoch_jd_utc: float | None = None,
                  orientation: EarthOrientation | None = None) -> Trajectory:
        """Integrate from (t0_s, x0) to every time in ``t_s``.

        Parameters
        ----------
        x0 : (6,) km, km/s, inertial, relative to the model's centre.
        t_s : (N,) output times, seconds from the epoch, monotonic away from t0_s.
        stm : integrate Φ and S too (else only the state, with ``state_model``).
        param_values : values of ``params`` other than their nominal ones.
        theta0_rad : Earth rotation angle at the epoch (GMST), used by gmst tesseral fields
            when no ``orientation`` is given.
        epoch_jd_utc : UTC Julian date of t = 0; required when third bodies are present.
        orientation : the scenario's Earth orientation; required by an iau2006 model with a
            field (its angle replaces ``theta0_rad``; with third bodies and centre changes the
            ephemeris is read at its TDB).

        Raises
        ------
        InputError
            Non-finite x0 or times, times not monotonic, unknown parameter names, a
            non-finite parameter value or a GM <= 0.
        PropagationError
            The integrator stopped early (see ``tapp.dynamics.compiled.STATUS``).
        """
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (6,) or not np.isfinite(x0).all():
            raise InputError("propagate", "state", "6 finite numbers (km, km/s)", x0.tolist())
        t_s = np.atleast_1d(np.asarray(t_s, dtype=float))
        if t_s.size == 0 or not np.isfinite(t_s).all():
            raise InputError("propagate", "times", "a non-empty grid of finite times", None)
        steps = np.empty_like(t_s)  # t_s - (t0_s, t_s[:-1]), without np.diff's overhead
        steps[0] = t_s[0] - t0_s
        np.subtract(t_s[1:], t_s[:-1], out=steps[1:])
        if not (steps.min() >= 0 or steps.max() <= 0):
            raise InputError("propagate", "times", "times monotonic away from t0", None)
        values = dict(self._nominal)
        for given, value in (param_values or {}).items():
            found = model_parameter(given, "propagate", "param_values")
            name = given if found is None else found.canonical
            if name not in values:
                raise InputError("propagate", "param_values", f"one of {self.params}", name)
            values[name] = check_parameter_value(name, value, "propagate",
                                                 f"param_values.{name}")
        pieces = self._centre_pieces(t0_s, float(t_s[-1]))
        if len(pieces) > 1 or pieces[0][2] != self.state_model.center:
            return self._across_centres(pieces, x0, t_s, stm, values, theta0_rad,
                                        epoch_jd_utc, orientation)
        eqs, lib = self.compiled()
        q = np.array([values[name] for name in self.params])
        if orientation is not None:
            if self.state_model.gravity.degree >= 2 and self.state_model.center == "earth" \
                    and orientation.model != self.state_model.earth_orientation:
                raise InputError("propagate", "orientation", f"the force model's Earth "
                                 f"orientation {self.state_model.earth_orientation!r}",
                                 orientation.model)
            theta0_rad = orientation.theta0_rad
        table = self._series(eqs, epoch_jd_utc, orientation, t0_s, t_s)
        y0 = initial_augmented(x0, len(self.params)) if stm else x0
        n_err = 6 if self.error_control == "state" or not stm else y0.size
        nystrom = self.method == "rkn12" and stm  # x alone is already [z, z'] = [r, v]
        if nystrom:
            y0 = to_second_order(y0)
        if self.method == "rkn12":  # the norm counts components of z and of z' alike
            n_err //= 2
        status, y, stats, log = lib.integrate(1 if stm else 0, y0, t0_s, t_s, q,
                                              np.array([theta0_rad]), table, self.rtol,
                                              self.atol, n_err, self.max_steps, len(eqs.events))
        if nystrom:
            y = from_second_order(y)
        if status != 0:
            raise PropagationError(f"propagation stopped: {STATUS.get(status, status)} after "
                                   f"{int(stats[0])} steps")
        if stm:
            states, phi, sens = split_augmented(y, len(self.params))
        else:
            states, phi, sens = y, None, None
        events = Events(log.t_s, tuple(eqs.events[i] for i in log.index), log.falling)
        return Trajectory(t_s, states, phi, sens, self.params, int(stats[0]), int(stats[2]),
                          events)

    def _centre_pieces(self, t0_s: float, t_end_s: float) -> list[tuple[float, float, str]]:
        """(start, end, centre) of each interval from ``t0_s`` to ``t_end_s`` between the
        centre changes strictly inside, in the direction of integration."""
        inside = [c.t_s for c in self.centre_changes
                  if min(t0_s, t_end_s) < c.t_s < max(t0_s, t_end_s)]
        cuts = [t0_s, *(inside if t_end_s >= t0_s else inside[::-1]), t_end_s]
        return [(a, b, centre_at(self.centre_changes, self.state_model.center, 0.5 * (a + b)))
                for a, b in zip(cuts[:-1], cuts[1:], strict=True)]

    def _across_centres(self, pieces: list[tuple[float, float, str]], x0: np.ndarray,
                        t_s: np.ndarray, stm: bool, values: dict[str, float],
                        theta0_rad: float, epoch_jd_utc: float | None,
                        orientation: EarthOrientation | None) -> Trajectory:
        """Propagate interval by interval about each one's centre (module docstring of
        :mod:`tapp.dynamics.centres`): translate the state in at each start, the outputs back
        to the model's centre, and compose Φ and S across the changes."""
        from tapp.dynamics.ephemeris import relative_state, tdb_reader  # jplephem, on first use

        if epoch_jd_utc is None and orientation is None:
            raise InputError("propagate", "epoch", "an epoch (UTC) for the ephemeris of the "
                             "centre changes", None)
        tdb = tdb_reader(epoch_jd_utc, None if orientation is None else orientation.scales)
        center = self.state_model.center

        def offset(centre: str, times: np.ndarray) -> np.ndarray:
            """States (n, 6) of ``centre`` relative to the model's centre at ``times``, its
            ephemeris offset added (:mod:`tapp.dynamics.ephemeris_offsets`)."""
            if centre == center:
                return np.zeros((times.size, 6))
            moved = relative_state(centre, center, *tdb(times))
            moved[:, :3] += offset_values(values, centre)
            return moved

        x_model, n_q = x0, len(self.params)
        phi0, s0 = np.eye(6), np.zeros((6, n_q))
        parts: dict[str, list] = {"states": [], "stm": [], "sensitivity": []}
        events, steps, rhs = [], 0, 0
        sign = 1.0 if t_s[-1] >= pieces[0][0] else -1.0
        for i, (a, b, centre) in enumerate(pieces):
            prop = _about(self, centre)
            names = names_about(self.params, self.state_model, centre)
            u = sign * t_s
            take = ((u >= sign * a) if i == 0 else (u > sign * a)) & (u <= sign * b)
            grid = np.append(t_s[take], b)
            traj = prop.propagate(
                x_model - offset(centre, np.array([a]))[0], grid, t0_s=a, stm=stm,
                param_values={n: values[p] for p, n in zip(self.params, names, strict=True)
                              if n is not None}, theta0_rad=theta0_rad,
                epoch_jd_utc=epoch_jd_utc, orientation=orientation)
            moved = traj.states + offset(centre, grid)
            parts["states"].append(moved[:-1])
            x_model = moved[-1]
            events.append(traj.events)
            steps, rhs = steps + traj.steps, rhs + traj.rhs_evaluations
            if stm:
                own = np.zeros((grid.size, 6, n_q))
                columns = [j for j, n in enumerate(names) if n is not None]
                own[:, :, columns] = traj.sensitivity
                # the translations by the centre's offset: -E into the interval, +E out
                e = selector(self.params, centre) if centre != center else np.zeros((6, n_q))
                own += e
                s_in = s0 - e
                parts["stm"].append(accurate_stacked(traj.stm[:-1], phi0))
                parts["sensitivity"].append(accurate_stacked(traj.stm[:-1], s_in, own[:-1]))
                phi0 = accurate_stacked(traj.stm[-1:], phi0)[0]
                s0 = accurate_stacked(traj.stm[-1:], s_in, own[-1:])[0]
        out = {key: np.concatenate(value) if value else None for key, value in parts.items()}
        return Trajectory(t_s, out["states"], out["stm"], out["sensitivity"], self.params,
                          steps, rhs, Events.join(events))

    def _series(self, eqs: Equations, epoch_jd_utc: float | None,
                orientation: EarthOrientation | None, t0_s: float, t_s: np.ndarray
                ) -> ChebyshevTable:
        """The driver's table: third-body positions, then the iau2006 slow terms if oriented,
        or the IAU pole of a centre with a J2 (at TDB of ``orientation``'s scales, else
        TDB ≈ TT of ``epoch_jd_utc``, as the ephemeris)."""
        lo, hi = min(t0_s, t_s.min()), max(t0_s, t_s.max())
        table = ChebyshevTable.empty()
        scales = orientation.scales if orientation is not None else None
        origin = None if scales is None else orientation.segment_origin_s  # one grid for both
        if eqs.oriented == "body_pole":
            from tapp.dynamics.ephemeris import tdb_reader  # jplephem, on first use

            if scales is None and epoch_jd_utc is None:
                raise InputError("propagate", "epoch", "an epoch (UTC) for the J2 of centre "
                                 f"{self.state_model.center} (its pole moves)", None)
            table = pole_table(self.state_model.center, tdb_reader(epoch_jd_utc, scales), lo,
                               hi, origin)
            lo, hi = table.t0_s, table.t_end_s  # the same segments for the ephemeris
        elif eqs.oriented:
            if scales is None:
                raise InputError("propagate", "orientation", "the scenario's iau2006 Earth "
                                 "orientation for a model with earth_orientation = 'iau2006'",
                                 None if orientation is None else orientation.model)
            table = orientation.series(lo, hi, eqs.oriented)
            lo, hi = table.t0_s, table.t_end_s  # the same segments for the ephemeris
        if eqs.bodies:
            if epoch_jd_utc is None:
                raise InputError("propagate", "epoch", "an epoch (UTC) when third bodies are "
                                 "modelled", None)
            from tapp.dynamics.ephemeris import chebyshev_table

            table = chebyshev_table(eqs.bodies, self.state_model.center, epoch_jd_utc, lo, hi,
                                    scales=scales, origin_s=origin).stacked(table)
        return table


@cache
def _about(prop: Propagator, centre: str) -> Propagator:
    """The propagator of an interval about ``centre``: ``prop``'s models about it
    (:func:`tapp.dynamics.centres.model_about`), the parameters that have a force there, and no
    centre changes (cached: one compiled model per centre)."""
    names = names_about(prop.params, prop.state_model, centre)
    return dataclasses.replace(prop, state_model=model_about(prop.state_model, centre),
                               var_model=model_about(prop.var_model, centre),
                               params=tuple(n for n in names if n is not None),
                               centre_changes=())

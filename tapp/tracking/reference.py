"""TAPP I's force model fitted to a mission's own trajectory, arc by arc.

A scenario's ``[reference]`` (:class:`tapp.io.trajectory_file.ReferenceTable`) names the
mission's trajectory file. The arcs are the intervals between its boundaries: t = 0 and the
start of every burn of the scenario's ``[[manoeuvre]]`` tables (an impulsive burn's time, a
finite burn's ignition; a burn at t = 0 is refused, as it could not be told from the state
there), the last arc ending at the last T13 time. TAPP I flies one continuous trajectory, the
state x₀ at t = 0 and the burns, and the fit makes it match the reference on every arc, in
time order, each arc from the end of the one before:

- arc 1, [0, t₁]: the state x₀;
- an arc that starts with an impulsive burn: its Δv (3, km/s, in the burn's axes at the state
  before it, which the arcs before fixed): x⁺ = x⁻ + [0; M(x⁻) Δv];
- an arc that starts with a finite burn: its thrust acceleration at ignition w = (F/m₀) d
  (3, km/s², in its axes), so its thrust F = m₀|w| and direction d = w/|w|; its ignition,
  duration, mass and mass flow are the scenario's, and are not fitted.

With ``fit_manoeuvres = false`` the burns are flown as the scenario gives them, and the arcs
after them are compared only. The state of an arc's start is never fitted beyond the first:
the trajectory does not jump where the reference does not say a burn is.

On each arc [t_a, t_b] the unknowns u are fitted by least squares to the reference positions
r̃_i at the reference's own times t_i in the arc (an OEM's states, an SPK's samples; a time two
segments share counted once):

.. math::
    \\min_{u} \\sum_i \\lVert \\tilde r_i - r(t_i; u) \\rVert^2,

Gauss-Newton from the reference state at t = 0 (arc 1) or the scenario's own burn, with the
scenario's propagator (its state model moves the orbit; the rows ∂r(t_i)/∂u come from its
variational model: [I 0] Φ(t_i, t_a) for x₀, [I 0] Φ(t_i, t_a) ∂x⁺/∂Δv for an impulsive burn,
[I 0] ∂x(t_i)/∂w from the thrust's sensitivities, carried past the cut-off by Φ, for a finite
one; a truncated variational model only slows the convergence), the columns scaled to unit
norm, and the step halved (up to :data:`MAX_HALVINGS` times) while it does not lower the sum.
It stops when the Gauss-Newton step would move each unknown by less than its tolerance
(:data:`STEP_TOL_KM`, :data:`STEP_TOL_KM_S`; a thrust acceleration by
:data:`STEP_TOL_KM_S` over the burn's duration), or lowers the RMS by less than
:data:`RMS_FLOOR` of it, or no halved step lowers the sum, or after :data:`MAX_ITERATIONS`.
On a long chaotic arc the sum has a floor of its own: the integrator's step sequence changes
with the state, and its rtol-sized differences grow through a swing-by (deep_space.toml read
back from its own SPK: 0.27 mm RMS over 30 days, where the injection it was written from
gives 0.17 µm).

The fit is reported per arc: what was fitted (the fitted value beside the scenario's for a
burn), the RMS and the largest of |r̃_i − r(t_i)| over the arc's reference states and when it
occurs. When the largest difference of any arc exceeds the scenario's ``max_fit_error_m``,
:func:`fitted` refuses (:class:`PoorFitError`, exit 2, naming the arc) unless told to accept
it (``tapp simulate --force``): a covariance about another trajectory is not the mission's.
Otherwise the scenario's injection becomes the fitted x₀ and its burns the fitted ones, and
TAPP I flies that: the nominal of its observables, partials and variational equations, and
of the burns' execution errors (Gates' proportional σ scale the fitted |Δv|).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tapp.dynamics import PropagationError, Propagator
from tapp.dynamics.manoeuvres import Burn, FiniteBurn, ImpulsiveBurn, impulse
from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.io.trajectory_file import Reference, ReferenceTrajectory
from tapp.tracking.pieces import Forcing

if TYPE_CHECKING:
    from tapp.tracking.scenario import Scenario

#: Gauss-Newton stops when a step moves the state by less than this (1 µm, 1 nm/s) ...
STEP_TOL_KM = 1e-9
STEP_TOL_KM_S = 1e-12
#: ... or lowers the RMS by less than this fraction of it (the fit has reached its floor) ...
RMS_FLOOR = 1e-6
#: ... or after this many iterations (a converging fit takes 2 to 5).
MAX_ITERATIONS = 20
#: Halvings of a step that raises the sum before the fit stops (a step 256 times shorter than
#: Gauss-Newton's that still raises it meets the sum's own noise).
MAX_HALVINGS = 8
#: What an arc fits (:attr:`ArcFit.fitted`), with its unit.
FITTED = {"state": "km, km/s", "dv_km_s": "km/s", "thrust_km_s2": "km/s^2", "none": ""}


class PoorFitError(InputError):
    """The force model does not fit the reference within ``max_fit_error_m`` (exit 2)."""


@dataclass(frozen=True, slots=True)
class ArcFit:
    """The fit on one arc.

    Attributes
    ----------
    t_start_s, t_end_s : the arc, s from the epoch.
    x0 : (6,) the flown state at ``t_start_s`` (after an impulsive burn there), km, km/s
        (scenario frame, Earth-centred).
    x0_reference : (6,) the reference's state there.
    points : reference states compared.
    rms_m, max_m : RMS and largest position difference, m; ``t_max_s`` when the largest is.
    iterations : Gauss-Newton iterations; ``converged`` : a stopping rule other than the cap.
    burn : the name of the burn the arc starts with (None for the first arc).
    fitted : what was fitted (:data:`FITTED`): ``"state"`` (x₀, the first arc), ``"dv_km_s"``
        (an impulsive burn's Δv), ``"thrust_km_s2"`` (a finite burn's w), ``"none"``.
    value, given : (n,) the fitted unknowns and the first guess (the reference's state, the
        scenario's Δv or w), in the burn's axes.
    """

    t_start_s: float
    t_end_s: float
    x0: np.ndarray
    x0_reference: np.ndarray
    points: int
    rms_m: float
    max_m: float
    t_max_s: float
    iterations: int
    converged: bool
    burn: str | None = None
    fitted: str = "state"
    value: np.ndarray | None = None
    given: np.ndarray | None = None

    @property
    def fits_burn(self) -> bool:
        """Whether the arc fitted its burn."""
        return self.fitted in ("dv_km_s", "thrust_km_s2")

    def burn_text(self) -> str:
        """What became of the arc's burn: '' for the first arc, else its fitted value beside
        the scenario's (Δv in m/s, w in mm/s²), or that it was flown as given."""
        if self.burn is None:
            return ""
        if not self.fits_burn:
            return f", after {self.burn} (flown as given)"
        scale, unit = (1e3, "m/s") if self.fitted == "dv_km_s" else (1e6, "mm/s^2")
        what = "dv" if self.fitted == "dv_km_s" else "thrust acceleration"

        def vector(v: np.ndarray) -> str:
            return "[" + ", ".join(f"{scale * x:.9g}" for x in v) + "]"

        return (f", after {self.burn}: {what} fitted {vector(self.value)} {unit} (the scenario "
                f"gives {vector(self.given)})")


@dataclass(frozen=True, slots=True)
class ReferenceFit:
    """The fit of the force model to a reference, arc by arc.

    Attributes
    ----------
    trajectory : the reference as read.
    max_fit_error_m : the scenario's limit on the largest position difference, m.
    arcs : one :class:`ArcFit` per arc, in time order.
    forced : True when a fit worse than the limit was accepted (``--force``).
    burns : the burns as fitted, in time order (the scenario's where not fitted), which
        :func:`fitted` flies; ``given_burns`` the scenario's.
    """

    trajectory: ReferenceTrajectory
    max_fit_error_m: float
    arcs: tuple[ArcFit, ...]
    forced: bool = False
    burns: tuple[Burn, ...] = ()
    given_burns: tuple[Burn, ...] = ()

    @property
    def worst(self) -> ArcFit:
        """The arc with the largest position difference."""
        return max(self.arcs, key=lambda a: a.max_m)

    @property
    def within_limit(self) -> bool:
        """Whether every arc's largest difference is within ``max_fit_error_m``."""
        return self.worst.max_m <= self.max_fit_error_m

    def arc_text(self, arc: ArcFit, epoch: Epoch) -> str:
        """``arc K (after NAME) from <UTC> to <UTC> UTC``, naming an arc in messages."""
        k = self.arcs.index(arc) + 1
        after = "" if arc.burn is None else f" (after {arc.burn})"
        return (f"arc {k}{after} from {epoch.iso_after(arc.t_start_s, 3)} to "
                f"{epoch.iso_after(arc.t_end_s, 3)} UTC")

    def lines(self, epoch: Epoch) -> tuple[str, ...]:
        """Lines that say what was fitted and how well (the report, OEM and SPK comments)."""
        tr = self.trajectory
        out = [f"Fitted to the reference {tr.source} ({tr.kind}, object {tr.body}); "
               f"{'; '.join(tr.notes)}. Limit {self.max_fit_error_m:g} m (largest position "
               "difference)" + (": exceeded, accepted by --force." if self.forced else ".")]
        for k, a in enumerate(self.arcs, start=1):
            out.append(f"Arc {k} {epoch.iso_after(a.t_start_s, 3)} to "
                       f"{epoch.iso_after(a.t_end_s, 3)} UTC{a.burn_text()}: {a.points} "
                       f"reference states, RMS {a.rms_m:.4g} m, largest {a.max_m:.4g} m at "
                       f"{epoch.iso_after(a.t_max_s, 3)} UTC, {a.iterations} iterations"
                       + ("" if a.converged else " (iteration cap reached)"))
        return tuple(out)

    def to_json(self, epoch: Epoch) -> dict:
        """The fit as JSON: the file, the limit, and per arc its span, the burn it starts with,
        what was fitted (``fitted``, the ``value`` beside the ``given`` first guess, in
        ``unit``), RMS, largest difference (m), the flown and reference states at
        its start (km, km/s)."""
        tr = self.trajectory
        return {"file": tr.source, "kind": tr.kind, "object": tr.body, "notes": list(tr.notes),
                "max_fit_error_m": self.max_fit_error_m, "forced": self.forced,
                "arcs": [{"t_start_s": a.t_start_s, "t_end_s": a.t_end_s,
                          "start_utc": epoch.iso_after(a.t_start_s, 6),
                          "end_utc": epoch.iso_after(a.t_end_s, 6), "burn": a.burn,
                          "fitted": a.fitted, "unit": FITTED[a.fitted],
                          "value": None if a.value is None else a.value.tolist(),
                          "given": None if a.given is None else a.given.tolist(),
                          "points": a.points, "rms_m": a.rms_m, "max_m": a.max_m,
                          "t_max_s": a.t_max_s, "max_utc": epoch.iso_after(a.t_max_s, 6),
                          "iterations": a.iterations, "converged": a.converged,
                          "x0_km_km_s": a.x0.tolist(),
                          "x0_reference_km_km_s": a.x0_reference.tolist()}
                         for a in self.arcs]}


#: How an arc's states depend on its unknowns u: (u, t (N,) ascending from the arc's start
#: t_a) -> (states (N, 6), ∂r/∂u (N, 3, n)).
Flight = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def _propagate(scenario: Scenario, prop: Propagator, x: np.ndarray, t: np.ndarray,
               t_a: float, values: dict | None = None):
    return prop.propagate(x, t, t0_s=t_a, stm=True,
                          param_values=dict(scenario.dynamic_values) if values is None
                          else values, orientation=scenario.orientation,
                          epoch_jd_utc=scenario.epoch.jd)


def _state_flight(scenario: Scenario, prop: Propagator, t_a: float) -> Flight:
    """The first arc: u = the state at t_a."""
    def flight(u: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        traj = _propagate(scenario, prop, u, t, t_a)
        return traj.states, traj.stm[:, :3, :]
    return flight


def _impulsive_flight(scenario: Scenario, prop: Propagator, burn: ImpulsiveBurn,
                      x_before: np.ndarray) -> Flight:
    """An arc after an impulsive burn at its start: u = Δv (km/s, burn axes) added to the
    state ``x_before`` there."""
    jump = impulse(burn.axes)

    def flight(u: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dx, _, ddx_du = (np.asarray(m) for m in jump(x_before, u))
        traj = _propagate(scenario, prop, x_before + dx[:, 0], t, burn.t_s)
        return traj.states, traj.stm[:, :3, :] @ ddx_du
    return flight


def _finite_flight(scenario: Scenario, prop: Propagator, burn: FiniteBurn,
                   x_before: np.ndarray) -> Flight:
    """An arc from a finite burn's ignition (state ``x_before``): u = its thrust acceleration
    at ignition w (km/s², burn axes), its partials from the thrust's sensitivities, carried
    past the cut-off by Φ."""
    names = burn.thrust_parameters()[:3]  # w's parameters

    def flight(u: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        seg_prop, values, _, _ = Forcing(None, (burn.with_thrust(u),)).segment(
            prop, dict(scenario.dynamic_values), burn.t_start_s, differentiate=False)
        during = t <= burn.t_end_s
        grid = np.unique(np.append(t[during], burn.t_end_s))
        thrust = _propagate(scenario, seg_prop, x_before, grid, burn.t_start_s, values)
        columns = [seg_prop.params.index(n) for n in names]
        s_w = thrust.sensitivity[:, :, columns]
        keep = np.isin(grid, t[during])
        states, rows = [thrust.states[keep]], [s_w[keep, :3, :]]
        if not during.all():
            coast = _propagate(scenario, prop, thrust.states[-1], t[~during], burn.t_end_s)
            states.append(coast.states)
            rows.append(coast.stm[:, :3, :] @ s_w[-1])
        return np.concatenate(states), np.concatenate(rows)
    return flight


def _cost(dr: np.ndarray) -> float:
    return float(np.sum(dr * dr))


def _gauss_newton(flight: Flight, u0: np.ndarray, tol: np.ndarray, t: np.ndarray,
                  at: np.ndarray, r_ref: np.ndarray, iterate: bool
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, bool]:
    """Fit u to the positions ``r_ref`` (M, 3) at ``t[at]`` (t (N,) ascending: module
    docstring); return (u, states at t (N, 6), r_ref − r (M, 3), iterations, whether a
    stopping rule other than the cap stopped it). Without ``iterate``, u0 is evaluated only."""
    def residuals(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        states, rows = flight(u, t)
        return states, r_ref - states[at, :3], rows[at]

    u = np.asarray(u0, dtype=float).copy()
    states, dr, rows = residuals(u)
    cost = _cost(dr)
    converged, iterations = not iterate, 0
    while iterations < MAX_ITERATIONS and not converged:
        iterations += 1
        a = rows.reshape(-1, u.size)
        scale = np.linalg.norm(a, axis=0)
        scale[scale == 0.0] = 1.0
        step = np.linalg.lstsq(a / scale, dr.ravel(), rcond=None)[0] / scale
        small = bool(np.all(np.abs(step) < tol))
        for _ in range(MAX_HALVINGS):
            trial = u + step
            states_new, dr_new, rows_new = residuals(trial)
            cost_new = _cost(dr_new)
            if cost_new <= cost:
                break
            step = 0.5 * step
        else:
            converged = True  # no step lowers the sum: the fit is at its floor
            break
        floor = np.sqrt(cost) - np.sqrt(cost_new) < RMS_FLOOR * np.sqrt(cost)
        u, states, dr, rows, cost = trial, states_new, dr_new, rows_new, cost_new
        converged = small or floor
    return u, states, dr, iterations, converged or iterations < MAX_ITERATIONS


def fit_arc(scenario: Scenario, trajectory: ReferenceTrajectory, t_a: float, t_b: float,
            flight: Flight, u0: np.ndarray, tol: np.ndarray, *, fitted: str = "state",
            burn: str | None = None) -> tuple[ArcFit, np.ndarray]:
    """Fit the unknowns u of ``flight`` (first guess ``u0``, step tolerances ``tol``) to the
    reference's positions in [t_a, t_b] (module docstring); ``fitted`` says what u is
    (:data:`FITTED`; ``"none"``: u0 is flown and compared only). Return the arc's fit and the
    state reached at ``t_b`` (6,).

    Raises
    ------
    InputError
        Fewer than 3 reference states in the arc (3 positions for the 6 unknowns of the
        state), or a propagation that stops during the fit (naming ``reference.file``).
    """
    inside = (trajectory.t_s >= t_a) & (trajectory.t_s <= t_b)
    t, first = np.unique(trajectory.t_s[inside], return_index=True)  # a shared epoch once
    r_ref = trajectory.states[inside, :3][first]
    where = f"{scenario.epoch.iso_after(t_a, 3)} to {scenario.epoch.iso_after(t_b, 3)} UTC"
    if t.size < 3:
        raise InputError(scenario.source, "reference.file", "at least 3 reference states in "
                         f"each arc ({where}" + ("" if burn is None else f", after {burn}")
                         + ")", int(t.size))
    grid = np.unique(np.concatenate([[t_a], t, [t_b]]))
    try:
        u, states, dr, iterations, converged = _gauss_newton(
            flight, u0, tol, grid, np.searchsorted(grid, t), r_ref, iterate=fitted != "none")
    except PropagationError as exc:
        raise InputError(scenario.source, "reference.file", "a trajectory TAPP I's force model "
                         f"can fit (arc {where})", f"the fit's propagation stopped: {exc}"
                         ) from None
    norm_m = 1e3 * np.linalg.norm(dr, axis=1)
    worst = int(np.argmax(norm_m))
    arc = ArcFit(float(t_a), float(t_b), states[0], trajectory.state_at_boundary(t_a),
                 int(t.size), float(np.sqrt(np.mean(norm_m**2))), float(norm_m[worst]),
                 float(t[worst]), iterations, converged, burn, fitted,
                 None if burn is None else u, None if burn is None else np.asarray(u0, float))
    return arc, states[-1]


def _burn_arc(scenario: Scenario, trajectory: ReferenceTrajectory, prop: Propagator,
              burn: Burn, x_before: np.ndarray, t_b: float, fit_burn: bool
              ) -> tuple[ArcFit, np.ndarray, Burn]:
    """Fit the arc [burn's start, t_b] that ``burn`` starts, from the state ``x_before`` (the
    state there before it); return the fit, the state at t_b and the burn as fitted."""
    if isinstance(burn, ImpulsiveBurn):
        flight = _impulsive_flight(scenario, prop, burn, x_before)
        u0, tol, what = np.array(burn.dv_km_s), np.full(3, STEP_TOL_KM_S), "dv_km_s"
    else:
        flight = _finite_flight(scenario, prop, burn, x_before)
        u0, tol = burn.w_km_s2, np.full(3, STEP_TOL_KM_S / burn.duration_s)
        what = "thrust_km_s2"
    arc, x_end = fit_arc(scenario, trajectory, burn.t_start_s, t_b, flight, u0, tol,
                         fitted=what if fit_burn else "none", burn=burn.name)
    if not arc.fits_burn:
        return arc, x_end, burn
    if isinstance(burn, ImpulsiveBurn):
        return arc, x_end, dataclasses.replace(burn, dv_km_s=tuple(map(float, arc.value)))
    return arc, x_end, burn.with_thrust(arc.value)


def fit_reference(scenario: Scenario, reference: Reference) -> ReferenceFit:
    """Fit every arc of the scenario's span to ``reference`` (module docstring): arcs from
    t = 0 and from each burn's start (the boundaries the reference was read at) to the next,
    the last to the last T13 time, each from the state the arcs before reached."""
    tr = reference.trajectory
    given = scenario.manoeuvres
    ends = (*(b.t_start_s for b in given), float(scenario.times.t13_s[-1]))
    prop = scenario.propagator()
    first, x_end = fit_arc(scenario, tr, 0.0, ends[0], _state_flight(scenario, prop, 0.0),
                           tr.state_at_boundary(0.0),
                           np.array([STEP_TOL_KM] * 3 + [STEP_TOL_KM_S] * 3))
    arcs, burns = [first], []
    for burn, t_b in zip(given, ends[1:], strict=True):
        arc, x_end, flown = _burn_arc(scenario, tr, prop, burn, x_end, t_b,
                                      reference.fit_manoeuvres)
        arcs.append(arc)
        burns.append(flown)
    return ReferenceFit(tr, reference.max_fit_error_m, tuple(arcs), burns=tuple(burns),
                        given_burns=given)


def fitted(scenario: Scenario, *, accept_poor_fit: bool = False
           ) -> tuple[Scenario, ReferenceFit | None]:
    """Return the scenario flying the fitted trajectory (x₀ and the burns), and the fit (None
    and the scenario itself without a ``[reference]``).

    Raises
    ------
    PoorFitError
        The largest position difference of some arc exceeds ``max_fit_error_m`` and
        ``accept_poor_fit`` is False (naming ``reference.max_fit_error_m``, the arc and the
        figures).
    """
    if scenario.reference is None:
        return scenario, None
    fit = fit_reference(scenario, scenario.reference)
    if not fit.within_limit:
        if not accept_poor_fit:
            w = fit.worst
            raise PoorFitError(
                scenario.source, "reference.max_fit_error_m",
                f"TAPP I's force model within {fit.max_fit_error_m:g} m of the reference "
                f"{fit.trajectory.source} on every arc (a covariance about another trajectory "
                "is not the mission's; --force accepts it)",
                f"largest {w.max_m:.4g} m at {scenario.epoch.iso_after(w.t_max_s, 3)} UTC, "
                f"RMS {w.rms_m:.4g} m, {fit.arc_text(w, scenario.epoch)}")
        fit = dataclasses.replace(fit, forced=True)
    x0 = fit.arcs[0].x0.copy()
    x0.setflags(write=False)
    return dataclasses.replace(scenario, x0=x0, manoeuvres=fit.burns), fit

"""TAPP I's force model fitted to a mission's own trajectory, arc by arc.

A scenario's ``[reference]`` (:class:`tapp.io.trajectory_file.ReferenceTable`) names the
mission's trajectory file. The arcs are the intervals between its boundaries (the times the
reference was read for: today t = 0 alone, so one arc up to the last T13 time; manoeuvre
times will add boundaries), and on each arc [t_a, t_b] the state x_a at t_a is fitted by
least squares to the reference positions r̃_i at the reference's own times t_i in the arc
(an OEM's states, an SPK's samples):

.. math::
    \\min_{x_a} \\sum_i \\lVert \\tilde r_i - r(t_i; x_a) \\rVert^2,

Gauss-Newton from the reference state at t_a, with the scenario's propagator (its state
model moves the orbit; the rows ∂r(t_i)/∂x_a = [I 0] Φ(t_i, t_a) come from its variational
model, so a truncated one only slows the convergence), the columns scaled to unit norm, and
the step halved (up to :data:`MAX_HALVINGS` times) while it does not lower the sum. It stops
when the Gauss-Newton step would move the state by less than :data:`STEP_TOL_KM` and
:data:`STEP_TOL_KM_S`, or lowers the RMS by less than :data:`RMS_FLOOR` of it, or no halved
step lowers the sum, or after :data:`MAX_ITERATIONS`. On a long chaotic arc the sum has a
floor of its own: the integrator's step sequence changes with the state, and its rtol-sized
differences grow through a swing-by (deep_space.toml read back from its own SPK: 0.27 mm RMS
over 30 days, where the injection it was written from gives 0.17 µm).

The fit is reported per arc: the RMS and the largest of |r̃_i − r(t_i)| over the arc's
reference states and when it occurs. When the largest difference of any arc exceeds the
scenario's ``max_fit_error_m``, :func:`fitted` refuses (:class:`PoorFitError`, exit 2)
unless told to accept it (``tapp simulate --force``): a covariance about another trajectory
is not the mission's. Otherwise the scenario's injection becomes the fitted state of the
first arc, and TAPP I flies that: the nominal of its observables, partials and variational
equations.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tapp.dynamics import PropagationError, Propagator
from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.io.trajectory_file import Reference, ReferenceTrajectory

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


class PoorFitError(InputError):
    """The force model does not fit the reference within ``max_fit_error_m`` (exit 2)."""


@dataclass(frozen=True, slots=True)
class ArcFit:
    """The fit on one arc.

    Attributes
    ----------
    t_start_s, t_end_s : the arc, s from the epoch.
    x0 : (6,) fitted state at ``t_start_s``, km, km/s (scenario frame, Earth-centred).
    x0_reference : (6,) the reference's state there (the first guess).
    points : reference states compared.
    rms_m, max_m : RMS and largest position difference, m; ``t_max_s`` when the largest is.
    iterations : Gauss-Newton iterations; ``converged`` : a stopping rule other than the cap.
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


@dataclass(frozen=True, slots=True)
class ReferenceFit:
    """The fit of the force model to a reference, arc by arc.

    Attributes
    ----------
    trajectory : the reference as read.
    max_fit_error_m : the scenario's limit on the largest position difference, m.
    arcs : one :class:`ArcFit` per arc, in time order.
    forced : True when a fit worse than the limit was accepted (``--force``).
    """

    trajectory: ReferenceTrajectory
    max_fit_error_m: float
    arcs: tuple[ArcFit, ...]
    forced: bool = False

    @property
    def worst(self) -> ArcFit:
        """The arc with the largest position difference."""
        return max(self.arcs, key=lambda a: a.max_m)

    @property
    def within_limit(self) -> bool:
        """Whether every arc's largest difference is within ``max_fit_error_m``."""
        return self.worst.max_m <= self.max_fit_error_m

    def lines(self, epoch: Epoch) -> tuple[str, ...]:
        """Lines that say what was fitted and how well (the report, OEM and SPK comments)."""
        tr = self.trajectory
        out = [f"Fitted to the reference {tr.source} ({tr.kind}, object {tr.body}); "
               f"{'; '.join(tr.notes)}. Limit {self.max_fit_error_m:g} m (largest position "
               "difference)" + (": exceeded, accepted by --force." if self.forced else ".")]
        for k, a in enumerate(self.arcs, start=1):
            out.append(f"Arc {k} {epoch.iso_after(a.t_start_s, 3)} to "
                       f"{epoch.iso_after(a.t_end_s, 3)} UTC: {a.points} reference states, "
                       f"RMS {a.rms_m:.4g} m, largest {a.max_m:.4g} m at "
                       f"{epoch.iso_after(a.t_max_s, 3)} UTC, {a.iterations} iterations"
                       + ("" if a.converged else " (iteration cap reached)"))
        return tuple(out)

    def to_json(self, epoch: Epoch) -> dict:
        """The fit as JSON: the file, the limit, and per arc its span, RMS, largest
        difference (m), the fitted and reference states at its start (km, km/s)."""
        tr = self.trajectory
        return {"file": tr.source, "kind": tr.kind, "object": tr.body, "notes": list(tr.notes),
                "max_fit_error_m": self.max_fit_error_m, "forced": self.forced,
                "arcs": [{"t_start_s": a.t_start_s, "t_end_s": a.t_end_s,
                          "start_utc": epoch.iso_after(a.t_start_s, 6),
                          "end_utc": epoch.iso_after(a.t_end_s, 6), "points": a.points,
                          "rms_m": a.rms_m, "max_m": a.max_m, "t_max_s": a.t_max_s,
                          "max_utc": epoch.iso_after(a.t_max_s, 6),
                          "iterations": a.iterations, "converged": a.converged,
                          "x0_km_km_s": a.x0.tolist(),
                          "x0_reference_km_km_s": a.x0_reference.tolist()}
                         for a in self.arcs]}


def _residuals(prop: Propagator, x: np.ndarray, t_a: float, t: np.ndarray, r_ref: np.ndarray,
               scenario: Scenario, stm: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """Position differences r̃ − r (N, 3) km and, with ``stm``, ∂r/∂x_a (N, 3, 6)."""
    traj = prop.propagate(x, t, t0_s=t_a, stm=stm, param_values=dict(scenario.dynamic_values),
                          orientation=scenario.orientation, epoch_jd_utc=scenario.epoch.jd)
    return r_ref - traj.states[:, :3], None if traj.stm is None else traj.stm[:, :3, :]


def _cost(dr: np.ndarray) -> float:
    return float(np.sum(dr * dr))


def fit_arc(scenario: Scenario, trajectory: ReferenceTrajectory, t_a: float, t_b: float
            ) -> ArcFit:
    """Fit the state at ``t_a`` to the reference's positions in [t_a, t_b] (module docstring).

    Raises
    ------
    InputError
        Fewer than 3 reference states in the arc (3 positions for the 6 unknowns), or a
        propagation that stops during the fit (naming ``reference.file``).
    """
    inside = (trajectory.t_s >= t_a) & (trajectory.t_s <= t_b)
    t, r_ref = trajectory.t_s[inside], trajectory.states[inside, :3]
    if t.size < 3:
        raise InputError(scenario.source, "reference.file", "at least 3 reference states in "
                         f"each arc ({scenario.epoch.iso_after(t_a, 3)} to "
                         f"{scenario.epoch.iso_after(t_b, 3)} UTC)", int(t.size))
    prop = scenario.propagator()
    x = trajectory.state_at_boundary(t_a).copy()
    x_ref = x.copy()
    try:
        dr, rows = _residuals(prop, x, t_a, t, r_ref, scenario, stm=True)
        cost = _cost(dr)
        converged, iterations = False, 0
        while iterations < MAX_ITERATIONS and not converged:
            iterations += 1
            a = rows.reshape(-1, 6)
            scale = np.linalg.norm(a, axis=0)
            scale[scale == 0.0] = 1.0
            step = np.linalg.lstsq(a / scale, dr.ravel(), rcond=None)[0] / scale
            small = (np.abs(step[:3]).max() < STEP_TOL_KM
                     and np.abs(step[3:]).max() < STEP_TOL_KM_S)
            for _ in range(MAX_HALVINGS):
                trial = x + step
                dr_new, rows_new = _residuals(prop, trial, t_a, t, r_ref, scenario, stm=True)
                cost_new = _cost(dr_new)
                if cost_new <= cost:
                    break
                step = 0.5 * step
            else:
                break  # no step lowers the sum: the fit is at its floor
            floor = np.sqrt(cost) - np.sqrt(cost_new) < RMS_FLOOR * np.sqrt(cost)
            x, dr, rows, cost = trial, dr_new, rows_new, cost_new
            converged = small or floor
    except PropagationError as exc:
        raise InputError(scenario.source, "reference.file", "a trajectory TAPP I's force model "
                         f"can fit (arc from {scenario.epoch.iso_after(t_a, 3)} UTC)",
                         f"the fit's propagation stopped: {exc}") from None
    norm_m = 1e3 * np.linalg.norm(dr, axis=1)
    worst = int(np.argmax(norm_m))
    return ArcFit(float(t_a), float(t_b), x, x_ref, int(t.size),
                  float(np.sqrt(np.mean(norm_m**2))), float(norm_m[worst]), float(t[worst]),
                  iterations, converged or iterations < MAX_ITERATIONS)


def fit_reference(scenario: Scenario, reference: Reference) -> ReferenceFit:
    """Fit every arc of the scenario's span to ``reference`` (module docstring): arcs from
    each boundary of the reference to the next, the last to the last T13 time."""
    tr = reference.trajectory
    ends = (*tr.boundaries_s[1:], float(scenario.times.t13_s[-1]))
    arcs = tuple(fit_arc(scenario, tr, float(a), float(b))
                 for a, b in zip(tr.boundaries_s, ends, strict=True))
    return ReferenceFit(tr, reference.max_fit_error_m, arcs)


def fitted(scenario: Scenario, *, accept_poor_fit: bool = False
           ) -> tuple[Scenario, ReferenceFit | None]:
    """Return the scenario flying the fitted trajectory, and the fit (None and the scenario
    itself without a ``[reference]``).

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
                f"RMS {w.rms_m:.4g} m, arc from {scenario.epoch.iso_after(w.t_start_s, 3)} "
                "UTC")
        fit = dataclasses.replace(fit, forced=True)
    x0 = fit.arcs[0].x0.copy()
    x0.setflags(write=False)
    return dataclasses.replace(scenario, x0=x0), fit

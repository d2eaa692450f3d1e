"""Equations of motion and variational equations as CasADi functions.

Two force models: the *state model* moves the trajectory, the *variational model* supplies
the Jacobians that drive the state transition matrix and the parameter sensitivities, both
evaluated on the state model's trajectory (the (J_N, J_M) choice of the approximate-STM study).
With x = (r, v), q the solve-for model parameters:

.. math::
    \\dot x = \\begin{pmatrix} v \\\\ a_N(t, r, v, q) \\end{pmatrix},\\quad
    \\dot\\Phi = A_M \\Phi,\\quad \\dot S = A_M S + B_M,\\qquad
    A_M = \\begin{pmatrix} 0 & I \\\\ \\partial a_M/\\partial r & \\partial a_M/\\partial v
    \\end{pmatrix},\\ B_M = \\begin{pmatrix} 0 \\\\ \\partial a_M/\\partial q \\end{pmatrix},

with Φ(t0) = I and S(t0) = 0, so Φ = ∂x(t)/∂x(t0) and S = ∂x(t)/∂q when M = N. The block
∂a_M/∂v is built only when the variational model has drag (:attr:`ForceModel.drag`) or the
parameters hold a finite burn's thrust in axes that move with the velocity (RIC, VNB:
:mod:`tapp.dynamics.manoeuvres`), the velocity-dependent forces; otherwise it is the zero
block, and the generated code is the same as before drag existed. The empirical accelerations
(:mod:`tapp.dynamics.empirical`) and a finite burn's thrust are added to both models, from
their parameters in q.

Layout of the augmented vector y (length 6 + 36 + 6 n_q): x, then Φ column-major, then S
column-major. Nobody slices it by hand: use :func:`split_augmented`.

Both CasADi functions share the signature ``f(t, y, q, c, rb) -> ydot`` with c = [θ0] (Earth
rotation angle at the epoch, rad) and rb the stacked third-body positions relative to the
centre (km), in the order of :attr:`Equations.bodies` (the third bodies and the Sun and Moon
that SRP and the Harris-Priester atmosphere read, :attr:`ForceModel.ephemeris_bodies`),
followed, when the field is oriented by the iau2006 model (:attr:`Equations.oriented`), by
the series that orient it: the ITRS pole ("pole", 3 entries: enough when every oriented field
is zonal) or the nine slow terms ("full",
:meth:`tapp.frames.orientation.EarthOrientation.slow_terms`), or, for the J2 of another
centre (:attr:`ForceModel.pole_field`), by that body's IAU pole ("body_pole", 3 entries,
:mod:`tapp.dynamics.poles`). The driver evaluates all of rb from one Chebyshev table.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from tapp.dynamics.empirical import empirical_acceleration
from tapp.dynamics.events import boundaries
from tapp.dynamics.forces import acceleration
from tapp.dynamics.manoeuvres import thrust_acceleration, thrust_moves_with_velocity
from tapp.dynamics.spec import ForceModel
from tapp.errors import InputError


@dataclass(frozen=True, slots=True)
class Equations:
    """The pair of CasADi functions of one (state model, variational model, parameters), and
    the event function of both models (:mod:`tapp.dynamics.events`):
    ``f_event(r, v, rb, rbd) -> (g, dg/dt)``, r, v the position and velocity (km, km/s), rb the
    driver's series as for the right-hand sides and rbd their rates (per s), one g per name
    of ``events`` (none: empty outputs)."""

    f_state: ca.Function
    f_var: ca.Function
    f_event: ca.Function
    events: tuple[str, ...]
    bodies: tuple[str, ...]
    params: tuple[str, ...]
    oriented: str = ""

    @property
    def n_aug(self) -> int:
        """Length of the augmented vector: 6 + 36 + 6 n_q."""
        return 42 + 6 * len(self.params)


def build_equations(state_model: ForceModel, var_model: ForceModel,
                    params: tuple[str, ...] = ()) -> Equations:
    """Build the state and augmented right-hand sides of a (state, variational) model pair.

    Raises
    ------
    InputError
        When the two models have different centres or Earth orientation models.
    """
    if state_model.center != var_model.center:
        raise InputError("model", "center", "the same centre for the state and variational "
                         "models", f"{state_model.center} vs {var_model.center}")
    if state_model.earth_orientation != var_model.earth_orientation:
        raise InputError("model", "earth_orientation", "the same Earth orientation for the "
                         "state and variational models", f"{state_model.earth_orientation} vs "
                         f"{var_model.earth_orientation}")
    bodies = tuple(sorted(set(state_model.ephemeris_bodies) | set(var_model.ephemeris_bodies)))
    models = [m for m in (state_model, var_model) if m.oriented_field]
    oriented = "" if not models else (
        "pole" if all(m.gravity.order == 0 for m in models) else "full")
    if state_model.pole_field or var_model.pole_field:  # the same centre, not the Earth
        oriented = "body_pole"
    nq = len(params)
    t = ca.SX.sym("t")
    c = ca.SX.sym("c", 1)
    q = ca.SX.sym("q", nq)
    rb = ca.SX.sym("rb", 3 * len(bodies) + {"": 0, "pole": 3, "body_pole": 3,
                                                  "full": 9}[oriented])
    r_bodies = {b: rb[3 * i:3 * i + 3] for i, b in enumerate(bodies)}
    slow = rb[3 * len(bodies):] if oriented else None
    q_map = {name: q[i] for i, name in enumerate(params)}

    x = ca.SX.sym("x", 6)
    r, v = x[:3], x[3:]
    a_state = acceleration(state_model, t, r, c[0], q_map, r_bodies, slow, v) + \
        empirical_acceleration(r, v, q_map) + thrust_acceleration(t, r, v, q_map)
    xdot = ca.vertcat(v, a_state)
    f_state = ca.Function("f_state", [t, x, q, c, rb], [ca.cse(xdot)],
                          ["t", "y", "q", "c", "rb"], ["ydot"])

    y = ca.SX.sym("y", 42 + 6 * nq)
    r, v = y[:3], y[3:6]
    # both models (tapp.dynamics.empirical, tapp.dynamics.manoeuvres)
    a_q = empirical_acceleration(r, v, q_map) + thrust_acceleration(t, r, v, q_map)
    a_n = acceleration(state_model, t, r, c[0], q_map, r_bodies, slow, v) + a_q
    a_m = acceleration(var_model, t, r, c[0], q_map, r_bodies, slow, v) + a_q
    phi = ca.reshape(y[6:42], 6, 6)
    da_dr = ca.jacobian(a_m, r)
    da_dv = (ca.jacobian(a_m, v) if var_model.drag or thrust_moves_with_velocity(params)
             else ca.SX.zeros(3, 3))
    a_mat = ca.vertcat(ca.horzcat(ca.SX.zeros(3, 3), ca.SX.eye(3)),
                       ca.horzcat(da_dr, da_dv))
    parts = [v, a_n, ca.vec(ca.mtimes(a_mat, phi))]
    if nq:
        s = ca.reshape(y[42:], 6, nq)
        b_mat = ca.vertcat(ca.SX.zeros(3, nq), ca.jacobian(a_m, q))
        parts.append(ca.vec(ca.mtimes(a_mat, s) + b_mat))
    f_var = ca.Function("f_var", [t, y, q, c, rb], [ca.cse(ca.vertcat(*parts))],
                        ["t", "y", "q", "c", "rb"], ["ydot"])
    names, f_event = _event_function(state_model, var_model, r_bodies, rb)
    return Equations(f_state, f_var, f_event, names, bodies, tuple(params), oriented)


def _event_function(state_model: ForceModel, var_model: ForceModel,
                    r_bodies: dict[str, ca.SX], rb: ca.SX) -> tuple[tuple[str, ...], ca.Function]:
    """The events of both models (each name once: the state model moves the trajectory, the
    variational model's Jacobian drives Φ, and every step must be smooth for both), as
    ``f_event(r, v, rb, rbd) -> (g, dg/dt)`` with dg/dt = ∂g/∂r · v + ∂g/∂rb · rbd."""
    r, v = ca.SX.sym("r", 3), ca.SX.sym("v", 3)
    rbd = ca.SX.sym("rbd", rb.numel())
    found = boundaries(state_model, r, r_bodies) | boundaries(var_model, r, r_bodies)
    g = ca.vertcat(*found.values()) if found else ca.SX(0, 1)
    g_dot = ca.jtimes(g, ca.vertcat(r, rb), ca.vertcat(v, rbd)) if found else ca.SX(0, 1)
    return tuple(found), ca.Function("f_event", [r, v, rb, rbd], [ca.cse(g), ca.cse(g_dot)],
                                     ["r", "v", "rb", "rbd"], ["g", "g_dot"])


def initial_augmented(x0: np.ndarray, n_params: int) -> np.ndarray:
    """Return y0 = [x0, vec(I_6), 0] for the augmented system (length 42 + 6 n_params)."""
    return np.concatenate([np.asarray(x0, dtype=float), np.eye(6).ravel(order="F"),
                           np.zeros(6 * n_params)])


def split_augmented(y: np.ndarray, n_params: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split augmented rows (N, 42 + 6 n_q) into states (N, 6), Φ (N, 6, 6), S (N, 6, n_q)."""
    y = np.asarray(y)
    n = y.shape[0]
    states = y[:, :6]
    phi = y[:, 6:42].reshape(n, 6, 6).transpose(0, 2, 1)
    sens = y[:, 42:].reshape(n, n_params, 6).transpose(0, 2, 1)
    return states, phi, sens


@cache
def _halves(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the position and velocity halves of the 6-blocks of a first-order vector."""
    blocks = np.arange(n).reshape(-1, 6)
    return blocks[:, :3].ravel(), blocks[:, 3:].ravel()


def velocity_dependent(eqs: Equations) -> bool:
    """True when an acceleration of either function depends on velocity (∂a/∂v ≠ 0).

    The structural test (``casadi.depends_on``) of the velocity-derivative halves of each
    6-block of ``f_state`` and ``f_var`` on the velocity halves of their input: the
    predicate a second-order method (y'' = f(t, y)) checks before it accepts a model.
    """
    for f in (eqs.f_state, eqs.f_var):
        y = ca.SX.sym("y", f.size1_in(1))
        ydot = f(ca.SX.sym("t"), y, ca.SX.sym("q", f.size1_in(2)), ca.SX.sym("c", 1),
                 ca.SX.sym("rb", f.size1_in(4)))
        _, vel = _halves(y.numel())
        if ca.depends_on(ydot[vel.tolist()], y[vel.tolist()]):
            return True
    return False


def second_order(eqs: Equations) -> Equations:
    """The same equations in second-order form z'' = g(t, z, q, c, rb).

    z gathers the position halves of the 6-blocks of the first-order vector (r, then the
    position rows of each column of Φ and of S); g is the velocity-derivative halves of
    ``f_state`` / ``f_var`` evaluated with the velocity halves set to zero, which is exact
    only when :func:`velocity_dependent` is False (Φ_r'' = (∂a/∂r) Φ_r, P'' = (∂a/∂r) P +
    ∂a/∂q: the second-order variational equations).
    """
    functions = []
    for f in (eqs.f_state, eqs.f_var):
        n = f.size1_in(1)
        pos, vel = _halves(n)
        t, q, c, rb = (ca.SX.sym("t"), ca.SX.sym("q", f.size1_in(2)), ca.SX.sym("c", 1),
                       ca.SX.sym("rb", f.size1_in(4)))
        z = ca.SX.sym("z", n // 2)
        y = ca.SX.zeros(n)
        y[pos.tolist()] = z
        zdd = f(t, y, q, c, rb)[vel.tolist()]
        functions.append(ca.Function(f.name(), [t, z, q, c, rb], [ca.cse(zdd)],
                                     ["t", "y", "q", "c", "rb"], ["ydot"]))
    return Equations(*functions, eqs.f_event, eqs.events, eqs.bodies, eqs.params, eqs.oriented)


def to_second_order(y: np.ndarray) -> np.ndarray:
    """First-order rows (..., n) -> [z, z'] rows (..., n): position halves, then velocity."""
    pos, vel = _halves(np.shape(y)[-1])
    return np.concatenate([y[..., pos], y[..., vel]], axis=-1)


def from_second_order(zz: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_second_order`."""
    zz = np.asarray(zz)
    pos, vel = _halves(zz.shape[-1])
    y = np.empty_like(zz)
    half = zz.shape[-1] // 2
    y[..., pos] = zz[..., :half]
    y[..., vel] = zz[..., half:]
    return y

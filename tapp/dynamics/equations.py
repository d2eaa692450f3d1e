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
∂a_M/∂v is built only when the variational model has drag (:attr:`ForceModel.drag`), the one
velocity-dependent force; otherwise it is the zero block, and the generated code is the same
as before drag existed.

Layout of the augmented vector y (length 6 + 36 + 6 n_q): x, then Φ column-major, then S
column-major. Nobody slices it by hand: use :func:`split_augmented`.

Both CasADi functions share the signature ``f(t, y, q, c, rb) -> ydot`` with c = [θ0] (Earth
rotation angle at the epoch, rad) and rb the stacked third-body positions relative to the
centre (km), in the order of :attr:`Equations.bodies` (the third bodies and the Sun and Moon
that SRP and the Harris-Priester atmosphere read, :attr:`ForceModel.ephemeris_bodies`),
followed, when the field is oriented by the iau2006 model (:attr:`Equations.oriented`), by
the series that orient it: the ITRS pole ("pole", 3 entries: enough when every oriented field
is zonal) or the nine slow terms ("full",
:meth:`tapp.frames.orientation.EarthOrientation.slow_terms`). The driver evaluates all of rb
from one Chebyshev table.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from tapp.dynamics.empirical import empirical_acceleration
from tapp.dynamics.forces import acceleration
from tapp.dynamics.spec import ForceModel
from tapp.errors import InputError


@dataclass(frozen=True, slots=True)
class Equations:
    """The pair of CasADi functions of one (state model, variational model, parameters)."""

    f_state: ca.Function
    f_var: ca.Function
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
    nq = len(params)
    t = ca.SX.sym("t")
    c = ca.SX.sym("c", 1)
    q = ca.SX.sym("q", nq)
    rb = ca.SX.sym("rb", 3 * len(bodies) + {"": 0, "pole": 3, "full": 9}[oriented])
    r_bodies = {b: rb[3 * i:3 * i + 3] for i, b in enumerate(bodies)}
    slow = rb[3 * len(bodies):] if oriented else None
    q_map = {name: q[i] for i, name in enumerate(params)}

    x = ca.SX.sym("x", 6)
    r, v = x[:3], x[3:]
    a_state = acceleration(state_model, t, r, c[0], q_map, r_bodies, slow, v) + \
        empirical_acceleration(r, v, q_map)
    xdot = ca.vertcat(v, a_state)
    f_state = ca.Function("f_state", [t, x, q, c, rb], [ca.cse(xdot)],
                          ["t", "y", "q", "c", "rb"], ["ydot"])

    y = ca.SX.sym("y", 42 + 6 * nq)
    r, v = y[:3], y[3:6]
    a_q = empirical_acceleration(r, v, q_map)  # both models (tapp.dynamics.empirical)
    a_n = acceleration(state_model, t, r, c[0], q_map, r_bodies, slow, v) + a_q
    a_m = acceleration(var_model, t, r, c[0], q_map, r_bodies, slow, v) + a_q
    phi = ca.reshape(y[6:42], 6, 6)
    da_dr = ca.jacobian(a_m, r)
    da_dv = ca.jacobian(a_m, v) if var_model.drag else ca.SX.zeros(3, 3)
    a_mat = ca.vertcat(ca.horzcat(ca.SX.zeros(3, 3), ca.SX.eye(3)),
                       ca.horzcat(da_dr, da_dv))
    parts = [v, a_n, ca.vec(ca.mtimes(a_mat, phi))]
    if nq:
        s = ca.reshape(y[42:], 6, nq)
        b_mat = ca.vertcat(ca.SX.zeros(3, nq), ca.jacobian(a_m, q))
        parts.append(ca.vec(ca.mtimes(a_mat, s) + b_mat))
    f_var = ca.Function("f_var", [t, y, q, c, rb], [ca.cse(ca.vertcat(*parts))],
                        ["t", "y", "q", "c", "rb"], ["ydot"])
    return Equations(f_state, f_var, bodies, tuple(params), oriented)


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

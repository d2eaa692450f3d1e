"""The two reference integrators of the propagation benchmark, on the same EGM96 field.

heyoka
    The potential is built by :func:`tapp.dynamics.forces.central_potential` from heyoka
    expressions (it uses only arithmetic and ``sqrt``), rotated to the Earth-fixed frame by
    θ = θ0 + ω_E t with ``heyoka.time``, and differentiated by heyoka: the same field as
    tapp's, term for term. The STM comes from ``heyoka.var_ode_sys`` (order 1).
SciPy
    ``solve_ivp(method="DOP853")`` with a NumPy right-hand side: the closed-form J2
    acceleration and its 3x3 gradient for J2 (checked against central differences and
    against tapp's field at start-up), and for 5x5 tapp's CasADi functions called from
    Python once per right-hand-side evaluation.

Augmented states use tapp's layout (x, then Φ column-major) so that
:func:`tapp.dynamics.equations.split_augmented` reads every tool's output.
"""

from __future__ import annotations

from dataclasses import dataclass

import heyoka as hy
import numpy as np
from scipy.integrate import solve_ivp

from tapp.constants import OMEGA_EARTH_rad_s, R_EARTH_km
from tapp.dynamics.equations import Equations, initial_augmented, split_augmented
from tapp.dynamics.forces import central_potential, default_parameters, field_coefficients
from tapp.dynamics.spec import ForceModel


@dataclass(frozen=True, slots=True)
class Run:
    """Output of one propagation on the grid: states (N, 6), stm (N, 6, 6) or None."""

    states: np.ndarray
    stm: np.ndarray | None
    steps: int | None
    rhs_evaluations: int | None


# ---------------------------------------------------------------- heyoka


def heyoka_system(model: ForceModel, theta0_rad: float = 0.0) -> list[tuple]:
    """Return the heyoka ODE system [(x, vx), ..., (vz, ∂U/∂z)] of ``model``'s field."""
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    if model.gravity.order > 0:
        theta = theta0_rad + OMEGA_EARTH_rad_s * hy.time
        c, s = hy.cos(theta), hy.sin(theta)
        r_fixed = [c * x + s * y, -s * x + c * y, z]
    else:
        r_fixed = [x, y, z]
    u = central_potential(model, r_fixed, model.gm_center_km3_s2, field_coefficients(model, {}),
                          sqrt=hy.sqrt)
    grad = hy.diff_tensors([u], [x, y, z], diff_order=1).gradient
    return [(x, vx), (y, vy), (z, vz), (vx, grad[0]), (vy, grad[1]), (vz, grad[2])]


class HeyokaPropagator:
    """A heyoka ``taylor_adaptive`` integrator, reset for every propagation.

    Parameters
    ----------
    system : output of :func:`heyoka_system`.
    stm : integrate the order-1 variational equations w.r.t. the initial state too.
    tol : heyoka's tolerance (relative and absolute); None for its default (machine epsilon).
    compact_mode : heyoka's compact mode (smaller code, faster JIT, usually slower steps).
    """

    def __init__(self, system: list[tuple], *, stm: bool, tol: float | None,
                 compact_mode: bool) -> None:
        sys = hy.var_ode_sys(system, hy.var_args.vars, order=1) if stm else system
        kwargs = {"compact_mode": compact_mode}
        if tol is not None:
            kwargs["tol"] = tol
        self.ta = hy.taylor_adaptive(sys, np.zeros(6), **kwargs)
        self.stm = stm
        if stm:
            phi0 = self.ta.state[self.ta.get_vslice(order=1)].reshape(6, 6)
            assert np.array_equal(phi0, np.eye(6)), "heyoka STM at t0 is not the identity"
            # heyoka's order-1 block: row i = component i, column j = initial value j.
            assert self.ta.get_vslice(order=1, component=0) == slice(6, 12)

    def propagate(self, x0: np.ndarray, t_s: np.ndarray, t0_s: float = 0.0) -> Run:
        """Integrate from (t0_s, x0) and return the states (and STM) on ``t_s``."""
        self.ta.time = t0_s
        self.ta.state[:6] = x0
        if self.stm:
            self.ta.state[6:42] = np.eye(6).ravel()
        outcome, _, _, n_steps, _, y = self.ta.propagate_grid(np.asarray(t_s, dtype=float))
        if outcome != hy.taylor_outcome.time_limit:
            raise RuntimeError(f"heyoka stopped early: {outcome}")
        phi = y[:, self.ta.get_vslice(order=1)].reshape(-1, 6, 6) if self.stm else None
        return Run(y[:, :6].copy(), phi, int(n_steps), None)


# ---------------------------------------------------------------- SciPy / NumPy


@dataclass(frozen=True, slots=True)
class J2Field:
    """Point mass + J2 in closed form (Vallado, 4th ed., eq. 8-30 without the higher zonals)."""

    gm_km3_s2: float
    j2: float
    radius_km: float

    @staticmethod
    def of(model: ForceModel) -> J2Field:
        """The constants of tapp's J2 model (EGM96 GM, radius and J2 = -√5 C̄20)."""
        j2 = default_parameters(model, ("J2",))["J2"]
        return J2Field(float(model.gm_center_km3_s2), float(j2), R_EARTH_km)

    def acceleration(self, r_km: np.ndarray) -> np.ndarray:
        """(3,) km/s^2 at inertial r (3,) km."""
        r2 = r_km @ r_km
        s = r_km[2] ** 2 / r2
        k = 1.5 * self.j2 * self.gm_km3_s2 * self.radius_km ** 2 / r2 ** 2.5
        c = np.array([1.0, 1.0, 3.0])
        return -self.gm_km3_s2 / r2 ** 1.5 * r_km - k * r_km * (c - 5.0 * s)

    def gradient(self, r_km: np.ndarray) -> np.ndarray:
        """(3, 3) ∂a/∂r (1/s^2) at inertial r (3,) km."""
        r2 = r_km @ r_km
        z = r_km[2]
        s = z * z / r2
        gm = self.gm_km3_s2
        eye = np.eye(3)
        g = -gm / r2 ** 1.5 * (eye - 3.0 * np.outer(r_km, r_km) / r2)
        # a_J2,i = f r_i (c_i - 5 s), f = -1.5 J2 μ R² r^-5
        f = -1.5 * self.j2 * gm * self.radius_km ** 2 / r2 ** 2.5
        df = -5.0 * f * r_km / r2
        ds = -2.0 * s * r_km / r2
        ds[2] += 2.0 * z / r2
        e = np.array([1.0, 1.0, 3.0]) - 5.0 * s
        return g + np.outer(r_km * e, df) + f * np.diag(e) - 5.0 * f * np.outer(r_km, ds)


def check_j2_field(field: J2Field, eqs: Equations) -> float:
    """Assert the NumPy J2 field against central differences and tapp's CasADi field.

    Returns the largest relative gradient error seen. Points include the equator, 30°
    and a near-polar, eccentric-orbit radius.
    """
    points_km = [np.array([6550.524, 0.0, 0.0]),
                 np.array([4000.0, 3000.0, 3500.0]),
                 np.array([-1200.0, 800.0, -9200.0])]
    h_km = 1e-2
    worst = 0.0
    for r in points_km:
        fd = np.empty((3, 3))
        for j in range(3):
            dr = np.zeros(3)
            dr[j] = h_km
            fd[:, j] = (field.acceleration(r + dr) - field.acceleration(r - dr)) / (2 * h_km)
        g = field.gradient(r)
        err = float(np.max(np.abs(g - fd)) / np.max(np.abs(g)))
        worst = max(worst, err)
        assert err < 1e-8, f"J2 gradient vs central differences: relative error {err:.2e}"
        ydot = np.asarray(eqs.f_state(0.0, np.concatenate([r, np.zeros(3)]), np.zeros(0),
                                      np.zeros(1), np.zeros(0))).ravel()
        a = field.acceleration(r)
        rel = float(np.max(np.abs(ydot[3:] - a)) / np.linalg.norm(a))
        assert rel < 1e-13, f"NumPy J2 vs tapp's field: relative difference {rel:.2e}"
    return worst


def numpy_j2_rhs(field: J2Field, stm: bool):
    """Right-hand side f(t, y) for solve_ivp; y = x or [x, vec(Φ)] (column-major)."""

    def f_state(t, y):
        return np.concatenate([y[3:6], field.acceleration(y[:3])])

    def f_var(t, y):
        phi = y[6:42].reshape(6, 6, order="F")
        dphi = np.empty((6, 6))
        dphi[:3] = phi[3:]
        dphi[3:] = field.gradient(y[:3]) @ phi[:3]
        return np.concatenate([y[3:6], field.acceleration(y[:3]), dphi.ravel(order="F")])

    return f_var if stm else f_state


def casadi_rhs(eqs: Equations, stm: bool, theta0_rad: float = 0.0):
    """Right-hand side calling tapp's CasADi function (f_var or f_state) from Python."""
    fn = eqs.f_var if stm else eqs.f_state
    q, c, rb = np.zeros(0), np.array([theta0_rad]), np.zeros(0)

    def f(t, y):
        return np.asarray(fn(t, y, q, c, rb)).ravel()

    return f


def scipy_propagate(rhs, x0: np.ndarray, t_s: np.ndarray, *, stm: bool, tol: float,
                    t0_s: float = 0.0) -> Run:
    """solve_ivp DOP853 with rtol = atol = tol (error on every component), outputs on t_s."""
    y0 = initial_augmented(x0, 0) if stm else np.asarray(x0, dtype=float)
    sol = solve_ivp(rhs, (t0_s, float(t_s[-1])), y0, method="DOP853", t_eval=t_s, rtol=tol,
                    atol=tol)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    y = sol.y.T
    if stm:
        states, phi, _ = split_augmented(y, 0)
        return Run(states.copy(), phi.copy(), None, int(sol.nfev))
    return Run(y.copy(), None, None, int(sol.nfev))

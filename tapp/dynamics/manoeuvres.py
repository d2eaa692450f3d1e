"""Manoeuvres: impulsive and finite burns in inertial, RIC or VNB axes, with Gates' errors.

**Axes.** A burn's vector is given in one of :data:`AXES`, whose unit vectors (columns of
M(r, v), axes → inertial) are those of the spacecraft's state (r, v) relative to the centre:

.. math::

    \\text{ric:}\\ \\hat R = \\frac{r}{|r|},\\ \\hat C = \\frac{r \\times v}{|r \\times v|},
    \\ \\hat I = \\hat C \\times \\hat R;\\qquad
    \\text{vnb:}\\ \\hat V = \\frac{v}{|v|},\\ \\hat N = \\frac{r \\times v}{|r \\times v|},
    \\ \\hat B = \\hat V \\times \\hat N;\\qquad \\text{inertial:}\\ M = I

(RIC as :mod:`tapp.frames.ric`; VNB as GMAT's "VNB" local axes: velocity, orbit normal,
binormal). In RIC and VNB the axes move with the state, so a burn depends on r and v beyond
the state it moves.

**Impulsive** (:class:`ImpulsiveBurn`): at t_b the velocity jumps, x⁺ = x⁻ + Δx(x⁻) with
Δx = [0; M(x⁻)(Δv + G(Δv) q)] (Δv in the burn's axes, q its execution errors,
:mod:`tapp.dynamics.gates`, nominal 0). The transition and sensitivities jump exactly:

.. math::

    \\Phi^+ = \\Big(I + \\frac{\\partial \\Delta x}{\\partial x^-}\\Big)\\Phi^-, \\qquad
    S^+ = \\Big(I + \\frac{\\partial \\Delta x}{\\partial x^-}\\Big) S^-
        + \\frac{\\partial \\Delta x}{\\partial q}, \\qquad
    \\frac{\\partial \\Delta x}{\\partial q} = \\begin{pmatrix} 0 \\\\ M\\,G(\\Delta v)
        \\end{pmatrix},

∂Δx/∂x⁻ = [0; ∂(M Δv)/∂x] from CasADi (zero in inertial axes): :func:`impulse`. An output at
t_b is the state before the burn.

**Finite** (:class:`FiniteBurn`): from t₀ for a duration Δt a thrust F (N) along the unit
direction d (burn axes) accelerates a mass m(t) = m₀ − ṁ (t − t₀) (kg, ṁ > 0 the mass flow),

.. math::

    a = M(r, v)\\Big[\\frac{w}{1 - \\beta (t - t_0)} + c\\Big],\\qquad
    w = \\frac{F}{m_0}\\,(d + q_3 \\hat e_1 + q_4 \\hat e_2)(1 + q_1),\\ \\
    c = \\frac{q_2 d + q_5 \\hat e_1 + q_6 \\hat e_2}{\\Delta t},\\ \\ \\beta = \\frac{\\dot m}{m_0}

to first order in q: the proportional errors scale and turn the thrust, the fixed ones add a
constant acceleration worth their velocity over the burn. w, c, β and t₀ are model parameters
of the equations (:data:`THRUST_PARAMETERS`, :func:`thrust_acceleration`, added to both the
state and the variational model by :mod:`tapp.dynamics.equations`), so the variational
equations carry ∂a/∂r, ∂a/∂v (the moving axes) and ∂x/∂(w, c); the execution errors' partials
are ∂x/∂q = ∂x/∂(w, c) · ∂(w, c)/∂q (:meth:`FiniteBurn.thrust_map`).

Every burn's execution-error parameters are the components of Gates' model with σ > 0
(:meth:`ImpulsiveBurn.parameters`), named ``<burn>.<label>`` (``TCM1.mag_prop``,
``TCM1.point_fixed_2_km_s``, ...), kind :data:`KIND` on the T13 tape, nominal 0, a priori
N(0, σ²) each.

References
----------
C. R. Gates, "A simplified model of midcourse maneuver execution errors", JPL Technical
Report 32-504 (1963). GMAT Mathematical Specifications (R2020a), §"Local coordinate systems"
(VNB).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from tapp.dynamics.gates import PARAMETERS as GATES_PARAMETERS
from tapp.dynamics.gates import PROPORTIONAL, GatesErrors, gates_partials

#: The axes a burn's vector may be given in, with their component labels.
AXES = {"inertial": ("x", "y", "z"), "ric": ("R", "I", "C"), "vnb": ("V", "N", "B")}
#: The parameter kind of execution errors on the T13 tape.
KIND = "execution"
#: The kinds of burn.
BURN_KINDS = ("impulsive", "finite")
#: Model parameters of a finite burn's thrust, per axes: w (3, km/s², the thrust acceleration
#: at ignition), c (3, km/s², the fixed errors' acceleration), β (1/s), t₀ (s).
THRUST_PARAMETERS = {axes: (*(f"thr_{axes}_{i}" for i in (1, 2, 3)),
                            *(f"thr_fixed_{axes}_{i}" for i in (1, 2, 3)),
                            "thr_flow_1_s", "thr_start_s") for axes in AXES}
#: Every thrust parameter name (nominal 0: :func:`tapp.dynamics.forces.default_parameters`).
THRUST_NAMES = tuple(dict.fromkeys(n for names in THRUST_PARAMETERS.values() for n in names))
#: Columns of (w, c) in a burn's thrust parameters (the rest, β and t₀, are not differentiated
#: by TAPP I).
THRUST_COLUMNS = 6


def axes_matrix(r: ca.SX, v: ca.SX, axes: str) -> ca.SX:
    """Return M (3, 3) SX: columns the unit vectors of ``axes`` (module docstring) at the
    state (r km, v km/s), so that a vector in the axes is M times its components."""
    if axes == "inertial":
        return ca.SX.eye(3)
    h = ca.cross(r, v)
    normal = h / ca.norm_2(h)
    if axes == "ric":
        radial = r / ca.norm_2(r)
        return ca.horzcat(radial, ca.cross(normal, radial), normal)
    along = v / ca.norm_2(v)
    return ca.horzcat(along, normal, ca.cross(along, normal))


def thrust_acceleration(t: ca.SX, r: ca.SX, v: ca.SX, q: Mapping[str, ca.SX]) -> ca.SX | float:
    """Return the thrust acceleration (km/s², inertial) of the thrust parameters in ``q``
    (module docstring; 0.0 when ``q`` holds none). ``q`` holds all eight of one axes or none."""
    for axes, names in THRUST_PARAMETERS.items():
        if names[0] in q:
            w = ca.vertcat(*(q[n] for n in names[:3]))
            c = ca.vertcat(*(q[n] for n in names[3:6]))
            mass_ratio = 1.0 - q[names[6]] * (t - q[names[7]])  # m(t) / m₀
            return ca.mtimes(axes_matrix(r, v, axes), w / mass_ratio + c)
    return 0.0


def thrust_moves_with_velocity(params: tuple[str, ...]) -> bool:
    """True when the thrust parameters among ``params`` are of axes that move with v."""
    return any(p in params for axes, names in THRUST_PARAMETERS.items() if axes != "inertial"
               for p in names)


@cache
def impulse(axes: str) -> ca.Function:
    """``impulse(x, dv) -> (Δx, ∂Δx/∂x, ∂Δx/∂dv)``: the jump of the state x (6: km, km/s) by a
    velocity change dv (3, km/s) in ``axes`` at that state, and its Jacobians (6, 6), (6, 3)."""
    x, dv = ca.SX.sym("x", 6), ca.SX.sym("dv", 3)
    dx = ca.vertcat(ca.SX.zeros(3), ca.mtimes(axes_matrix(x[:3], x[3:], axes), dv))
    return ca.Function("impulse", [x, dv], [dx, ca.jacobian(dx, x), ca.jacobian(dx, dv)])


@dataclass(frozen=True, slots=True, kw_only=True)
class _Burn:
    """What both kinds of burn share: a name, the axes of its vector, its execution errors."""

    name: str
    axes: str
    errors: GatesErrors

    @property
    def _columns(self) -> np.ndarray:
        """Indices into Gates' six parameters of those with σ > 0."""
        return np.flatnonzero(self.errors.sigmas > 0)

    def parameters(self) -> tuple[tuple[str, str, float], ...]:
        """Its execution-error parameters: (name, unit, σ) of each component with σ > 0, in
        Gates' order (:data:`tapp.dynamics.gates.PARAMETERS`)."""
        return tuple((f"{self.name}.{GATES_PARAMETERS[i][0]}", GATES_PARAMETERS[i][1],
                      float(self.errors.sigmas[i])) for i in self._columns)


@dataclass(frozen=True, slots=True, kw_only=True)
class ImpulsiveBurn(_Burn):
    """An instantaneous velocity change (module docstring).

    Attributes
    ----------
    t_s : time, s from the epoch (an output at t_s is the state before it).
    dv_km_s : (3,) the velocity change in ``axes``, km/s.
    """

    t_s: float
    dv_km_s: tuple[float, float, float]

    kind = "impulsive"

    @property
    def t_start_s(self) -> float:
        return self.t_s

    @property
    def t_end_s(self) -> float:
        return self.t_s

    @property
    def duration_s(self) -> float:
        return 0.0

    def apply(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return (x⁺ (6,), I + ∂Δx/∂x⁻ (6, 6), ∂Δx/∂q (6, n_e)) at the pre-burn state x
        (module docstring), q the burn's execution errors (:meth:`parameters`)."""
        dv = np.asarray(self.dv_km_s, dtype=float)
        dx, dx_dx, dx_ddv = (np.asarray(m) for m in impulse(self.axes)(x, dv))
        return (x + dx[:, 0], np.eye(6) + dx_dx,
                dx_ddv @ gates_partials(dv)[:, self._columns])


@dataclass(frozen=True, slots=True, kw_only=True)
class FiniteBurn(_Burn):
    """A constant thrust over an interval, with the mass flowing out (module docstring).

    Attributes
    ----------
    t_start_s, duration_s : ignition time (s from the epoch) and duration (s, > 0).
    thrust_N : F, N (> 0).
    direction : (3,) unit vector d of the thrust in ``axes``.
    mass_kg : m₀, the mass at ignition, kg.
    mass_flow_kg_s : ṁ, kg/s (> 0; m₀ − ṁ Δt > 0).
    """

    t_start_s: float
    duration_s: float
    thrust_N: float
    direction: tuple[float, float, float]
    mass_kg: float
    mass_flow_kg_s: float

    kind = "finite"

    @property
    def t_end_s(self) -> float:
        return self.t_start_s + self.duration_s

    @property
    def w_km_s2(self) -> np.ndarray:
        """w = (F / m₀) d (3,), the thrust acceleration at ignition in the burn's axes, km/s²
        (F in N = kg m/s²)."""
        return self.thrust_N / self.mass_kg * 1e-3 * np.asarray(self.direction, dtype=float)

    def with_thrust(self, w_km_s2) -> FiniteBurn:
        """The same burn with the thrust acceleration at ignition ``w_km_s2`` (3,), km/s²: its
        thrust F = m₀ |w| and direction w / |w| (the mass and the flow kept)."""
        w = np.asarray(w_km_s2, dtype=float)
        norm = float(np.linalg.norm(w))
        return dataclasses.replace(self, thrust_N=norm * self.mass_kg * 1e3,
                                   direction=tuple(float(x) for x in w / norm))

    def thrust_parameters(self) -> tuple[str, ...]:
        """The model parameters of its thrust (:data:`THRUST_PARAMETERS` of its axes)."""
        return THRUST_PARAMETERS[self.axes]

    def thrust_values(self) -> dict[str, float]:
        """Their nominal values: w, c = 0, β = ṁ/m₀, t₀."""
        values = [*self.w_km_s2, 0.0, 0.0, 0.0, self.mass_flow_kg_s / self.mass_kg,
                  self.t_start_s]
        return dict(zip(self.thrust_parameters(), map(float, values), strict=True))

    def thrust_map(self) -> np.ndarray:
        """∂(w, c)/∂q, (6, n_e): the proportional columns of G(w) for w, the fixed ones of
        G(w)/Δt for c (module docstring)."""
        g = gates_partials(self.w_km_s2)
        out = np.zeros((THRUST_COLUMNS, 6))
        out[:3, PROPORTIONAL] = g[:, PROPORTIONAL]
        out[3:, ~PROPORTIONAL] = g[:, ~PROPORTIONAL] / self.duration_s
        return out[:, self._columns]

    def delta_v_km_s(self) -> float:
        """The ideal velocity change of the burn, km/s: (F/ṁ) ln(m₀ / (m₀ − ṁ Δt))
        (Tsiolkovsky, exhaust speed F/ṁ)."""
        m_end = self.mass_kg - self.mass_flow_kg_s * self.duration_s
        return self.thrust_N / self.mass_flow_kg_s * np.log(self.mass_kg / m_end) * 1e-3


Burn = ImpulsiveBurn | FiniteBurn

__all__ = ["AXES", "BURN_KINDS", "KIND", "THRUST_COLUMNS", "THRUST_NAMES", "THRUST_PARAMETERS",
           "Burn", "FiniteBurn", "ImpulsiveBurn", "axes_matrix", "impulse",
           "thrust_acceleration", "thrust_moves_with_velocity"]

"""Integration events: the surfaces on which the force model is not smooth.

A Runge-Kutta step is accurate to its order only where the right-hand side is smooth across
the whole step. The surface forces have boundaries where it is not:

- the edges of each shadow (:data:`tapp.dynamics.radiation.SHADOW_BOUNDARIES`): the visible
  fraction ν of the solar disc is continuous there, but near an edge it goes as δ^{3/2} in the
  distance δ to it (the lens of two discs at contact), so its second derivative is unbounded;
- the table heights of the Harris-Priester atmosphere (ln ρ piecewise linear in h): ρ is
  continuous, ∂ρ/∂h jumps.

Stepped over, such a boundary costs accuracy that the step-size control does not see (it ends
the step with an error estimate of a smooth function): measured on a 500 km LEO with
A/m = 0.05 m²/kg, DOP853 at 1e-10 ended a day 44 m from its 1e-13 run, and rkn12's Hermite
dense output, fitted across several step ends, put states 176 m off inside eclipses. Each
boundary is therefore an *event* g(t, r) = 0 with g negative on the shadow (or lower) side: the
drivers (``driver_common.c``) check the sign of every g at every step end, locate a root on the
quintic Hermite polynomial through (r, v, a) at the two ends of the step (and an extremum when
dg/dt changes sign, so that a step that enters and leaves a region is not missed), shorten the
step to end on it, and restart there: every step then integrates a smooth function.

The variational equations need no jump at these events. With the saltation matrix of a
trajectory crossing g = 0 at t* (Müller 1995, "Higher order sensitivity analysis of
non-smooth systems"; Hiskens & Pai 2000, eq. 14),

.. math::
    \\Phi(t^{*+}) = \\left(I + \\frac{(f^+ - f^-)\\, \\nabla g^T}{\\nabla g \\cdot f^-}\\right)
        \\Phi(t^{*-}),

the jump f⁺ − f⁻ of the right-hand side is zero for every event here (ν and ρ are continuous),
so Φ and S are continuous and only need the restart (tests compare them with central
differences through the boundaries).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import casadi as ca
import numpy as np

from tapp.constants import RADIUS_km
from tapp.dynamics.atmosphere import HP_HEIGHT_km, height_km
from tapp.dynamics.radiation import SHADOW_BOUNDARIES, disc_geometry
from tapp.dynamics.spec import ForceModel


def boundaries(model: ForceModel, r: ca.SX, r_bodies: Mapping[str, ca.SX]
               ) -> dict[str, ca.SX]:
    """Return the event functions of ``model``: name -> g(r) (SX scalar), negative on the
    shadow side of a shadow boundary and below a Harris-Priester table height.

    Parameters
    ----------
    model : the force model.
    r : SX (3,) position relative to the model's centre, km.
    r_bodies : positions of the bodies the model reads relative to the centre, km
        (:attr:`ForceModel.ephemeris_bodies`).
    """
    surface = model.surface
    out: dict[str, ca.SX] = {}
    if surface is None:
        return out
    def position(body: str) -> ca.SX:
        return ca.SX.zeros(3) if body == model.center else r_bodies[body]

    if surface.srp and surface.shadows:
        for body in model.occulters:
            a, b, c = disc_geometry(r, position("sun"), position(body), RADIUS_km[body])
            for kind, g in SHADOW_BOUNDARIES.items():
                out[f"{body} {kind}"] = g(a, b, c)
    if surface.drag and surface.atmosphere == "harris_priester":
        h = height_km(r)
        # ln ρ is extrapolated linearly beyond the two end heights: only the inner ones kink.
        for h_i in HP_HEIGHT_km[1:-1]:
            out[f"harris-priester {h_i:g} km"] = h - h_i
    return out


@dataclass(frozen=True, slots=True)
class Events:
    """The events met along a propagation, in the order of time.

    Attributes
    ----------
    t_s : (n,) seconds from the epoch.
    name : the event function of each (:func:`boundaries`), e.g. ``"earth umbra"``.
    falling : (n,) bool: g went from positive to negative in forward time (into a shadow
        region, down through a table height).
    """

    t_s: np.ndarray
    name: tuple[str, ...]
    falling: np.ndarray

    @staticmethod
    def none() -> Events:
        return Events(np.zeros(0), (), np.zeros(0, dtype=bool))

    def __len__(self) -> int:
        return int(self.t_s.size)

    def labels(self) -> tuple[str, ...]:
        """Readable labels: ``earth umbra entry`` / ``exit``, ``harris-priester 320 km
        down`` / ``up``."""
        def label(name: str, falling: bool) -> str:
            if name.startswith("harris-priester"):
                return f"{name} {'down' if falling else 'up'}"
            return f"{name} {'entry' if falling else 'exit'}"
        return tuple(label(n, bool(f)) for n, f in zip(self.name, self.falling, strict=True))

    @staticmethod
    def join(parts: list[Events]) -> Events:
        """The events of consecutive propagations, in order."""
        if not parts:
            return Events.none()
        return Events(np.concatenate([p.t_s for p in parts]),
                      tuple(n for p in parts for n in p.name),
                      np.concatenate([p.falling for p in parts]))

"""Constant empirical accelerations as model parameters: the carrier of stochastic accelerations.

Three parameters per frame, nominal 0, in km/s²:

- ``acc_R``, ``acc_I``, ``acc_C``: radial, in-track and cross-track components along the
  RIC axes of the current state,

  .. math::
      \\hat R = \\frac{\\mathbf r}{|\\mathbf r|},\\quad
      \\hat C = \\frac{\\mathbf r \\times \\mathbf v}{|\\mathbf r \\times \\mathbf v|},\\quad
      \\hat I = \\hat C \\times \\hat R,\\qquad
      \\mathbf a = a_R \\hat R + a_I \\hat I + a_C \\hat C;

- ``acc_x``, ``acc_y``, ``acc_z``: components along the inertial axes, a = (a_x, a_y, a_z).

Their sensitivities S = ∂x(t)/∂a = ∫ Φ(t, τ) B(τ) dτ with B = [0; R(τ)] (R the RIC → inertial
rotation [R̂ Î Ĉ] of the trajectory, or I) come out of the variational equations
(:mod:`tapp.dynamics.equations`); TAPP I turns them into the partials of piecewise-constant
stochastic accelerations (:mod:`tapp.tracking.pieces`). The variational equations take
∂a/∂r only (the A matrix has no ∂a/∂v block); the RIC term depends on v, but its ∂/∂r and ∂/∂v
are proportional to a, so they vanish at the nominal a = 0 where TAPP I evaluates them.
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca

#: Component labels of each frame, in parameter order.
COMPONENTS = {"ric": ("R", "I", "C"), "inertial": ("x", "y", "z")}
#: The model-parameter names of each frame's acceleration components (km/s²).
PARAMETERS = {frame: tuple(f"acc_{c}" for c in comps) for frame, comps in COMPONENTS.items()}
#: Every empirical-acceleration parameter name.
NAMES = PARAMETERS["ric"] + PARAMETERS["inertial"]


def empirical_acceleration(r: ca.SX, v: ca.SX, q: Mapping[str, ca.SX]) -> ca.SX | float:
    """Return the empirical acceleration (km/s², inertial) of the parameters in ``q``.

    Parameters
    ----------
    r, v : SX (3,)  position (km) and velocity (km/s), inertial.
    q : mapping of parameter name to symbol; names absent from it are 0 (module docstring).
        Returns 0.0 when ``q`` holds none of :data:`NAMES`.
    """
    acc: ca.SX | float = 0.0
    if any(name in q for name in PARAMETERS["ric"]):
        h = ca.cross(r, v)
        radial = r / ca.norm_2(r)
        cross = h / ca.norm_2(h)
        axes = (radial, ca.cross(cross, radial), cross)
        for name, axis in zip(PARAMETERS["ric"], axes, strict=True):
            if name in q:
                acc = acc + q[name] * axis
    for i, name in enumerate(PARAMETERS["inertial"]):
        if name in q:
            unit = ca.DM.zeros(3)
            unit[i] = 1.0
            acc = acc + q[name] * unit
    return acc

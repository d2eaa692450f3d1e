"""Changes of integration centre at stated times: one trajectory, integrated about the body near it.

A heliocentric cruise with an Earth departure and a planetary approach is one force model (the
point masses of the bodies it names) about one centre C, the model's ``center``, in which the
caller gives the initial state and receives every output. Integrated about C throughout, the
step control sees the state's distance from C: at rtol 1e-13 a Sun-centred state 2e8 km out
is held to ~2e-5 km per step, coarse beside a 1e4 km Mars pericentre, and the planet's pull
is formed from the difference of two heliocentric vectors. A :class:`CentreChange` at time
b_k makes the propagator integrate from b_k on (until the next change) about the body K of
the change, and nothing else changes for the caller: states, Φ and S stay about C at every
time (:meth:`tapp.dynamics.propagate.Propagator.propagate`).

The force model about K (:func:`model_about`) has the same bodies acting: K, a third body of
the model, becomes the central point mass, and C a point-mass third body,

.. math::
    \\ddot{\\mathbf r}_K = -\\frac{GM_K\\,\\mathbf r_K}{r_K^3}
        - \\sum_{j \\ne K} GM_j \\left(\\frac{\\mathbf r_K - \\mathbf s_{j/K}}
        {|\\mathbf r_K - \\mathbf s_{j/K}|^3} + \\frac{\\mathbf s_{j/K}}{s_{j/K}^3}\\right),

the sum over C and the other third bodies (Montenbruck & Gill, *Satellite Orbits*, 2000,
eq. 3.37), with the same surface forces but drag. What belongs to C alone acts only while C is
the centre: its field beyond the point mass (harmonics, a J2 about its pole; the Earth's J2
pulls 2.6e-17 km/s² at 1e6 km, 1e-11 of the Sun's pull there) and the Earth's atmosphere, and
their parameters (``Jn``, ``Cnm``, ``Snm``, ``Cd``) have no partials on other intervals. K acts
as the model has it, a point mass. The indirect term is K's acceleration by the model's bodies,
as about C it is C's: the two frames agree to the difference between the model's
Newtonian relative acceleration of K and C and the ephemeris's (relativity, asteroids, the
figures of the bodies; measured in the tests).

At b_k the state moves from the centre K' of the interval before to K by the ephemeris state
of K relative to K' at TDB(b_k) (DE421 through :func:`tapp.dynamics.ephemeris.relative_state`,
the same time scale as the ephemeris tables), and every output at t in an interval about K
moves back to C:

.. math::
    \\mathbf x_K(b_k) = \\mathbf x_{K'}(b_k) - \\mathbf s_{K/K'}(b_k),\\qquad
    \\mathbf x_C(t) = \\mathbf x_K(t) + \\mathbf s_{K/C}(t).

The translations depend neither on the spacecraft's state nor on the model parameters, so
∂x_C(t)/∂x_C(b_k) = ∂x_K(t)/∂x_K(b_k) = Φ_k(t, b_k) and, with S_k the sensitivities of the
interval's own propagation (zero at b_k),

.. math::
    \\Phi(t, t_0) = \\Phi_k(t, b_k)\\,\\Phi(b_k, t_0),\\qquad
    S(t) = \\Phi_k(t, b_k)\\,S(b_k) + S_k(t),

exactly, the columns of S_k matched by :func:`names_about` (the model's ``GM_km3_s2`` is the
interval about K's ``GM_<C>_km3_s2``, the model's ``GM_<K>_km3_s2`` its ``GM_km3_s2``). The
ephemeris enters through the translations and the bodies' positions relative to K. With an
ephemeris offset δ_K of K among the parameters (:mod:`tapp.dynamics.ephemeris_offsets`) the
translations move by it: S enters K's interval as S(b_k) − E_K and leaves each output as
... + E_K (E_K the identity in the position rows of δ_K's columns), and on the interval the
other bodies sit at s_j/K + δ_j − δ_K as the spacecraft sees them (S_k carries that through
∂a/∂s_j).

Parameters whose force follows the orbit about the centre (empirical accelerations in RIC
axes, a finite burn's thrust in RIC or VNB axes: :mod:`tapp.dynamics.empirical`,
:mod:`tapp.dynamics.manoeuvres`) would follow it about K on K's intervals, a force the choice
of centre would change: they are refused with centre changes.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

from tapp.dynamics.empirical import PARAMETERS as EMPIRICAL_PARAMETERS
from tapp.dynamics.manoeuvres import thrust_moves_with_velocity
from tapp.dynamics.parameters import gm_name, meaning
from tapp.dynamics.spec import BODIES, ForceModel, GravitySpec
from tapp.errors import InputError

#: Kinds of the parameters of the model centre's own forces (its field beyond the point
#: mass, drag: :mod:`tapp.dynamics.parameters`): they act on its intervals only (module
#: docstring).
_CENTRE_ONLY = ("zonal", "harmonic", "drag")


@dataclass(frozen=True, slots=True)
class CentreChange:
    """From ``t_s`` (s from the epoch, > 0) until the next change, integrate about ``center``
    (a body of :data:`tapp.dynamics.spec.BODIES`)."""

    t_s: float
    center: str


def check_centre_changes(changes: Sequence[CentreChange], state_model: ForceModel,
                         var_model: ForceModel, params: tuple[str, ...] = (),
                         source: str = "propagator", field: str = "centre_changes"
                         ) -> tuple[CentreChange, ...]:
    """Return ``changes`` as a tuple if they are a valid schedule for the two models.

    Valid: times finite, > 0 and strictly ascending; each centre the model's centre or a third
    body of both models (else the interval would add a body the model has not) and not the
    centre of the interval before; no parameter of a force that follows the orbit (module
    docstring) among ``params``.

    Raises
    ------
    InputError
        Naming ``source`` and ``field[i].time`` or ``field[i].center`` (``field`` for the
        parameters), with what was expected.
    """
    changes = tuple(changes)
    previous_t, previous = 0.0, state_model.center
    bodies = set(state_model.third_bodies) & set(var_model.third_bodies) | {state_model.center}
    for i, change in enumerate(changes):
        t = change.t_s
        if not (isinstance(t, int | float) and not isinstance(t, bool) and math.isfinite(t)
                and t > previous_t):
            after = "the epoch (t > 0)" if i == 0 else f"the change before ({previous_t:g} s)"
            raise InputError(source, f"{field}[{i}].time", f"a finite time after {after}, s",
                             t)
        if change.center not in BODIES or change.center not in bodies:
            raise InputError(source, f"{field}[{i}].center", "the model's centre or a third "
                             f"body of both models ({', '.join(sorted(bodies))})",
                             change.center)
        if change.center == previous:
            raise InputError(source, f"{field}[{i}].center", "a centre other than the one "
                             f"before ({previous})", change.center)
        previous_t, previous = float(t), change.center
    ric = [p for p in params if p in EMPIRICAL_PARAMETERS["ric"]]
    if changes and (ric or thrust_moves_with_velocity(params)):
        raise InputError(source, field, "no centre changes with forces in axes that follow the "
                         "orbit (RIC empirical accelerations, thrust in RIC or VNB axes: they "
                         "would follow it about each interval's centre)",
                         ric or [p for p in params if p.startswith("thr_")])
    return changes


def centre_at(changes: tuple[CentreChange, ...], center: str, t_s: float) -> str:
    """The centre of the integration at ``t_s`` (a change at ``t_s`` already made)."""
    for change in reversed(changes):
        if change.t_s <= t_s:
            return change.center
    return center


def model_about(model: ForceModel, centre: str) -> ForceModel:
    """The same bodies acting about ``centre`` (the model's centre or one of its third
    bodies): ``centre`` the point mass, the model's centre a third body, SRP kept, the model
    centre's field and drag dropped (module docstring)."""
    if centre == model.center:
        return model
    surface = model.surface
    if surface is not None and surface.drag:
        surface = dataclasses.replace(surface, atmosphere="none") if surface.srp else None
    bodies = tuple(b for b in model.third_bodies if b != centre) + (model.center,)
    return ForceModel(GravitySpec(0, 0), centre, bodies, model.earth_orientation, surface)


def names_about(params: tuple[str, ...], model: ForceModel, centre: str
                ) -> tuple[str | None, ...]:
    """Each of the model's parameter names as the model about ``centre``
    (:func:`model_about`) spells it: ``GM_km3_s2`` → ``GM_<model centre>_km3_s2``,
    ``GM_<centre>_km3_s2`` → ``GM_km3_s2``, None for a parameter of the model centre's own
    forces, others unchanged."""
    if centre == model.center:
        return params

    def about(name: str) -> str | None:
        if name == gm_name():
            return gm_name(model.center)
        if name == gm_name(centre):
            return gm_name()
        found = meaning(name)
        return None if found is not None and found.kind in _CENTRE_ONLY else name

    return tuple(about(name) for name in params)

"""Ephemeris offsets: a body's ephemeris position moved by a constant vector, as parameters.

The error of a planet's ephemeris is a leading error of a planetary approach (the B-plane is
measured from the planet's centre, which the ephemeris places). tapp models it as a constant
offset δ_B of body B's DE421 position over the arc, in ICRF axes, km: the three dynamic
parameters ``dr_<body>_x_km``, ``dr_<body>_y_km``, ``dr_<body>_z_km`` (nominal 0; named by
:mod:`tapp.dynamics.parameters`). A constant offset is the first term of an ephemeris error over the
weeks of an approach, where the planet's ephemeris uncertainty is a near-constant position
error (its velocity error moves it by ~1e-3 of itself in a month).

The offset enters wherever the body's position does:

- the force model: the spacecraft sees body j at s_j/K + δ_j − δ_K relative to the
  integration centre K (:func:`offset_bodies`: its pull, the Sun's light, the shadows),
  while the centre's own acceleration, the indirect term μ_j s_j/K / s_j/K³, stays its
  ephemeris path's, which a constant offset does not change (moving it with δ would make the
  offset a change of the bodies' dynamics: about the Moon, 7e-12 km/s² per km of the Moon's
  offset from the Earth's pull, 6 m a day); the variational equations then give ∂x/∂δ
  through ∂a/∂s_j as for any parameter;
- a change of integration centre into or out of B (:mod:`tapp.dynamics.centres`): the
  translation by B's ephemeris state moves by δ_B, so the state about the model's centre C
  gains ∂x_C/∂δ_B = +E on B's intervals, and the state entering B's interval −E
  (:func:`selector`, E = [I₃; 0] in B's three columns);
- the B-plane of B: the spacecraft relative to B, z = x − (s_B + δ_B), ∂z/∂δ_B = −E
  (:func:`tapp.tracking.simulate.miss_partials`).

The shadow boundaries (integration events) are located on the ephemeris without the offsets:
with δ ≠ 0 (a differenced run; the nominal is 0) a boundary the state model crosses moves by
|δ| / v, a fraction of a second for kilometres. The offsets of the Earth (the stations' frame)
and of the model's centre are refused by the scenario (:mod:`tapp.tracking.scenario_build`).
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca
import numpy as np

from tapp.dynamics.parameters import OFFSET_AXES, meaning, offset_name


def offset_names(body: str) -> tuple[str, str, str]:
    """The three parameter names of ``body``'s ephemeris offset."""
    return tuple(offset_name(body, i) for i in range(len(OFFSET_AXES)))  # type: ignore[return-value]


def offset_of(name: str) -> tuple[str, int] | None:
    """(body, axis index) of an offset parameter's name, else None."""
    found = meaning(name)
    return (found.body, found.axis) if found and found.kind == "ephemeris_offset" else None


def offset_bodies(r_bodies: Mapping[str, ca.SX], q: Mapping[str, ca.SX], centre: str
                  ) -> dict[str, ca.SX]:
    """Return the bodies' positions relative to ``centre`` with their offsets: s_j + δ_j − δ_K
    for every body j of ``r_bodies`` (SX 3-vectors), δ from the parameter symbols of ``q``
    (an absent axis: 0). The same expressions when ``q`` has no offsets."""
    def delta(body: str) -> ca.SX | None:
        names = offset_names(body)
        if not any(n in q for n in names):
            return None
        return ca.vertcat(*(q[n] if n in q else 0.0 for n in names))

    own = delta(centre)
    out = {}
    for body, s in r_bodies.items():
        d = delta(body)
        if d is not None:
            s = s + d
        if own is not None:
            s = s - own
        out[body] = s
    return out


def selector(params: tuple[str, ...], body: str) -> np.ndarray:
    """E (6, n_q): ∂(state)/∂(params) of a translation by ``body``'s offset, the identity in
    the position rows of its three columns (zeros if it has none among ``params``)."""
    e = np.zeros((6, len(params)))
    for j, name in enumerate(params):
        found = offset_of(name)
        if found is not None and found[0] == body:
            e[found[1], j] = 1.0
    return e


def offset_values(values: Mapping[str, float], body: str) -> np.ndarray:
    """δ (3,) km of ``body`` from parameter values (absent: 0)."""
    return np.array([values.get(n, 0.0) for n in offset_names(body)], dtype=float)

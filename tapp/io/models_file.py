"""The ``[model]`` table of tracking scenarios and SEARCH files: the two force models.

A propagation takes two force models (the study's (J_N, J_M) choice): the state model moves
the trajectory, and the variational model's Jacobian drives Φ and the sensitivities along it
(the seed's truncated variational equations). Every file names them the same way::

    [model]
    gravity = "5x5"            # the state model: Earth field J0, Jn or NxM ...
    third_bodies = ["moon"]    # ... and point-mass third bodies (DE421)
    var_gravity = "J2"         # the variational model (default: the state model's)
    var_third_bodies = []
    rtol = 1e-13               # integrator tolerances
    atol = 1e-13
    method = "dop853"          # or "rkn12" (tapp.dynamics.propagate)

and the study file's runs name their models ``gravity`` and ``var_gravity`` too. The
spellings ``stm_gravity`` and ``stm_third_bodies`` of earlier SEARCH files are refused, naming
the new key.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import AfterValidator, Field

from tapp.constants import MAX_DEGREE
from tapp.dynamics.compiled import METHODS
from tapp.dynamics.spec import BODIES, ForceModel, earth_model, parse_gravity
from tapp.errors import InputError
from tapp.io.schema import Invalid, Schema, Tolerance, Unique


def _gravity(spec: str) -> str:
    try:
        parse_gravity(spec)
    except InputError as exc:
        raise Invalid(exc.expected, spec) from None
    return spec


#: A gravity spec: J0, Jn or NxM (checked by :func:`tapp.dynamics.parse_gravity`).
GravityName = Annotated[str, AfterValidator(_gravity), Field(json_schema_extra={
    "allowed": f"J0 (point mass), Jn (zonals to degree n) or NxM (degree N >= order M), "
               f"degree <= {MAX_DEGREE}"})]
#: A third body: a DE421 body other than the Earth.
ThirdBody = Literal[tuple(b for b in BODIES if b != "earth")]  # type: ignore[valid-type]
#: Third bodies, each once.
ThirdBodies = Annotated[list[ThirdBody], Unique]
#: An integration method of :class:`tapp.dynamics.Propagator`.
Method = Literal[tuple(METHODS)]  # type: ignore[valid-type]


class ModelTable(Schema):
    """``[model]``: the state and variational force models and the integrator tolerances."""

    renamed_keys = {"stm_gravity": "var_gravity", "stm_third_bodies": "var_third_bodies"}

    gravity: GravityName = Field(
        description="The Earth's gravity field in the state model, which moves the trajectory.")
    third_bodies: ThirdBodies = Field(
        [], description="Point-mass third bodies of the state model (positions from DE421).")
    var_gravity: GravityName | None = Field(
        None, description="The Earth's gravity field in the variational model, whose Jacobian "
        "drives the STM and the sensitivities along the state model's trajectory (the "
        "truncated variational equations); default: gravity.")
    var_third_bodies: ThirdBodies | None = Field(
        None, description="Third bodies of the variational model; default: third_bodies.")
    rtol: Tolerance = Field(1e-13, description="Relative tolerance of the integrator.")
    atol: Tolerance = Field(1e-13, description="Absolute tolerance of the integrator, on km "
                            "and km/s.")
    method: Method = Field(
        "dop853", description="Integration method: 'dop853' (Dormand-Prince 8(5,3), any "
        "force model) or 'rkn12' (Runge-Kutta-Nystrom 12(10) on r'' = a(t, r): about 4x "
        "fewer evaluations than dop853 at 1e-12; refuses velocity-dependent forces).")

    def force_models(self, source: str, earth_orientation: str
                     ) -> tuple[ForceModel, ForceModel]:
        """The (state, variational) Earth-centred force models under ``earth_orientation``.

        Raises
        ------
        InputError
            Naming ``source`` and ``model.gravity`` or ``model.var_gravity``.
        """
        state = earth_model(self.gravity, tuple(self.third_bodies), source=source,
                            field="model.gravity", earth_orientation=earth_orientation)
        var = earth_model(self.gravity if self.var_gravity is None else self.var_gravity,
                          tuple(self.third_bodies if self.var_third_bodies is None
                                else self.var_third_bodies),
                          source=source, field="model.var_gravity",
                          earth_orientation=earth_orientation)
        return state, var

"""The ``[model]`` table of tracking scenarios and SEARCH files: the two force models.

A propagation takes two force models (the study's (J_N, J_M) choice): the state model moves
the trajectory, and the variational model's Jacobian drives Φ and the sensitivities along it
(the seed's truncated variational equations). Every file names them the same way::

    [model]
    gravity = "5x5"            # the state model: Earth field J0, Jn or NxM ...
    third_bodies = ["moon"]    # ... and point-mass third bodies (DE421)
    var_gravity = "J2"         # the variational model (default: the state model's)
    var_third_bodies = []
    area_to_mass_m2_kg = 0.01  # cannonball spacecraft, for SRP and drag ...
    c_r = 1.3                  # ... its radiation pressure coefficient (parameter "Cr")
    c_d = 2.2                  # ... and its drag coefficient (parameter "Cd")
    srp = true                 # solar radiation pressure (Earth and Moon shadows) ...
    var_srp = false            # ... in the variational model (default: srp)
    shadows = true             # SRP dimmed in Earth and Moon shadows ...
    var_shadows = false        # ... in the variational model (default: shadows)
    atmosphere = "harris_priester"   # drag: "none", "exponential" or "harris_priester" ...
    var_atmosphere = "none"    # ... in the variational model (default: atmosphere)
    rho0_kg_m3 = 3.725e-12     # the "exponential" layer: ρ0 at h0, scale height H
    h0_km = 400.0
    scale_height_km = 58.515
    rtol = 1e-13               # integrator tolerances
    atol = 1e-13
    method = "dop853"          # or "rkn12" (tapp.dynamics.propagate)
    centre_changes = [         # integrate about another body from a time on (tracking
        { time = 259200.0, center = "sun" },           # scenarios: s or UTC date) ...
        { time = "2031-07-22T00:00:00", center = "mars" },
    ]                          # ... inputs and outputs stay about `center`

and the study file's runs name their models ``gravity`` and ``var_gravity`` too. The
spellings ``stm_gravity`` and ``stm_third_bodies`` of earlier SEARCH files are refused, naming
the new key.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Literal

from pydantic import AfterValidator, Field

from tapp.constants import MAX_DEGREE
from tapp.dynamics.centres import CentreChange
from tapp.dynamics.compiled import METHODS
from tapp.dynamics.propagate import Propagator
from tapp.dynamics.spec import (
    ATMOSPHERES,
    BODIES,
    SURFACE_RANGES,
    ExponentialLayer,
    ForceModel,
    SurfaceForces,
    check_surface_value,
    parse_gravity,
)
from tapp.errors import InputError
from tapp.io.schema import Invalid, Schema, Time, Tolerance, Unique


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
#: A DE421 body: the centre of the integration, or a third body (not the centre).
Body = Literal[BODIES]  # type: ignore[valid-type]
ThirdBody = Body
#: Third bodies, each once.
ThirdBodies = Annotated[list[ThirdBody], Unique]
#: An atmosphere model of the drag force ("none": no drag).
Atmosphere = Literal[ATMOSPHERES]  # type: ignore[valid-type]


def _surface_value(name: str):
    """A float checked by :func:`tapp.dynamics.spec.check_surface_value`, its range shown."""

    def check(value: float) -> float:
        try:
            return check_surface_value(name, value)
        except InputError as exc:
            raise Invalid(exc.expected, value) from None

    lo, hi, closed, _ = SURFACE_RANGES[name]
    bounds = {"minimum" if closed else "exclusiveMinimum": lo, "maximum": hi}
    return Annotated[float, AfterValidator(check), Field(json_schema_extra=bounds)]


AreaToMass = _surface_value("area_to_mass_m2_kg")
RadiationCoefficient = _surface_value("c_r")
DragCoefficient = _surface_value("c_d")
LayerDensity = _surface_value("rho0_kg_m3")
LayerHeight = _surface_value("h0_km")
ScaleHeight = _surface_value("scale_height_km")
#: The exponential atmosphere's default layer (Vallado 2013 Table 8-4, 400 km).
_LAYER = ExponentialLayer()
#: An integration method of :class:`tapp.dynamics.Propagator`.
Method = Literal[tuple(METHODS)]  # type: ignore[valid-type]


class CentreChangeRow(Schema):
    """One ``[model] centre_changes`` entry: from ``time`` on, integrate about ``center``."""

    time: Time = Field(description="When the centre changes: s from the epoch (> 0) or a UTC "
                       "date, after the change before.")
    center: Body = Field(description="The body to integrate about from then on: the model's "
                         "centre or one of its third bodies (of both models).")


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
    area_to_mass_m2_kg: AreaToMass | None = Field(
        None, description="Cross-section over mass of the cannonball spacecraft, m^2/kg, in "
        "(0, 50] (spacecraft ~0.002-0.05, solar sails ~10); required by srp and atmosphere.")
    c_r: RadiationCoefficient = Field(
        1.3, description="Radiation pressure coefficient C_r = 1 + reflectivity, in [0, 2.5] "
        "(a sphere: [1, 2]; margin for estimated values); the nominal value of parameter Cr.")
    c_d: DragCoefficient = Field(
        2.2, description="Drag coefficient, in (0, 5] (free-molecular flow: ~2-4); the nominal "
        "value of parameter Cd.")
    srp: bool = Field(False, description="Solar radiation pressure on a cannonball, with "
                      "conical Earth and Moon shadows, in the state model.")
    var_srp: bool | None = Field(None, description="Solar radiation pressure in the "
                                 "variational model; default: srp.")
    shadows: bool = Field(True, description="Dim SRP in the conical shadows of the Earth and "
                          "the Moon (penumbra included), in the state model.")
    var_shadows: bool | None = Field(
        None, description="Shadows in the variational model's SRP; default: shadows (the "
        "integrators locate every shadow boundary, so Φ and the C_r partials stay exact "
        "through them).")
    atmosphere: Atmosphere = Field(
        "none", description="Drag in the state model: \"none\", \"exponential\" (one layer, "
        "Vallado 2013 Table 8-4 at 400 km) or \"harris_priester\" (Montenbruck & Gill Table "
        "3.8, mean solar activity); Earth-centred orbits only.")
    rho0_kg_m3: LayerDensity = Field(
        _LAYER.rho0_kg_m3, description="Density at h0_km of the \"exponential\" atmosphere, "
        "kg/m^3 (default: Vallado 2013 Table 8-4, 400 km).")
    h0_km: LayerHeight = Field(
        _LAYER.h0_km, description="Base height of the \"exponential\" atmosphere above the "
        "WGS84 ellipsoid, km.")
    scale_height_km: ScaleHeight = Field(
        _LAYER.scale_height_km, description="Scale height H of the \"exponential\" "
        "atmosphere, ρ = ρ0 exp(−(h − h0)/H), km.")
    var_atmosphere: Atmosphere | None = Field(
        None, description="Drag in the variational model (its Jacobian then has ∂a/∂v); "
        "default: atmosphere.")
    rtol: Tolerance = Field(1e-13, description="Relative tolerance of the integrator.")
    atol: Tolerance = Field(1e-13, description="Absolute tolerance of the integrator, on km "
                            "and km/s.")
    center: Body = Field(
        "earth", description="Centre of the integration (ICRF axes, origin at its centre; "
        "the [injection] state is relative to it): the Earth, or any DE421 body, as a point "
        "mass or with its J2 (the Moon, Mars, Venus); the other bodies as third bodies.")
    method: Method = Field(
        "dop853", description="Integration method: 'dop853' (Dormand-Prince 8(5,3), any "
        "force model) or 'rkn12' (Runge-Kutta-Nystrom 12(10) on r'' = a(t, r): about 4x "
        "fewer evaluations than dop853 at 1e-12; refuses velocity-dependent forces).")
    centre_changes: list[CentreChangeRow] = Field(
        [], description="Changes of the integration centre, ascending in time (tracking "
        "scenarios): each interval is integrated about its body, with the same bodies acting "
        "as point masses (the centre's field and drag only about it), and the state, STM and "
        "sensitivities translated back, so every input and output stays about center "
        "(tapp.dynamics.centres).")

    def force_models(self, source: str, earth_orientation: str
                     ) -> tuple[ForceModel, ForceModel]:
        """The (state, variational) force models about :attr:`center` under
        ``earth_orientation``.

        Raises
        ------
        InputError
            Naming ``source`` and ``model.gravity``, ``model.var_gravity``,
            ``model.third_bodies``, ``model.var_third_bodies`` (the centre among them; a field
            the centre has not) or ``model.atmosphere``, or ``model.area_to_mass_m2_kg`` when
            SRP or drag is asked without it.
        """
        state = self._model(source, "", self.gravity, self.third_bodies,
                            earth_orientation, self._surface(source, self.srp, self.atmosphere,
                                                             self.shadows))
        var = self._model(source, "var_",
                          self.gravity if self.var_gravity is None else self.var_gravity,
                          self.third_bodies if self.var_third_bodies is None
                          else self.var_third_bodies, earth_orientation,
                          self._surface(
                              source, self.srp if self.var_srp is None else self.var_srp,
                              self.atmosphere if self.var_atmosphere is None
                              else self.var_atmosphere,
                              self.shadows if self.var_shadows is None else self.var_shadows))
        return state, var

    def _model(self, source: str, prefix: str, gravity: str, third_bodies: list[str],
               earth_orientation: str, surface: SurfaceForces | None) -> ForceModel:
        """One force model about :attr:`center`, its errors named ``model.<prefix><key>``."""
        spec = parse_gravity(gravity, source=source, field=f"model.{prefix}gravity")
        try:
            return ForceModel(spec, self.center, tuple(third_bodies), earth_orientation,
                              surface)
        except InputError as exc:  # named after the kernel, not the file
            key = exc.field if exc.field == "atmosphere" else f"{prefix}{exc.field}"
            raise InputError(source, f"model.{key}", exc.expected, exc.got) from None

    def propagator(self, source: str, state_model: ForceModel, var_model: ForceModel,
                   params: tuple[str, ...] = (),
                   time_s: Callable[[object, str], float] | None = None) -> Propagator:
        """The propagator of the table's models (:meth:`force_models`), tolerances, method
        and centre changes, with the sensitivities to ``params``.

        ``time_s(value, field)`` converts a file time (s or UTC date) to s from the epoch;
        a file whose reader gives none cannot have centre changes.

        Raises
        ------
        InputError
            Naming ``source`` and ``model.method``: "rkn12" for forces that depend on the
            velocity (drag, or ``params`` whose partials do: stochastic accelerations in RIC
            axes); or ``model.centre_changes[i].time`` / ``.center``
            (:func:`tapp.dynamics.centres.check_centre_changes`), or ``model.centre_changes``
            in a file without times.
        """
        if self.centre_changes and time_s is None:
            raise InputError(source, "model.centre_changes", "no centre changes in this file "
                             "(tracking scenarios only)", len(self.centre_changes))
        changes = tuple(CentreChange(time_s(row.time, f"model.centre_changes[{i}].time"),
                                     row.center) for i, row in enumerate(self.centre_changes))
        try:
            return Propagator(state_model, var_model, params, rtol=self.rtol, atol=self.atol,
                              method=self.method, centre_changes=changes)
        except InputError as exc:  # named after the Propagator, not the file
            raise InputError(source, f"model.{exc.field}", exc.expected, exc.got) from None

    def _surface(self, source: str, srp: bool, atmosphere: str, shadows: bool
                 ) -> SurfaceForces | None:
        """The surface forces of one model, None when it has neither SRP nor drag."""
        if not srp and atmosphere == "none":
            return None
        if self.area_to_mass_m2_kg is None:
            raise InputError(source, "model.area_to_mass_m2_kg", "the spacecraft's area-to-mass "
                             "ratio (m^2/kg) when srp or an atmosphere is modelled")
        return SurfaceForces(self.area_to_mass_m2_kg, srp, self.c_r, atmosphere, self.c_d,
                             shadows, ExponentialLayer(self.rho0_kg_m3, self.h0_km,
                                                       self.scale_height_km))

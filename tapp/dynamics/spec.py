"""Force-model specifications: what a trajectory or a variational model contains.

A gravity spec is written as in the approximate-STM study: ``J0`` (point mass), ``Jn``
(zonal harmonics to degree n), ``NxM`` (degree N, order M, zonals and tesserals). A force
model adds the central body, the third bodies and the surface forces of a cannonball
spacecraft (solar radiation pressure and atmospheric drag, :class:`SurfaceForces`). These are
plain data; the CasADi expressions are built from them in :mod:`tapp.dynamics.forces`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from tapp.constants import J2_CENTRE, MAX_DEGREE, GM_km3_s2
from tapp.dynamics.parameters import SURFACE_FIELDS
from tapp.errors import InputError
from tapp.frames.orientation import check_model

#: Bodies whose shadows SRP models about any centre (:attr:`ForceModel.occulters`).
SHADOW_BODIES = ("earth", "moon")

_ZONAL = re.compile(r"^[Jj](\d+)$")
_FIELD = re.compile(r"^(\d+)\s*[xX]\s*(\d+)$")

#: Bodies whose ephemeris DE421 provides (centre or third body).
BODIES = ("sun", "mercury", "venus", "earth", "moon", "mars", "jupiter", "saturn", "uranus",
          "neptune")
#: Atmosphere models of the drag force (:mod:`tapp.dynamics.atmosphere`); "none": no drag.
ATMOSPHERES = ("none", "exponential", "harris_priester")
#: Accepted values of the surface-force inputs: name -> (low, high, low included, why).
#: Area-to-mass (m^2/kg): spacecraft lie between ~0.002 (a dense bus) and ~0.05 (large
#: arrays); solar sails reach ~10 (LightSail 2: 32 m^2 / 5 kg = 6.4) and thin MLI debris ~30:
#: above 50 the value is a unit slip (cm^2/g). C_r = 1 + ε for a sphere of reflectivity ε in
#: [0, 1] lies in [1, 2] (0: a transparent body); the margin to 2.5 admits values estimated on
#: flight data, which absorb unmodelled forces. C_d: free-molecular flow gives 2 to 2.5 for a
#: compact body and up to ~4 for a flat plate in very rarefied flow. The exponential layer:
#: densities above sea level's 1.225 kg/m^3, base heights beyond 2500 km (where no drag is
#: left to model) and scale heights above 1000 km (the thermosphere's are < 300 km) are slips.
SURFACE_RANGES = {
    "area_to_mass_m2_kg": (0.0, 50.0, False,
                           "m^2/kg: spacecraft ~0.002-0.05, solar sails ~10; above 50 is a "
                           "unit slip"),
    "c_r": (0.0, 2.5, True, "C_r = 1 + reflectivity lies in [1, 2]; up to 2.5 for estimated "
                            "values"),
    "c_d": (0.0, 5.0, False, "free-molecular drag coefficients are ~2-4"),
    "rho0_kg_m3": (0.0, 1.3, False, "kg/m^3: sea level's density is 1.225"),
    "h0_km": (0.0, 2500.0, True, "km above the ellipsoid, within the atmosphere"),
    "scale_height_km": (0.0, 1000.0, False, "km: thermospheric scale heights are 5-300 km"),
}


def check_surface_value(name: str, value: object, source: str = "model",
                        field: str | None = None) -> float:
    """Return ``value`` as a float if the input ``name`` (a key of :data:`SURFACE_RANGES`,
    or the parameter ``Cr``/``Cd`` of its field: :data:`tapp.dynamics.parameters.SURFACE_FIELDS`)
    accepts it, else raise InputError naming ``source``, ``field`` (default ``name``), the
    range and its reason."""
    field = name if field is None else field
    key = SURFACE_FIELDS.get(name, name)
    if key not in SURFACE_RANGES:
        raise InputError(source, field, f"one of {', '.join(SURFACE_RANGES)}", name)
    lo, hi, closed, why = SURFACE_RANGES[key]
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or not (lo <= value <= hi if closed else lo < value <= hi):
        raise InputError(source, field, f"a value in {'[' if closed else '('}{lo:g}, {hi:g}] "
                         f"({why})", value)
    return float(value)


@dataclass(frozen=True, slots=True)
class ExponentialLayer:
    """One-layer exponential atmosphere ρ = ρ0 exp(−(h − h0)/H).

    The defaults are the 400-450 km band of Vallado (*Fundamentals of Astrodynamics and
    Applications*, 4th ed., 2013, Table 8-4, from CIRA-72), used at every height.
    """

    rho0_kg_m3: float = 3.725e-12
    h0_km: float = 400.0
    scale_height_km: float = 58.515

    def __post_init__(self) -> None:
        for name in ("rho0_kg_m3", "h0_km", "scale_height_km"):
            check_surface_value(name, getattr(self, name))


@dataclass(frozen=True, slots=True)
class GravitySpec:
    """Spherical-harmonic truncation of the central body's field: degree and order."""

    degree: int
    order: int

    @property
    def name(self) -> str:
        """The spec in the study's notation (``J0``, ``J2``, ``5x5``)."""
        if self.order == 0:
            return f"J{self.degree}"
        return f"{self.degree}x{self.order}"


def parse_gravity(spec: str, *, source: str = "model", field: str = "gravity") -> GravitySpec:
    """Parse ``J0`` / ``Jn`` / ``NxM`` into a :class:`GravitySpec`.

    Raises
    ------
    InputError
        For an unknown spec, order above degree, or a degree above the shipped field
        (``tapp.constants.MAX_DEGREE``). J1 is accepted as the point mass (degree-1
        coefficients vanish in a centre-of-mass frame).
    """
    text = str(spec).strip()
    if m := _ZONAL.match(text):
        degree, order = int(m.group(1)), 0
    elif m := _FIELD.match(text):
        degree, order = int(m.group(1)), int(m.group(2))
    else:
        raise InputError(source, field, "a gravity model J0, Jn (zonals to degree n) or NxM "
                         "(degree N, order M)", spec)
    if order > degree:
        raise InputError(source, field, "order M <= degree N in NxM", spec)
    if degree > MAX_DEGREE:
        raise InputError(source, field, f"degree <= {MAX_DEGREE} (the shipped EGM96 field)",
                         spec)
    return GravitySpec(degree=degree, order=order)


@dataclass(frozen=True, slots=True)
class SurfaceForces:
    """Non-gravitational forces on a cannonball spacecraft (one area for every direction).

    Attributes
    ----------
    area_to_mass_m2_kg : cross-section over mass, m^2/kg, in :data:`SURFACE_RANGES`.
    srp : True to include solar radiation pressure (:mod:`tapp.dynamics.radiation`).
    c_r : radiation pressure coefficient (1 + reflectivity), in :data:`SURFACE_RANGES`; its nominal
        value as the parameter ``Cr``.
    atmosphere : one of :data:`ATMOSPHERES`: the density model of the drag force
        (:mod:`tapp.dynamics.atmosphere`), ``"none"`` for no drag.
    c_d : drag coefficient, in :data:`SURFACE_RANGES`; its nominal value as the parameter ``Cd``.
    shadows : True to dim SRP in the occulting bodies' shadows (:attr:`ForceModel.occulters`;
        their boundaries are integration events: :mod:`tapp.dynamics.events`). Without them
        SRP is the gradient of a potential (−k/|r − r☉|) and the STM symplectic; with them,
        and with drag, it is not.
    exponential : the layer of the ``"exponential"`` atmosphere.
    """

    area_to_mass_m2_kg: float
    srp: bool = False
    c_r: float = 1.3
    atmosphere: str = "none"
    c_d: float = 2.2
    shadows: bool = True
    exponential: ExponentialLayer = field(default_factory=ExponentialLayer)

    def __post_init__(self) -> None:
        check_surface_value("area_to_mass_m2_kg", self.area_to_mass_m2_kg)
        check_surface_value("c_r", self.c_r)
        check_surface_value("c_d", self.c_d)
        if self.atmosphere not in ATMOSPHERES:
            raise InputError("model", "atmosphere", f"one of {', '.join(ATMOSPHERES)}",
                             self.atmosphere)

    @property
    def drag(self) -> bool:
        """True when an atmosphere is modelled."""
        return self.atmosphere != "none"

    @property
    def name(self) -> str:
        """Short label: ``srp`` (or ``srp(no shadows)``), ``drag(harris_priester)``, both
        joined by ``+``, or ``""``."""
        srp = "srp" if self.shadows else "srp(no shadows)"
        parts = [srp] * self.srp + [f"drag({self.atmosphere})"] * self.drag
        return "+".join(parts)


@dataclass(frozen=True, slots=True)
class ForceModel:
    """The accelerations acting on the spacecraft, relative to ``center``.

    Attributes
    ----------
    gravity : GravitySpec
        Truncation of the central body's field: any within EGM96 for the Earth; ``J0`` or
        ``J2`` for the Moon, Mars and Venus (:data:`tapp.constants.J2_CENTRE`, about their IAU
        pole, :mod:`tapp.dynamics.poles`); ``J0`` for the other centres.
    center : str
        Central body of the integration frame (EME2000 axes), one of ``BODIES``.
    third_bodies : tuple of str
        Point-mass perturbers, from DE421, with the indirect term of a non-inertial centre;
        each at most once (a repeated body would add its pull twice).
    earth_orientation : str
        How the Earth's field is oriented (:data:`tapp.frames.orientation.MODELS`):
        ``"gmst"`` (a zonal field about the inertial z axis, tesserals by GMST + ω t) or
        ``"iau2006"`` (the full GCRS → ITRS rotation). Scenario files default to iau2006;
        this kernel default keeps the study's model.
    surface : SurfaceForces or None
        Solar radiation pressure and drag; None (the default) for neither. Drag needs an
        Earth centre (the atmospheres are the Earth's).
    """

    gravity: GravitySpec
    center: str = "earth"
    third_bodies: tuple[str, ...] = ()
    earth_orientation: str = "gmst"
    surface: SurfaceForces | None = None

    def __post_init__(self) -> None:
        check_model(self.earth_orientation, "model")
        if self.center not in BODIES:
            raise InputError("model", "center", f"one of {', '.join(BODIES)}", self.center)
        if self.center != "earth":
            check_center_field(self.center, self.gravity)
        for body in self.third_bodies:
            if body not in BODIES or body == self.center:
                raise InputError("model", "third_bodies",
                                 f"bodies among {', '.join(BODIES)} other than the centre", body)
        for i, body in enumerate(self.third_bodies):
            if body in self.third_bodies[:i]:
                raise InputError("model", "third_bodies", f"each body once ({body} given "
                                 f"{self.third_bodies.count(body)} times would multiply its "
                                 "pull)", list(self.third_bodies))
        if self.drag and self.center != "earth":
            raise InputError("model", "atmosphere", "drag only about the Earth (the atmosphere "
                             f"models are the Earth's; centre {self.center})",
                             self.surface.atmosphere)

    @property
    def srp(self) -> bool:
        """True when solar radiation pressure is modelled."""
        return self.surface is not None and self.surface.srp

    @property
    def drag(self) -> bool:
        """True when atmospheric drag is modelled (the acceleration then depends on v)."""
        return self.surface is not None and self.surface.drag

    @property
    def occulters(self) -> tuple[str, ...]:
        """Bodies whose shadows SRP has (none without shadows): the Earth and the Moon
        (:data:`SHADOW_BODIES`), and the centre itself when it is another body (Mars' shadow
        on an approach through its periapsis); never the Sun."""
        if not (self.srp and self.surface.shadows):
            return ()
        return tuple(b for b in dict.fromkeys((*SHADOW_BODIES, self.center)) if b != "sun")

    @property
    def ephemeris_bodies(self) -> tuple[str, ...]:
        """Bodies whose positions the model reads: third bodies, the Sun and the occulting
        bodies for SRP (source and shadows), the Sun for the Harris-Priester bulge; not the
        centre."""
        need = set(self.third_bodies)
        if self.srp:
            need |= {"sun", *self.occulters}
        if self.drag and self.surface.atmosphere == "harris_priester":
            need.add("sun")
        return tuple(sorted(need - {self.center}))

    @property
    def gm_center_km3_s2(self) -> float:
        """GM of the central body (km^3/s^2)."""
        return GM_km3_s2[self.center]

    @property
    def name(self) -> str:
        """Short label, e.g. ``J2`` or ``5x5+sun+moon``."""
        surface = () if self.surface is None or not self.surface.name else (self.surface.name,)
        return "+".join((self.gravity.name, *self.third_bodies, *surface))

    @property
    def pole_field(self) -> bool:
        """True when the field is the J2 of a centre other than the Earth, about that body's
        moving IAU pole (:mod:`tapp.dynamics.poles`)."""
        return self.center != "earth" and self.gravity.degree >= 2

    @property
    def oriented_field(self) -> bool:
        """True when the field needs the full Earth orientation (iau2006 and degree >= 2)."""
        return self.earth_orientation == "iau2006" and self.center == "earth" and \
            self.gravity.degree >= 2


def check_center_field(center: str, gravity: GravitySpec) -> None:
    """Raise InputError naming ``gravity`` unless a centre other than the Earth has a field
    it ships: ``J0`` or ``J2`` for the bodies of :data:`tapp.constants.J2_CENTRE`, ``J0`` for
    the others."""
    has_j2 = center in J2_CENTRE
    if gravity.order > 0 or gravity.degree > (2 if has_j2 else 1):
        zonal = ", ".join(sorted(J2_CENTRE))
        expected = (f"J0 or J2 for centre {center} (only its zonal J2 is shipped)" if has_j2
                    else f"J0 for centre {center} (no field shipped; J2 exists for {zonal}, "
                    "any EGM96 truncation for the earth)")
        raise InputError("model", "gravity", expected, gravity.name)


def earth_model(spec: str, third_bodies: tuple[str, ...] = (), *, source: str = "model",
                field: str = "gravity", earth_orientation: str = "gmst",
                surface: SurfaceForces | None = None) -> ForceModel:
    """Return an Earth-centred :class:`ForceModel` from a gravity spec string."""
    return ForceModel(parse_gravity(spec, source=source, field=field), "earth",
                      tuple(third_bodies), earth_orientation, surface)

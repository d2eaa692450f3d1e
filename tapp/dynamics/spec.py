"""Force-model specifications: what a trajectory or a variational model contains.

A gravity spec is written as in the approximate-STM study: ``J0`` (point mass), ``Jn``
(zonal harmonics to degree n), ``NxM`` (degree N, order M, zonals and tesserals). A force
model adds the central body and the third bodies. These are plain data; the CasADi
expressions are built from them in :mod:`tapp.dynamics.forces`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from tapp.constants import MAX_DEGREE, GM_km3_s2
from tapp.errors import InputError
from tapp.frames.orientation import check_model

_ZONAL = re.compile(r"^[Jj](\d+)$")
_FIELD = re.compile(r"^(\d+)\s*[xX]\s*(\d+)$")

#: Bodies whose ephemeris DE421 provides (centre or third body).
BODIES = ("sun", "mercury", "venus", "earth", "moon", "mars", "jupiter", "saturn", "uranus",
          "neptune")


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
class ForceModel:
    """The accelerations acting on the spacecraft, relative to ``center``.

    Attributes
    ----------
    gravity : GravitySpec
        Truncation of the central body's field; only the Earth has harmonics here, other
        centres must be point masses (``J0``).
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
    """

    gravity: GravitySpec
    center: str = "earth"
    third_bodies: tuple[str, ...] = ()
    earth_orientation: str = "gmst"

    def __post_init__(self) -> None:
        check_model(self.earth_orientation, "model")
        if self.center not in BODIES:
            raise InputError("model", "center", f"one of {', '.join(BODIES)}", self.center)
        if self.center != "earth" and self.gravity.degree > 1:
            raise InputError("model", "gravity",
                             "J0 for a centre other than the Earth (no field shipped)",
                             self.gravity.name)
        for body in self.third_bodies:
            if body not in BODIES or body == self.center:
                raise InputError("model", "third_bodies",
                                 f"bodies among {', '.join(BODIES)} other than the centre", body)
        for i, body in enumerate(self.third_bodies):
            if body in self.third_bodies[:i]:
                raise InputError("model", "third_bodies", f"each body once ({body} given "
                                 f"{self.third_bodies.count(body)} times would multiply its "
                                 "pull)", list(self.third_bodies))

    @property
    def gm_center_km3_s2(self) -> float:
        """GM of the central body (km^3/s^2)."""
        return GM_km3_s2[self.center]

    @property
    def name(self) -> str:
        """Short label, e.g. ``J2`` or ``5x5+sun+moon``."""
        return "+".join((self.gravity.name, *self.third_bodies))

    @property
    def oriented_field(self) -> bool:
        """True when the field needs the full Earth orientation (iau2006 and degree >= 2)."""
        return self.earth_orientation == "iau2006" and self.center == "earth" and \
            self.gravity.degree >= 2


def earth_model(spec: str, third_bodies: tuple[str, ...] = (), *, source: str = "model",
                field: str = "gravity", earth_orientation: str = "gmst") -> ForceModel:
    """Return an Earth-centred :class:`ForceModel` from a gravity spec string."""
    return ForceModel(parse_gravity(spec, source=source, field=field), "earth",
                      tuple(third_bodies), earth_orientation)

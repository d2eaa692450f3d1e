"""The guidance file (TOML) of a TAPP II study, and its binding to a T32 tape.

Layout (units at the edge: mrad, mm/s, deg; the code works in rad, km/s)::

    title = "..."
    [tape]                          # optional expectation checked against the tape
    iden = "DSN-LUNAR-2026-03-10"
    [targets]
    miss = ["b_dot_t_km", "b_dot_r_km"]   # 2 or 3 miss components of the tape to null
    [manoeuvres]
    recycles = [1, 2, 3]            # recycle numbers i' of the tape (default: all)
    [navigation]
    after_manoeuvre = "tape"        # the tape's estimator, which does not know of the
                                    # manoeuvres; "inflate": its a priori after a manoeuvre
                                    # holds the execution-error covariance
                                    # (tapp.guidance.navigation)
    [execution]                     # 1σ, Gates-type (tapp.guidance.execution)
    sigma_proportional = 0.02       # magnitude error, fraction of |Δv|, < 1
    sigma_pointing_mrad = 10.0      # per axis perpendicular to Δv, <= 200 (small angles)
    sigma_fixed_mm_s = 1.0          # per axis, isotropic, <= 1e6 (1 km/s)
    [corridor]                      # optional: about the aim point
    radius_km = 100.0               # a circle in the B-plane, or
    # semi_axes_km = [150.0, 80.0]  # an ellipse, the first axis at angle_deg
    # angle_deg = 30.0              # from T toward R
    flight_time_s = 60.0            # optional |Δt_f| limit

Every σ must be finite and >= 0; the corridor's sizes > 0; targets and manoeuvres are
checked against the tape when bound (:func:`bind`), and the corridor's terms must be on
targeted components (B·T and B·R for the B-plane, the flight time for its limit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from tapp.dynamics.gates import MAX_FIXED_km_s, MAX_POINTING_rad
from tapp.errors import InputError
from tapp.guidance.execution import ExecutionErrors
from tapp.guidance.model import Problem, build_problem
from tapp.guidance.navigation import inflate_after_manoeuvres
from tapp.guidance.statistics import BPLANE, FLIGHT_TIME, Corridor, bplane_rows, flight_time_row
from tapp.io.schema import Invalid, Schema, Unique, load
from tapp.io.tape.t32 import T32

#: Largest pointing σ, mrad, and fixed σ per axis, mm/s: Gates' model's bounds
#: (:data:`tapp.dynamics.gates.MAX_POINTING_rad`, :data:`~tapp.dynamics.gates.MAX_FIXED_km_s`).
MAX_POINTING_MRAD = MAX_POINTING_rad * 1e3
MAX_FIXED_MM_S = MAX_FIXED_km_s * 1e6

Positive = Annotated[float, Field(gt=0)]


class TapeExpect(Schema):
    """``[tape]``: what the guidance file expects of the tape, checked when it is bound."""

    iden: str | None = Field(None, description="The tape's identification (the scenario's "
                             "iden).")


class Targets(Schema):
    """``[targets]``: the miss components each manoeuvre nulls (its estimate of them)."""

    miss: Annotated[list[str], Field(min_length=2, max_length=3), Unique] = Field(
        description="Miss components of the tape (b_dot_r_km, b_dot_t_km, flight_time_s, ...).")


class Manoeuvres(Schema):
    """``[manoeuvres]``: when the midcourse manoeuvres are made."""

    recycles: Annotated[list[int], Field(min_length=1), Unique] | None = Field(
        None, description="Recycle numbers of the tape (1-based); default: every recycle.")


class Navigation(Schema):
    """``[navigation]``: how the orbit determination treats a manoeuvre."""

    after_manoeuvre: Literal["tape", "inflate"] = Field(
        "tape", description="\"tape\": the tape's estimator, which never hears of the "
        "manoeuvres; \"inflate\": its information after a manoeuvre holds the "
        "execution-error covariance.")


class ExecutionTable(Schema):
    """``[execution]``: Gates-type execution errors of each manoeuvre, 1σ."""

    sigma_proportional: Annotated[float, Field(ge=0, lt=1)] = Field(
        0.0, description="Magnitude error along Δv, a fraction of |Δv|.",
        json_schema_extra={"unit": "1"})
    sigma_pointing_mrad: Annotated[float, Field(ge=0, le=MAX_POINTING_MRAD)] = Field(
        0.0, description="Pointing error per axis perpendicular to Δv (small angles).")
    sigma_fixed_mm_s: Annotated[float, Field(ge=0, le=MAX_FIXED_MM_S)] = Field(
        0.0, description="Error per axis independent of Δv.")


class CorridorTable(Schema):
    """``[corridor]``: the accepted arrival about the aim point, on targeted components."""

    radius_km: Positive | None = Field(None, description="A circle in the B-plane (or "
                                       "semi_axes_km).")
    semi_axes_km: Annotated[list[Positive], Field(min_length=2, max_length=2)] | None = Field(
        None, description="An ellipse in the B-plane, the first axis at angle_deg.")
    angle_deg: float = Field(0.0, description="Angle of the ellipse's first axis from T "
                             "toward R.")
    flight_time_s: Positive | None = Field(None, description="Largest |Δ flight time| "
                                           "accepted; default: no limit.")

    @model_validator(mode="after")
    def _one_shape(self) -> CorridorTable:
        if (self.radius_km is None) == (self.semi_axes_km is None):
            raise Invalid("either radius_km or semi_axes_km (the B-plane corridor)",
                          {"radius_km": self.radius_km, "semi_axes_km": self.semi_axes_km})
        return self


class GuideFile(Schema):
    """The guidance file (module docstring); validated strictly, unknown keys are errors."""

    title: str = Field("", description="Free text, printed in the report.")
    tape: TapeExpect = Field(TapeExpect(), description="Expectations checked against the tape.")
    targets: Targets = Field(description="What the manoeuvres null.")
    manoeuvres: Manoeuvres = Field(Manoeuvres(), description="When they are made.")
    navigation: Navigation = Field(Navigation(), description="How the navigation treats them.")
    execution: ExecutionTable = Field(ExecutionTable(), description="Their execution errors.")
    corridor: CorridorTable | None = Field(None, description="The accepted arrival; default: "
                                           "none.")


def read_guide(path: Path | str) -> GuideFile:
    """Read and validate a guidance file (errors name the file and the field)."""
    return load(GuideFile, path)


@dataclass(frozen=True, slots=True, eq=False)
class Study:
    """A guidance file bound to its tape: the problem, the corridor, the navigation model
    ("tape" or "inflate") and the title."""

    problem: Problem
    corridor: Corridor | None
    navigation: str
    title: str


def _corridor(table: CorridorTable | None, t32: T32, targets: tuple[str, ...], source: str
              ) -> Corridor | None:
    """The corridor of the guidance file, on targeted miss components only.

    A corridor term on a component the guidance does not target (a flight-time limit when
    the flight time is not among ``targets.miss``, a B-plane corridor without both B·T and
    B·R) is refused rather than printed with a warning. A corridor is the acceptance test
    of the guidance; on a component no manoeuvre corrects, the fraction outside measures
    that component's free dispersion instead (on the deep-space tape an untargeted flight
    time ends with σ = 18,000 s against 0.33 s targeted, an untargeted B·T with 1,500 km
    against 0.42 km), and it swamps the targeted terms in "outside either". Its likely
    cause is a component left out of the targets; and refusing loses nothing, since the
    final-miss table gives the σ of every component, targeted or not.
    """
    if table is None:
        return None
    names = t32.miss_name
    if bplane_rows(names) is None:
        raise InputError(source, "corridor", f"a tape with the B-plane miss components "
                         f"{', '.join(BPLANE)}", ", ".join(names))
    ft = flight_time_row(names)
    if table.flight_time_s is not None and ft is None:
        raise InputError(source, "corridor.flight_time_s", f"a tape with a flight time miss "
                         f"component ({' or '.join(FLIGHT_TIME)})", ", ".join(names))
    terms = {"radius_km" if table.semi_axes_km is None else "semi_axes_km": BPLANE}
    if table.flight_time_s is not None:
        terms["flight_time_s"] = (names[ft],)
    for field, components in terms.items():
        free = [c for c in components if c not in targets]
        if free:
            raise InputError(source, f"corridor.{field}", "a corridor on targeted miss "
                             f"components only (targets.miss: {', '.join(targets)})",
                             f"{', '.join(free)} not targeted")
    axes = (table.radius_km, table.radius_km) if table.semi_axes_km is None \
        else tuple(table.semi_axes_km)
    return Corridor(axes, math.radians(table.angle_deg), table.flight_time_s)


def bind(guide: GuideFile, t32: T32, source: str, tape_source: str = "T32") -> Study:
    """Return the study a guidance file asks of a tape.

    Raises
    ------
    InputError
        A tape other than the one expected, targets or manoeuvre recycles the tape does not
        have, targets the velocity cannot control, a corridor without B-plane (or flight-time)
        miss components or on components not targeted (naming the guidance file), or orbit
        parameters that are not Cartesian (naming the tape).
    """
    if guide.tape.iden is not None and guide.tape.iden != t32.iden:
        raise InputError(source, "tape.iden", f"the tape's identification {t32.iden!r}",
                         guide.tape.iden)
    ex = guide.execution
    errors = ExecutionErrors(ex.sigma_proportional, ex.sigma_pointing_mrad * 1e-3,
                             ex.sigma_fixed_mm_s * 1e-6)
    recycles = guide.manoeuvres.recycles
    manoeuvres = tuple(r.number for r in t32.recycles) if recycles is None else tuple(recycles)
    problem = build_problem(t32, tuple(guide.targets.miss), manoeuvres, errors,
                            tape_source=tape_source, guide_source=source)
    navigation = guide.navigation.after_manoeuvre
    if navigation == "inflate":
        problem = inflate_after_manoeuvres(problem, t32)
    return Study(problem, _corridor(guide.corridor, t32, tuple(guide.targets.miss), source),
                 navigation, guide.title)


__all__ = ["GuideFile", "MAX_FIXED_MM_S", "MAX_POINTING_MRAD", "Study", "bind", "read_guide"]

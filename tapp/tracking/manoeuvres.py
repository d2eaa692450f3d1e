"""The ``[[manoeuvre]]`` tables of tracking scenarios: impulsive and finite burns TAPP I flies.

Each table is one burn (:mod:`tapp.dynamics.manoeuvres`), its vector in inertial, RIC or VNB
axes of the state, with Gates' execution errors (:mod:`tapp.dynamics.gates`)::

    [[manoeuvre]]
    name = "TCM1"                 # default: burn1, burn2, ... (in file order)
    kind = "impulsive"
    time = 86400.0                # s from the epoch, or a UTC date; the state there is the
                                  # one before the burn
    axes = "vnb"                  # "inertial" (the tape's), "ric" or "vnb" (of the state)
    dv_m_s = [2.0, 0.0, -0.5]     # or dv_km_s
    sigma_magnitude_proportional = 0.01     # Gates' four σ (0: that source is left out)
    sigma_magnitude_fixed_mm_s = 5.0
    sigma_pointing_proportional_mrad = 10.0
    sigma_pointing_fixed_mm_s = 5.0

    [[manoeuvre]]
    name = "LOI"
    kind = "finite"
    start = "2026-03-14T02:00:00"
    duration_s = 900.0
    axes = "vnb"
    direction = [-1.0, 0.0, 0.0]  # the thrust's direction (normalised)
    thrust_N = 440.0
    mass_kg = 2000.0              # at ignition
    mass_flow_kg_s = 0.14         # m(t) = mass_kg − mass_flow_kg_s (t − start)

Every burn lies in the arc, from the injection to the last T13 time (an impulsive one before
that time); burns do not overlap (an impulsive burn inside a finite one is an overlap). The
execution errors with σ > 0 are parameters of kind ``execution`` appended to x after the
stochastic accelerations (nominal 0; TAPP III takes their a priori from the tape).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Annotated, Literal, NoReturn

import numpy as np
from pydantic import Field

from tapp.dynamics.gates import MAX_PROPORTIONAL, GatesErrors, MAX_FIXED_km_s, MAX_POINTING_rad
from tapp.dynamics.manoeuvres import AXES, BURN_KINDS, Burn, FiniteBurn, ImpulsiveBurn
from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.io.noise_file import Positive
from tapp.io.schema import Schema, Time

#: Most burns a scenario may fly: each restarts the integration and adds up to six
#: parameters (a column of every factor on the tape).
MAX_MANOEUVRES = 100

Vector = Annotated[list[float], Field(min_length=3, max_length=3)]


class ManoeuvreTable(Schema):
    """``[[manoeuvre]]``: one burn, impulsive (time, dv_m_s or dv_km_s) or finite (start,
    duration_s, thrust_N, direction, mass_kg, mass_flow_kg_s), in inertial, RIC or VNB axes,
    with Gates' four execution-error σ's; burns lie in the arc and do not overlap."""

    name: str | None = Field(None, description="Names its execution-error parameters "
                             "(NAME.mag_prop, ...); default: burn1, burn2, ... in file order.")
    kind: Literal[BURN_KINDS] = Field(  # type: ignore[valid-type]
        description="\"impulsive\" (a velocity change at one time) or \"finite\" (a thrust "
        "over an interval).")
    axes: Literal[tuple(AXES)] = Field(  # type: ignore[valid-type]
        "inertial", description="Axes of dv or direction: \"inertial\" (the tape's frame), "
        "\"ric\" (radial, in-track, cross-track) or \"vnb\" (velocity, orbit normal, binormal) "
        "of the state at the burn.")
    time: Time | None = Field(None, description="An impulsive burn's time (s from the epoch "
                              "or a UTC date); outputs at that time precede it.")
    dv_m_s: Vector | None = Field(None, description="An impulsive burn's velocity change in "
                                  "its axes (or dv_km_s).", json_schema_extra={"unit": "m/s"})
    dv_km_s: Vector | None = Field(None, description="The same in km/s.")
    start: Time | None = Field(None, description="A finite burn's ignition (s from the epoch "
                               "or a UTC date).")
    duration_s: Positive | None = Field(None, description="A finite burn's duration.")
    thrust_N: Positive | None = Field(None, description="A finite burn's thrust.",
                                      json_schema_extra={"unit": "N"})
    direction: Vector | None = Field(None, description="A finite burn's thrust direction in "
                                     "its axes (normalised).")
    mass_kg: Positive | None = Field(None, description="The mass at ignition (finite).",
                                     json_schema_extra={"unit": "kg"})
    mass_flow_kg_s: Positive | None = Field(None, description="The mass flow (finite): "
                                            "m(t) = mass_kg - mass_flow_kg_s (t - start).",
                                            json_schema_extra={"unit": "kg/s"})
    sigma_magnitude_proportional: Annotated[float, Field(ge=0, lt=MAX_PROPORTIONAL)] = Field(
        0.0, description="1σ magnitude error proportional to |Δv|, a fraction of it (0: "
        "none).", json_schema_extra={"unit": "1"})
    sigma_magnitude_fixed_mm_s: Annotated[float, Field(ge=0, le=MAX_FIXED_km_s * 1e6)] = Field(
        0.0, description="1σ magnitude error independent of |Δv| (0: none).")
    sigma_pointing_proportional_mrad: Annotated[
        float, Field(ge=0, le=MAX_POINTING_rad * 1e3)] = Field(
        0.0, description="1σ pointing error per axis across Δv, an angle (small; 0: none).")
    sigma_pointing_fixed_mm_s: Annotated[float, Field(ge=0, le=MAX_FIXED_km_s * 1e6)] = Field(
        0.0, description="1σ velocity error per axis across Δv, independent of |Δv| (0: "
        "none).")


#: The keys of each kind (beside name, kind, axes and the σ's).
_KEYS = {"impulsive": ("time", "dv_m_s", "dv_km_s"),
         "finite": ("start", "duration_s", "thrust_N", "direction", "mass_kg",
                    "mass_flow_kg_s")}


def scenario_manoeuvres(source: str, tables: list[ManoeuvreTable], *,
                        time_s: Callable[[object, str], float], last_s: float, method: str,
                        forbidden: str | None = None, not_at_start: str | None = None
                        ) -> tuple[Burn, ...]:
    """Build the burns of a scenario's ``[[manoeuvre]]`` tables, ascending in time.

    Parameters
    ----------
    source : the scenario file, named in errors.
    tables : the validated tables, in file order.
    time_s : the scenario's conversion of a time (s or UTC date) to s from the epoch, given
        the value and the field it came from.
    last_s : the last T13 time, s (the arc ends there).
    method : the integration method (``rkn12`` refuses a thrust in moving axes).
    forbidden : why the scenario cannot fly burns at all (None: it can).
    not_at_start : why a burn at t = 0 is refused (None: it is not).

    Raises
    ------
    InputError
        ``manoeuvre[i].FIELD``: a key of the other kind or one missing, a burn outside the
        arc (or at t = 0 with ``not_at_start``), overlapping burns, a zero vector, a mass flow
        that empties the tank, a name used twice, a thrust in RIC or VNB axes with ``rkn12``.
    """
    def fail(field: str, expected: str, got: object = None) -> NoReturn:
        raise InputError(source, field, expected, got)

    if tables and forbidden is not None:
        fail("manoeuvre", forbidden, f"{len(tables)} [[manoeuvre]] tables")
    burns: list[tuple[int, Burn]] = []
    for i, table in enumerate(tables):
        where = f"manoeuvre[{i}]"
        for key in _KEYS["finite" if table.kind == "impulsive" else "impulsive"]:
            if getattr(table, key) is not None:
                fail(f"{where}.{key}", f"no {key} for a burn of kind \"{table.kind}\" "
                     f"(its keys: {', '.join(_KEYS[table.kind])})", getattr(table, key))
        name = f"burn{i + 1}" if table.name is None else table.name
        if not name or "." in name or name != name.strip():
            fail(f"{where}.name", "a name without dots or surrounding spaces", name)
        errors = GatesErrors(table.sigma_magnitude_proportional,
                             table.sigma_magnitude_fixed_mm_s * 1e-6,
                             table.sigma_pointing_proportional_mrad * 1e-3,
                             table.sigma_pointing_fixed_mm_s * 1e-6)
        common = {"name": name, "axes": table.axes, "errors": errors}
        if table.kind == "impulsive":
            burn = _impulsive(table, where, common, time_s, last_s, fail)
        else:
            burn = _finite(table, where, common, time_s, last_s, method, fail)
        if not_at_start is not None and burn.t_start_s == 0.0:
            fail(f"{where}.{'time' if burn.kind == 'impulsive' else 'start'}", not_at_start,
                 burn.t_start_s)
        burns.append((i, burn))
    names = [b.name for _, b in burns]
    for i, name in enumerate(names):
        if name in names[:i]:
            fail(f"manoeuvre[{i}].name", "a name of its own (names its parameters)", name)
    burns.sort(key=lambda ib: (ib[1].t_start_s, ib[1].t_end_s))
    for (i, before), (j, after) in zip(burns, burns[1:], strict=False):
        if after.t_start_s < before.t_end_s or after.t_start_s == before.t_start_s:
            field = "time" if after.kind == "impulsive" else "start"
            fail(f"manoeuvre[{j}].{field}", f"a burn that does not overlap manoeuvre[{i}] "
                 f"({before.name}, {before.t_start_s:g} to {before.t_end_s:g} s)",
                 after.t_start_s)
    return tuple(b for _, b in burns)


def _vector(value: list[float], field: str, what: str, fail) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(v)) or not np.any(v != 0):
        fail(field, f"a non-zero {what}", value)
    return v


def _impulsive(table: ManoeuvreTable, where: str, common: dict, time_s, last_s: float,
               fail) -> ImpulsiveBurn:
    if table.time is None:
        fail(f"{where}.time", "the time of an impulsive burn")
    if (table.dv_m_s is None) == (table.dv_km_s is None):
        fail(f"{where}.dv_m_s", "exactly one of dv_m_s or dv_km_s")
    t = time_s(table.time, f"{where}.time")
    if not 0 <= t < last_s:
        fail(f"{where}.time", f"a time in the arc, [0, {last_s:g}) s (the injection to the "
             "last T13 time)", t)
    if table.dv_m_s is not None:
        dv = _vector(table.dv_m_s, f"{where}.dv_m_s", "velocity change", fail) * 1e-3
    else:
        dv = _vector(table.dv_km_s, f"{where}.dv_km_s", "velocity change", fail)
    return ImpulsiveBurn(**common, t_s=t, dv_km_s=tuple(float(x) for x in dv))


def _finite(table: ManoeuvreTable, where: str, common: dict, time_s, last_s: float,
            method: str, fail) -> FiniteBurn:
    for key in _KEYS["finite"]:
        if getattr(table, key) is None:
            fail(f"{where}.{key}", f"the {key} of a finite burn")
    t0 = time_s(table.start, f"{where}.start")
    if t0 < 0:
        fail(f"{where}.start", "an ignition at or after the injection (>= 0 s)", t0)
    if t0 + table.duration_s > last_s:
        fail(f"{where}.duration_s", f"a burn that ends in the arc, by the last T13 time "
             f"{last_s:g} s (at most {last_s - t0:g} s from its start {t0:g} s)",
             table.duration_s)
    d = _vector(table.direction, f"{where}.direction", "direction", fail)
    if table.mass_flow_kg_s * table.duration_s >= table.mass_kg:
        fail(f"{where}.mass_flow_kg_s", f"a mass flow that leaves mass at cut-off (below "
             f"mass_kg / duration_s = {table.mass_kg / table.duration_s:g} kg/s)",
             table.mass_flow_kg_s)
    if method == "rkn12" and table.axes != "inertial":
        fail(f"{where}.axes", "\"inertial\" with model.method = \"rkn12\" (a thrust in RIC or "
             "VNB axes depends on the velocity; rkn12 integrates r'' = a(t, r) only)",
             table.axes)
    return FiniteBurn(**common, t_start_s=t0, duration_s=float(table.duration_s),
                      thrust_N=float(table.thrust_N),
                      direction=tuple(float(x) for x in d / math.hypot(*d)),
                      mass_kg=float(table.mass_kg), mass_flow_kg_s=float(table.mass_flow_kg_s))


def describe(burn: Burn, epoch: Epoch, decimals: int = 3) -> str:
    """One line on ``burn``: its name, kind, time (UTC, ``decimals`` digits of the seconds),
    vector (:func:`vector_text`) and axes (the OEM's and SPK's COMMENT lines)."""
    when = (f"impulsive at {epoch.iso_after(burn.t_s, decimals)} UTC"
            if isinstance(burn, ImpulsiveBurn) else
            f"finite from {epoch.iso_after(burn.t_start_s, decimals)} UTC for "
            f"{burn.duration_s:g} s")
    return (f"{burn.name} {when}: {vector_text(burn)} in {burn.axes} axes "
            f"({''.join(AXES[burn.axes])})")


def vector_text(burn: Burn) -> str:
    """An impulsive burn's ``dv = [..] m/s``; a finite burn's thrust, direction, mass, flow
    and ideal Δv."""
    def vector(v) -> str:
        return "[" + ", ".join(f"{x:.9g}" for x in v) + "]"

    if isinstance(burn, ImpulsiveBurn):
        return f"dv = {vector(1e3 * np.asarray(burn.dv_km_s))} m/s"
    return (f"thrust {burn.thrust_N:.9g} N along {vector(burn.direction)}, mass "
            f"{burn.mass_kg:g} kg, flow {burn.mass_flow_kg_s:g} kg/s (ideal dv "
            f"{1e3 * burn.delta_v_km_s():.6g} m/s)")

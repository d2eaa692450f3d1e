"""The SEARCH file and a tracking scenario's ``[targeting]`` table: their schemas, and the
:class:`~tapp.targeting.program.BPlaneSearch` each one builds (:func:`scenario_search`,
:func:`scenario_targeting`). The reference of the SEARCH file is ``docs/reference/search.md``.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, Field

from tapp.constants import SECONDS_PER_DAY, RADIUS_km
from tapp.dynamics import Propagator
from tapp.dynamics.ephemeris import tdb_reader
from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch, parse_epoch
from tapp.io.eop_file import orientation_for
from tapp.io.models_file import ModelTable
from tapp.io.orbits import OrbitTable
from tapp.io.schema import (
    EarthOrientationName,
    EopSource,
    Invalid,
    Schema,
    Unique,
    UtcDate,
    validate,
)
from tapp.orbit.bplane import REFERENCE_PLANES
from tapp.targeting.program import (
    FIRST_GUESSES,
    MAX_SCAN_STEPS,
    REFERENCE_HELP,
    X_NAMES,
    Y_NAMES,
    BPlaneProgram,
    BPlaneSearch,
    check_reference,
    frozen_array,
)


def _nonzero(value: float) -> float:
    if value == 0:
        raise Invalid("a finite number != 0", value)
    return value


_Positive = Annotated[float, Field(gt=0)]
_Count = Annotated[int, Field(ge=1)]


class ScanTable(Schema):
    """The program's closest-approach scan and periapsis iteration (:class:`BPlaneProgram`)."""

    max_flight_time_s: _Positive = Field(8.0 * SECONDS_PER_DAY, description="Horizon of the "
                                         "scan for the closest approach, from the injection.")
    scan_step_s: _Positive = Field(600.0, description="Step of that scan (shorter than the "
                                   "horizon).")
    periapsis_time_tol_s: _Positive = Field(1e-3, description="The periapsis time is iterated "
                                            "until its correction is below this.")


class SearchTarget(ScanTable):
    """``[target]``: the target body, B-plane reference and the closest-approach scan."""

    body: str = Field("moon", description="The target body, a third body of the state model.")
    reference: Literal[REFERENCE_PLANES] = Field(  # type: ignore[valid-type]
        "earth_equator", description=f"The B-plane's reference plane (it sets the T axis): "
        f"{REFERENCE_HELP}.")


_BR, _BT, _TF = "B·R of the target-relative hyperbola", "B·T of the target-relative " \
    "hyperbola", "Flight time from the injection to periapsis at the target"


class YValues(Schema):
    """Values of the dependent variables (B·R km, B·T km, flight time s)."""

    b_dot_r_km: float = Field(description=f"{_BR}.")
    b_dot_t_km: float = Field(description=f"{_BT}.")
    flight_time_s: float = Field(description=f"{_TF}.")


class YIncrements(Schema):
    """theta: target increments of the dependent variables (each default 0)."""

    b_dot_r_km: float = Field(0.0, description=f"Added to the first nominal case's {_BR}.")
    b_dot_t_km: float = Field(0.0, description=f"Added to the first nominal case's {_BT}.")
    flight_time_s: float = Field(0.0, description="Added to the first nominal case's flight "
                                 "time.")


class YTolerances(Schema):
    """Convergence tolerances of the dependent variables, > 0."""

    b_dot_r_km: _Positive = Field(description="Converged when |B·R - target| is below this.")
    b_dot_t_km: _Positive = Field(description="Converged when |B·T - target| is below this.")
    flight_time_s: _Positive = Field(description="Converged when the flight time is this "
                                     "close to its target.")


_Increment = Annotated[float, AfterValidator(_nonzero), Field(json_schema_extra={
    "allowed": "!= 0"})]
_DELTA = "Increment of the injection velocity's {} component for differenced partials."


class XIncrements(Schema):
    """Difference increments of the injection velocity, km/s, != 0."""

    vx_km_s: _Increment = Field(description=_DELTA.format("x"))
    vy_km_s: _Increment = Field(description=_DELTA.format("y"))
    vz_km_s: _Increment = Field(description=_DELTA.format("z"))


class SearchControls(Schema):
    """SEARCH's iteration control (seed Table 1: ITER, NPR, AP) and the opt-in improvements."""

    iterations_per_partials: _Count = Field(3, description="Newton iterations on one set of "
                                            "partials (the seed's ITER).")
    partial_sets: _Count = Field(3, description="Sets of partials computed before SEARCH "
                                 "stops as diverged (the seed's NPR).")
    analytic_partials: bool = Field(False, description="Partials from the variational "
                                    "equations instead of differences.")
    broyden: bool = Field(False, description="Broyden updates of the partials between sets.")
    step_halving: bool = Field(False, description="Halve a step that increases the miss.")


class SearchTable(SearchControls):
    """``[search]``: targets, tolerances, increments and SEARCH's iteration control."""

    targets: YValues = Field(description="The aim (y_T; replaced by y_0 + θ where "
                             "target_increments are given).")
    target_increments: YIncrements = Field(
        YIncrements(), description="θ: target modifications relative to the first case.")
    tolerances: YTolerances = Field(description="Convergence tolerances (the seed's EPSD).")
    increments: XIncrements = Field(description="Difference increments (the seed's DELI).")


class AimPoint(Schema):
    """``[targeting.targets]``: the B-plane aim point (km) and, optionally, the flight time (s,
    from the injection to periapsis)."""

    b_dot_r_km: float = Field(description=f"The aim point's {_BR}.")
    b_dot_t_km: float = Field(description=f"The aim point's {_BT}.")
    flight_time_s: _Positive | None = Field(None, description=f"{_TF} (optional).")


class AimTolerances(YTolerances):
    """``[targeting.tolerances]``: SEARCH's EPSD, by default those of the shipped SEARCH
    scenario (1 km, 1 km, 1 s)."""

    b_dot_r_km: _Positive = Field(1.0, description="Converged when |B·R - aim| is below this.")
    b_dot_t_km: _Positive = Field(1.0, description="Converged when |B·T - aim| is below this.")
    flight_time_s: _Positive = Field(1.0, description="Converged when the flight time is this "
                                     "close to its aim.")


class AimIncrements(XIncrements):
    """``[targeting.increments]``: SEARCH's DELI, by default those of the shipped SEARCH
    scenario (1 cm/s)."""

    vx_km_s: _Increment = Field(1e-5, description=_DELTA.format("x"))
    vy_km_s: _Increment = Field(1e-5, description=_DELTA.format("y"))
    vz_km_s: _Increment = Field(1e-5, description=_DELTA.format("z"))


class TargetingTable(SearchControls, ScanTable):
    """``[targeting]`` of a tracking scenario (:func:`scenario_targeting` for the keys)."""

    first_guess: Literal[FIRST_GUESSES] = Field(  # type: ignore[valid-type]
        "conic", description="\"conic\": a two-body Lambert transfer through the aim point; "
        "\"injection\": the scenario's own injection velocity.")
    vary: Annotated[list[Literal[X_NAMES]],  # type: ignore[valid-type]
                    Field(min_length=2, max_length=3), Unique] | None = Field(
        None, description="The velocity components SEARCH moves, one per target; default: all "
        "three (two must be named without a flight time).")
    targets: AimPoint = Field(description="The aim point.")
    tolerances: AimTolerances = Field(AimTolerances(), description="Convergence tolerances.")
    increments: AimIncrements = Field(AimIncrements(), description="Difference increments.")


class SearchFile(Schema):
    """Schema of a SEARCH scenario (:func:`scenario_search` for the tables)."""

    title: str = Field("", description="Free text, printed in the report.")
    epoch: UtcDate = Field(description="UTC of the injection, t = 0.")
    earth_orientation: EarthOrientationName = "iau2006"
    eop: EopSource = "iers"
    injection: OrbitTable = Field(description="The injection: its position is kept, its "
                                  "velocity is SEARCH's first guess.")
    model: ModelTable = Field(description="The state and variational force models.")
    target: SearchTarget = Field(SearchTarget(), description="The target body and its "
                                 "B-plane.")
    search: SearchTable = Field(description="SEARCH's targets and controls.")


def _values(table: Schema, names: tuple[str, ...]) -> np.ndarray:
    return frozen_array([getattr(table, name) for name in names])


def scenario_search(data: Mapping, source: str) -> BPlaneSearch:
    """Build a :class:`BPlaneSearch` from a parsed scenario table (TOML), validating it all.

    Tables and keys (units in the names; the example ``search_bplane.toml`` is the
    commented example; the schema is :class:`SearchFile`):

    - ``epoch``: UTC date of the injection (t = 0); ``title``: free text (optional);
      ``earth_orientation`` ("iau2006", the default, or "gmst") and ``eop`` ("iers", "none" or
      a finals2000A path): :func:`tapp.io.eop_file.orientation_for`.
    - ``[injection]``: the injection state, the tracking scenario's table
      (:class:`tapp.io.orbits.OrbitTable`): ``r_km`` (3) and ``v_km_s`` (3, the first guess x0),
      or classical elements; EME2000, Earth-centred; a first guess whose perigee is below the
      Earth's surface is refused unless ``allow_subsurface = true``
      (:func:`tapp.io.orbits.check_perigee`).
    - ``[model]``: the tracking scenario's table (:class:`tapp.io.models_file.ModelTable`):
      ``gravity`` (J0, Jn, NxM), ``third_bodies`` (list), optional
      ``var_gravity``/``var_third_bodies`` (variational model, default the state model),
      ``rtol``/``atol`` (default 1e-13, within ``tapp.dynamics.propagate.TOLERANCE_RANGE``).
    - ``[target]``: ``body`` (default moon), ``reference`` (earth_equator | ecliptic |
      body_equator: :meth:`tapp.targeting.program.BPlaneProgram.reference_pole`),
      ``max_flight_time_s``, ``scan_step_s``, ``periapsis_time_tol_s`` (optional).
    - ``[search]``: ``targets``, ``tolerances`` (tables keyed b_dot_r_km, b_dot_t_km,
      flight_time_s), ``target_increments`` (same keys, optional, theta), ``increments``
      (keyed vx_km_s, vy_km_s, vz_km_s), ``iterations_per_partials``, ``partial_sets``,
      ``analytic_partials``, ``broyden``, ``step_halving``.

    Raises
    ------
    InputError
        Naming ``source`` and the field (dotted path) for any missing, unknown or invalid
        entry.
    """
    doc = validate(SearchFile, data, source)
    epoch_text = doc.epoch
    if isinstance(epoch_text, dt.datetime):
        epoch_text = epoch_text.isoformat().removesuffix("+00:00")
    try:
        epoch = parse_epoch(str(epoch_text), source=source)
    except InputError as exc:
        raise InputError(source, "epoch", exc.expected, epoch_text) from None

    mod = doc.model
    orientation = orientation_for(doc.earth_orientation, epoch, doc.eop,
                                  Path(source).parent, source)
    x0 = doc.injection.state(source, "injection", center=mod.center,
                             how_to_allow="injection.allow_subsurface = true",
                             tdb=tdb_reader(epoch.jd, orientation.scales))
    r0, v0 = x0[:3], x0[3:]
    if np.linalg.norm(r0) <= RADIUS_km[mod.center]:
        raise InputError(source, "injection", f"a position above the {mod.center.capitalize()}'s "
                         "surface", r0.tolist())

    bodies = tuple(mod.third_bodies)
    state_model, var_model = mod.force_models(source, orientation.model)
    propagator = mod.propagator(source, state_model, var_model)

    tgt = doc.target
    if tgt.body not in bodies:
        raise InputError(source, "target.body", f"one of model.third_bodies {list(bodies)}",
                         tgt.body)
    check_reference(tgt.reference, tgt.body, source, "target.reference")
    program = _program(tgt, source, "target", epoch=epoch, r0_km=r0, propagator=propagator,
                       target=tgt.body, reference=tgt.reference, orientation=orientation)
    srch = doc.search
    return BPlaneSearch(
        program=program,
        v0_km_s=frozen_array(v0),
        targets=_values(srch.targets, Y_NAMES),
        target_increments=_values(srch.target_increments, Y_NAMES),
        tolerances=_values(srch.tolerances, Y_NAMES),
        increments=_values(srch.increments, X_NAMES),
        **_controls(srch),
    )


def _program(scan: ScanTable, source: str, table: str, **kwargs) -> BPlaneProgram:
    """The program with the scan of ``scan`` (the file's table ``table``), checked first."""
    if scan.scan_step_s >= scan.max_flight_time_s:
        raise InputError(source, f"{table}.scan_step_s",
                         f"a step shorter than {table}.max_flight_time_s = "
                         f"{scan.max_flight_time_s:g} s", scan.scan_step_s)
    if scan.max_flight_time_s / scan.scan_step_s > MAX_SCAN_STEPS:
        raise InputError(source, f"{table}.max_flight_time_s",
                         f"at most {MAX_SCAN_STEPS:,} scan steps of {table}.scan_step_s = "
                         f"{scan.scan_step_s:g} s", f"{scan.max_flight_time_s:g} s, "
                         f"{scan.max_flight_time_s / scan.scan_step_s:.3g} steps")
    return BPlaneProgram(max_flight_time_s=scan.max_flight_time_s, scan_step_s=scan.scan_step_s,
                         periapsis_time_tol_s=scan.periapsis_time_tol_s, **kwargs)


def _controls(table: SearchControls) -> dict:
    """SEARCH's iteration control of a table, as :class:`BPlaneSearch` keywords."""
    return {name: getattr(table, name) for name in SearchControls.model_fields}


def scenario_targeting(table: TargetingTable, source: str, *, epoch: Epoch,
                       state_km_km_s: np.ndarray, propagator: Propagator, body: str,
                       reference: str, orientation: EarthOrientation) -> BPlaneSearch:
    """Build the :class:`BPlaneSearch` of a tracking scenario's ``[targeting]`` table.

    The program flies the scenario's own models (``propagator``: its state and variational
    force models and tolerances, no parameters) under its Earth orientation, from its
    injection ``state_km_km_s`` (6,) (position kept, velocity the first guess), to the
    B-plane of its miss body and reference plane. Keys (SEARCH's names and defaults where
    SEARCH has them):

    - ``targets``: ``b_dot_r_km``, ``b_dot_t_km`` (the aim point) and optionally
      ``flight_time_s`` (s from the injection to periapsis, below ``max_flight_time_s``);
      no theta: the aim point is absolute (y_0 + theta would move with the first guess).
    - ``vary``: the velocity components SEARCH moves, one per target: default all three with
      a flight time; two of them must be named without one.
    - ``first_guess``: "conic" (default;
      :func:`tapp.targeting.program.patched_conic_guess`, arriving at the target flight time
      or, without one, at the injection's own closest approach) or "injection".
    - ``tolerances`` (default 1 km, 1 km, 1 s), ``increments`` (default 1e-5 km/s),
      ``iterations_per_partials``, ``partial_sets``, ``analytic_partials``, ``broyden``,
      ``step_halving`` (:class:`SearchControls`), and the scan ``max_flight_time_s``,
      ``scan_step_s``, ``periapsis_time_tol_s`` (:class:`ScanTable`).

    Raises
    ------
    InputError
        Naming ``source`` and the ``targeting.*`` field.
    """
    aim = table.targets
    targeted = (0, 1) if aim.flight_time_s is None else (0, 1, 2)
    if table.vary is None and len(targeted) == 2:
        raise InputError(source, "targeting.vary", "two of vx_km_s, vy_km_s, vz_km_s (one "
                         "per target b_dot_r_km, b_dot_t_km; all three vary when "
                         "targeting.targets.flight_time_s is given)")
    vary = tuple(X_NAMES.index(name) for name in (table.vary or X_NAMES))
    if len(vary) != len(targeted):
        raise InputError(source, "targeting.vary", f"{len(targeted)} components, one per "
                         f"target ({', '.join(Y_NAMES[i] for i in targeted)})", table.vary)
    if aim.flight_time_s is not None and aim.flight_time_s >= table.max_flight_time_s:
        raise InputError(source, "targeting.targets.flight_time_s", "a flight time below "
                         f"targeting.max_flight_time_s = {table.max_flight_time_s:g} s",
                         aim.flight_time_s)
    program = _program(table, source, "targeting", epoch=epoch,
                       r0_km=state_km_km_s[:3], propagator=propagator, target=body,
                       reference=reference, orientation=orientation)
    return BPlaneSearch(
        program=program,
        v0_km_s=frozen_array(state_km_km_s[3:]),
        targets=frozen_array([aim.b_dot_r_km, aim.b_dot_t_km, aim.flight_time_s or 0.0]),
        target_increments=frozen_array(np.zeros(3)),
        tolerances=_values(table.tolerances, Y_NAMES),
        increments=_values(table.increments, X_NAMES),
        vary=vary, targeted=targeted, first_guess=table.first_guess,
        **_controls(table),
    )

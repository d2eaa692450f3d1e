r"""Encounters: a B-plane miss must describe one, and ``[targeting]`` makes it the aim point.

TAPP I's B-plane miss parameters are those of the osculating hyperbola relative to the miss
body at the miss time t_m (:mod:`tapp.tracking.simulate`, item 4). They describe an encounter
only where the body's gravity governs the motion. :func:`prepare_encounter` runs before
anything is simulated or written, and refuses a scenario without one.

**Definition.** A B-plane miss at t_m describes an encounter when, at t_m, the spacecraft is
inside the body's *sphere of attraction* and on a hyperbola relative to it:

.. math::

    |\mathbf r - \mathbf r_b| \le \rho_A = D\,\sqrt{\mu_b/\mu_P}, \qquad
    \tfrac12\,|\mathbf v - \mathbf v_b|^2 - \frac{\mu_b}{|\mathbf r - \mathbf r_b|} > 0,

with D the distance between the body and its primary P (:data:`PRIMARY`: the Earth for the
Moon, the Sun for a planet) at t_m from DE421, and the GMs of :data:`tapp.constants.GM_km3_s2`
(the scenario's value of the body's GM in the energy). At :math:`\rho_A` the body attracts
the spacecraft as strongly as the primary attracts the body,
:math:`\mu_b/\rho_A^2 = \mu_P/D^2` (the "sphere of attraction" of the classical
sphere-of-action literature, beside Laplace's :math:`D(\mu_b/\mu_P)^{2/5}` and Hill's
:math:`D(\mu_b/3\mu_P)^{1/3}`). For the Moon it is 0.111 D: 40,000 to 45,000 km.

Why not Laplace's sphere of influence, which SEARCH's scan uses to look for a closest approach
(:meth:`tapp.targeting.program.BPlaneProgram.soi_radius_km`, 66,000 km for the Moon)? It admits
passes the B-plane does not describe. ``deep_space.toml`` with its epoch one day later and
its injection unchanged passes the Moon at 46,450 km, inside it, on a Moon-relative hyperbola
of e = 11 (bent by 10 deg), where the Earth's tidal acceleration is a quarter of the Moon's
attraction: its osculating B moves by 11,000 km over the day and a half before the closest
approach, and |B| = 50,000 km at the file's miss time. Even the shipped flyby's osculating B at
Laplace's radius is 1,100 km from its value at periapsis.

**Miss time "periapsis"** (``miss.time = "periapsis"``): the trajectory's first periapsis
relative to the body, as SEARCH's program finds it (:meth:`tapp.targeting.program.BPlaneProgram
.evaluate`: the first closest approach inside the sphere of influence on a 600 s scan, then
Newton on r·v = 0), within SEARCH's default horizon (8 days) or the scenario's span if longer.
That program flies the nominal model parameters: with ``[parameters.values]`` other than
nominal the miss is at the nominal trajectory's periapsis (still inside the encounter).

**Retargeting** (``[targeting]``): SEARCH on the scenario's own models and Earth orientation
(:func:`tapp.targeting.searchfile.scenario_targeting`) moves the injection velocity to the aim
point; the miss time is then the targeted periapsis. A targeted injection whose perigee is below the
Earth's surface is refused as the file's own would be (``injection.allow_subsurface``).
"""

from __future__ import annotations

import dataclasses
import json
import math
import time

import numpy as np

from search import EXIT_FLAG
from tapp.constants import GM_km3_s2
from tapp.dynamics import PropagationError, Propagator
from tapp.dynamics.forces import default_parameters
from tapp.dynamics.parameters import gm_name
from tapp.errors import DivergenceError, InputError, NotHyperbolicError, TappError
from tapp.io.orbits import check_perigee
from tapp.orbit.bplane import b_plane
from tapp.targeting.program import (
    BPlaneProgram,
    ClosestApproach,
    FailedCaseError,
    FirstGuessError,
    TargetingRun,
    run_search,
)
from tapp.targeting.searchfile import ScanTable
from tapp.tracking.pieces import fly
from tapp.tracking.scenario import Scenario

#: The primary of each body that can carry a B-plane miss (the body it orbits).
PRIMARY = {"moon": "earth", "mercury": "sun", "venus": "sun", "mars": "sun", "jupiter": "sun",
           "saturn": "sun", "uranus": "sun", "neptune": "sun"}


class NoEncounterError(InputError):
    """A B-plane miss without an encounter (module docstring): names the scenario file, the
    ``miss`` field and the trajectory's closest approach to the body.

    Attributes
    ----------
    closest : ClosestApproach
        Time (s from the epoch) and distance (km, to the body's centre) of the closest
        approach within the horizon searched.
    """

    def __init__(self, source: str, expected: str, got: str, closest: ClosestApproach):
        self.closest = closest
        super().__init__(source, "miss", expected, got)


class TargetingError(TappError):
    """SEARCH did not reach a scenario's ``[targeting]`` aim point.

    ``status`` is SEARCH's exit ("diverged", "singular": :data:`search.EXIT_FLAG`) or "failed"
    (a case that could not be evaluated, or no first guess).
    """

    def __init__(self, source: str, status: str, detail: str):
        self.status = status
        super().__init__(f"{source}: targeting: SEARCH {status}: {detail}")


def attraction_radius_km(program: BPlaneProgram, t_s: float) -> float:
    """Return the body's sphere-of-attraction radius D sqrt(mu_b / mu_P), km, at t_s (s).

    ``program.target`` is the body; D its distance from its primary (:data:`PRIMARY`), DE421.
    """
    primary = PRIMARY[program.target]
    t = np.array([t_s])
    d_km = program.body_position_km(program.target, t)[0]
    if primary != program.propagator.state_model.center:
        d_km = d_km - program.body_position_km(primary, t)[0]
    return float(np.linalg.norm(d_km) * math.sqrt(GM_km3_s2[program.target]
                                                  / GM_km3_s2[primary]))


def _program(scenario: Scenario, horizon_s: float) -> BPlaneProgram:
    """SEARCH's program on the scenario's models, with a scan up to ``horizon_s``."""
    miss = scenario.miss
    if miss.body not in PRIMARY:
        raise InputError(scenario.source, "miss.body", f"a body with a primary for its "
                         f"encounter sphere ({', '.join(PRIMARY)})", miss.body)
    scan = ScanTable()
    last_s = float(scenario.times.t13_s[-1])
    return BPlaneProgram(
        scenario.epoch, scenario.x0[:3],
        Propagator(scenario.state_model, scenario.var_model, rtol=scenario.rtol,
                   atol=scenario.atol, method=scenario.method,
                   centre_changes=scenario.centre_changes),
        target=miss.body, reference=miss.reference, scan_step_s=scan.scan_step_s,
        max_flight_time_s=max(scan.max_flight_time_s, last_s, horizon_s),
        orientation=scenario.orientation)


def _no_encounter(scenario: Scenario, at_miss: str, retargeted: bool) -> NoEncounterError:
    """The error naming the closest approach and how to retarget (``at_miss``: what was
    wrong at the miss time)."""
    miss = scenario.miss
    t_m = 0.0 if math.isnan(miss.t_s) else miss.t_s
    program = _program(scenario, t_m)
    closest = program.closest_approach(scenario.x0[3:])
    how = ("an aim point nearer the body (targeting.targets)" if retargeted else
           'the injection retargeted by a [targeting] table (aim point targets.b_dot_r_km, '
           'targets.b_dot_t_km; miss.time = "periapsis")')
    expected = (f"a {miss.body} encounter at the miss time: within the {miss.body}'s sphere of "
                f"attraction (D (GM_{miss.body} / GM_{PRIMARY[miss.body]})^(1/2), "
                f"tapp.tracking.encounter) on a {miss.body}-relative hyperbola; {how}")
    got = (f"{at_miss}; closest approach {closest.distance_km:,.1f} km from the "
           f"{miss.body}'s centre at {scenario.epoch.iso_after(closest.t_s, 3)} UTC (t = "
           f"{closest.t_s:.0f} s from the epoch), sphere of attraction there "
           f"{attraction_radius_km(program, closest.t_s):,.0f} km")
    return NoEncounterError(scenario.source, expected, got, closest)


def _periapsis_s(scenario: Scenario) -> float:
    """The first periapsis at the miss body, s from the epoch (module docstring)."""
    try:
        return _program(scenario, 0.0).evaluate(scenario.x0[3:]).t_periapsis_s
    except (NotHyperbolicError, PropagationError, DivergenceError) as exc:
        raise _no_encounter(scenario, f"no periapsis (miss.time = \"periapsis\"): {exc}",
                            retargeted=False) from None


def check_encounter(scenario: Scenario, *, retargeted: bool = False) -> None:
    """Raise :class:`NoEncounterError` unless the B-plane miss at ``scenario.miss.t_s``
    describes an encounter (module docstring); the state comes from the scenario's own
    propagation (its parameter values and burns too). ``retargeted``: the injection is SEARCH's (the
    message then suggests another aim point rather than a ``[targeting]`` table)."""
    miss = scenario.miss
    traj = fly(scenario.propagator(), scenario.manoeuvres, scenario.x0, np.array([miss.t_s]),
               param_values=dict(scenario.dynamic_values), orientation=scenario.orientation,
               epoch_jd_utc=scenario.epoch.jd)
    program = _program(scenario, miss.t_s)
    z = traj.states[0] - program.target_state(np.array([miss.t_s]))[0][0]
    name = gm_name(miss.body)
    gm = {**default_parameters(scenario.state_model, (name,)),
          **dict(scenario.dynamic_values)}[name]
    r_km = float(np.linalg.norm(z[:3]))
    energy = 0.5 * float(z[3:] @ z[3:]) - gm / r_km
    radius_km = attraction_radius_km(program, miss.t_s)
    if r_km <= radius_km and energy > 0.0:
        check_entry(scenario, z, gm)
        return
    raise _no_encounter(scenario, f"at the miss time {scenario.epoch.iso_after(miss.t_s, 3)} UTC "
                        f"(t = {miss.t_s:.3f} s) {r_km:,.1f} km from the centre, sphere of "
                        f"attraction {radius_km:,.0f} km, {miss.body}-relative energy "
                        f"{energy:.4g} km^2/s^2", retargeted)


def check_entry(scenario: Scenario, z: np.ndarray, gm_km3_s2: float) -> None:
    """Raise :class:`~tapp.errors.InputError` naming ``miss.entry_radius_km`` unless the
    osculating hyperbola of the body-relative state ``z`` (6,) (km, km/s) at the miss time
    enters the interface sphere ahead: a radius below the spacecraft's distance and at or
    above the hyperbola's periapsis radius (:func:`tapp.orbit.bplane.entry_flight_path_angle`;
    ``gm_km3_s2`` the body's GM). Nothing to check without ``entry_fpa_rad`` in the miss."""
    miss = scenario.miss
    if "entry_fpa_rad" not in miss.quantities:
        return
    r_km = float(np.linalg.norm(z[:3]))
    if miss.entry_radius_km >= r_km:
        raise InputError(scenario.source, "miss.entry_radius_km", "a radius below the "
                         f"spacecraft's distance from the {miss.body}'s centre at the miss time, "
                         f"{r_km:,.3f} km", miss.entry_radius_km)
    r_p_km = float(b_plane(z[:3], z[3:], gm_km3_s2).periapsis_radius_km)
    if r_p_km > miss.entry_radius_km:
        raise InputError(scenario.source, "miss.entry_radius_km", "a radius at or above the "
                         f"periapsis radius of the {miss.body}-relative hyperbola at the miss "
                         f"time, {r_p_km:,.3f} km (below it the spacecraft does not enter: no "
                         "entry flight-path angle)", miss.entry_radius_km)


def _retarget(scenario: Scenario) -> tuple[TargetingRun, float]:
    """Run the scenario's SEARCH; return the converged run and its wall time, s."""
    problem = scenario.targeting
    start = time.perf_counter()
    try:
        run = run_search(problem)
    except (FailedCaseError, FirstGuessError) as exc:
        other = "injection" if problem.first_guess == "conic" else "conic"
        raise TargetingError(scenario.source, "failed", f"{exc} (or try "
                             f"targeting.first_guess = \"{other}\")") from exc
    result = run.result
    if result.status != "converged":
        miss = ", ".join(f"{n} {m:+.6g} (tolerance {t:g})" for n, m, t in zip(
            problem.y_names, result.miss, result.inputs.tolerances, strict=True))
        raise TargetingError(scenario.source, result.status, f"after {result.n_cases} cases "
                             f"(partial_sets = {problem.partial_sets}, iterations_per_partials "
                             f"= {problem.iterations_per_partials}): miss {miss}")
    return run, time.perf_counter() - start


def targeting_record(scenario: Scenario, run: TargetingRun, wall_s: float) -> dict:
    """What the tape records of a retargeting (provenance ``targeting``, JSON)."""
    problem, result, enc = scenario.targeting, run.result, run.encounter
    return {
        "aim": dict(zip(problem.y_names, result.targets.tolist(), strict=True)),
        "achieved": dict(zip(problem.y_names, result.y.tolist(), strict=True)),
        "tolerances": dict(zip(problem.y_names, result.inputs.tolerances.tolist(), strict=True)),
        "vary": list(problem.x_names),
        "first_guess": problem.first_guess,
        "v0_file_km_s": np.asarray(scenario.x0[3:]).tolist(),
        "v0_first_case_km_s": run.start_km_s.tolist(),
        "v0_targeted_km_s": enc.v0_km_s.tolist(),
        "t_periapsis_s": enc.t_periapsis_s,
        "periapsis_radius_km": float(enc.b_plane.periapsis_radius_km),
        "status": result.status, "flag": EXIT_FLAG[result.status],
        "cases": result.n_cases, "partial_sets": len(result.history.partial_sets),
        "propagations": run.propagations, "analytic_partials": problem.analytic_partials,
        "wall_time_s": wall_s,
    }


def prepare_encounter(scenario: Scenario) -> tuple[Scenario, dict[str, str]]:
    """Return the scenario TAPP I simulates and the provenance of its encounter.

    For a B-plane miss: SEARCH on ``[targeting]`` (the injection velocity replaced by the
    targeted one, the miss time by its periapsis), or the periapsis found for
    ``miss.time = "periapsis"``, then the encounter check (module docstring). The scenario
    returned has ``targeting = None`` and a resolved miss time. Other miss kinds pass
    unchanged. Provenance: ``{"targeting": JSON of targeting_record}`` when retargeted.

    Raises
    ------
    NoEncounterError
        No encounter at the miss time, or no periapsis (naming the closest approach).
    TargetingError
        SEARCH diverged, met a singular matrix, or a case failed.
    InputError
        The miss body has no primary; a targeted injection below the Earth's surface.
    """
    miss = scenario.miss
    if miss.kind != "bplane":
        return scenario, {}
    provenance: dict[str, str] = {}
    x0, t_m = np.array(scenario.x0), miss.t_s
    if scenario.targeting is not None:
        run, wall_s = _retarget(scenario)
        x0[3:] = run.encounter.v0_km_s
        # the file's own rule for its injection (its table, as read: tape provenance)
        allowed = json.loads(scenario.document_json)["injection"].get("allow_subsurface", False)
        check_perigee(x0, scenario.source, "targeting", allow_subsurface=allowed,
                      how_to_allow="injection.allow_subsurface = true")
        t_m = run.encounter.t_periapsis_s
        provenance["targeting"] = json.dumps(targeting_record(scenario, run, wall_s))
    elif miss.at_periapsis:
        t_m = _periapsis_s(scenario)
    x0.setflags(write=False)
    prepared = dataclasses.replace(scenario, x0=x0, miss=dataclasses.replace(miss, t_s=t_m),
                                   targeting=None)
    check_encounter(prepared, retargeted=bool(provenance))
    return prepared, provenance

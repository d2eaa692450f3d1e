"""``search``: SEARCH's Newton-Raphson targeting of a B-plane problem (a SEARCH file, a
tracking scenario with a ``[targeting]`` table, or the problem in memory), the result
rendering ``tapp search``'s report and JSON."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from search import format_report
from tapp.constants import RADIUS_km
from tapp.errors import InputError
from tapp.io.tomlfile import read_toml
from tapp.targeting.exits import exit_code
from tapp.targeting.program import BPlaneSearch, TargetingRun, run_search
from tapp.targeting.searchfile import scenario_search
from tapp.tracking.scenario_build import parse_scenario

__all__ = ["TargetingResult", "is_tracking_scenario", "problem_of", "search"]

# Column names in the report (the seed's IV1N.., DV1N..), at most 17 characters.
_X_LABELS = ("VX (KM/S)", "VY (KM/S)", "VZ (KM/S)")
_Y_LABELS = ("B.R (KM)", "B.T (KM)", "TF (S)")

def is_tracking_scenario(data: dict) -> bool:
    """Whether a parsed file is a tracking scenario (else a SEARCH file)."""
    return "tracking" in data or "targeting" in data


def problem_of(data: dict, path: Path | str, earth_orientation: str | None) -> BPlaneSearch:
    """The search problem of a parsed scenario file (a SEARCH file, or a tracking scenario
    with a ``[targeting]`` table); ``earth_orientation`` overrides the file's model.

    Raises
    ------
    InputError
        A bad file or field (naming both), or a tracking scenario without ``[targeting]``.
    """
    if is_tracking_scenario(data):
        problem = parse_scenario(data, str(path), earth_orientation).targeting
        if problem is None:
            raise InputError(str(path), "targeting", "a [targeting] table (the aim point) in "
                             "a tracking scenario given to tapp search")
        return problem
    if earth_orientation is not None:
        data["earth_orientation"] = earth_orientation
    return scenario_search(data, str(path))


@dataclass(frozen=True, slots=True)
class TargetingResult:
    """A SEARCH run: the problem, the run (the result with its history, and the encounter
    of the final trajectory), whether the partials were analytic, the scenario's name and
    the wall time (s)."""

    problem: BPlaneSearch
    run: TargetingRun
    analytic_partials: bool
    scenario: str
    wall_s: float

    @property
    def status(self) -> str:
        """SEARCH's exit: "converged", "diverged" or "singular"."""
        return self.run.result.status

    @property
    def converged(self) -> bool:
        """Whether SEARCH converged."""
        return self.status == "converged"

    def encounter_dict(self) -> dict:
        """The encounter of the final trajectory: periapsis time (s, UTC), radius and altitude
        (km), v∞ (km/s), eccentricity, LTOF (s)."""
        enc = self.run.encounter
        body = self.problem.program.target
        r_p = float(enc.b_plane.periapsis_radius_km)
        return {"body": body,
                "t_periapsis_s": enc.t_periapsis_s,
                "periapsis_utc": self.problem.program.epoch.iso_after(enc.t_periapsis_s, 3),
                "periapsis_radius_km": r_p,
                "periapsis_altitude_km": r_p - RADIUS_km[body],
                "v_inf_km_s": float(enc.b_plane.v_inf_km_s),
                "eccentricity": float(enc.b_plane.eccentricity),
                "ltof_s": float(enc.b_plane.ltof_s)}

    def _history_dict(self) -> dict:
        history = self.run.result.history
        return {
            "cases": [{"n": c.number, "kind": c.kind, "set": c.partial_set, "index": c.index,
                       "x": c.x, "y": c.y} for c in history.cases],
            "partial_sets": [{"set": ps.number, "update": ps.update, "source": ps.source,
                              "after_case": ps.after_case, "partials": ps.partials,
                              "determinant": ps.determinant,
                              "steps": [{"case": s.case, "step": s.step,
                                         "total_step": s.total_step} for s in ps.steps]}
                             for ps in history.partial_sets],
        }

    def to_json(self) -> dict:
        """What ``tapp search --json`` writes (arrays as numpy arrays, which the JSON writer
        turns into lists): the exit, the variables and targets reached, the cases, the
        encounter and the history of cases and partials."""
        problem, run = self.problem, self.run
        result = run.result
        return {
            "scenario": self.scenario,
            "status": result.status,
            "flag": result.flag,
            "exit_code": exit_code(result.status),
            "x_names": list(problem.x_names),
            "y_names": list(problem.y_names),
            "x": result.x,
            "y": result.y,
            "targets": result.targets,
            "miss": result.miss,
            "tolerances": result.inputs.tolerances,
            "total_increments_km_s": result.x - result.inputs.x0,
            "first_guess": problem.first_guess,
            "v0_km_s": run.encounter.v0_km_s,
            "v0_first_case_km_s": run.start_km_s,
            "cases_run": result.n_cases,
            "cases": {"nominal": result.n_nominal, "perturbed": result.n_perturbed,
                      "applied": result.n_applied},
            "trajectories": run.trajectories,
            "propagations": run.propagations,
            "analytic_partials": self.analytic_partials,
            "wall_time_s": self.wall_s,
            "encounter": self.encounter_dict(),
            "history": self._history_dict(),
        }

    def report(self) -> str:
        """The report ``tapp search`` prints: SEARCH's (inputs, cases, partials, increments,
        exit; :func:`search.format_report`) and the encounter of the final trajectory."""
        problem, run = self.problem, self.run
        labels = (tuple(_X_LABELS[i] for i in problem.vary),
                  tuple(_Y_LABELS[i] for i in problem.targeted))
        enc = self.encounter_dict()
        dv_m_s = 1e3 * float(np.linalg.norm(run.encounter.v0_km_s - problem.v0_km_s))
        partials = ("ANALYTIC (VARIATIONAL EQUATIONS)" if self.analytic_partials
                    else "DIFFERENCED")
        return format_report(run.result, *labels) + (
            f"ENCOUNTER WITH THE {enc['body'].upper()}: PERIAPSIS {enc['periapsis_utc']} UTC "
            f"(T = {enc['t_periapsis_s']:.3f} S), RADIUS {enc['periapsis_radius_km']:.3f} KM "
            f"(ALTITUDE {enc['periapsis_altitude_km']:.3f} KM), V_INF "
            f"{enc['v_inf_km_s']:.6f} KM/S\n"
            f"TOTAL CHANGE OF THE INJECTION VELOCITY {dv_m_s:.3f} M/S\n"
            f"{run.trajectories} TRAJECTORIES ({run.propagations} PROPAGATIONS), PARTIALS "
            f"{partials}, {self.wall_s:.2f} S\n")


def search(scenario: BPlaneSearch | Path | str, *, analytic_partials: bool = False,
           earth_orientation: str | None = None, source: str = "search") -> TargetingResult:
    """Run SEARCH on a B-plane problem; return its exit, its history and the encounter.

    Parameters
    ----------
    scenario : a SEARCH file or a tracking scenario with a ``[targeting]`` table (TOML;
        ``earth_orientation`` overrides its model), or the problem in memory.
    analytic_partials : partials from the variational equations, whatever the problem says
        (else as it says).
    source : the name of a problem given in memory, in the JSON (a file's is its path).

    Raises
    ------
    InputError
        A bad file or field, as ``tapp search`` reports it (naming both).
    tapp.targeting.program.FailedCaseError
        A case that failed (the trajectory missed the target's sphere of influence, or was
        not hyperbolic there).
    """
    if isinstance(scenario, BPlaneSearch):
        problem, name = scenario, source
    else:
        problem = problem_of(dict(read_toml(scenario)), scenario, earth_orientation)
        name = str(scenario)
    analytic = analytic_partials or problem.analytic_partials
    start = time.perf_counter()
    run = run_search(problem, analytic_partials=analytic)
    return TargetingResult(problem, run, analytic, name, time.perf_counter() - start)

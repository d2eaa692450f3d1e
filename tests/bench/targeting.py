"""Benchmark of the B-plane targeting case (the example search_bplane.toml).

``run()`` returns a Markdown section: wall time and trajectories flown by SEARCH with
differenced partials (the seed's perturbed cases) and with analytic partials from the
variational equations, plus the cost of one case with and without the STM. Times are the
best of several repeats after a warm-up run (the compiled right-hand side is cached on disk;
the warm-up also loads DE421).
"""

from __future__ import annotations

import time
import tomllib

import numpy as np

from tapp.examples import FOLDER as EXAMPLES
from tapp.targeting.program import BPlaneSearch, run_search
from tapp.targeting.searchfile import scenario_search

SCENARIO = EXAMPLES / "search_bplane.toml"
REPEATS = 5


def _best_s(fn, repeats: int = REPEATS) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def _problem() -> BPlaneSearch:
    return scenario_search(tomllib.loads(SCENARIO.read_text()), str(SCENARIO))


NAME = "targeting"


def run() -> str:
    """Return the Markdown section of the targeting benchmark."""
    problem = _problem()
    program = problem.program
    v0 = np.array(problem.v0_km_s)
    program.evaluate(v0, partials=True)  # warm-up: compile/load, DE421
    rows = []
    for label, analytic in (("differenced (seed)", False), ("analytic (STM)", True)):
        outcome = run_search(problem, analytic_partials=analytic)
        wall = _best_s(lambda a=analytic: run_search(problem, analytic_partials=a))
        r = outcome.result
        miss = ", ".join(f"{m:+.3g}" for m in (r.miss[0] * 1e3, r.miss[1] * 1e3, r.miss[2]))
        rows.append(
            f"| {label} | {r.status} | {r.n_nominal}/{r.n_perturbed}/{r.n_applied} | "
            f"{len(r.history.partial_sets)} | {outcome.trajectories} | {outcome.propagations} | "
            f"{wall * 1e3:.0f} | {wall * 1e3 / outcome.trajectories:.1f} | {miss} |")
    one_case = _best_s(lambda: program.evaluate(v0))
    one_case_stm = _best_s(lambda: program.evaluate(v0, partials=True))
    return "\n".join([
        "## SEARCH: lunar B-plane targeting",
        "",
        f"Scenario `{SCENARIO.name}`: injection from a 185 km parking orbit, J2 + Sun + Moon "
        "(DE421), DOP853 at 1e-13; targets B·R = -2000 km, B·T = 5300 km, flight time = first "
        "guess + 1 h; tolerances 1 km, 1 km, 1 s. Wall time: best of "
        f"{REPEATS} searches.",
        "",
        "| partials | exit | cases nom/pert/appl | sets | trajectories | propagations | "
        "wall (ms) | ms per trajectory | miss (m, m, s) |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        f"One case (scan + periapsis): {one_case * 1e3:.1f} ms without the STM, "
        f"{one_case_stm * 1e3:.1f} ms with it and the analytic partials.",
        "",
    ])


if __name__ == "__main__":
    print(run())

"""Measurements of ITER's own cost: per-case overhead and the speed-up from a second worker.

For the benchmark script; no test asserts on these timings. Functions that start a local
cluster must be called under ``if __name__ == "__main__":`` (the workers are spawned).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from .body import CallableBody
from .errors import IterError
from .execute import Execution, local_cluster
from .loops import Loop
from .run import run_sweep
from .sweep import Sweep

#: Default work of :func:`cpu_bound_body`, loop iterations (about 0.1 s of CPython).
CPU_BOUND_ITERATIONS = 1_000_000


def trivial_body(x: float) -> dict[str, float]:
    """Return ``{"y": x}``: a body that costs nothing, to expose ITER's own overhead."""
    return {"y": x}


def cpu_bound_body(x: float, n_iterations: int) -> dict[str, float]:
    """Return ``{"y": ...}`` after ``n_iterations`` of pure-Python arithmetic (holds the GIL)."""
    acc = x
    for k in range(n_iterations):
        acc = (acc * 1.000001 + k) % 1.0e6
    return {"y": acc}


def _sweep(target: str, n_cases: int, constants: dict[str, object]) -> Sweep:
    loop = Loop(type=2, names=("x",), sets=n_cases, vary=(0.0,), delta=(1.0,))
    return Sweep(loops=(loop,), body=CallableBody(target=target, constants=constants),
                 source="iter.bench")


def _wall_s(sweep: Sweep, execution: Execution) -> float:
    start_s = time.perf_counter()
    result = run_sweep(sweep, execution=execution)
    wall_s = time.perf_counter() - start_s
    if result.table.n_failed:
        raise IterError(f"benchmark body failed in {result.table.n_failed} cases: "
                        f"{result.table.rows[0].error}")
    return wall_s


@dataclass(frozen=True, slots=True)
class OverheadReport:
    """Per-case cost of ITER itself with a body that does nothing.

    Parameters
    ----------
    n_cases : int
        Cases in the timed sweep.
    workers : int
        Local-cluster workers; 0 for a serial run.
    wall_s : float
        Wall time of the sweep of ``n_cases``, s (connection and set-up included).
    fixed_s : float
        Wall time of a one-case sweep, s: the fixed cost (connect, submit, gather).
    per_case_s : float
        ``(wall_s - fixed_s) / (n_cases - 1)``, s per case.
    """

    n_cases: int
    workers: int
    wall_s: float
    fixed_s: float
    per_case_s: float


def measure_overhead(n_cases: int = 2000, workers: int = 2) -> OverheadReport:
    """Return ITER's per-case overhead with a trivial body, serial (``workers=0``) or on Dask.

    The local cluster is started before timing and reused for a one-case sweep (the fixed
    cost) and an ``n_cases`` sweep; the difference over ``n_cases - 1`` is the cost per case.
    """
    if n_cases < 2:
        raise ValueError(f"n_cases must be at least 2, got {n_cases}")
    target = f"{__name__}:trivial_body"
    if workers == 0:
        return _overhead(n_cases, 0, Execution(serial=True), target)
    with local_cluster(workers) as address:
        execution = Execution(scheduler=address)
        _wall_s(_sweep(target, 4 * workers, {}), execution)  # warm-up: imports on workers
        return _overhead(n_cases, workers, execution, target)


def _overhead(n_cases: int, workers: int, execution: Execution, target: str) -> OverheadReport:
    fixed_s = _wall_s(_sweep(target, 1, {}), execution)
    wall_s = _wall_s(_sweep(target, n_cases, {}), execution)
    return OverheadReport(n_cases=n_cases, workers=workers, wall_s=wall_s, fixed_s=fixed_s,
                          per_case_s=(wall_s - fixed_s) / (n_cases - 1))


@dataclass(frozen=True, slots=True)
class SpeedupReport:
    """Wall times of one CPU-bound sweep on 1 and on 2 local workers.

    Parameters
    ----------
    n_cases : int
        Cases in the sweep.
    n_iterations : int
        Work per case, iterations of :func:`cpu_bound_body`.
    wall_1_s, wall_2_s : float
        Wall time on 1 and on 2 workers, s (cluster start-up excluded).
    speedup : float
        ``wall_1_s / wall_2_s``; 2 is perfect.
    """

    n_cases: int
    n_iterations: int
    wall_1_s: float
    wall_2_s: float
    speedup: float


def measure_speedup(n_cases: int = 16,
                    n_iterations: int = CPU_BOUND_ITERATIONS) -> SpeedupReport:
    """Return the speed-up of a CPU-bound sweep from 1 to 2 local-cluster workers."""
    sweep = _sweep(f"{__name__}:cpu_bound_body", n_cases, {"n_iterations": n_iterations})
    walls_s = []
    for workers in (1, 2):
        with local_cluster(workers) as address:
            execution = Execution(scheduler=address)
            _wall_s(_sweep(f"{__name__}:trivial_body", 2 * workers, {}), execution)  # warm-up
            walls_s.append(_wall_s(sweep, execution))
    return SpeedupReport(n_cases=n_cases, n_iterations=n_iterations, wall_1_s=walls_s[0],
                         wall_2_s=walls_s[1], speedup=walls_s[0] / walls_s[1])

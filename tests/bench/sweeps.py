"""ITER benchmark: per-case overhead with a trivial body (serial and on a local Dask
cluster) and the speed-up of 2 workers over 1 on a CPU-bound body.

Targets of the issue: < 5 ms per case with batching; >= 1.7x with 2 workers on 2 cores. The
serial run of the same sweep is the peer of the Dask runs.
"""

from __future__ import annotations

from iter.bench import measure_overhead, measure_speedup

NAME = "sweeps"


def run() -> str:
    rows = []
    for workers in (0, 1, 2):
        rep = measure_overhead(2000, workers)
        label = "serial" if workers == 0 else f"Dask, {workers} worker(s)"
        rows.append(f"| {label} | {rep.n_cases} | {rep.wall_s:.2f} | {rep.fixed_s * 1e3:.0f} | "
                    f"{rep.per_case_s * 1e6:.0f} | "
                    f"{'yes' if rep.per_case_s < 5e-3 else 'no'} |")
    sp = measure_speedup()
    return "\n".join([
        "## ITER sweeps", "",
        "| execution | cases | wall (s) | fixed cost (ms) | per case (us) | target < 5 ms |",
        "|---|---|---|---|---|---|", *rows, "",
        f"CPU-bound body ({sp.n_cases} cases): 2 workers vs 1: {sp.speedup:.2f}x "
        f"(target >= 1.7x: {'yes' if sp.speedup >= 1.7 else 'no'}).", ""])

"""Benchmark of TAPP II: the deep-space guidance study, 10⁶ samples, serially and on Dask.

Set-up (timed apart, in a temporary folder): TAPP I on the example ``deep_space.toml`` -> T13
tape, TAPP III with the example ``tapp3_deep_space.toml`` -> T32 tape, through the library calls
``tapp simulate``, ``tapp process --tape`` and the pipeline make. Measured, with the guidance
file the example ``tapp2_deep_space.toml`` (three manoeuvres, B·R, B·T and the flight time
targeted, "inflate" navigation) and :data:`N_SAMPLES` samples:

(a) the study serially in this process (``Execution(serial=True)``);
(b) the study on a local Dask cluster of :data:`WORKERS` worker processes as tapp starts it
    (:func:`iter.execute.local_cluster`), started before the timing (its start-up and the
    first study on the fresh workers, which import tapp, are reported apart);
(b') the same with Dask's ``MALLOC_TRIM_THRESHOLD_`` of 64 kB back in the workers, as they
    were started before tapp left it out (``iter.execute.WORKER_ENVIRON``): it also fixes
    glibc's mmap threshold at 128 kB, so every temporary array of a block (0.2 to 0.9 MB) is
    a fresh mmap whose pages fault in again;
(c) the linear covariance alone, with its Imhof ΔV percentiles and corridor fractions
    (:func:`tapp.guidance.statistics.linear_outcome`), and the propagation of the covariance
    without them.

The Monte Carlo wall time is the study's own ``wall_s`` (:func:`tapp.guidance.shards.run_shards`:
connecting to the cluster, scattering the problem, simulating, gathering in sample order); the
whole study call adds binding the guidance file, the sample statistics and the linear
covariance. (a) and (b) must be bitwise identical, per sample and in every statistic (the
promise of :mod:`tapp.guidance.shards`); the section raises otherwise. Memory: the
tracemalloc peak of one serial study (untimed). Target: 10⁶ samples in under 10 s.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from iter.execute import Execution, local_cluster
from tapp.examples import FOLDER as EXAMPLES
from tapp.guidance.guidefile import GuideFile, bind, read_guide
from tapp.guidance.linear import linear_covariance
from tapp.guidance.montecarlo import outcome_maps
from tapp.guidance.statistics import linear_outcome
from tapp.guidance.study import MAX_SAMPLES, GuidanceResult, guidance_study
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.io.tape.t32 import T32
from tapp.io.tape.t32_hdf5 import read_t32, write_t32
from tapp.pipeline.steps import process_tape
from tapp.processor.deck import read_deck
from tapp.processor.tape32 import build_t32, t32_provenance
from tapp.report.guidance import guidance_dict
from tapp.tracking.scenario import read_scenario
from tapp.tracking.simulate import simulate
from tests.bench.common import (
    Section,
    logger,
    markdown_table,
    time_calls,
    timed_once,
    traced_peak_mb,
)

NAME = "guidance"
SCENARIOS = EXAMPLES
SCENARIO = SCENARIOS / "deep_space.toml"
DECK = SCENARIOS / "tapp3_deep_space.toml"
GUIDE = SCENARIOS / "tapp2_deep_space.toml"
N_SAMPLES = 1_000_000
SEED = 20260310
WORKERS = 2
#: Samples of the first study on a fresh cluster (the workers import tapp), not timed as such.
WARM_SAMPLES = 2000
REPEATS_SERIAL = 3
REPEATS_DASK = 3
REPEATS_LINEAR = 5
TARGET_S = 10.0
#: Dask's setting of glibc's trim threshold in the workers it spawns (see (b') above), and
#: its value there.
MALLOC_TRIM = "MALLOC_TRIM_THRESHOLD_"
DASK_MALLOC_TRIM = "65536"
_M_PER_KM = 1e3

log = logger(NAME)


def write_tapes(folder: Path) -> tuple[Path, dict[str, float]]:
    """TAPP I and TAPP III of the deep-space study into ``folder``: the T32 path and the
    set-up times, s."""
    t13_path, t32_path = folder / "deep_space.t13.h5", folder / "deep_space.t32.h5"
    simulate_s, sim = timed_once(lambda: simulate(read_scenario(SCENARIO)))
    write_t13(t13_path, sim.tape)
    deck = read_deck(DECK)
    process_s, (run, plan, header) = timed_once(lambda: process_tape(t13_path, deck, str(DECK)))
    write_t32(t32_path, build_t32(run, plan, header,
                                  t32_provenance(header, deck, str(DECK), t13_path.name)))
    return t32_path, {"simulate_s": simulate_s, "process_s": process_s}


def study(t32: T32, guide: GuideFile, execution: Execution, samples: int = N_SAMPLES
          ) -> GuidanceResult:
    """The guidance study of :data:`GUIDE` on the tape (what ``tapp guide`` runs)."""
    return guidance_study(t32, guide, samples=samples, seed=SEED, execution=execution,
                          guide_source=str(GUIDE), tape_source="deep_space.t32.h5")


def timed_studies(t32: T32, guide: GuideFile, execution: Execution, repeats: int
                  ) -> tuple[dict, GuidanceResult]:
    """Run the study ``repeats`` times: the Monte Carlo wall times (the study's ``wall_s``),
    the timing of the whole call, and the last result."""
    walls_s: list[float] = []

    def once() -> GuidanceResult:
        result = study(t32, guide, execution)
        walls_s.append(result.wall_s)
        return result

    timing, result = time_calls(once, repeats)
    return {"monte_carlo_s": walls_s, "monte_carlo_best_s": min(walls_s), "study": timing,
            "samples_per_s": N_SAMPLES / min(walls_s), "shard_samples": result.shard_samples,
            "where": result.where}, result


@contextlib.contextmanager
def worker_malloc_trim(dask_s: bool) -> Iterator[None]:
    """Within: local clusters spawn workers with Dask's trim threshold (``dask_s``) or
    without it, as tapp starts them.

    The workers inherit this process's environment (tapp's clusters leave the variable out
    of Dask's pre-spawn environment, not out of the environment it is given), so the
    variable is set, or removed, here for the time of the context and put back after.
    """
    saved = os.environ.pop(MALLOC_TRIM, None)
    if dask_s:
        os.environ[MALLOC_TRIM] = DASK_MALLOC_TRIM
    try:
        yield
    finally:
        os.environ.pop(MALLOC_TRIM, None)
        if saved is not None:
            os.environ[MALLOC_TRIM] = saved


def dask_studies(t32: T32, guide: GuideFile, *, malloc_trim: bool
                 ) -> tuple[dict, GuidanceResult]:
    """Start a local cluster of :data:`WORKERS` (timed), run a first small study (the workers
    import tapp), then time the study; the cluster's stop is timed too."""
    with worker_malloc_trim(malloc_trim), contextlib.ExitStack() as stack:
        start_s, address = timed_once(lambda: stack.enter_context(local_cluster(WORKERS)))
        execution = Execution(scheduler=address)
        warm_s, _ = timed_once(lambda: study(t32, guide, execution, WARM_SAMPLES))
        stats, result = timed_studies(t32, guide, execution, REPEATS_DASK)
        stop_s, _ = timed_once(stack.close)
    return {**stats, "cluster_start_s": start_s, "first_study_s": warm_s,
            "cluster_stop_s": stop_s, "malloc_trim_threshold": malloc_trim}, result


def bitwise_identical(a: GuidanceResult, b: GuidanceResult) -> dict[str, bool]:
    """Whether the per-sample outcomes (compared as bit patterns) and the Monte Carlo
    statistics (as written by ``tapp guide --json``, floats by their repr) are the same."""
    samples = all(np.array_equal(x.view(np.uint64), y.view(np.uint64))
                  for x, y in ((a.samples.dv_km_s, b.samples.dv_km_s),
                               (a.samples.miss, b.samples.miss)))
    statistics = (json.dumps(guidance_dict(a)["monte_carlo"])
                  == json.dumps(guidance_dict(b)["monte_carlo"]))
    return {"samples": samples, "statistics": statistics}


def _ok(seconds: float) -> str:
    return "yes" if seconds < TARGET_S else "NO"


def _mc_row(label: str, r: dict, repeats: int) -> list[str]:
    return [label, str(repeats), f"{r['monte_carlo_best_s']:.2f}",
            f"{r['samples_per_s']:,.0f}", f"{r['study'].best_s:.2f}",
            f"{r['shard_samples']:,}", _ok(r["monte_carlo_best_s"])]


def run() -> Section:
    """Run the guidance section; return its Markdown and raw numbers."""
    load_before = os.getloadavg()
    guide = read_guide(GUIDE)
    with tempfile.TemporaryDirectory(prefix="tapp2-bench-") as tmp:
        t32_path, setup = write_tapes(Path(tmp))
        t32 = read_t32(t32_path)
    log(f"set-up: T13 simulated in {setup['simulate_s']:.1f} s, processed to a T32 tape in "
        f"{setup['process_s']:.2f} s")

    serial, res_a = timed_studies(t32, guide, Execution(serial=True), REPEATS_SERIAL)
    log(f"(a) serial: Monte Carlo {serial['monte_carlo_best_s']:.2f} s, study "
        f"{serial['study'].best_s:.2f} s (best of {REPEATS_SERIAL})")
    peak_mb = traced_peak_mb(lambda: study(t32, guide, Execution(serial=True)))
    outcomes_mb = (res_a.samples.dv_km_s.nbytes + res_a.samples.miss.nbytes) / 1e6
    log(f"serial study under tracemalloc: peak {peak_mb:.0f} MB "
        f"(gathered outcomes {outcomes_mb:.0f} MB)")

    runs = {}
    identical = {}
    for key, trim in (("dask", False), ("dask_malloc_trim", True)):
        runs[key], res = dask_studies(t32, guide, malloc_trim=trim)
        identical[key] = bitwise_identical(res_a, res)
        del res
        r = runs[key]
        log(f"({key}): cluster start {r['cluster_start_s']:.2f} s, first study "
            f"{r['first_study_s']:.2f} s, Monte Carlo {r['monte_carlo_best_s']:.2f} s, study "
            f"{r['study'].best_s:.2f} s; identical to serial: {identical[key]}")

    study_of = bind(guide, t32, str(GUIDE))
    problem = study_of.problem
    cov_timing, _ = time_calls(lambda: linear_covariance(problem), REPEATS_LINEAR)
    lin_timing, _ = time_calls(lambda: linear_outcome(problem, linear_covariance(problem),
                                                      study_of.corridor), REPEATS_LINEAR)
    log(f"(c) linear covariance {1e3 * cov_timing.best_s:.2f} ms, with its Imhof statistics "
        f"{lin_timing.best_s:.3f} s")
    load_after = os.getloadavg()

    mismatch = {key: flags for key, flags in identical.items() if not all(flags.values())}
    if mismatch:
        raise AssertionError(f"Dask and serial studies differ (not bitwise identical): "
                             f"{mismatch}")

    dask_run = runs["dask"]
    ratio = dask_run["samples_per_s"] / serial["samples_per_s"]
    ratio_trim = runs["dask_malloc_trim"]["samples_per_s"] / serial["samples_per_s"]
    cold_s = (dask_run["cluster_start_s"] + dask_run["first_study_s"]
              + dask_run["monte_carlo_best_s"])
    stats = guidance_dict(res_a)
    mc, lin = stats["monte_carlo"], stats["linear"]
    tcm = "; ".join(
        f"TCM-{i + 1} {_M_PER_KM * m['magnitude']['mean_km_s']:.3f} vs "
        f"{_M_PER_KM * n['magnitude']['mean_km_s']:.3f} m/s"
        for i, (m, n) in enumerate(zip(mc["manoeuvres"], lin["manoeuvres"], strict=True)))
    md = "\n".join([
        "## TAPP II: Monte Carlo midcourse guidance (deep space, 10⁶ samples)",
        "",
        f"T32 tape of `{SCENARIO.name}` through `{DECK.name}` (set-up, not timed with the "
        f"study: TAPP I {setup['simulate_s']:.1f} s, TAPP III {setup['process_s']:.2f} s); "
        f"guidance file `{GUIDE.name}`: {len(problem.manoeuvres)} manoeuvres, n_o = "
        f"{problem.n_o}, {outcome_maps(problem).n_normals} normals a sample; {N_SAMPLES:,} "
        f"samples, seed {SEED}. Monte Carlo: the study's own wall time (connect, scatter, "
        "simulate, gather); study: the whole call (bind, Monte Carlo, sample statistics, "
        "linear covariance with its Imhof percentiles). Best of the repeats. Target: "
        f"{N_SAMPLES:,} samples in < {TARGET_S:.0f} s. Load average (1 min) "
        f"{load_before[0]:.1f} before and {load_after[0]:.1f} after the section (2 logical "
        "CPUs; other work inflates times).",
        "",
        markdown_table(
            ["execution", "repeats", "Monte Carlo (s)", "samples/s", "study (s)",
             "samples a shard", f"< {TARGET_S:.0f} s"],
            [_mc_row("(a) serial, this process", serial, REPEATS_SERIAL),
             _mc_row(f"(b) Dask, local cluster of {WORKERS} workers", dask_run, REPEATS_DASK),
             _mc_row(f"(b') as (b), with Dask's {MALLOC_TRIM} in the workers (as before)",
                     runs["dask_malloc_trim"], REPEATS_DASK),
             ["(c) linear covariance + Imhof statistics", str(REPEATS_LINEAR), "—", "—",
              f"{lin_timing.best_s:.3f}", "—", "—"]]),
        "",
        f"**(b)/(a) samples per second: {ratio:.2f}x** ({WORKERS} workers; {ratio_trim:.2f}x "
        f"with Dask's {MALLOC_TRIM}, as before). Cluster start-up "
        f"{dask_run['cluster_start_s']:.2f} s, first study on the fresh workers "
        f"({WARM_SAMPLES:,} samples, tapp imported) {dask_run['first_study_s']:.2f} s, stop "
        f"{dask_run['cluster_stop_s']:.2f} s; with "
        f"the start-up and the first study, (b) takes {cold_s:.2f} s (< {TARGET_S:.0f} s: "
        f"{_ok(cold_s)}). (c): the covariance propagation alone "
        f"{1e3 * cov_timing.best_s:.2f} ms; the rest is the Imhof integrals (mean, 50/90/99 % "
        "of each |Δv|, the corridor fraction).",
        "",
        "**Bitwise identity of (b) and (a): yes**, every per-sample Δv and miss (as bit "
        "patterns) and every Monte Carlo statistic (as `tapp guide --json PATH` writes it); "
        "(b') too (checked: the section raises otherwise). Memory of one serial study: "
        f"tracemalloc peak {peak_mb:.0f} MB, of which the gathered outcomes "
        f"{outcomes_mb:.0f} MB ({outcomes_mb * 1e6 / N_SAMPLES:.0f} bytes a sample, held once "
        f"per shard and once concatenated; MAX_SAMPLES = {MAX_SAMPLES:,}). Mean |Δv|, Monte "
        f"Carlo vs linear covariance: {tcm}; outside the corridor (B-plane) "
        f"{mc['outside_corridor']['bplane']:.2e} vs {lin['outside_corridor']['bplane']:.2e} "
        "(the linear values take the later Δv and the miss as Gaussian; the execution errors "
        "scale with the earlier |Δv|, so their tails are heavier).",
    ])
    data = {"target_s": TARGET_S, "n_samples": N_SAMPLES, "seed": SEED, "workers": WORKERS,
            "setup": setup, "serial": serial, **runs, "ratio_dask_to_serial": ratio,
            "ratio_dask_malloc_trim_to_serial": ratio_trim, "dask_cold_s": cold_s,
            "linear_covariance": cov_timing, "linear_with_imhof": lin_timing,
            "bitwise_identical": identical, "tracemalloc_peak_mb": peak_mb,
            "outcomes_mb": outcomes_mb, "max_samples": MAX_SAMPLES,
            "statistics": {"monte_carlo": mc, "linear": lin},
            "load_average": [load_before, load_after],
            "config": {"scenario": SCENARIO.name, "deck": DECK.name, "guide": GUIDE.name,
                       "warm_samples": WARM_SAMPLES, "repeats_serial": REPEATS_SERIAL,
                       "repeats_dask": REPEATS_DASK, "repeats_linear": REPEATS_LINEAR}}
    return Section(NAME, md, data)


if __name__ == "__main__":
    print(run().markdown)

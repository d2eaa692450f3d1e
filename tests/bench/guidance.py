"""Benchmark of TAPP II: the deep-space guidance study, 10⁶ samples, before and after the
sampler drew in the space of the outcomes, serially and on Dask.

Set-up (timed apart, in a temporary folder): two T32 tapes, through the library calls of
``tapp simulate`` and ``tapp process --tape``:

- the shipped study, the example ``deep_space.toml`` through ``tapp3_deep_space.toml``: n_o =
  69 (the orbit, GM and GM of the Moon, Cr, three stations' locations and biases, 45 stochastic
  accelerations);
- its 23-parameter variant (:func:`variant_23`): the same files without Cr among the
  parameters and without the stochastic accelerations, in the scenario and in the deck, the
  size of the study before those joined it.

Guidance file: the example ``tapp2_deep_space.toml`` (three manoeuvres, B·R, B·T and the
flight time targeted, "inflate" navigation), :data:`N_SAMPLES` samples, seed :data:`SEED`.
Measured:

(a) after: the study serially in this process (``Execution(serial=True)``), on each tape;
(a₀) before: the same study with the library of commit :data:`SAMPLER_BEFORE_COMMIT`, the last
    that drew the whole state (n_o(1 + K) + 7M normals a sample), in a child process
    (:mod:`tests.bench.legacy`) on the same tape files; its repeats alternate with (a)'s, so
    that both see the same load;
(b) the study on a local Dask cluster of :data:`WORKERS` worker processes as tapp starts it
    (:func:`iter.execute.local_cluster`), 69-parameter tape, started before the timing (its
    start-up and the first study on the fresh workers, which import tapp, are reported apart);
(b') the same with Dask's ``MALLOC_TRIM_THRESHOLD_`` of 64 kB back in the workers, as they
    were started before tapp left it out (``iter.execute.WORKER_ENVIRON``): it also fixes
    glibc's mmap threshold at 128 kB, so every temporary array of a block is a fresh mmap
    whose pages fault in again;
(c) the linear covariance alone on one BLAS thread, as the study runs it, with its Imhof ΔV
    percentiles and corridor fractions (:func:`tapp.guidance.statistics.linear_outcome`), and
    the propagation of the covariance without them.

The Monte Carlo wall time is the study's own ``wall_s`` (:func:`tapp.guidance.shards.run_shards`:
forming the outcome maps, connecting to the cluster, scattering, simulating, gathering in
sample order); the whole study call adds binding the guidance file, the sample statistics and
the linear covariance. (a) and (b) must be bitwise identical, per sample and in every
statistic (the promise of :mod:`tapp.guidance.shards`); the section raises otherwise. Memory:
the tracemalloc peak of one serial study (untimed).

Targets (issue 33 item 2): the serial Monte Carlo within :data:`TARGETS` (6 s at n_o = 69,
1.5 s at n_o = 23), set when the whole-state sampler took 16.4 s and 3.43 s. Other work on the
machine inflates both columns alike, so each target is also stated as a ratio, after/before in
this run against the target's own (6/16.4 = 0.37, 1.5/3.43 = 0.44).
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from iter.execute import Execution, local_cluster
from tapp.examples import FOLDER as EXAMPLES
from tapp.guidance.guidefile import GuideFile, bind, read_guide
from tapp.guidance.linear import linear_covariance
from tapp.guidance.montecarlo import outcome_maps
from tapp.guidance.statistics import linear_outcome
from tapp.guidance.study import MAX_SAMPLES, GuidanceResult, guidance_study
from tapp.io.schema import validate
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.io.tape.t32 import T32
from tapp.io.tape.t32_hdf5 import read_t32, write_t32
from tapp.io.tomlfile import read_toml
from tapp.pipeline.steps import process_tape
from tapp.processor.deck import Deck
from tapp.processor.tape32 import build_t32, t32_provenance
from tapp.report.guidance import guidance_dict
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate
from tests.bench import legacy
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
#: The last commit whose TAPP II drew the whole state per sample (main before issue 33 item 2).
SAMPLER_BEFORE_COMMIT = "d1ec057"
#: Samples of the first study on a fresh cluster (the workers import tapp), not timed as such.
WARM_SAMPLES = 2000
REPEATS_SERIAL = 3
REPEATS_DASK = 3
REPEATS_LINEAR = 5
#: n_o: (target of the serial Monte Carlo, s; the whole-state sampler's time when it was set,
#: s) (issue 33 item 2).
TARGETS = {69: (6.0, 16.4), 23: (1.5, 3.43)}
#: Dask's setting of glibc's trim threshold in the workers it spawns (see (b') above), and
#: its value there.
MALLOC_TRIM = "MALLOC_TRIM_THRESHOLD_"
DASK_MALLOC_TRIM = "65536"
_M_PER_KM = 1e3

log = logger(NAME)


@dataclass(frozen=True, slots=True)
class Tape:
    """A T32 tape of the section: its label, file and contents, and its set-up times, s."""

    label: str
    path: Path
    t32: T32
    setup: dict[str, float]


def variant_23() -> tuple[dict, dict]:
    """The scenario and deck documents of the 23-parameter variant (module docstring)."""
    scenario = read_toml(SCENARIO)
    scenario.pop("stochastic")
    scenario["parameters"]["dynamic"].remove("Cr")
    deck = read_toml(DECK)
    deck["tape"].pop("n_o")
    for world in ("fit", "real"):
        deck[world]["stochastic"] = "ignore"
        deck[world]["apriori"]["sigma"].pop("Cr")
    return scenario, deck


def write_tape(folder: Path, label: str, scenario: dict, deck: dict) -> Tape:
    """TAPP I and TAPP III of a scenario and a deck (documents) into ``folder``."""
    stem = label.replace(" ", "_")
    t13_path, t32_path = folder / f"{stem}.t13.h5", folder / f"{stem}.t32.h5"
    simulate_s, sim = timed_once(lambda: simulate(parse_scenario(scenario, SCENARIO.name)))
    write_t13(t13_path, sim.tape)
    plan = validate(Deck, deck, DECK.name)
    process_s, (run, bound, header) = timed_once(
        lambda: process_tape(t13_path, plan, DECK.name))
    write_t32(t32_path, build_t32(run, bound, header,
                                  t32_provenance(header, plan, DECK.name, t13_path.name)))
    return Tape(label, t32_path, read_t32(t32_path),
                {"simulate_s": simulate_s, "process_s": process_s})


def write_tapes(folder: Path) -> tuple[Path, dict[str, float]]:
    """The shipped study's T32 tape into ``folder``: its path and the set-up times, s (what
    section ``cli`` runs ``tapp guide`` on)."""
    tape = write_tape(folder, "shipped", read_toml(SCENARIO), read_toml(DECK))
    return tape.path, tape.setup


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


#: The child of :func:`study_before`, on commit :data:`SAMPLER_BEFORE_COMMIT`'s library (after
#: :mod:`tests.bench.legacy`'s prelude): one serial study on the tape file; it replies with
#: its Monte Carlo wall time, the normals a sample drew and its Monte Carlo statistics.
_BEFORE_CHILD = """
from iter.execute import Execution
from tapp.guidance.guidefile import bind, read_guide
from tapp.guidance.study import guidance_study
from tapp.io.tape.t32_hdf5 import read_t32
from tapp.report.guidance import guidance_dict

t32 = read_t32(ARGS["t32"])
guide = read_guide(ARGS["guide"])
result = guidance_study(t32, guide, samples=ARGS["samples"], seed=ARGS["seed"],
                        execution=Execution(serial=True))
reply({"wall_s": result.wall_s, "n_normals": bind(guide, t32, "guide").problem.n_normals,
       "monte_carlo": guidance_dict(result)["monte_carlo"]})
"""


def study_before(checkout: legacy.Checkout, tape: Tape, cache: Path) -> dict:
    """One serial study of the tape with the whole-state sampler (:data:`_BEFORE_CHILD`)."""
    return legacy.run_child(checkout, _BEFORE_CHILD, {
        "t32": str(tape.path), "guide": str(GUIDE), "samples": N_SAMPLES, "seed": SEED},
        cache_dir=cache)


def serial_before_and_after(tapes: list[Tape], guide: GuideFile, folder: Path
                            ) -> tuple[dict, dict, str]:
    """(a) and (a₀) on every tape, their repeats alternating: ({label: (a)'s timings},
    {label: (a₀)'s best reply and times}, a note: how (a₀) ran, or why it did not)."""
    checkout, skipped = legacy.extract(folder, SAMPLER_BEFORE_COMMIT)
    cache = folder / "before-cache"
    cache.mkdir()
    after: dict[str, list] = {t.label: [] for t in tapes}
    before: dict[str, list] = {t.label: [] for t in tapes}
    for repeat in range(REPEATS_SERIAL):
        for tape in tapes:
            after[tape.label].append(timed_once(
                lambda tape=tape: study(tape.t32, guide, Execution(serial=True))))
            log(f"(a) {tape.label}, repeat {repeat + 1}: Monte Carlo "
                f"{after[tape.label][-1][1].wall_s:.2f} s")
            if skipped:
                continue
            try:
                before[tape.label].append(study_before(checkout, tape, cache))
            except RuntimeError as exc:  # e.g. a tape format the old library cannot read
                skipped = f"its child failed: {exc}"
                continue
            log(f"(a₀) {tape.label}, repeat {repeat + 1}: Monte Carlo "
                f"{before[tape.label][-1]['wall_s']:.2f} s")
    serial = {}
    for label, runs in after.items():
        walls = [r.wall_s for _, r in runs]
        serial[label] = {"monte_carlo_s": walls, "monte_carlo_best_s": min(walls),
                         "study_best_s": min(s for s, _ in runs),
                         "samples_per_s": N_SAMPLES / min(walls), "result": runs[-1][1]}
    old = {label: {"monte_carlo_s": [r["wall_s"] for r in runs],
                   "monte_carlo_best_s": min(r["wall_s"] for r in runs),
                   "n_normals": runs[0]["n_normals"], "monte_carlo": runs[-1]["monte_carlo"]}
           for label, runs in before.items() if runs and not skipped}
    note = (f"(a₀) not timed: {skipped}" if skipped else
            f"(a₀): the library of commit {checkout.commit[:7]} (`git archive` of tapp, search, "
            "iter) in a child process with only that folder on its path, one study per "
            "repeat, alternating with (a)'s")
    return serial, old, note


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


def _yes(ok: bool) -> str:
    return "yes" if ok else "NO"


def _serial_row(tape: Tape, after: dict, before: dict | None, n_normals: int) -> list[str]:
    """One row of the before/after table."""
    n_o = tape.t32.n_o
    target_s, set_at_s = TARGETS.get(n_o, (None, None))
    now = after["monte_carlo_best_s"]
    row = [tape.label, str(n_o)]
    if before is None:
        row += [f"— → {n_normals}", "—", f"{now:.2f}", "—"]
    else:
        was = before["monte_carlo_best_s"]
        row += [f"{before['n_normals']} → {n_normals}", f"{was:.2f}", f"{now:.2f}",
                f"{now / was:.3f}"]
    if target_s is None:
        return [*row, "—", "—", "—", "—"]
    ratio_ok = "—" if before is None else _yes(now / before["monte_carlo_best_s"]
                                               <= target_s / set_at_s)
    return [*row, f"{target_s:g}", _yes(now <= target_s), f"{target_s / set_at_s:.3f}",
            ratio_ok]


def _mc_row(label: str, r: dict, repeats: int) -> list[str]:
    return [label, str(repeats), f"{r['monte_carlo_best_s']:.2f}",
            f"{r['samples_per_s']:,.0f}", f"{r['study'].best_s:.2f}",
            f"{r['shard_samples']:,}"]


def _magnitudes(mc: dict) -> str:
    """Mean and 99 % |Δv| of each manoeuvre, m/s, from a ``monte_carlo`` section."""
    return "; ".join(
        f"TCM-{i + 1} {_M_PER_KM * m['magnitude']['mean_km_s']:.3f} / "
        f"{_M_PER_KM * dict(m['magnitude']['percentiles_km_s'])['99']:.3f}"
        for i, m in enumerate(mc["manoeuvres"]))


def run() -> Section:
    """Run the guidance section; return its Markdown and raw numbers."""
    load_before = os.getloadavg()
    guide = read_guide(GUIDE)
    with tempfile.TemporaryDirectory(prefix="tapp2-bench-") as tmp:
        folder = Path(tmp)
        tapes = [write_tape(folder, "shipped", read_toml(SCENARIO), read_toml(DECK)),
                 write_tape(folder, "without Cr and stochastic", *variant_23())]
        for t in tapes:
            log(f"set-up {t.label} (n_o = {t.t32.n_o}): T13 simulated in "
                f"{t.setup['simulate_s']:.1f} s, processed to a T32 tape in "
                f"{t.setup['process_s']:.2f} s")
        serial, before, before_note = serial_before_and_after(tapes, guide, folder)
    shipped = tapes[0]
    t32 = shipped.t32
    res_a = serial[shipped.label].pop("result")
    for t in tapes[1:]:
        serial[t.label].pop("result")
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

    with threadpool_limits(limits=1, user_api="blas"):
        study_of = bind(guide, t32, str(GUIDE))
        problem = study_of.problem
        n_normals = {t.label: outcome_maps(bind(guide, t.t32, str(GUIDE)).problem).n_normals
                     for t in tapes}
        cov_timing, _ = time_calls(lambda: linear_covariance(problem), REPEATS_LINEAR)
        lin_timing, _ = time_calls(lambda: linear_outcome(problem, linear_covariance(problem),
                                                          study_of.corridor), REPEATS_LINEAR)
        maps_timing, maps = time_calls(lambda: outcome_maps(problem), REPEATS_LINEAR)
    log(f"(c) linear covariance {1e3 * cov_timing.best_s:.2f} ms, with its Imhof statistics "
        f"{lin_timing.best_s:.3f} s; outcome maps {1e3 * maps_timing.best_s:.2f} ms")
    load_after = os.getloadavg()

    mismatch = {key: flags for key, flags in identical.items() if not all(flags.values())}
    if mismatch:
        raise AssertionError(f"Dask and serial studies differ (not bitwise identical): "
                             f"{mismatch}")

    a = serial[shipped.label]
    dask_run = runs["dask"]
    ratio = dask_run["samples_per_s"] / a["samples_per_s"]
    ratio_trim = runs["dask_malloc_trim"]["samples_per_s"] / a["samples_per_s"]
    cold_s = (dask_run["cluster_start_s"] + dask_run["first_study_s"]
              + dask_run["monte_carlo_best_s"])
    stats = guidance_dict(res_a)
    mc, lin = stats["monte_carlo"], stats["linear"]
    old_mc = before.get(shipped.label, {}).get("monte_carlo")
    compared = ("" if old_mc is None else
                f" Before: {_magnitudes(old_mc)}; outside the corridor (B-plane) "
                f"{old_mc['outside_corridor']['bplane']:.2e}.")
    md = "\n".join([
        "## TAPP II: Monte Carlo midcourse guidance (deep space, 10⁶ samples)",
        "",
        f"T32 tapes of `{SCENARIO.name}` through `{DECK.name}`, and of both without Cr and the "
        "stochastic accelerations (set-up, not timed with the studies: TAPP I "
        + ", ".join(f"{t.setup['simulate_s']:.1f} s" for t in tapes) + "; TAPP III "
        + ", ".join(f"{t.setup['process_s']:.2f} s" for t in tapes) + f"); guidance file "
        f"`{GUIDE.name}`: {len(problem.manoeuvres)} manoeuvres, {N_SAMPLES:,} samples, seed "
        f"{SEED}. Monte Carlo: the study's own wall time (outcome maps, connect, scatter, "
        "simulate, gather), best of the repeats. Load average (1 min) "
        f"{load_before[0]:.1f} before and {load_after[0]:.1f} after the section (2 logical "
        "CPUs; other work inflates times, both columns alike).",
        "",
        "### Serial Monte Carlo, whole state (before) and outcome space (after)",
        "",
        markdown_table(
            ["tape", "n_o", "normals a sample", "before (s)", "after (s)", "after/before",
             "target (s)", "met", "target ratio", "met"],
            [_serial_row(t, serial[t.label], before.get(t.label), n_normals[t.label])
             for t in tapes]),
        "",
        f"{before_note}. Targets: issue 33 item 2, set when the whole-state sampler took "
        + " and ".join(f"{was:g} s at n_o = {n}" for n, (_, was) in TARGETS.items())
        + "; the ratio column is the target over that time. Mean / 99 % |Δv| (m/s) of the "
        f"shipped study, after: {_magnitudes(mc)}; outside the corridor (B-plane) "
        f"{mc['outside_corridor']['bplane']:.2e}.{compared} (Different draws of the same "
        "law; the two samplers' statistics are tested equal to their sampling error in "
        "`tests/tapp/guidance/test_reduction.py`.)",
        "",
        "### Shipped tape: Dask and the linear covariance",
        "",
        markdown_table(
            ["execution", "repeats", "Monte Carlo (s)", "samples/s", "study (s)",
             "samples a shard"],
            [["(a) serial, this process", str(REPEATS_SERIAL), f"{a['monte_carlo_best_s']:.2f}",
              f"{a['samples_per_s']:,.0f}", f"{a['study_best_s']:.2f}", "—"],
             _mc_row(f"(b) Dask, local cluster of {WORKERS} workers", dask_run, REPEATS_DASK),
             _mc_row(f"(b') as (b), with Dask's {MALLOC_TRIM} in the workers (as before)",
                     runs["dask_malloc_trim"], REPEATS_DASK),
             ["(c) linear covariance + Imhof statistics (one BLAS thread)",
              str(REPEATS_LINEAR), "—", "—", f"{lin_timing.best_s:.3f}", "—"]]),
        "",
        f"**(b)/(a) samples per second: {ratio:.2f}x** ({WORKERS} workers; {ratio_trim:.2f}x "
        f"with Dask's {MALLOC_TRIM}, as before). Cluster start-up "
        f"{dask_run['cluster_start_s']:.2f} s, first study on the fresh workers "
        f"({WARM_SAMPLES:,} samples, tapp imported) {dask_run['first_study_s']:.2f} s, stop "
        f"{dask_run['cluster_stop_s']:.2f} s; with the start-up and the first study, (b) takes "
        f"{cold_s:.2f} s. (c): the covariance propagation alone "
        f"{1e3 * cov_timing.best_s:.2f} ms; the rest is the Imhof integrals (mean, 50/90/99 % "
        "of each |Δv|, the corridor fraction). The outcome maps F, C, F_s (formed once per study, "
        f"inside the Monte Carlo time): {1e3 * maps_timing.best_s:.2f} ms, {maps.n_y} outcomes.",
        "",
        "**Bitwise identity of (b) and (a): yes**, every per-sample Δv and miss (as bit "
        "patterns) and every Monte Carlo statistic (as `tapp guide --json PATH` writes it); "
        "(b') too (checked: the section raises otherwise). Memory of one serial study: "
        f"tracemalloc peak {peak_mb:.0f} MB, of which the gathered outcomes "
        f"{outcomes_mb:.0f} MB ({outcomes_mb * 1e6 / N_SAMPLES:.0f} bytes a sample, written in "
        "place by a serial run; a Dask shard's part is copied in as it completes; MAX_SAMPLES = "
        f"{MAX_SAMPLES:,}). Mean |Δv|, Monte "
        "Carlo vs linear covariance: "
        + "; ".join(f"TCM-{i + 1} {_M_PER_KM * m['magnitude']['mean_km_s']:.3f} vs "
                    f"{_M_PER_KM * n['magnitude']['mean_km_s']:.3f} m/s"
                    for i, (m, n) in enumerate(zip(mc["manoeuvres"], lin["manoeuvres"],
                                                   strict=True)))
        + f"; outside the corridor (B-plane) {mc['outside_corridor']['bplane']:.2e} vs "
        f"{lin['outside_corridor']['bplane']:.2e} (the linear values take the later Δv and "
        "the miss as Gaussian; the execution errors scale with the earlier |Δv|, so their "
        "tails are heavier).",
    ])
    data = {"targets": TARGETS, "n_samples": N_SAMPLES, "seed": SEED, "workers": WORKERS,
            "setup": {t.label: {"n_o": t.t32.n_o, **t.setup} for t in tapes},
            "serial": serial, "serial_before": before, "before_note": before_note,
            **runs, "ratio_dask_to_serial": ratio,
            "ratio_dask_malloc_trim_to_serial": ratio_trim, "dask_cold_s": cold_s,
            "linear_covariance": cov_timing, "linear_with_imhof": lin_timing,
            "outcome_maps": maps_timing,
            "bitwise_identical": identical, "tracemalloc_peak_mb": peak_mb,
            "outcomes_mb": outcomes_mb, "max_samples": MAX_SAMPLES,
            "statistics": {"monte_carlo": mc, "linear": lin},
            "load_average": [load_before, load_after],
            "config": {"scenario": SCENARIO.name, "deck": DECK.name, "guide": GUIDE.name,
                       "sampler_before_commit": SAMPLER_BEFORE_COMMIT,
                       "warm_samples": WARM_SAMPLES, "repeats_serial": REPEATS_SERIAL,
                       "repeats_dask": REPEATS_DASK, "repeats_linear": REPEATS_LINEAR}}
    return Section(NAME, md, data)


if __name__ == "__main__":
    print(run().markdown)

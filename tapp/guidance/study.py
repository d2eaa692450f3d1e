"""A TAPP II study: a T32 tape and a guidance file in, ΔV and miss statistics out.

:func:`guidance_study` (objects; :func:`tapp.pipeline.steps.run_guidance` from the files) binds
the guidance file to the tape (:func:`tapp.guidance.guidefile.bind`), runs the Monte Carlo in
shards (:func:`tapp.guidance.shards.run_shards`), propagates the linear covariance
(:func:`tapp.guidance.linear.linear_covariance`) and returns both sets of statistics
(:mod:`tapp.guidance.statistics`), the linear statistics the samples contradict
(:mod:`tapp.guidance.agreement`) and the per-sample outcomes, in one :class:`GuidanceResult`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from iter.execute import Execution
from tapp.constants import C_LIGHT_km_s
from tapp.errors import InputError
from tapp.guidance.agreement import Agreement, compare
from tapp.guidance.execution import ExecutionErrors
from tapp.guidance.guidefile import GuideFile, bind
from tapp.guidance.linear import LinearCovariance, linear_covariance
from tapp.guidance.model import Problem
from tapp.guidance.montecarlo import BLOCK_SAMPLES, Samples
from tapp.guidance.shards import run_shards
from tapp.guidance.statistics import Corridor, Outcome, linear_outcome, sample_outcome
from tapp.io.tape.t32 import T32

#: Fewest samples (a covariance needs two).
MIN_SAMPLES = 2
#: Most samples: the gathered outcomes are ~100 bytes a sample (3 manoeuvres, 3 miss
#: components), 0.5 GB at this bound.
MAX_SAMPLES = 5_000_000
#: Largest σ of a final miss component, in its unit (km, s, rad): as the a priori σ's of TAPP
#: III (:data:`tapp.processor.deck.SIGMA_RANGE`); the Monte Carlo's 4th moments of samples a
#: few σ wide then stay below 1e130.
MAX_MISS_SIGMA = 1e30


@dataclass(frozen=True, slots=True, eq=False)
class GuidanceResult:
    """The outcome of a guidance study.

    Attributes
    ----------
    title : the guidance file's title.
    tape_iden : identification of the T32 tape.
    tape_source, guide_source : the files (or labels) read.
    targets : names of the targeted miss components.
    errors : the execution errors.
    navigation : the navigation after a manoeuvre, "tape" or "inflate"
        (:mod:`tapp.guidance.navigation`).
    corridor : the corridor, or None.
    miss_name, miss_unit : the miss components of the final miss.
    n_samples, seed : the Monte Carlo's size and root seed.
    block_samples, shard_samples : samples per RNG block and per shard.
    where : where the shards ran (e.g. "local cluster (2 workers)").
    wall_s : wall time of the Monte Carlo, s.
    monte_carlo, linear : the statistics of the samples and of the linear covariance.
    agreement : every linear statistic against the samples: which ones they contradict.
    samples : the per-sample outcomes, in sample order.
    """

    title: str
    tape_iden: str
    tape_source: str
    guide_source: str
    targets: tuple[str, ...]
    errors: ExecutionErrors
    navigation: str
    corridor: Corridor | None
    miss_name: tuple[str, ...]
    miss_unit: tuple[str, ...]
    n_samples: int
    seed: int
    block_samples: int
    shard_samples: int
    where: str
    wall_s: float
    monte_carlo: Outcome
    linear: Outcome
    agreement: Agreement
    samples: Samples


def check_samples(n: int, option: str = "samples") -> int:
    """Return ``n`` if MIN_SAMPLES <= n <= MAX_SAMPLES, else raise InputError naming it."""
    if isinstance(n, bool) or not isinstance(n, int) or not MIN_SAMPLES <= n <= MAX_SAMPLES:
        raise InputError(option, "value", f"a whole number of samples {MIN_SAMPLES}.."
                         f"{MAX_SAMPLES:,}", n)
    return n


def check_shard_samples(n: int | None, option: str = "shard_samples") -> int | None:
    """Return ``n`` if None or a positive multiple of BLOCK_SAMPLES, else raise InputError."""
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < BLOCK_SAMPLES
                          or n % BLOCK_SAMPLES):
        raise InputError(option, "value", f"a whole multiple of {BLOCK_SAMPLES:,} samples (the "
                         "RNG block)", n)
    return n


def check_seed(seed: int, option: str = "seed") -> int:
    """Return ``seed`` if it is a whole number >= 0 (a SeedSequence entropy)."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(option, "value", "a whole number >= 0 (a seed for numpy's "
                         "SeedSequence)", seed)
    return seed


def physical_linear_covariance(problem: Problem, tape_source: str = "T32"
                               ) -> LinearCovariance:
    """Return the linear covariance of ``problem``, checked physically possible, before any
    sample is drawn (the samples follow the same maps, a few σ wide).

    Every manoeuvre's Δv σ (√tr Cov(Δv)) must be below the speed of light, every final miss
    σ within :data:`MAX_MISS_SIGMA`, and no product on the way may overflow: the tape's
    covariances and partials, each within the tapes' bound, can still be too large together.

    Raises
    ------
    InputError
        Naming the tape: the first manoeuvre or miss component at fault, or the overflow.
    """
    try:
        with np.errstate(over="raise", invalid="raise"):
            linear = linear_covariance(problem)
    except FloatingPointError as exc:
        raise InputError(tape_source, "recycles", "covariances and partials whose products "
                         "are finite (the linear covariance of the guidance)", str(exc)) from None
    dv_sigma = np.sqrt(np.trace(linear.dv_cov, axis1=1, axis2=2))
    for step, sigma in zip(problem.manoeuvres, dv_sigma, strict=True):
        if not sigma < C_LIGHT_km_s:
            raise InputError(tape_source, f"recycles/{step.number}", "a manoeuvre whose Δv σ "
                             f"is below the speed of light ({C_LIGHT_km_s:,} km/s)",
                             f"{sigma:.3g} km/s")
    miss_sigma = np.sqrt(np.diagonal(linear.miss_cov))
    for name, unit, sigma in zip(problem.miss_name, problem.miss_unit, miss_sigma,
                                 strict=True):
        if not sigma <= MAX_MISS_SIGMA:
            raise InputError(tape_source, f"miss/{name}", f"a final miss σ within "
                             f"{MAX_MISS_SIGMA:g} {unit}", f"{sigma:.3g} {unit}")
    return linear


def guidance_study(t32: T32, guide: GuideFile, *, samples: int, seed: int,
                   execution: Execution | None = None, shard_samples: int | None = None,
                   progress: Callable[[int, int], None] | None = None,
                   guide_source: str = "guidance", tape_source: str = "T32"
                   ) -> GuidanceResult:
    """Run a guidance study on a tape in memory (module docstring).

    Parameters
    ----------
    t32 : the T32 tape.
    guide : the validated guidance file.
    samples : Monte Carlo samples, MIN_SAMPLES..MAX_SAMPLES.
    seed : root seed, >= 0.
    execution : where the shards run (``iter.Execution``); None: automatic, in this process
        below :data:`tapp.guidance.shards.DASK_MIN_SAMPLES` samples and on a local Dask
        cluster of one worker per core from there; ``Execution(serial=True)`` runs in this
        process.
    shard_samples : samples per shard, a multiple of BLOCK_SAMPLES; None chooses.
    progress : called with (samples done, samples) as shards complete.
    guide_source, tape_source : named in errors and in the result.

    Raises
    ------
    InputError
        Bad sizes or seed, a guidance file that does not fit the tape, or a tape whose
        guidance is physically impossible (:func:`physical_linear_covariance`).
    iter.SchedulerError
        The scheduler does not answer.

    Notes
    -----
    BLAS runs on one thread meanwhile (``threadpoolctl``), as under ``tapp guide`` and in a
    local cluster's workers: the factors are n_o x n_o, and on a loaded 2-core machine two
    threads took the 69-parameter study's navigation refit ("inflate") from 12 ms to 1.2 s
    and its linear covariance from 8 ms to 1.1 s.
    """
    check_samples(samples)
    check_seed(seed)
    check_shard_samples(shard_samples)
    with threadpool_limits(limits=1, user_api="blas"):
        study = bind(guide, t32, guide_source, tape_source)
        problem = study.problem
        linear = physical_linear_covariance(problem, tape_source)
        start = time.perf_counter()
        run = run_shards(problem, seed, samples,
                         Execution() if execution is None else execution, shard_samples,
                         progress)
        wall_s = time.perf_counter() - start
        mc = sample_outcome(problem, run.samples, study.corridor)
        lin = linear_outcome(problem, linear, study.corridor)
        agreement = compare(problem.miss_name, run.samples, study.corridor, mc, lin)
    return GuidanceResult(
        study.title, t32.iden, tape_source, guide_source,
        tuple(problem.miss_name[i] for i in problem.targets), problem.errors,
        study.navigation, study.corridor,
        problem.miss_name, problem.miss_unit, samples, seed, BLOCK_SAMPLES, run.shard_samples,
        run.where, wall_s, mc, lin, agreement, run.samples)


__all__ = ["MAX_MISS_SIGMA", "MAX_SAMPLES", "MIN_SAMPLES", "GuidanceResult", "check_samples",
           "check_shard_samples", "check_seed", "guidance_study", "physical_linear_covariance"]

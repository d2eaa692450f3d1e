"""Run the Monte Carlo in shards, in this process or on Dask, as ITER runs its cases.

A shard is a run of whole RNG blocks (:data:`tapp.guidance.montecarlo.BLOCK_SAMPLES`
samples each) simulated by :func:`tapp.guidance.montecarlo.simulate_blocks` from the maps of
:func:`tapp.guidance.montecarlo.outcome_maps`, formed once here and sent to every shard (so no
worker forms its own, with its own BLAS); shards run on
the executor of :func:`iter.execute.open_executor` (serially, on a local Dask cluster, or on
a running cluster given its scheduler address; by default in this process below
:data:`DASK_MIN_SAMPLES` samples and on a local cluster from there), complete in any order,
and are copied into their rows of the result (in this process, written there in place).
Since every sample depends on its own block's generator and row only, the gathered samples,
and every statistic of them, are bitwise the same whatever the shard size and the number of
workers.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from iter.execute import DaskExecutor, Execution, open_executor, too_small
from tapp.guidance.model import Problem
from tapp.guidance.montecarlo import (
    BLOCK_SAMPLES,
    OutcomeMaps,
    Samples,
    outcome_maps,
    simulate_blocks,
)

#: Shards per worker slot when the shard size is chosen automatically (load balance).
SHARDS_PER_SLOT = 4
#: Largest automatic shard, blocks (keeps the progress bar moving and worker memory small).
MAX_AUTO_SHARD_BLOCKS = 50
#: Fewest samples an automatic execution runs on a local Dask cluster: below, this process
#: is faster. Since a sample draws only in the space of the outcomes (tapp.guidance.montecarlo)
#: it costs about 1 µs in this process (0.5 µs of CPU), and a local cluster of 2 workers on
#: 2 cores gathers the outcomes at 0.53x that rate, after 3 to 10 s of start-up (``make
#: bench`` section ``guidance``, 2026-11-28, load average 7): it repays no run up to the
#: largest one (MAX_SAMPLES, 5 million), so an automatic execution stays here; ``--workers N``
#: or ``--scheduler`` still choose one. (When a sample took 3.5 to 12 µs, the crossover was 3
#: to 5.5 million; at 2.6 µs, a cluster gathered at 0.73x.)
DASK_MIN_SAMPLES = 10_000_000


@dataclass(frozen=True, slots=True)
class Shard:
    """RNG blocks first_block .. first_block + n_blocks − 1, the ``index``-th shard."""

    index: int
    first_block: int
    n_blocks: int


def plan_shards(n_samples: int, shard_samples: int) -> tuple[Shard, ...]:
    """Split ``n_samples`` into shards of ``shard_samples`` (a multiple of the block)."""
    per = shard_samples // BLOCK_SAMPLES
    n_blocks = math.ceil(n_samples / BLOCK_SAMPLES)
    return tuple(Shard(i, b, min(per, n_blocks - b))
                 for i, b in enumerate(range(0, n_blocks, per)))


def default_shard_samples(n_samples: int, slots: int) -> int:
    """About :data:`SHARDS_PER_SLOT` shards per slot, 1 to :data:`MAX_AUTO_SHARD_BLOCKS`
    blocks each, in samples."""
    n_blocks = math.ceil(n_samples / BLOCK_SAMPLES)
    per = max(1, min(MAX_AUTO_SHARD_BLOCKS, math.ceil(n_blocks / (SHARDS_PER_SLOT * slots))))
    return per * BLOCK_SAMPLES


@dataclass(frozen=True, slots=True, eq=False)
class ShardRun:
    """The gathered samples and how they were run."""

    samples: Samples
    shard_samples: int
    where: str


def run_shards(problem: Problem, seed: int, n_samples: int, execution: Execution,
               shard_samples: int | None = None,
               progress: Callable[[int, int], None] | None = None) -> ShardRun:
    """Simulate ``n_samples`` samples in shards on ``execution``; gather in sample order.

    Parameters
    ----------
    problem : the guidance problem.
    seed : root seed of the RNG blocks.
    n_samples : number of samples, >= 1.
    execution : where to run (``iter.Execution``); an automatic one (none of serial,
        scheduler and workers) runs in this process below :data:`DASK_MIN_SAMPLES`.
    shard_samples : samples per shard, a multiple of BLOCK_SAMPLES; None chooses.
    progress : called with (samples done, n_samples) as shards complete.

    Raises
    ------
    iter.SchedulerError
        The scheduler address does not answer, or its cluster has no worker.
    """
    small = too_small("samples", n_samples, DASK_MIN_SAMPLES)
    maps = outcome_maps(problem)
    samples = Samples(np.empty((n_samples, maps.n_man, 3)),
                      np.empty((n_samples, maps.n_y - 3 * maps.n_man)))
    with open_executor(execution, small=small) as executor:
        size = shard_samples or default_shard_samples(n_samples, executor.slots)
        shards = plan_shards(n_samples, size)
        done = 0

        def record(n_done: int) -> None:
            nonlocal done
            done += n_done
            if progress is not None:
                progress(done, n_samples)

        def gather(shard: Shard, part: Samples) -> None:
            """Copy a shard computed elsewhere into its rows."""
            rows = slice(shard.first_block * BLOCK_SAMPLES,
                         shard.first_block * BLOCK_SAMPLES + part.n)
            samples.dv_km_s[rows] = part.dv_km_s
            samples.miss[rows] = part.miss
            record(part.n)

        if isinstance(executor, DaskExecutor):
            _on_dask(executor, maps, seed, n_samples, shards, gather)
        else:
            for shard in shards:
                record(simulate_blocks(maps, seed, shard.first_block, shard.n_blocks,
                                       n_samples, out=samples).n)
        where = executor.description
    return ShardRun(samples, size, where)


def _on_dask(executor: DaskExecutor, maps: OutcomeMaps, seed: int, n_samples: int,
             shards: tuple[Shard, ...], gather: Callable[[Shard, Samples], None]) -> None:
    """Submit every shard (the maps scattered once); gather each as it completes."""
    from distributed import as_completed

    client = executor.client
    [remote] = client.scatter([maps], broadcast=True)
    pending = {client.submit(simulate_blocks, remote, seed, s.first_block, s.n_blocks,
                             n_samples, pure=False): s for s in shards}
    try:
        for future in as_completed(list(pending), loop=client.loop):
            gather(pending.pop(future), future.result())
            future.release()
    finally:
        if pending:
            client.cancel(list(pending))


__all__ = ["DASK_MIN_SAMPLES", "MAX_AUTO_SHARD_BLOCKS", "SHARDS_PER_SLOT", "Shard", "ShardRun",
           "default_shard_samples", "plan_shards", "run_shards"]

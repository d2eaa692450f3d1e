"""Monte Carlo samples of the guidance model (:mod:`tapp.guidance`), block by block.

Randomness comes in fixed blocks of :data:`BLOCK_SAMPLES` samples: block b draws one
(n_b, n_normals) array of standard normals, row-major, from its own generator
``np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(b,)))`` (the b-th child of
the root ``SeedSequence(seed)``). Sample s is row s mod :data:`BLOCK_SAMPLES` of block
s // :data:`BLOCK_SAMPLES`; its columns are, in order, the normals of Λ̄⁰ (n_o), then per
step those of Σ_k (n_o) and, at a manoeuvre, those of its execution error (7).

Every product is an :func:`numpy.einsum` (not a BLAS matrix product, whose rounding depends
on the number of rows and threads), so each sample's numbers depend on its own row only:
the samples are bitwise the same whatever the block, shard or worker count, and the first
N samples of a larger run are those of a run of N.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.guidance.execution import NORMALS_PER_MANOEUVRE, sample_errors
from tapp.guidance.model import Problem

#: Samples per RNG block; shards are whole numbers of blocks.
BLOCK_SAMPLES = 1000


@dataclass(frozen=True, slots=True, eq=False)
class Samples:
    """Per-sample outcomes, in sample order.

    Attributes
    ----------
    dv_km_s : (n, n_man, 3) commanded corrections Δv of each manoeuvre, km/s, inertial.
    miss : (n, n_m) final true miss deviation B_final d, in the tape's miss units.
    """

    dv_km_s: np.ndarray
    miss: np.ndarray

    @property
    def n(self) -> int:
        """Number of samples."""
        return self.miss.shape[0]

    @property
    def dv_magnitude_km_s(self) -> np.ndarray:
        """(n, n_man) |Δv| of each manoeuvre, km/s."""
        return np.sqrt(np.einsum("smi,smi->sm", self.dv_km_s, self.dv_km_s))


def block_normals(seed: int, block: int, n: int, n_normals: int) -> np.ndarray:
    """Return the (n, n_normals) standard normals of RNG block ``block`` (module docstring)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(block,)))
    return rng.standard_normal((n, n_normals))


def _apply(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Rows of x mapped by M: (n, c) -> (n, r), each row on its own."""
    return np.einsum("ij,sj->si", M, x)


def propagate(problem: Problem, normals: np.ndarray) -> Samples:
    """Return the outcomes of samples given their normals (n, n_normals) (model of
    :mod:`tapp.guidance`).

    d ~ N(0, Λ̄⁰), e = −d; at each step d ← T d, e ← L T e + w; at a manoeuvre
    Δv = −G B_t (d + e), d_v ← d_v + Δv + ε, e_v ← e_v − ε; finally m = B_final d.
    """
    n_o = problem.n_o
    vel = list(problem.velocity)
    d = _apply(problem.lambda0_factor, normals[:, :n_o])
    e = -d
    col = n_o
    dvs = []
    for step in problem.steps:
        d = _apply(step.transition, d)
        e = _apply(step.LT, e) + _apply(step.sigma_factor, normals[:, col:col + n_o])
        col += n_o
        if step.correction is None:
            continue
        c = step.correction
        dv = -_apply(c.gain, _apply(c.B_target, d + e))
        eps = sample_errors(dv, normals[:, col:col + NORMALS_PER_MANOEUVRE], problem.errors)
        col += NORMALS_PER_MANOEUVRE
        d[:, vel] += dv + eps
        e[:, vel] -= eps
        dvs.append(dv)
    return Samples(np.stack(dvs, axis=1), _apply(problem.B_final, d))


def simulate_blocks(problem: Problem, seed: int, first_block: int, n_blocks: int,
                    n_samples: int) -> Samples:
    """Return the samples of RNG blocks first_block .. first_block + n_blocks − 1 of a run
    of ``n_samples`` samples (the last block of the run may be partial): one shard."""
    n_normals = problem.n_normals
    start = first_block * BLOCK_SAMPLES
    stop = min((first_block + n_blocks) * BLOCK_SAMPLES, n_samples)
    dv = np.empty((stop - start, len(problem.manoeuvres), 3))
    miss = np.empty((stop - start, problem.B_final.shape[0]))
    for b in range(first_block, first_block + n_blocks):
        lo, hi = b * BLOCK_SAMPLES, min((b + 1) * BLOCK_SAMPLES, n_samples)
        if lo >= hi:
            break
        out = propagate(problem, block_normals(seed, b, hi - lo, n_normals))
        dv[lo - start:hi - start] = out.dv_km_s
        miss[lo - start:hi - start] = out.miss
    return Samples(dv, miss)


__all__ = ["BLOCK_SAMPLES", "Samples", "block_normals", "propagate", "simulate_blocks"]

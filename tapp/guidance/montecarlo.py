"""Monte Carlo samples of the guidance model (:mod:`tapp.guidance`), drawn in the space of
the outcomes, block by block.

What a sample is made of
------------------------
Let g = [n₀; n₁; …; n_K] be the standard normals of the model: d₀ = F₀ n₀ (F₀F₀ᵀ = Λ̄⁰)
and the tracking noise of step k, w_k = F_k n_k (F_kF_kᵀ = Σ_k); and ε_j the execution error
of manoeuvre j. Every map of a step is linear in z = [d; e]: the recycle
z ← diag(T_k, L_kT_k) z + [0; w_k], the correction Δv_j = K_j z with K_j = −G_j B_t [I I],
and z ← z + [S; 0] Δv_j + [S; −S] ε_j (S: the velocity columns of the identity); the final
miss is m = B_final d. By induction over the steps, the outcomes every statistic of a sample
reads, y = [Δv₁; …; Δv_M; m] (n_y = 3M + n_m), are

.. math::

    y = A\\,g + C\\,\\varepsilon, \\qquad \\varepsilon = [\\varepsilon_1; \\dots;
        \\varepsilon_M],

A (n_y x n_g; n_g = n_o + the columns of every Σ_k's factor, n_o(1 + K) on TAPP III's
tapes) and C (n_y x 3M) fixed, C strictly block lower triangular (ε_j acts on
what follows manoeuvre j only: C_ji = 0 for the rows of Δv_j, j ≤ i). What is not linear is
ε_j = ε(Δv_j, ν_j) (Gates, :mod:`tapp.guidance.execution`: its law given Δv_j scales with
|Δv_j|), with ν_j its 7 normals, independent of g and of one another.

The reduction (exact)
---------------------
So y = Y(a, ν) is one fixed function of a = A g and ν = [ν₁; …; ν_M]: in turn
Δv_j = a_j + Σ_{i<j} C_ji ε(Δv_i, ν_i), then m = a_m + C_m ε. a ~ N(0, A Aᵀ) and ν are
independent; any a′ ~ N(0, A Aᵀ) independent of ν gives (a′, ν) the joint law of (a, ν), and
Y(a′, ν) the joint law of y: every outcome of a sample, jointly, and so every statistic of the
samples (magnitudes, percentiles, corridor counts, covariances), has the law it has when the
whole state is drawn. So

.. math:: a' = F u, \\qquad u \\sim N(0, I_{n_y}), \\qquad F F^T = A A^T,

will do, and its arithmetic does not grow with n_o. Its second moments are those of the linear
covariance (:mod:`tapp.guidance.linear`): Cov(y) = F Fᵀ + C diag(E[ε_jε_jᵀ]) Cᵀ, since
E[ε_j | a, ν_{<j}] = 0 leaves ε_j uncorrelated with a and with every other ε_i.

The execution errors in fewer normals (exact)
---------------------------------------------
Gates' error with σ₂ = σ₄ = σ_f (:mod:`tapp.guidance.execution`) is ε_j = p_j + σ_f f_j: a
fixed part, f_j ~ N(0, I₃), and a proportional part whose law given Δv_j is
N(0, |Δv_j|² (σ_p² ûûᵀ + σ_θ² (I − ûûᵀ))), û = Δv_j/|Δv_j|. The fixed parts act on y only
through C, linearly, and are independent of everything else: b = a + σ_f C f, f = [f₁; …;
f_M], is Gaussian and independent of the proportional parts' normals, and y is the same
function of b as it was of a, with p_j for ε_j (C_ji = 0 for the rows of Δv_j, j ≤ i, so
Δv_j = b_j + Σ_{i<j} C_ji p_i still). A sample therefore draws

.. math:: b' = F_s u, \\qquad u \\sim N(0, I_{n_y}), \\qquad F_s F_s^T = F F^T
    + \\sigma_f^2\\,C C^T,

and the proportional part from 3 normals h_j ~ N(0, I₃), independent of u and of one another,
by :func:`tapp.guidance.execution.proportional_errors`:

.. math:: p_j = \\sigma_\\theta \\lvert\\Delta v_j\\rvert\\, h_j + (\\sigma_p
    - \\sigma_\\theta)\\,(\\hat u\\cdot h_j)\\,\\Delta v_j,

whose law given Δv_j is the one above (û·h_j ~ N(0, 1) and (I − ûûᵀ) h_j ~ N(0, I − ûûᵀ),
independent). So y has the law of the whole-state model still, from n_y + 3M normals (21
for three manoeuvres and three miss components; Gates' seven a manoeuvre made it 33) instead
of n_o(1 + K) + 7M (297 at n_o = 69, K = 3): the normals were 0.40 s of CPU of the 0.73 s
that 10⁶ samples took at 33 (2026-11-28).

:func:`outcome_maps` forms F and C once per problem, as :mod:`tapp.guidance.linear` forms its
square-root covariance: the columns of a factor of the Gaussian part of [d; e; y] go through
the maps (Σ_k's factor columns appended at each recycle, the rows of Δv_j filled in at its
manoeuvre and of m at the end) and are compressed back to 2 n_o + n_y by a Householder QR
after each recycle; F is the lower-triangular factor of the y rows, (QR of their transpose)ᵀ,
so A Aᵀ is never formed. Householder QR of a transpose is backward stable row by row: each
row of F keeps the digits of its own norm, so the Gaussian parts of the later corrections and
of the miss (what the nulling leaves, 1e-4 of the first correction on the deep-space study)
are not rounded against the larger ones. C is the same maps acting on unit execution errors,
with no QR. F_s is the lower-triangular factor of [F, σ_f C] the same way.

Randomness comes in fixed blocks of :data:`BLOCK_SAMPLES` samples: block b draws one
(n_b, n_y + 3M) array of standard normals, row-major, from its own generator
``np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(b,)))`` (the b-th child of
the root ``SeedSequence(seed)``). Sample s is row s mod :data:`BLOCK_SAMPLES` of block
s // :data:`BLOCK_SAMPLES`; its columns are u (n_y), then h_j (3) of each manoeuvre in time
order.

A run propagates :data:`CHUNK_BLOCKS` blocks at a time with the samples as columns: the
normals of each block are transposed into an (n_normals, n) array, and every operation is a
NumPy element-wise one (+, −, ×, ÷, √) on rows of n samples, in a fixed order per sample:
products with F_s and C column by column (:func:`_apply`), the proportional errors by
:func:`tapp.guidance.execution.proportional_errors`; no reduction, no einsum, no BLAS (whose
rounding depends on the number of rows and threads). Each sample's numbers are then the same
IEEE arithmetic on its own normals whatever the chunk, block, shard or worker count, and F_s
and C are formed once, in the process that plans the shards: the samples are bitwise the same for
any of those, and the first N samples of a larger run are those of a run of N.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from tapp.estimation.factors import triangularize
from tapp.guidance.execution import ExecutionErrors, proportional_errors
from tapp.guidance.model import Problem

#: Samples per RNG block; shards are whole numbers of blocks.
BLOCK_SAMPLES = 1000
#: Standard normals a sample draws per manoeuvre: h_j (module docstring).
NORMALS_PER_MANOEUVRE = 3
#: RNG blocks propagated at once (module docstring). Measured on 10⁶ samples of three
#: manoeuvres (:func:`simulate_blocks`, CPU time, 2026-11-28): 1 block 0.67 s, 4 0.50 s,
#: 8 0.48 s, 12 0.57 s, 32 0.63 s; NumPy's cost per call dominates small chunks, and from 12
#: blocks a chunk's arrays (21 normals and 12 outcomes of 8 bytes a sample) leave the cache.
CHUNK_BLOCKS = 8


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


@dataclass(frozen=True, slots=True, eq=False)
class OutcomeMaps:
    """The maps from a sample's normals to its outcomes y = F u + C ε (module docstring).

    Attributes
    ----------
    gauss_factor : (n_y, n_y) F, lower triangular, F Fᵀ = Cov of the Gaussian part A g of
        y = [Δv₁; …; Δv_M; m] (km/s and miss units).
    error_map : (n_y, 3 n_man) C = ∂y/∂ε, strictly block lower triangular.
    errors : the execution errors.
    sample_factor : (n_y, n_y) F_s, lower triangular, F_s F_sᵀ = F Fᵀ + σ_f² C Cᵀ: the
        Gaussian part with the fixed execution errors, what a sample draws.
    """

    gauss_factor: np.ndarray
    error_map: np.ndarray
    errors: ExecutionErrors
    sample_factor: np.ndarray

    @property
    def n_man(self) -> int:
        """Number of manoeuvres."""
        return self.error_map.shape[1] // 3

    @property
    def n_y(self) -> int:
        """Number of outcomes a sample has, 3 n_man + n_m."""
        return self.gauss_factor.shape[0]

    @property
    def n_normals(self) -> int:
        """Standard normals one sample draws: u (n_y), then 3 per manoeuvre."""
        return self.n_y + NORMALS_PER_MANOEUVRE * self.n_man


def outcome_maps(problem: Problem) -> OutcomeMaps:
    """Return F and C of ``problem`` (module docstring).

    Rows of the working factors: d (n_o), e (n_o), then y (n_y); the Gaussian factor's columns
    are compressed after each recycle, the n_man unit execution errors keep 3 columns each.
    BLAS runs on one thread meanwhile (``threadpoolctl``): the QRs are (3 n_o + n_y) x
    (2 n_o + n_y), where two threads on a loaded 2-core machine took 0.3 s for the 69-parameter
    tape against 2 ms on one, and F and C then do not depend on the thread count.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _outcome_maps(problem)


def _outcome_maps(problem: Problem) -> OutcomeMaps:
    n = problem.n_o
    n_man = len(problem.manoeuvres)
    n_m = problem.B_final.shape[0]
    y0 = 2 * n                                       # first row of y
    vel = list(problem.velocity)
    gauss = np.zeros((2 * n + 3 * n_man + n_m, n))
    gauss[:n] = problem.lambda0_factor               # d₀ = F₀ n₀, e₀ = −d₀
    gauss[n:y0] = -problem.lambda0_factor
    unit = np.zeros((gauss.shape[0], 3 * n_man))
    j = 0
    for step in problem.steps:
        noise = np.zeros((gauss.shape[0], step.sigma_factor.shape[1]))
        noise[n:y0] = step.sigma_factor
        for block in (gauss, unit):                  # z ← diag(T, LT) z
            block[:n] = step.transition @ block[:n]
            block[n:y0] = step.LT @ block[n:y0]
        gauss = triangularize(np.hstack([gauss, noise]).T).T
        if step.correction is None:
            continue
        K = -step.correction.gain @ step.correction.B_target
        rows = slice(y0 + 3 * j, y0 + 3 * j + 3)
        for block in (gauss, unit):                  # Δv_j = K (d + e); d_v ← d_v + Δv_j
            block[rows] = K @ (block[:n] + block[n:y0])
            block[vel] += block[rows]
        cols = slice(3 * j, 3 * j + 3)               # d_v ← d_v + ε_j, e_v ← e_v − ε_j
        unit[vel, cols] += np.eye(3)
        unit[[n + v for v in vel], cols] -= np.eye(3)
        j += 1
    for block in (gauss, unit):                      # m = B_final d
        block[y0 + 3 * n_man:] = problem.B_final @ block[:n]
    F, C = triangularize(gauss[y0:].T).T, unit[y0:]
    return OutcomeMaps(F, C, problem.errors,
                       triangularize(F.T, problem.errors.sigma_fixed_km_s * C.T).T)


def block_normals(seed: int, block: int, n: int, n_normals: int) -> np.ndarray:
    """Return the (n, n_normals) standard normals of RNG block ``block`` (module docstring)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(block,)))
    return rng.standard_normal((n, n_normals))


def _apply(M: np.ndarray, x: np.ndarray, lower: bool = False) -> np.ndarray:
    """M x (r, n) for samples as columns x (c, n): column by column, an element-wise multiply
    and add each, in column order (module docstring); ``lower``: M is lower triangular and its
    zeros are skipped."""
    out = np.zeros((M.shape[0], x.shape[1]))
    term = np.empty_like(out)
    for j in range(M.shape[1]):
        rows = slice(j if lower else 0, None)
        np.multiply(M[rows, j, None], x[j], out=term[rows])
        out[rows] += term[rows]
    return out


def outcome_columns(maps: OutcomeMaps, normals: np.ndarray) -> np.ndarray:
    """Return the outcomes y (n_y, n) of samples given their normals as columns
    (``maps.n_normals``, n) (module docstring): rows Δv₁, …, Δv_M (3 each), then m.

    b = F_s u; in turn Δv_j = b_j + Σ_{i<j} C_ji p_i, p_j = p(Δv_j, h_j); m = b_m + C_m p.
    """
    n_y, n_man = maps.n_y, maps.n_man
    C = maps.error_map
    y = _apply(maps.sample_factor, normals[:n_y], lower=True)
    p = np.empty((3 * n_man, normals.shape[1]))
    col = n_y
    for j in range(n_man):
        rows = slice(3 * j, 3 * j + 3)
        y[rows] += _apply(C[rows, :3 * j], p[:3 * j])
        p[rows] = proportional_errors(y[rows], normals[col:col + NORMALS_PER_MANOEUVRE],
                                      maps.errors)
        col += NORMALS_PER_MANOEUVRE
    y[3 * n_man:] += _apply(C[3 * n_man:], p)
    return y


def propagate(maps: OutcomeMaps, normals: np.ndarray) -> Samples:
    """Return the outcomes of samples given their normals (n, ``maps.n_normals``), one a row:
    :func:`outcome_columns` of the transpose."""
    y = outcome_columns(maps, normals.T)
    n_dv = 3 * maps.n_man
    return Samples(np.ascontiguousarray(y[:n_dv].T).reshape(-1, maps.n_man, 3),
                   np.ascontiguousarray(y[n_dv:].T))


def simulate_blocks(maps: OutcomeMaps, seed: int, first_block: int, n_blocks: int,
                    n_samples: int, out: Samples | None = None) -> Samples:
    """Return the samples of RNG blocks first_block .. first_block + n_blocks − 1 of a run
    of ``n_samples`` samples (the last block of the run may be partial): one shard,
    :data:`CHUNK_BLOCKS` blocks at a time (module docstring).

    ``out``: the whole run's samples (``n_samples`` of them), whose rows of these blocks are
    written and returned (views) instead of new arrays: a serial run fills its result in
    place, with no copy to gather.
    """
    start = first_block * BLOCK_SAMPLES
    stop = min((first_block + n_blocks) * BLOCK_SAMPLES, n_samples)
    n_dv = 3 * maps.n_man
    if out is None:
        out = Samples(np.empty((stop - start, maps.n_man, 3)),
                      np.empty((stop - start, maps.n_y - n_dv)))
    else:
        out = Samples(out.dv_km_s[start:stop], out.miss[start:stop])
    for lo in range(start, stop, CHUNK_BLOCKS * BLOCK_SAMPLES):
        hi = min(lo + CHUNK_BLOCKS * BLOCK_SAMPLES, stop)
        normals = np.empty((maps.n_normals, hi - lo))
        for b_lo in range(lo, hi, BLOCK_SAMPLES):
            b_hi = min(b_lo + BLOCK_SAMPLES, hi)
            normals[:, b_lo - lo:b_hi - lo] = block_normals(
                seed, b_lo // BLOCK_SAMPLES, b_hi - b_lo, maps.n_normals).T
        y = outcome_columns(maps, normals)
        rows = slice(lo - start, hi - start)
        out.dv_km_s[rows] = y[:n_dv].T.reshape(-1, maps.n_man, 3)
        out.miss[rows] = y[n_dv:].T
    return out


__all__ = ["BLOCK_SAMPLES", "CHUNK_BLOCKS", "NORMALS_PER_MANOEUVRE", "OutcomeMaps", "Samples",
           "block_normals", "outcome_columns", "outcome_maps", "propagate", "simulate_blocks"]

"""TAPP II: Monte Carlo midcourse guidance from a T32 tape, beside its linear covariance.

The model
---------
Linear deviations about the nominal trajectory, in each recycle's representation
x^k = [orbit at t_k (x, y, z km; vx, vy, vz km/s, the tape's inertial frame); q] of the T32
tape (:mod:`tapp.io.tape.t32`). Per sample, d (n_o) is the true deviation and e = x̂ − x (n_o) the
error of the navigation's estimate.

1. Injection: d₀ ~ N(0, Λ̄⁰) (``apriori/Lambda0_real``); the a priori estimate is the
   nominal, so e₀ = −d₀.
2. At recycle k (tape order): d ← T_k d and

   .. math:: e \\leftarrow L_k (T_k e) + w_k, \\qquad w_k \\sim N(0, \\Sigma_k)

   independent of everything before, with T_k = ∂x^k/∂x^{k_prev} (``transition``), L_k the
   fit-world estimator's ∂(a posteriori error)/∂(a priori error) and Σ_k = Λ'J̃Λ' the real
   tracking noise mapped through the fit-world gain (``L``, ``Sigma``). Without manoeuvres,
   Cov(e) then follows TAPP III's recursion for the real-world covariance Λ̄',

   .. math:: \\bar\\Lambda'_k = L_k (T_k \\bar\\Lambda'_{k-1} T_k^T) L_k^T + \\Sigma_k

   (seed TAPP III eq. 2-46 in the representation of each recycle; it holds on the tapes
   ``tapp process`` writes to ~1e-11 of the magnitude of its terms, the accuracy of the
   orbit link's adjoint): so the fit-world estimator's real-world error, mis-modelling and
   consider parameters included, is what the samples carry.
3. At a manoeuvre recycle, after the update: the estimated targeted miss
   m̂ = B_t (d + e) (B_t: the rows of B_k = ∂m/∂x^k of the targeted components, e.g. B·T,
   B·R and optionally the flight time) is nulled through the velocity columns B_v of B_t:

   .. math:: \\Delta v = -G\\,\\hat m, \\qquad G = B_v^T (B_v B_v^T)^{-1}

   (minimum norm for 2 targets, the inverse for 3; a rank-deficient B_v is refused). The
   applied change is Δv + ε with ε the Gates-type execution error of
   :mod:`tapp.guidance.execution` (proportional magnitude σ_p, pointing σ_θ on the two axes
   perpendicular to Δv, fixed σ_f per axis); d_v ← d_v + Δv + ε, and since the navigation
   knows the commanded Δv only, e_v ← e_v − ε.
4. A recycle that is not a manoeuvre only updates the estimate. The final true miss after
   the last correction is m = B_last d, every miss component of the tape.

The tape's estimator never hears of a manoeuvre: its a priori after one claims a velocity
knowledge of fractions of a mm/s while e holds the execution error, so its later estimates
(and corrections) degrade. ``[navigation] after_manoeuvre = "inflate"`` in the guidance file
replaces L_k, Σ_k after the first manoeuvre by those of the same fit world whose a priori
holds the manoeuvre's execution-error covariance (:mod:`tapp.guidance.navigation`); the maps
stay linear and everything else is unchanged.

The Monte Carlo (:mod:`tapp.guidance.montecarlo`) draws in the space of the outcomes: the
state errors and the fixed execution errors reach the corrections and the miss through fixed
linear maps, so a sample draws their Gaussian image there (n_y = 3 per manoeuvre + the miss
components) and only the execution errors proportional to |Δv| step by step (3 normals a
manoeuvre), with the joint law of the whole-state model exactly; it draws the samples
in fixed RNG blocks and runs them in shards on Dask (:mod:`tapp.guidance.shards`),
reproducibly whatever the workers and shard size; the linear covariance
(:mod:`tapp.guidance.linear`) propagates the exact second moments of [d; e] through the same
maps; :mod:`tapp.guidance.statistics` turns both into ΔV and miss statistics, and
:mod:`tapp.guidance.agreement` sets the linear statistics that take a law as Gaussian (the
|Δv| statistics, the corridor fractions) against the samples of the same run, marking those
the samples contradict.

Public API
----------
:func:`guidance_study` runs a study on a T32 tape and a guidance file in memory and returns a
:class:`GuidanceResult` (:func:`tapp.pipeline.steps.run_guidance` runs one from their paths:
this package reads no tape file); :func:`tapp.report.guidance.guidance_markdown` renders it.
"""

from tapp.guidance.agreement import Agreement, Check, compare
from tapp.guidance.execution import ExecutionErrors, error_second_moment, sample_errors
from tapp.guidance.guidefile import GuideFile, Study, bind, read_guide
from tapp.guidance.linear import LinearCovariance, linear_covariance
from tapp.guidance.model import Problem, Step, build_problem
from tapp.guidance.montecarlo import (
    BLOCK_SAMPLES,
    OutcomeMaps,
    Samples,
    outcome_maps,
    propagate,
    simulate_blocks,
)
from tapp.guidance.shards import run_shards
from tapp.guidance.statistics import Corridor, Outcome, linear_outcome, sample_outcome
from tapp.guidance.study import GuidanceResult, guidance_study

__all__ = ["BLOCK_SAMPLES", "Agreement", "Check", "Corridor", "ExecutionErrors",
           "GuidanceResult", "GuideFile", "LinearCovariance", "Outcome", "OutcomeMaps",
           "Problem", "Samples", "Step", "Study", "bind", "build_problem", "compare",
           "error_second_moment", "guidance_study", "linear_covariance",
           "linear_outcome", "outcome_maps", "propagate", "read_guide", "run_shards",
           "sample_errors", "sample_outcome", "simulate_blocks"]

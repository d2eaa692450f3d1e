"""Limits with known answers: a perfect estimator (L_k = 0, Σ_k = 0: e ≡ 0 from the first
recycle on) and perfect execution leave no miss; execution errors alone leave
B_v E[εεᵀ] B_vᵀ."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.guidance.execution import error_second_moment
from tapp.guidance.guidefile import bind
from tapp.guidance.linear import linear_covariance
from tapp.guidance.montecarlo import outcome_maps, simulate_blocks
from tests.tapp.guidance.helpers import EXECUTION, deep_space_t32, guide, with_recycles

ALL = ["b_dot_r_km", "b_dot_t_km", "flight_time_s"]  # the tape's order of the miss
#: B_v G = I holds to ~1e-14 (the SVD of the row-scaled 3 x 3 B_v, condition ~30): the miss
#: left is the rounding of nulling a miss of ~1e4 km, below 1e-10 of it.
NULLED = 1e-10
#: Miss partials of two recycles mapped to one another (B_k T_k = B_{k-1}) by the tape's STMs:
#: the integrations agree to ~1e-10 relative.
INTEGRATION = 1e-8
#: Sample covariance entries, z-scores from their own sampling σ, 6 entries: |z| < 5.
COV_Z = 5.0
N = 40_000


@pytest.fixture(scope="module")
def perfect_tape():
    zeros = np.zeros_like(deep_space_t32().recycles[0].L)
    return with_recycles(deep_space_t32(), L=zeros, Sigma_factor=zeros)


def _problem(tape, targets, execution, recycles=(1,)):
    return bind(guide(targets={"miss": targets}, execution=execution,
                      manoeuvres={"recycles": list(recycles)}), tape, "guide.toml").problem


def test_a_perfect_estimator_and_perfect_execution_leave_no_miss(perfect_tape):
    problem = _problem(perfect_tape, ALL, {})
    bv = problem.steps[0].correction.B_target[:, 3:6]
    out = simulate_blocks(outcome_maps(problem), 5, 0, 2, 2000)
    nulled = np.abs(out.dv_km_s[:, 0] @ bv.T)  # the miss each correction removed
    assert np.all(np.abs(out.miss) < NULLED * nulled.max(axis=0))
    lin = linear_covariance(problem)
    removed = np.diag(bv @ lin.dv_cov[0] @ bv.T)
    # the covariance's nulling cancels terms of the removed variance: rounding of those
    assert np.all(np.abs(lin.miss_cov) < NULLED * np.outer(removed, removed) ** 0.5)


def test_two_targets_leave_only_the_untargeted_component(perfect_tape):
    problem = _problem(perfect_tape, ALL[:2], {}, recycles=(1, 3))
    out = simulate_blocks(outcome_maps(problem), 5, 0, 1, 1000)
    assert np.abs(out.miss[:, :2]).max() < NULLED * np.abs(out.miss[:, 2]).max()
    # the second correction sees the first one's miss again through B_3 T_3 T_2 = B_1, which
    # the tape's partials satisfy to the integrator's accuracy (~1e-10 relative)
    assert np.abs(out.dv_km_s[:, 1]).max() < INTEGRATION * np.abs(out.dv_km_s[:, 0]).max()


def test_execution_errors_alone_give_the_analytic_miss_covariance(perfect_tape):
    problem = _problem(perfect_tape, ALL, EXECUTION)
    step = problem.steps[0]
    c = step.correction
    bv = c.B_target[:, 3:6]
    # Δv = −G B_t T₁ d₀ (e ≡ 0 after the update), d₀ ~ N(0, Λ̄⁰)
    gbt = c.gain @ c.B_target @ step.transition
    P = gbt @ problem.Lambda0 @ gbt.T
    want = bv @ error_second_moment(P, problem.errors) @ bv.T
    lin = linear_covariance(problem)
    np.testing.assert_allclose(lin.dv_cov[0], P, rtol=1e-9, atol=1e-9 * np.abs(P).max())
    d = np.sqrt(np.diag(want))
    assert np.max(np.abs(lin.miss_cov - want) / np.outer(d, d)) < 1e-8
    samples = simulate_blocks(outcome_maps(problem), 17, 0, N // 1000, N).miss
    prod = samples[:, :, None] * samples[:, None, :]
    z = (prod.mean(axis=0) - want) / (prod.std(axis=0) / np.sqrt(N))
    assert np.all(np.abs(z) < COV_Z), z
    # a rotated error model would not pass: the pointing part alone is far off
    assert np.max(np.abs(prod.mean(axis=0) - bv @ (0.01 ** 2 * P) @ bv.T)
                  / (prod.std(axis=0) / np.sqrt(N))) > 10 * COV_Z


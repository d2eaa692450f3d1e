"""The recursion TAPP II relies on, checked on a real tape, and the guidance problem built from
it: the gain, the refusals, and the linear covariance without manoeuvres."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.guidance.execution import ExecutionErrors
from tapp.guidance.linear import linear_covariance
from tapp.guidance.model import build_problem
from tests.tapp.guidance.helpers import deep_space_t32, with_recycles

#: The tape's T_k and L_k are formed with the orbit link's adjoint (the symplectic inverse of
#: the STM), exact only to the integrator's symplecticity: the recursion closes to ~2e-12 of
#: the magnitude |L||TΛ̄Tᵀ||L|ᵀ + |Σ| of its terms on this tape (their sum is up to 1e4 times
#: smaller than the terms: the data remove most of the a priori error).
ADJOINT = 1e-10
#: Cov(e) of the linear covariance (the tape's L_k as a matrix, acting on a factor of the
#: mapped a priori) against the tape's Λ̄'_3, on its scale: the 1e-12 rounding of those terms
#: times their ratio to the result, up to 1e3; measured 8.4e-10.
RECURSION = 1e-8
#: Products of matrices whose terms cancel as above: the same bound, relative to the terms.
TERMS = ADJOINT
BT = ("b_dot_t_km", "b_dot_r_km")
NONE = ExecutionErrors()


def _relative_to_terms(got: np.ndarray, want: np.ndarray, magnitude: np.ndarray) -> float:
    """Largest |got − want| relative to the terms plus 1e-6 of √(want_ii want_jj): where the
    terms vanish (the consider parameters GM_moon and Cr, which nothing correlates) the entry
    is rounding, ~1e-17 of that scale, so these are held to 1e-16 of it."""
    scale = np.sqrt(np.abs(np.outer(np.diag(want), np.diag(want))))
    return float(np.max(np.abs(got - want) / (magnitude + 1e-6 * scale)))


def test_the_real_world_covariance_follows_the_recursion_the_samples_use():
    """Λ̄'_k = L_k (T_k Λ̄'_{k−1} T_kᵀ) L_kᵀ + Σ_k, Λ̄'_0 = Λ̄⁰, all in the tape's x^k."""
    t32 = deep_space_t32()
    prev = t32.Lambda0_real
    for rc in t32.recycles:
        mapped = rc.transition @ prev @ rc.transition.T
        got = rc.L @ mapped @ rc.L.T + rc.Sigma
        magnitude = np.abs(rc.L) @ np.abs(mapped) @ np.abs(rc.L).T + np.abs(rc.Sigma)
        assert _relative_to_terms(got, rc.Lambda_real, magnitude) < ADJOINT, rc.number
        # the noise term matters: without it the recursion is far off
        assert _relative_to_terms(got - rc.Sigma, rc.Lambda_real, magnitude) > 1e3 * ADJOINT
        prev = rc.Lambda_real


def test_without_manoeuvres_the_estimate_error_has_the_tapes_covariance():
    t32 = deep_space_t32()
    problem = build_problem(t32, BT, (3,), NONE)
    n = problem.n_o
    last = t32.recycles[-1]
    scale = np.sqrt(np.outer(np.diag(last.Lambda_real), np.diag(last.Lambda_real)))
    steps = tuple(dataclasses.replace(s, correction=None) for s in problem.steps)
    Z = linear_covariance(dataclasses.replace(problem, steps=steps)).Z
    # Cov(e) = Λ̄'_3 through the tape's own Σ_k factors (no positive part to take: Σ_k is a
    # Gram matrix on the tape)
    assert np.max(np.abs(Z[n:, n:] - last.Lambda_real) / scale) < RECURSION
    phi = np.eye(n)
    for rc in t32.recycles:
        phi = rc.transition @ phi
    cov_d = phi @ t32.Lambda0_real @ phi.T
    d_scale = np.sqrt(np.outer(np.diag(cov_d), np.diag(cov_d)))
    assert np.max(np.abs(Z[:n, :n] - cov_d) / d_scale) < TERMS
    np.testing.assert_array_equal(Z[:n, n:], Z[n:, :n].T)


def test_the_gain_nulls_the_targeted_miss_with_the_smallest_velocity_change():
    t32 = deep_space_t32()
    for targets in (BT, ("b_dot_t_km", "b_dot_r_km", "flight_time_s")):
        problem = build_problem(t32, targets, (1, 2, 3), NONE)
        for step in problem.manoeuvres:
            c = step.correction
            bv = c.B_target[:, list(problem.velocity)]
            np.testing.assert_allclose(bv @ c.gain, np.eye(len(targets)), atol=1e-12)
            np.testing.assert_allclose(c.gain, np.linalg.pinv(bv), rtol=1e-9,
                                       atol=1e-9 * np.abs(c.gain).max())


def test_the_problem_draws_from_the_tapes_own_factors():
    """Λ̄⁰ and every Σ_k are the Gram matrices of the T32 factors, exactly as stored: nothing
    to clip (the normal-matrix T32 had Σ_k indefinite to 2e-4 of its scale)."""
    t32 = deep_space_t32()
    problem = build_problem(t32, BT, (3,), NONE)
    np.testing.assert_array_equal(problem.lambda0_factor, t32.Lambda0_real_factor.T)
    for step, rc in zip(problem.steps, t32.recycles, strict=True):
        np.testing.assert_array_equal(step.sigma_factor, rc.Sigma_factor.T)
        assert np.all(np.linalg.eigvalsh(step.Sigma) > -1e-13 * np.max(np.diag(step.Sigma)))
    assert problem.lambda0_factor[7].any()  # GM_moon, the consider parameter


def test_an_orbit_that_is_not_cartesian_is_refused():
    t32 = deep_space_t32()
    par = t32.parameters
    units = ("km", "", "rad", "rad", "rad", "rad", *par.unit[6:])
    bad = dataclasses.replace(t32, parameters=dataclasses.replace(par, unit=units))
    with pytest.raises(InputError, match=r"^run.t32.h5: parameters/unit: expected a Cartesian"):
        build_problem(bad, BT, (1,), NONE, tape_source="run.t32.h5")


def test_targets_the_velocity_cannot_control_are_refused():
    def dependent(rc):
        b = rc.B.copy()
        b[1] = 2.0 * b[0]  # B·R moves only as B·T does
        return b

    bad = with_recycles(deep_space_t32(), B=dependent)
    with pytest.raises(InputError, match=r"guide.toml: targets.miss: expected miss components "
                                         r"that the velocity at recycle 2 controls"):
        build_problem(bad, BT, (2,), NONE, guide_source="guide.toml")


@pytest.mark.parametrize(("targets", "manoeuvres", "field"), [
    (("b_dot_t_km", "c3_km2_s2"), (1,), r"targets.miss\[1\]: expected a miss component"),
    (BT, (1, 4), r"manoeuvres.recycles\[1\]: expected a recycle number of the tape \(1..3\)"),
])
def test_names_and_recycles_not_on_the_tape_are_refused(targets, manoeuvres, field):
    with pytest.raises(InputError, match="^guide.toml: " + field):
        build_problem(deep_space_t32(), targets, manoeuvres, NONE, guide_source="guide.toml")

"""The recursion TAPP II relies on, checked on a real tape, and the guidance problem built from
it: the gain, the refusals, and the linear covariance without manoeuvres."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.guidance.execution import ExecutionErrors
from tapp.guidance.linear import linear_covariance
from tapp.guidance.model import build_problem, psd_factor
from tests.tapp.guidance.helpers import deep_space_t32, with_recycles

#: The tape's T_k and L_k are formed with the orbit link's adjoint (the symplectic inverse of
#: the STM), exact only to the integrator's symplecticity: the recursion closes to ~4e-12 of
#: the magnitude |L||TΛ̄Tᵀ||L|ᵀ + |Σ| of its terms on this tape (their sum is up to 1e4 times
#: smaller than the terms: the data remove most of the a priori error).
ADJOINT = 1e-10
#: Products of matrices whose terms cancel as above: the same bound, relative to the terms.
TERMS = ADJOINT
BT = ("b_dot_t_km", "b_dot_r_km")
NONE = ExecutionErrors()


def _relative_to_terms(got: np.ndarray, want: np.ndarray, magnitude: np.ndarray) -> float:
    return float(np.max(np.abs(got - want) / magnitude))


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

    def drift(sigma):  # no manoeuvre; Σ_k as given
        steps = tuple(dataclasses.replace(s, correction=None, Sigma=sigma(s, rc))
                      for s, rc in zip(problem.steps, t32.recycles, strict=True))
        return linear_covariance(dataclasses.replace(problem, steps=steps)).Z

    # with the tape's Σ_k: Cov(e) = Λ̄'_3, to the recursion's closure over three recycles
    # (1e-10 of the terms, which are up to 1e4 times the result)
    Z = drift(lambda s, rc: rc.Sigma)
    assert np.max(np.abs(Z[n:, n:] - last.Lambda_real) / scale) < 1e-6
    phi = np.eye(n)
    for rc in t32.recycles:
        phi = rc.transition @ phi
    cov_d = phi @ t32.Lambda0_real @ phi.T
    d_scale = np.sqrt(np.outer(np.diag(cov_d), np.diag(cov_d)))
    assert np.max(np.abs(Z[:n, :n] - cov_d) / d_scale) < TERMS
    np.testing.assert_array_equal(Z[:n, n:], Z[n:, :n].T)
    # the samples' Σ_k, the PSD part of the tape's (PSD only to 8e-5 of its scale), moves
    # Λ̄'_3 by up to 1 % (a station bias variance): TAPP III's rounding, not the model
    Z = drift(lambda s, rc: s.Sigma)
    assert np.max(np.abs(Z[n:, n:] - last.Lambda_real) / scale) < 0.02


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


def test_the_factor_of_a_covariance_reproduces_its_positive_semi_definite_part():
    t32 = deep_space_t32()
    for c in (t32.Lambda0_real, *(rc.Sigma for rc in t32.recycles)):
        f = psd_factor(c)
        d = np.sqrt(np.diag(c))
        d[d == 0] = 1.0
        w, v = np.linalg.eigh(c / np.outer(d, d))
        negative = float(max(-w.min(), 0.0))  # what the factor leaves out, scaled
        # F Fᵀ = C to rounding (1e-13 of the scale) where C is PSD; otherwise it differs by
        # the negative eigenvalues dropped
        err = np.max(np.abs(f @ f.T - c) / np.outer(d, d))
        assert err <= negative + 1e-13
        assert np.all(np.linalg.eigvalsh(f @ f.T / np.outer(d, d)) > -1e-13)
    assert psd_factor(t32.Lambda0_real)[7].any()  # GM_moon, the consider parameter


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

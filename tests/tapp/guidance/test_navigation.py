"""The navigation that knows its manoeuvres (tapp.guidance.navigation): its regression gives
back the tape's estimator when nothing is added, and a later correction then improves the
miss where the tape's estimator makes it worse."""

from __future__ import annotations

import numpy as np

from tapp.estimation.regression import regression
from tapp.guidance.guidefile import bind
from tapp.guidance.linear import linear_covariance
from tapp.guidance.navigation import add_velocity_noise, fit_system
from tests.tapp.guidance.helpers import deep_space_t32, guide

#: The navigation's regression re-runs TAPP III's on the tape's factors, in the recycle's
#: representation x^k (the a priori S'_{k−1} mapped by the tape's adjoint transition), where
#: TAPP III ran it at the program epoch and mapped the results: the same numbers through
#: another representation, whose one-day transitions have condition numbers of 1e6 to 1e8.
#: Λ'_k on its scale: measured 2.6e-10 (the normal-matrix tape: 5e-6).
FIT_COVARIANCE = 1e-8
#: L_k acting on 1σ a priori errors, relative to the a posteriori σ: the same, times the ratio
#: of the a priori to the a posteriori σ's (up to 1e3); measured 2.9e-8 (before: 1.7e-4).
ESTIMATOR = 1e-6
#: Σ_k on its scale: measured 2.5e-9 (before: 9e-6, and the tape's own Σ_k was off its
#: definition by 1e-3 to 1e-2).
NOISE_COVARIANCE = 1e-7
#: The miss covariance of the two navigations without execution errors, on its scale: the
#: differences above carried through three corrections; measured 6.9e-10 (before: 2.1e-2 on
#: an AVX-512 machine, 3.5e-3 elsewhere).
SAME_NAVIGATION = 1e-8


def _scaled(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.abs(np.diag(b)))
    d[d == 0] = 1.0
    return float(np.max(np.abs(a - b) / np.outer(d, d)))


def test_without_a_manoeuvre_the_regression_gives_back_the_tapes_estimator():
    t32 = deep_space_t32()
    fit = fit_system(t32)
    assert np.allclose(fit.D @ fit.E, np.eye(fit.D.shape[0]), rtol=0, atol=1e-15)
    for prev, rc in zip(t32.recycles[:-1], t32.recycles[1:], strict=True):
        r = regression(fit, prev.S_fit_factor @ rc.transition_adjoint.T, rc.J_factor,
                       Rt=rc.Jt_factor)
        assert _scaled(r.Lambda1_00, rc.Lambda_fit) < FIT_COVARIANCE
        # L acting on a priori errors of 1σ: the same a posteriori errors, relative to σ'
        d0 = np.sqrt(np.diag(rc.transition @ prev.Lambda_real @ rc.transition.T))
        d1 = np.sqrt(np.diag(rc.Lambda_real))
        assert np.max(np.abs((r.L - rc.L) * d0[None, :]) / d1[:, None]) < ESTIMATOR
        assert _scaled(r.Sigma, rc.Sigma) < NOISE_COVARIANCE


def test_added_velocity_noise_is_the_covariance_added_in_information_form():
    """R⁺ from the square-root process-noise step against (S⁻¹ + S_v H Hᵀ S_vᵀ)⁻¹ formed
    directly, on an invertible information matrix."""
    rng = np.random.default_rng(3)
    n = 8
    r = rng.standard_normal((n, n)) + 4 * np.eye(n)
    h = rng.standard_normal((3, 3)) * 0.1
    velocity = (3, 4, 5)
    s_v = np.zeros((n, 3))
    s_v[list(velocity), [0, 1, 2]] = 1.0
    plus = add_velocity_noise(r, velocity, h)
    want = np.linalg.inv(np.linalg.inv(r.T @ r) + s_v @ h @ h.T @ s_v.T)
    assert _scaled(plus.T @ plus, want) < 1e-12
    assert np.array_equal(plus, np.triu(plus))


def _bplane_sigma(navigation: str, recycles: list[int]) -> np.ndarray:
    study = bind(guide(navigation={"after_manoeuvre": navigation},
                       manoeuvres={"recycles": recycles}), deep_space_t32(), "guide.toml")
    cov = linear_covariance(study.problem).miss_cov
    return np.sqrt(np.diag(cov)[:2])


def test_later_corrections_help_when_the_navigation_knows_its_manoeuvres():
    first = _bplane_sigma("tape", [1])  # ~440 x 210 km: the first correction's errors
    assert np.allclose(first, _bplane_sigma("inflate", [1]))  # nothing to re-form
    informed = _bplane_sigma("inflate", [1, 2, 3])
    assert np.all(informed < 0.1 * first)
    # the tape's estimator after a manoeuvre: its a priori claims 1e4 times better velocity
    # knowledge than it has; the later corrections make the miss worse, not better
    assert np.all(_bplane_sigma("tape", [1, 2, 3]) > 3 * first)


def test_without_execution_errors_both_navigations_agree():
    a = bind(guide(execution={}, navigation={"after_manoeuvre": "inflate"}), deep_space_t32(),
             "guide.toml").problem
    b = bind(guide(execution={}), deep_space_t32(), "guide.toml").problem
    ca, cb = linear_covariance(a), linear_covariance(b)
    assert _scaled(ca.miss_cov, cb.miss_cov) < SAME_NAVIGATION

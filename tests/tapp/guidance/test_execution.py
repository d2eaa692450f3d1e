"""The Gates-type execution errors: their conditional structure and second moment."""

from __future__ import annotations

import numpy as np

from tapp.dynamics.gates import GatesErrors
from tapp.guidance.execution import (
    NORMALS_PER_MANOEUVRE,
    ExecutionErrors,
    error_second_moment,
    proportional_errors,
    sample_errors,
)

ERRORS = ExecutionErrors(0.05, 0.02, 3e-4)
N = 200_000
#: Sample covariance entries against the formula: z-scores from each entry's own sampling σ
#: (the sample variance of the products / N); |z| < 5 over 6 + 6 entries: family-wise false
#: alarm below 1e-5.
Z_LIMIT = 5.0


def _z(samples: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """z-scores of the zero-mean second moments of samples (n, 3) against cov."""
    prod = samples[:, :, None] * samples[:, None, :]
    return (prod.mean(axis=0) - cov) / (prod.std(axis=0) / np.sqrt(samples.shape[0]))


def test_a_fixed_correction_gets_magnitude_error_along_and_pointing_error_across():
    rng = np.random.default_rng(11)
    dv = np.array([3e-3, -4e-3, 0.0])  # 5 m/s
    eps = sample_errors(np.tile(dv, (N, 1)), rng.standard_normal((N, NORMALS_PER_MANOEUVRE)),
                        ERRORS)
    u = dv / np.linalg.norm(dv)
    p1 = np.array([0.8, 0.6, 0.0])
    basis = np.array([u, p1, np.cross(u, p1)])  # along, across, across
    mag = np.linalg.norm(dv)
    want = (np.diag([(ERRORS.sigma_proportional * mag) ** 2,
                     (ERRORS.sigma_pointing_rad * mag) ** 2,
                     (ERRORS.sigma_pointing_rad * mag) ** 2])
            + ERRORS.sigma_fixed_km_s ** 2 * np.eye(3))
    assert np.all(np.abs(_z(eps @ basis.T, want)) < Z_LIMIT)


def test_over_gaussian_corrections_the_second_moment_is_the_formula():
    rng = np.random.default_rng(12)
    P = np.array([[4.0, 1.0, 0.5], [1.0, 2.0, -0.3], [0.5, -0.3, 1.0]]) * 1e-6
    dv = rng.standard_normal((N, 3)) @ np.linalg.cholesky(P).T
    eps = sample_errors(dv, rng.standard_normal((N, NORMALS_PER_MANOEUVRE)), ERRORS)
    assert np.all(np.abs(_z(eps, error_second_moment(P, ERRORS))) < Z_LIMIT)
    # and it is uncorrelated with the correction it scales with
    cross = (dv[:, :, None] * eps[:, None, :])
    z = cross.mean(axis=0) / (cross.std(axis=0) / np.sqrt(N))
    assert np.all(np.abs(z) < Z_LIMIT)


def test_a_zero_correction_gets_the_fixed_error_only():
    normals = np.ones((2, NORMALS_PER_MANOEUVRE))
    eps = sample_errors(np.zeros((2, 3)), normals, ERRORS)
    np.testing.assert_array_equal(eps, np.full((2, 3), ERRORS.sigma_fixed_km_s))


def test_the_proportional_part_has_gates_law_given_the_correction():
    """Given Δv, TAPP II's Monte Carlo draws the proportional part from 3 normals
    (tapp.guidance.montecarlo): its covariance must be the shared kernel's E[εεᵀ | Δv] with
    the fixed σ's zero (GatesErrors.covariance, G diag(σ²) Gᵀ), for Δv along no axis and
    along one, and it must vanish for Δv = 0."""
    rng = np.random.default_rng(14)
    without_fixed = GatesErrors(ERRORS.sigma_proportional, 0.0, ERRORS.sigma_pointing_rad, 0.0)
    for dv in (np.array([3e-3, -4e-3, 1e-3]), np.array([0.0, 0.0, 2e-3])):
        p = proportional_errors(np.tile(dv, (N, 1)).T, rng.standard_normal((3, N)), ERRORS).T
        assert np.all(np.abs(_z(p, without_fixed.covariance(dv))) < Z_LIMIT)
    assert not np.any(proportional_errors(np.zeros((3, 4)), np.ones((3, 4)), ERRORS))

"""Gates' execution-error model: the linear partials against the physical model they
linearise, the triad, the conditional covariance and the second moment by sampling."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.dynamics.gates import (
    NORMALS_PER_SAMPLE,
    GatesErrors,
    GatesRangeError,
    gates_partials,
    pointing_axes,
)
from tests.tapp.dynamics.burn_reference import executed

#: 5 m/s with all four sources, σ₂ ≠ σ₄ (the general case TAPP I flies).
ERRORS = GatesErrors(0.02, 2e-6, 0.01, 5e-6)
DV = np.array([[3e-3, -4e-3, 0.0], [0.0, 0.0, 2e-3], [1e-3, 1e-3, 1e-3], [-1e-4, 0.0, 0.0]])
#: Central differences of the physical model below, step 1e-6 in q (relative to |Δv| for the
#: km/s ones): truncation ~ h² ~ 1e-12 relative, rounding ~ 1e-16/1e-6 = 1e-10 (measured 9.3e-11).
FD_TOL = 1e-8
N = 200_000
#: |z| of the 6 + 6 sample moments below 5: family-wise false alarm below 1e-5.
Z_LIMIT = 5.0


@pytest.mark.parametrize("dv", DV)
def test_the_partials_are_the_derivative_of_the_executed_manoeuvre(dv):
    g = gates_partials(dv)
    scale = np.array([1.0, np.linalg.norm(dv), 1.0, 1.0, np.linalg.norm(dv), np.linalg.norm(dv)])
    for i in range(6):
        h = 1e-6 * scale[i]
        e = np.zeros(6)
        e[i] = h
        fd = (executed(dv, e) - executed(dv, -e)) / (2 * h)
        assert np.max(np.abs(fd - g[:, i])) <= FD_TOL * np.max(np.abs(g[:, i])), i


def test_a_sample_is_the_partials_times_the_scaled_projections():
    """ε = G (σ ⊙ ξ), ξ = (n, û·f, ê₁·g, ê₂·g, ê₁·f, ê₂·f) on the triad, formed here, against
    the sampler's closed form without the triad: to rounding (1e-15 of |ε|), Δv = 0 too."""
    rng = np.random.default_rng(5)
    dv = np.concatenate([DV, rng.standard_normal((20, 3)) * 1e-3, np.zeros((1, 3))])
    normals = rng.standard_normal((dv.shape[0], NORMALS_PER_SAMPLE))
    u, e1, e2 = pointing_axes(dv)
    g, f = normals[:, 1:4], normals[:, 4:7]
    xi = np.stack([normals[:, 0], *(np.sum(a * b, axis=-1) for a, b in
                                    ((u, f), (e1, g), (e2, g), (e1, f), (e2, f)))], axis=-1)
    expected = np.einsum("sij,sj->si", gates_partials(dv), xi * ERRORS.sigmas)
    got = ERRORS.sample(dv, normals)
    scale = np.linalg.norm(expected, axis=-1, keepdims=True)
    assert np.all(np.abs(got - expected) <= 1e-15 * scale)


def test_the_triad_is_right_handed_and_orthonormal_and_exact_on_the_axes():
    rng = np.random.default_rng(3)
    dv = np.concatenate([rng.standard_normal((50, 3)), np.eye(3), -np.eye(3)])
    u, e1, e2 = pointing_axes(dv)
    frame = np.stack([u, e1, e2], axis=-2)
    np.testing.assert_allclose(frame @ np.swapaxes(frame, -1, -2),
                               np.broadcast_to(np.eye(3), frame.shape), atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(frame), 1.0, atol=1e-15)
    np.testing.assert_array_equal(pointing_axes(np.array([2.0, 0, 0]))[1:], [[0, 1, 0], [0, 0, 1]])
    np.testing.assert_array_equal(pointing_axes(np.zeros(3))[0], [1, 0, 0])


def test_samples_have_the_conditional_covariance_of_the_four_sources():
    rng = np.random.default_rng(5)
    dv = DV[0]
    eps = ERRORS.sample(np.tile(dv, (N, 1)), rng.standard_normal((N, NORMALS_PER_SAMPLE)))
    u, e1, e2 = pointing_axes(dv)
    m = np.linalg.norm(dv)
    s1, s2, s3, s4 = 0.02, 2e-6, 0.01, 5e-6
    # in (û, ê₁, ê₂): diag(σ₁²m² + σ₂², σ₃²m² + σ₄², σ₃²m² + σ₄²), Gates' Table 1 form
    want = np.diag([(s1 * m) ** 2 + s2**2, (s3 * m) ** 2 + s4**2, (s3 * m) ** 2 + s4**2])
    local = eps @ np.array([u, e1, e2]).T
    prod = local[:, :, None] * local[:, None, :]
    z = (prod.mean(axis=0) - want) / (prod.std(axis=0) / np.sqrt(N))
    assert np.all(np.abs(z) < Z_LIMIT), z
    np.testing.assert_allclose(ERRORS.covariance(dv), np.array([u, e1, e2]).T @ want
                               @ np.array([u, e1, e2]), rtol=0, atol=1e-13 * want.max())


def test_the_second_moment_needs_equal_fixed_sigmas():
    with pytest.raises(ValueError, match="equal fixed magnitude and pointing"):
        ERRORS.second_moment(np.eye(3))
    equal = GatesErrors(0.02, 3e-6, 0.01, 3e-6)
    rng = np.random.default_rng(7)
    P = np.array([[4.0, 1.0, 0.5], [1.0, 2.0, -0.3], [0.5, -0.3, 1.0]]) * 1e-6
    dv = rng.standard_normal((N, 3)) @ np.linalg.cholesky(P).T
    eps = equal.sample(dv, rng.standard_normal((N, NORMALS_PER_SAMPLE)))
    prod = eps[:, :, None] * eps[:, None, :]
    z = (prod.mean(axis=0) - equal.second_moment(P)) / (prod.std(axis=0) / np.sqrt(N))
    assert np.all(np.abs(z) < Z_LIMIT), z


@pytest.mark.parametrize(("field", "value"), [
    ("sigma_magnitude_proportional", 1.0), ("sigma_magnitude_fixed_km_s", -1e-6),
    ("sigma_pointing_proportional_rad", 0.3), ("sigma_pointing_fixed_km_s", float("nan"))])
def test_a_sigma_out_of_range_names_its_field(field, value):
    with pytest.raises(GatesRangeError, match=field):
        GatesErrors(**{field: value})

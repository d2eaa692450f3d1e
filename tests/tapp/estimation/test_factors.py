"""The factor algebra: QR stacking, Gram products, factors of given matrices, the AR(1)
whitening, the twice-precision products and inverse, and the growth of a map, each against
an independent computation."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from tapp.errors import SingularMatrixError
from tapp.estimation.factors import (
    accurate_inverse,
    accurate_map,
    accurate_matmul,
    ar1_whitened,
    digits_held,
    gram,
    map_growth,
    product_unit,
    psd_factor,
    triangularize,
)

#: Rounding of a QR or product of well-conditioned matrices of order 10, relative.
TIGHT = 1e-13


def _scaled(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.abs(np.diag(b)))
    d[d == 0] = 1.0
    return float(np.max(np.abs(a - b) / np.outer(d, d)))


def test_triangularize_stacks_the_gram_matrices_and_is_upper_with_a_positive_diagonal():
    rng = np.random.default_rng(1)
    blocks = [rng.standard_normal((m, 6)) * np.logspace(-6, 6, 6) for m in (1, 4, 9)]
    r = triangularize(*blocks)
    assert r.shape == (6, 6) and np.array_equal(r, np.triu(r))
    assert np.all(np.diagonal(r) >= 0)
    assert _scaled(gram(r), sum(gram(b) for b in blocks)) < TIGHT


def test_fewer_rows_than_columns_give_zero_rows_and_nothing_gives_zeros():
    r = triangularize(np.array([[3.0, 4.0, 0.0]]))
    np.testing.assert_allclose(r, [[3.0, 4.0, 0.0], [0, 0, 0], [0, 0, 0]])
    assert np.array_equal(triangularize(np.zeros((0, 4))), np.zeros((4, 4)))
    assert np.array_equal(triangularize(n=2), np.zeros((2, 2)))
    with pytest.raises(ValueError):
        triangularize()


def test_gram_of_two_maps_is_the_product_and_of_one_is_exactly_symmetric():
    rng = np.random.default_rng(2)
    k, x, y = (rng.standard_normal(s) for s in ((7, 5), (3, 5), (4, 5)))
    np.testing.assert_allclose(gram(k, x, y), x @ k.T @ k @ y.T, rtol=1e-12)
    g = gram(k, x)
    assert np.array_equal(g, g.T) and np.all(np.diag(g) >= 0)


@pytest.mark.parametrize("case", ["definite", "semi-definite", "zero variance"])
def test_psd_factor_reproduces_a_given_matrix_of_mixed_units(case):
    rng = np.random.default_rng(3)
    scale = np.logspace(-8, 4, 5)
    a = rng.standard_normal((5, 5 if case == "definite" else 3)) * scale[:, None]
    m = a @ a.T
    if case == "zero variance":
        m[2, :] = m[:, 2] = 0.0
    k = psd_factor(m)
    assert np.array_equal(k, np.triu(k)) and np.all(np.diagonal(k) >= 0)
    assert _scaled(gram(k), m) < 1e-12
    if case == "zero variance":
        assert np.all(k[:, 2] == 0)


def test_the_ar1_recursion_is_the_cholesky_factor_of_the_exponential_kernel():
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(5.0, 60.0, 30))
    b = rng.standard_normal((30, 4))
    kernel = np.exp(-np.abs(t[:, None] - t[None, :]) / 90.0)
    want = np.linalg.cholesky(kernel).T @ b
    np.testing.assert_allclose(ar1_whitened(b, t, 90.0), want, rtol=1e-12,
                               atol=1e-12 * np.abs(want).max())
    assert ar1_whitened(np.zeros((0, 4)), np.zeros(0), 90.0).shape == (0, 4)


def _exact(a, b, c=None) -> np.ndarray:
    with mpmath.workdps(60):
        m = mpmath.matrix(a.tolist()) * mpmath.matrix(b.tolist())
        if c is not None:
            m += mpmath.matrix(c.tolist())
        return np.array(m.tolist(), dtype=float)


def test_accurate_matmul_is_the_correctly_rounded_product_where_the_plain_one_is_not():
    """Terms that cancel to 1e-12 of their size: the plain product keeps ~4 digits, Dot2 all
    (rounded once from twice the precision: within 1 ulp)."""
    rng = np.random.default_rng(5)
    a = rng.standard_normal((6, 8))
    b = rng.standard_normal((8, 5))
    c = -(a @ b) + 1e-12 * rng.standard_normal((6, 5))  # the sum cancels
    want = _exact(a, b, c)
    got = accurate_matmul(a, b, c)
    assert np.all(np.abs(got - want) <= 2 * np.spacing(np.abs(want)))
    assert np.max(np.abs((a @ b + c) - want) / np.abs(want)) > 1e-6
    hi, lo = accurate_matmul(a, b, c, split=True)
    assert np.array_equal(hi, got) and np.max(np.abs(lo)) <= np.max(np.spacing(np.abs(hi)))


def test_accurate_map_uses_the_identity_parts_and_the_remainder():
    rng = np.random.default_rng(6)
    n, p = 9, 3
    x = np.eye(n)
    x[:p, :p] = rng.standard_normal((p, p)) * 1e4
    x[p:, :p] = rng.standard_normal((n - p, p)) * 1e4
    lo = np.zeros((n, n))
    lo[p:, :p] = 1e-13 * rng.standard_normal((n - p, p))
    k = rng.standard_normal((5, n))
    with mpmath.workdps(60):
        xm = mpmath.matrix(x.tolist()) + mpmath.matrix(lo.tolist())
        want = np.array((mpmath.matrix(k.tolist()) * xm.T).tolist(), dtype=float)
    got = accurate_map(k, x, lo)
    assert np.all(np.abs(got - want) <= 2 * np.spacing(np.abs(want)))
    np.testing.assert_array_equal(accurate_map(k, np.eye(n)), k)
    np.testing.assert_array_equal(accurate_map(k, x[:2]), accurate_matmul(k, x[:2].T))


def test_digits_held_is_capped_by_the_working_precision():
    assert digits_held(1e-9) == pytest.approx(9.0)
    assert digits_held(0.0) == pytest.approx(-math.log10(np.finfo(float).eps))
    assert digits_held(5.0) == 0.0


#: A double-double rounded twice from the exact value: within 2 ulps of ulps, relative
#: (ε² = 4.9e-32; the remainder's own rounding is half an ulp of an ulp).
DOUBLE_DOUBLE = 2.0 * np.finfo(float).eps ** 2


def _ill_conditioned_block(rng: np.random.Generator) -> np.ndarray:
    """A 6 x 6 matrix of condition ~1e13 with rows scaled from 1e-3 to 1e3 (a transition's
    orbit block after a swing-by has cond 4.5e13 and entries up to 4.7e6)."""
    u, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    v, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    return np.logspace(-3, 3, 6)[:, None] * (u @ np.diag(np.logspace(4, -4, 6)) @ v.T)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_accurate_inverse_is_the_exact_inverse_rounded_to_a_double_double(seed):
    """Against mpmath at 80 digits (the inverse of the rounded matrix, taken as exact): hi is
    the correctly rounded inverse and hi + lo holds it to ε² of each entry; the correctly
    rounded inverse alone leaves |A hi − I| of ε cond A, the double-double ~ε² cond A."""
    a = _ill_conditioned_block(np.random.default_rng(seed))
    assert np.linalg.cond(a) > 1e11
    hi, lo = accurate_inverse(a)
    with mpmath.workdps(80):
        exact = mpmath.inverse(mpmath.matrix(a.tolist()))
        err = max(float(abs(exact[i, j] - mpmath.mpf(hi[i, j]) - mpmath.mpf(lo[i, j])
                            ) / abs(exact[i, j])) for i in range(6) for j in range(6))
        assert all(hi[i, j] == float(exact[i, j]) for i in range(6) for j in range(6))
    assert err <= DOUBLE_DOUBLE
    eye = np.eye(6)
    residual_hi = np.max(np.abs(accurate_matmul(a, hi, -eye)))
    residual_dd = np.max(np.abs(accurate_matmul(np.hstack([a, a]), np.vstack([hi, lo]), -eye)))
    assert residual_hi > 1e-6 and residual_dd < 1e-14


def test_accurate_inverse_of_exact_cases_and_a_singular_matrix():
    hi, lo = accurate_inverse(np.diag([4.0, -0.5, 1e300]))
    np.testing.assert_array_equal(hi, np.diag([0.25, -2.0, 1e-300]))
    assert not np.any(lo[[0, 1], [0, 1]])
    with pytest.raises(SingularMatrixError, match="singular"):
        accurate_inverse(np.array([[1.0, 2.0], [2.0, 4.0]]))
    with pytest.raises(SingularMatrixError, match="not finite"):
        accurate_inverse(np.array([[np.nan, 0.0], [0.0, 1.0]]))


def test_map_growth_is_one_for_an_orthogonal_map_and_the_cancellation_of_a_shear():
    rng = np.random.default_rng(8)
    k = rng.standard_normal((5, 4))
    norms = np.linalg.norm(k, axis=0)
    q, _ = np.linalg.qr(rng.standard_normal((4, 4)))
    m = k @ q.T
    # orthogonal: Σ_i ‖K_:i‖ |Q_ji| ≥ ‖M_:j‖, equal to 1 only for a permutation, ≤ √n here
    assert 1.0 <= map_growth(norms, q, np.linalg.norm(m, axis=0)) <= 2.0
    # a shear that cancels to 1e-6: (1 + 1 − 1e-6) / 1e-6
    k2 = np.array([[1.0, 1.0 - 1e-6]])
    x = np.array([[1.0, -1.0]])
    assert map_growth(np.abs(k2[0]), x, np.abs(k2 @ x.T)[0]) == pytest.approx(2e6 - 1, rel=1e-9)
    assert map_growth(np.zeros(2), x, np.zeros(1)) == 0.0


def test_product_unit_is_gamma_n_and_its_square():
    u = np.finfo(float).eps / 2
    assert product_unit(10, accurate=False) == pytest.approx(10 * u / (1 - 10 * u))
    assert product_unit(10, accurate=True) == pytest.approx((10 * u / (1 - 10 * u)) ** 2)

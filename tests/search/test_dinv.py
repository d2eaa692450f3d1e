"""DINV (seed section V-B) against numpy.linalg on random, ill-conditioned and singular matrices.

Error bounds are stated in terms of the 2-norm condition number kappa: for Gauss-Jordan with
complete pivoting, as for LU with pivoting, the forward error of A^-1, of X and of det A is a
modest multiple of n * kappa * eps (Higham, *Accuracy and Stability of Numerical Algorithms*,
2nd ed., ch. 14). numpy (LAPACK getrf/getri/gesv) has its own error of the same order, so the
two may differ by the sum: we allow ``SLACK * n * kappa * eps`` relative. Over 3000 random and
ill-conditioned (kappa up to 1e10) samples of order 2-8 the worst observed ratio was 0.46, so
SLACK = 5 leaves a factor of 10 of margin while still failing on an O(1) error in one element.
An exactly rank-deficient product showed a smallest relative pivot of at most 3.2e-16, far
below the default threshold of 1e-12.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from search import DEFAULT_PIVOT_RTOL, SearchInputError, SingularMatrixError, dinv

EPS = np.finfo(np.float64).eps
SLACK = 5.0  # multiple of n * kappa * eps allowed between DINV and LAPACK (see module doc)

seeds = st.integers(min_value=0, max_value=2**32 - 1)
orders = st.integers(min_value=1, max_value=8)


def _bound(n: int, kappa: float) -> float:
    return SLACK * n * kappa * EPS


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _orthogonal(rng: np.random.Generator, n: int) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(n, n)))
    return q * np.sign(np.diag(r))


def _with_condition(rng: np.random.Generator, n: int, log10_kappa: float) -> np.ndarray:
    """A = U diag(s) V^T with singular values from 1 down to 10^-log10_kappa."""
    s = np.logspace(0.0, -log10_kappa, n)
    return _orthogonal(rng, n) @ np.diag(s) @ _orthogonal(rng, n).T


def _check_against_numpy(a: np.ndarray, b: np.ndarray) -> None:
    n = a.shape[0]
    kappa = np.linalg.cond(a)
    result = dinv(a, b)
    assert _rel(result.inverse, np.linalg.inv(a)) <= _bound(n, kappa)
    assert _rel(result.x, np.linalg.solve(a, b)) <= _bound(n, kappa)
    det_np = np.linalg.det(a)
    assert abs(result.determinant - det_np) <= _bound(n, kappa) * abs(det_np)
    assert result.x.shape == b.shape


@settings(max_examples=150, deadline=None)
@given(seed=seeds, n=orders, m=st.integers(min_value=1, max_value=3))
def test_random_matrices_match_numpy(seed, n, m):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n))
    b = rng.normal(size=(n, m))
    _check_against_numpy(a, b)


@settings(max_examples=150, deadline=None)
@given(seed=seeds, n=st.integers(min_value=2, max_value=8), log10_kappa=st.floats(3.0, 10.0))
def test_ill_conditioned_matrices_match_numpy(seed, n, log10_kappa):
    rng = np.random.default_rng(seed)
    a = _with_condition(rng, n, log10_kappa)
    b = rng.normal(size=(n, 2))
    _check_against_numpy(a, b)


@settings(max_examples=100, deadline=None)
@given(seed=seeds, n=st.integers(min_value=2, max_value=8), data=st.data())
def test_rank_deficient_matrices_are_singular(seed, n, data):
    rank = data.draw(st.integers(min_value=0, max_value=n - 1), label="rank")
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, rank)) @ rng.normal(size=(rank, n))
    with pytest.raises(SingularMatrixError) as info:
        dinv(a)
    assert info.value.order == n
    assert info.value.step >= rank + 1  # the first `rank` pivots are healthy
    assert abs(info.value.pivot) <= info.value.threshold


def test_duplicate_row_is_singular_and_message_has_numbers():
    a = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [1.0, 2.0, 3.0]])
    with pytest.raises(SingularMatrixError, match=r"pivot 3 of 3 is .* threshold 6\.000e-12"):
        dinv(a)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, n=orders, log10_scale=st.floats(-150.0, 150.0))
def test_threshold_is_relative_so_scaling_does_not_matter(seed, n, log10_scale):
    rng = np.random.default_rng(seed)
    a = _with_condition(rng, n, 6.0)
    scale = 10.0**log10_scale
    small = dinv(a * scale)  # must not be declared singular however small the scale
    # normwise, as the bound is (an element that cancels may differ by more, relatively:
    # 1.6e-8 against 8.9e-9 for seed 45, n = 8)
    assert _rel(small.inverse * scale, dinv(a).inverse) < _bound(n, 1e6)


def test_threshold_rejects_only_beyond_the_stated_condition_number():
    # Rejected pivot => kappa_2 >= 1 / (n * pivot_rtol); a kappa of 1e10 (n = 4) must pass the
    # default threshold and fail one of 1e-8.
    a = _with_condition(np.random.default_rng(7), 4, 10.0)
    dinv(a)
    assert 1.0 / (4 * DEFAULT_PIVOT_RTOL) > 1e10
    with pytest.raises(SingularMatrixError):
        dinv(a, pivot_rtol=1e-8)


def test_inversion_only_and_vector_right_hand_side():
    a = np.array([[0.0, 2.0], [3.0, 1.0]])  # needs a row interchange: det = -6
    only = dinv(a)
    assert only.x is None
    assert only.determinant == pytest.approx(-6.0, rel=4 * EPS)
    np.testing.assert_allclose(only.inverse @ a, np.eye(2), atol=4 * EPS)
    vec = dinv(a, [2.0, 4.0])
    assert vec.x.shape == (2,)
    np.testing.assert_allclose(vec.x, [1.0, 1.0], rtol=4 * EPS)
    np.testing.assert_allclose(np.abs(vec.pivots), [3.0, 2.0], rtol=4 * EPS)


def test_input_is_not_modified():
    a = np.array([[4.0, 1.0], [2.0, 3.0]])
    b = np.array([1.0, 2.0])
    a0, b0 = a.copy(), b.copy()
    dinv(a, b)
    np.testing.assert_array_equal(a, a0)
    np.testing.assert_array_equal(b, b0)


@pytest.mark.parametrize(
    ("a", "b", "kwargs", "argument"),
    [
        (np.ones((2, 3)), None, {}, "a"),
        (np.ones((0, 0)), None, {}, "a"),
        (np.array([[1.0, np.nan], [0.0, 1.0]]), None, {}, "a"),
        (np.eye(2), np.ones(3), {}, "b"),
        (np.eye(2), np.array([1.0, np.inf]), {}, "b"),
        (np.eye(2), None, {"pivot_rtol": -1.0}, "pivot_rtol"),
    ],
)
def test_bad_input_names_the_argument(a, b, kwargs, argument):
    with pytest.raises(SearchInputError) as info:
        dinv(a, b, **kwargs)
    assert info.value.argument == argument
    assert isinstance(info.value, ValueError)
    assert str(info.value).startswith(f"{argument}: expected")

"""TR packing (upper triangle by rows) of symmetric matrices."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tapp.errors import InputError
from tapp.io.tape.packing import (
    pack_tr,
    scaled_difference,
    scaled_difference_tr,
    symmetry_defect,
    tr_diagonal,
    tr_index,
    tr_nonzero_rows,
    tr_order,
    tr_rows,
    tr_size,
    unpack_tr,
    upper_from_tr,
)
from tests.tapp.io.tape.legacy import upper_by_rows


def test_order_is_the_upper_triangle_by_rows() -> None:
    m = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]])
    np.testing.assert_array_equal(pack_tr(m), [1, 2, 3, 4, 5, 6])
    assert [tr_index(i, j, 3) for i, j in ((0, 0), (0, 2), (2, 0), (1, 1), (1, 2), (2, 2))] == [
        0, 2, 2, 3, 4, 5]
    assert tr_size(23) == 276 and tr_order(276) == 23 and tr_order(0) == 0


@settings(max_examples=40, deadline=None)
@given(n=st.integers(0, 12), lead=st.lists(st.integers(0, 3), max_size=2),
       seed=st.integers(0, 2**31))
def test_upper_triangles_by_rows_unpack_and_show_their_zero_rows(n: int, lead: list[int],
                                                                 seed: int) -> None:
    """upper_from_tr inverts the packing of upper-triangular stacks (zero below the
    diagonal, every bit kept); tr_nonzero_rows finds the rows left all zero."""
    rng = np.random.default_rng(seed)
    u = np.triu(rng.normal(size=(*lead, n, n)))
    u[rng.random(u.shape[:-1]) < 0.4] = 0.0  # whole rows zero
    packed = upper_by_rows(u) if n else np.zeros((*lead, 0))
    back = upper_from_tr(packed, n)
    assert back.shape == u.shape
    np.testing.assert_array_equal(back.view(np.uint64), u.view(np.uint64))
    np.testing.assert_array_equal(tr_nonzero_rows(packed, n), np.any(u != 0, axis=-1))
    assert [stop - start for _, start, stop in tr_rows(n)] == list(range(n, 0, -1))


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 12), count=st.integers(1, 4), seed=st.integers(0, 2**31))
def test_round_trip_of_stacks(n: int, count: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(count, n, n))
    m = a + np.swapaxes(a, -1, -2)
    packed = pack_tr(m)
    assert packed.shape == (count, tr_size(n))
    np.testing.assert_array_equal(unpack_tr(packed, n), m)
    for i in range(n):
        for j in range(n):
            np.testing.assert_array_equal(packed[:, tr_index(i, j, n)], m[:, i, j])


def test_bad_lengths_and_shapes_are_refused() -> None:
    with pytest.raises(InputError, match="triangular number"):
        tr_order(7)
    with pytest.raises(InputError, match="6 entries"):
        unpack_tr(np.zeros(10), 3)
    with pytest.raises(InputError, match=r"\(\.\.\., n, n\)"):
        pack_tr(np.zeros((2, 3)))
    with pytest.raises(InputError):
        tr_index(3, 0, 3)


def test_symmetry_defect() -> None:
    m = np.array([[2.0, 1.0], [1.0 + 1e-6, 2.0]])
    assert symmetry_defect(m) == pytest.approx(5e-7)
    assert symmetry_defect(np.zeros((2, 2))) == 0.0


@settings(max_examples=30, deadline=None)
@given(n=st.integers(1, 9), seed=st.integers(0, 2**31))
def test_scaled_difference_packed_and_full_agree(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(3, n + 1, n))
    b = np.swapaxes(a, -1, -2) @ a  # normal matrices: |b_ij| <= sqrt(b_ii b_jj)
    c = b + 1e-9 * (b + np.swapaxes(b, -1, -2))
    full = scaled_difference(c, b)
    np.testing.assert_allclose(scaled_difference_tr(pack_tr(c), pack_tr(b)), full, rtol=1e-12)
    assert np.all(full <= 2e-9 * 1.0001)
    np.testing.assert_array_equal(pack_tr(b)[:, tr_diagonal(n)], np.diagonal(b, 0, 1, 2))


def test_scaled_difference_of_a_zero_scale_and_empty_stacks() -> None:
    b = np.diag([1.0, 0.0])
    assert scaled_difference(b + np.array([[0, 0], [0, 1e-30]]), b) == np.inf
    assert scaled_difference(b, b) == 0.0
    assert scaled_difference(np.zeros((0, 2, 2)), np.zeros((0, 2, 2))).shape == (0,)
    assert scaled_difference_tr(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)

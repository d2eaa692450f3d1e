"""Packed storage of symmetric matrices: the upper triangle by rows ("TR", seed TAPP III §3.1).

A symmetric n x n matrix M is stored as the vector of its n (n + 1) / 2 upper-triangle entries
taken row by row:

.. math::

    (M_{11}, M_{12}, \\dots, M_{1n}, M_{22}, M_{23}, \\dots, M_{2n}, \\dots, M_{nn}),

so that entry (i, j), 0-based with i <= j, sits at position i n - i (i - 1) / 2 + (j - i).
Arrays are time-major: a stack of N matrices (N, n, n) packs to (N, n (n + 1) / 2). The T13
tape stores its normal matrices ΔJ, ΔJ̃ this way; the T32 tape uses the same helpers.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from tapp.errors import InputError


def tr_size(n: int) -> int:
    """Return the packed length n (n + 1) / 2 of a symmetric n x n matrix (n >= 0)."""
    if n < 0:
        raise InputError("packing", "n", "an order n >= 0", n)
    return n * (n + 1) // 2


def tr_order(length: int) -> int:
    """Return the order n of a symmetric matrix whose TR-packed length is ``length``.

    Raises
    ------
    InputError
        If ``length`` is not a triangular number n (n + 1) / 2.
    """
    n = (math.isqrt(8 * length + 1) - 1) // 2 if length >= 0 else -1
    if n < 0 or tr_size(n) != length:
        raise InputError("packing", "length", "a triangular number n (n + 1) / 2", length)
    return n


@cache
def _upper(n: int) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = np.triu_indices(n)  # row-major order: exactly the TR sequence
    rows.setflags(write=False)
    cols.setflags(write=False)
    return rows, cols


def tr_index(i: int, j: int, n: int) -> int:
    """Return the position of entry (i, j) (0-based, either order) in the TR vector of order n."""
    if not (0 <= i < n and 0 <= j < n):
        raise InputError("packing", "index", f"0 <= i, j < {n}", (i, j))
    i, j = min(i, j), max(i, j)
    return i * n - i * (i - 1) // 2 + (j - i)


def pack_tr(matrix) -> np.ndarray:
    """Return the TR vector(s) of symmetric matrices, shape (..., n (n + 1) / 2).

    Parameters
    ----------
    matrix : array_like, shape (..., n, n)
        Symmetric matrices; only the upper triangle is read (the caller owns symmetry; see
        :func:`symmetry_defect` to measure it).

    Examples
    --------
    >>> pack_tr([[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]])
    array([1., 2., 3., 4., 5., 6.])
    """
    m = np.asarray(matrix, dtype=float)
    if m.ndim < 2 or m.shape[-1] != m.shape[-2]:
        raise InputError("packing", "matrix", "an array of shape (..., n, n)", m.shape)
    rows, cols = _upper(m.shape[-1])
    return m[..., rows, cols]


def unpack_tr(packed, n: int | None = None) -> np.ndarray:
    """Return the full symmetric matrices of TR vectors, shape (..., n, n).

    Parameters
    ----------
    packed : array_like, shape (..., n (n + 1) / 2)
        TR vectors.
    n : int, optional
        Expected order; derived from the length when omitted.

    Raises
    ------
    InputError
        If the length is not triangular or does not match ``n``.
    """
    v = np.asarray(packed, dtype=float)
    order = tr_order(v.shape[-1]) if v.ndim else -1
    if n is not None and order != n:
        raise InputError("packing", "length", f"{tr_size(n)} entries (order {n})",
                         v.shape[-1] if v.ndim else v.shape)
    rows, cols = _upper(order)
    out = np.empty(v.shape[:-1] + (order, order))
    out[..., rows, cols] = v
    out[..., cols, rows] = v
    return out


@cache
def tr_rows(n: int) -> tuple[tuple[int, int, int], ...]:
    """Return (i, start, stop) for each row i of the TR vector of order n: positions
    start..stop-1 hold entries (i, i..n-1).

    Examples
    --------
    >>> tr_rows(3)
    ((0, 0, 3), (1, 3, 5), (2, 5, 6))
    """
    starts = [i * n - i * (i - 1) // 2 for i in range(n + 1)]
    return tuple((i, starts[i], starts[i + 1]) for i in range(n))


def upper_from_tr(packed: np.ndarray, n: int) -> np.ndarray:
    """Return the upper-triangular matrices (..., n, n) of TR vectors (..., n (n + 1) / 2),
    zero below the diagonal.

    Copied row by row (n slice copies), 8x faster than scattering by index lists on a
    block of factors of order 50.

    Examples
    --------
    >>> upper_from_tr(np.array([1.0, 2.0, 3.0]), 2)
    array([[1., 2.],
           [0., 3.]])
    """
    out = np.zeros(packed.shape[:-1] + (n, n))
    for i, start, stop in tr_rows(n):
        out[..., i, i:] = packed[..., start:stop]
    return out


def tr_nonzero_rows(packed: np.ndarray, n: int) -> np.ndarray:
    """Return which rows of upper-triangular matrices packed TR (..., n (n + 1) / 2) hold a
    non-zero entry, (..., n) bool (read on the packed entries, half those of the matrices).

    Examples
    --------
    >>> tr_nonzero_rows(np.array([1.0, 2.0, 0.0]), 2)  # [[1, 2], [0, 0]]
    array([ True, False])
    """
    if n == 0:
        return np.zeros(packed.shape[:-1] + (0,), dtype=bool)
    starts = [start for _, start, _ in tr_rows(n)]
    return np.logical_or.reduceat(packed != 0, starts, axis=-1)


def symmetry_defect(matrix) -> np.ndarray:
    r"""Return the relative asymmetry of each matrix, shape (...).

    .. math:: \max_{ij} \frac{|M_{ij} - M_{ji}|}{\sqrt{|M_{ii} M_{jj}|}}

    The scale is that of a normal (or covariance) matrix, |M_ij| <= sqrt(M_ii M_jj), so the
    measure does not depend on the parameters' units; an asymmetric pair whose scale is zero
    gives inf.
    """
    m = np.asarray(matrix, dtype=float)
    d = np.sqrt(np.abs(np.diagonal(m, axis1=-2, axis2=-1)))
    scale = d[..., :, None] * d[..., None, :]
    diff = np.abs(m - np.swapaxes(m, -1, -2))
    ratio = np.divide(diff, scale, out=np.where(diff > 0, np.inf, 0.0), where=scale > 0)
    return np.max(ratio, axis=(-2, -1))


def tr_diagonal(n: int) -> np.ndarray:
    """Return the positions of the diagonal entries (i, i) in the TR vector of order n, (n,)."""
    i = np.arange(n)
    return i * n - i * (i - 1) // 2


def scaled_difference(a, b) -> np.ndarray:
    r"""Return the difference of matrices on the scale of ``b``, shape (...).

    .. math:: \max_{ij} \frac{|A_{ij} - B_{ij}|}{\sqrt{|B_{ii} B_{jj}|}}

    The natural scale of a normal (or covariance) matrix (as in :func:`symmetry_defect`); a
    difference where the scale is zero gives inf.

    Parameters
    ----------
    a, b : array_like, shape (..., n, n)
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    d = np.sqrt(np.abs(np.diagonal(b, axis1=-2, axis2=-1)))
    return _ratio(np.abs(a - b), d[..., :, None] * d[..., None, :], axes=(-2, -1))


def scaled_difference_tr(a, b) -> np.ndarray:
    """Return :func:`scaled_difference` of TR-packed matrices (..., n (n + 1) / 2), shape (...)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    n = tr_order(b.shape[-1])
    d = np.sqrt(np.abs(b[..., tr_diagonal(n)]))
    rows, cols = _upper(n)
    return _ratio(np.abs(a - b), d[..., rows] * d[..., cols], axes=(-1,))


def _ratio(diff: np.ndarray, scale: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
    ratio = np.divide(diff, scale, out=np.where(diff > 0, np.inf, 0.0), where=scale > 0)
    if ratio.size == 0:
        return np.zeros(ratio.shape[:ratio.ndim - len(axes)])
    return np.max(ratio, axis=axes)

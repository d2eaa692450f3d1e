"""DINV: Gauss-Jordan elimination with complete pivoting (seed TM 33-203, section V-B).

DINV "solves the matrix equation AX = B, where A is a square coefficient matrix and B is a
matrix of constant vectors. A^-1 is also obtained [...]. Finally, the determinant of A is
available. Jordan's method is used to reduce a matrix A to the identity matrix I through a
succession of elementary transformations: t_n t_(n-1) ... t_1 A = I. If these transformations
are simultaneously applied to I and to a matrix B of constant vectors, the result is A^-1 and
X where AX = B." (Newhall 1965, JPL TM 33-203, section V-B.)

The seed's DINV is a modification of B. S. Garbow's Argonne routine, which keeps three work
arrays whose names are kept here: ``PIVOT`` (the pivot elements), ``INDEX`` (the row
interchanges, one (IROW, ICOLUM) pair per step) and ``IPIVOT`` (which rows/columns have already
been pivoted on, "to prevent duplicate pivotings on any single row"). Each step searches the
whole not-yet-pivoted submatrix for its largest element (complete pivoting), moves it to the
diagonal by a row interchange, and eliminates its column from every other row; the inverse is
built in place and its columns are unscrambled at the end. The seed's N <= 6 limit (a FORTRAN
DIMENSION statement) does not apply here. The seed's "M <= 0 means inversion only" is
``b=None``.

The loop runs over the n pivots; the row operations inside a step are vectorised.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from search.errors import SearchInputError, SingularMatrixError

#: Default relative pivot threshold of :func:`dinv`. A pivot |p| <= DEFAULT_PIVOT_RTOL *
#: max|a_ij| is declared singular. With complete pivoting every pivot satisfies
#: |p| >= sigma_min / n and max|a_ij| <= sigma_max, so a rejected pivot implies (in exact
#: arithmetic) cond_2(A) >= 1 / (n * pivot_rtol) = 1e12 / n: about 4500 machine epsilons, well
#: above the rounding left in the last pivot of an exactly singular matrix.
DEFAULT_PIVOT_RTOL = 1e-12


@dataclass(frozen=True, slots=True)
class DinvResult:
    """What DINV returns: A^-1, the solution X of AX = B, det A, and the pivots.

    Attributes
    ----------
    inverse : numpy.ndarray, shape (n, n)
        A^-1 (in the seed, returned in place of A).
    x : numpy.ndarray or None, shape (n,) or (n, m)
        X with AX = B, the same shape as the ``b`` given (in the seed, returned in place of B);
        None when no ``b`` was given (the seed's M <= 0, inversion only).
    determinant : float
        det A: the product of the pivots, with the sign flipped once per row interchange.
        Like ``numpy.linalg.det`` it overflows to +-inf or underflows to 0 when det A is
        outside the float64 range (e.g. a 7x7 matrix scaled by 1e48); A^-1 and X are
        unaffected.
    pivots : numpy.ndarray, shape (n,)
        The seed's PIVOT array, in elimination order.
    """

    inverse: np.ndarray
    x: np.ndarray | None
    determinant: float
    pivots: np.ndarray


def dinv(
    a: ArrayLike, b: ArrayLike | None = None, *, pivot_rtol: float = DEFAULT_PIVOT_RTOL
) -> DinvResult:
    r"""Return A^-1, X with AX = B, and det A by Gauss-Jordan elimination with complete pivoting.

    Step i (i = 1..n) picks the largest |a_jk| among the rows and columns not yet pivoted on
    (``IPIVOT``), interchanges rows so that it sits on the diagonal at (ICOLUM, ICOLUM)
    (recorded in ``INDEX``), divides that row by the pivot and subtracts multiples of it from
    every other row of A and B. Finally the columns of the inverse are interchanged back in
    reverse order of ``INDEX``.

    .. math::

        t_n t_{n-1} \cdots t_1 A = I, \qquad
        A^{-1} = t_n \cdots t_1 I, \qquad X = t_n \cdots t_1 B, \qquad
        \det A = (-1)^{s} \prod_{i=1}^{n} p_i

    with :math:`p_i` the pivots and :math:`s` the number of row interchanges.

    Parameters
    ----------
    a : array_like, shape (n, n)
        The square coefficient matrix A; finite. Not modified.
    b : array_like, shape (n,) or (n, m), optional
        The constant vectors B. Omit for inversion only.
    pivot_rtol : float, optional
        Relative singularity threshold: A is declared singular when a pivot satisfies
        :math:`|p_i| \le \text{pivot\_rtol} \cdot \max_{jk} |a_{jk}|`. Since complete pivoting
        guarantees :math:`|p_i| \ge \sigma_{\min}/n` and :math:`\max|a_{jk}| \le \sigma_{\max}`,
        a rejected pivot implies :math:`\kappa_2(A) \ge 1/(n\,\text{pivot\_rtol})` (exact
        arithmetic). Must be finite and >= 0; 0 rejects only exactly zero pivots.

    Returns
    -------
    DinvResult
        ``inverse`` (n, n), ``x`` (shape of ``b``, or None), ``determinant``, ``pivots`` (n,).

    Raises
    ------
    SearchInputError
        If ``a`` is not a non-empty finite square matrix, ``b`` does not have n rows or is not
        finite, or ``pivot_rtol`` is negative or not finite.
    SingularMatrixError
        If a pivot is at or below the threshold; it carries the step, pivot and threshold.

    Notes
    -----
    Source: N. S. Newhall, "A Users' Guide for SEARCH and ITER", JPL TM 33-203 (1965),
    section V-B, after B. S. Garbow (Argonne). Work per call: n steps of O(n (n + m)) each.
    """
    a_in = np.asarray(a, dtype=np.float64)
    if a_in.ndim != 2 or a_in.shape[0] != a_in.shape[1] or a_in.shape[0] == 0:
        raise SearchInputError("a", "a non-empty square matrix, shape (n, n)", a_in.shape)
    if not np.all(np.isfinite(a_in)):
        raise SearchInputError("a", "finite elements", a_in.tolist())
    if not (np.isfinite(pivot_rtol) and pivot_rtol >= 0.0):
        raise SearchInputError("pivot_rtol", "a finite number >= 0", pivot_rtol)
    n = a_in.shape[0]
    A = a_in.copy()  # becomes A^-1 in place, as in the seed
    if b is None:
        B = np.zeros((n, 0))
        b_shape = None
    else:
        b_in = np.asarray(b, dtype=np.float64)
        if b_in.ndim not in (1, 2) or b_in.shape[0] != n:
            raise SearchInputError("b", f"shape ({n},) or ({n}, m) to match a", b_in.shape)
        if not np.all(np.isfinite(b_in)):
            raise SearchInputError("b", "finite elements", b_in.tolist())
        b_shape = b_in.shape
        B = b_in.reshape(n, -1).copy()

    threshold = pivot_rtol * float(np.max(np.abs(A)))
    IPIVOT = np.zeros(n, dtype=bool)  # True once a row/column has been pivoted on
    INDEX = np.empty((n, 2), dtype=np.intp)  # (IROW, ICOLUM) of each step
    PIVOT = np.empty(n)
    DETERM = 1.0
    others = np.empty(n, dtype=bool)

    for i in range(n):
        # Search for the pivot element: the largest |a_jk| over rows and columns not yet used.
        free = np.flatnonzero(~IPIVOT)
        sub = np.abs(A[np.ix_(free, free)])
        j, k = np.unravel_index(np.argmax(sub), sub.shape)
        IROW, ICOLUM = free[j], free[k]
        if not abs(A[IROW, ICOLUM]) > threshold:
            raise SingularMatrixError(i + 1, n, float(abs(A[IROW, ICOLUM])), threshold)
        IPIVOT[ICOLUM] = True
        # Interchange rows to put the pivot element on the diagonal.
        if IROW != ICOLUM:
            DETERM = -DETERM
            A[[IROW, ICOLUM]] = A[[ICOLUM, IROW]]
            B[[IROW, ICOLUM]] = B[[ICOLUM, IROW]]
        INDEX[i] = IROW, ICOLUM
        PIVOT[i] = A[ICOLUM, ICOLUM]
        with np.errstate(over="ignore", under="ignore"):  # det may leave the float range
            DETERM *= PIVOT[i]
        # Divide the pivot row by the pivot element (the diagonal becomes 1/pivot).
        A[ICOLUM, ICOLUM] = 1.0
        A[ICOLUM] /= PIVOT[i]
        B[ICOLUM] /= PIVOT[i]
        # Reduce the non-pivot rows: row_L1 -= T * pivot row, with T = a(L1, ICOLUM).
        others[:] = True
        others[ICOLUM] = False
        T = np.where(others, A[:, ICOLUM], 0.0)
        A[others, ICOLUM] = 0.0
        A -= np.outer(T, A[ICOLUM])
        B -= np.outer(T, B[ICOLUM])

    # Interchange columns, in reverse order of the row interchanges.
    for IROW, ICOLUM in INDEX[::-1]:
        if IROW != ICOLUM:
            A[:, [IROW, ICOLUM]] = A[:, [ICOLUM, IROW]]

    x = None if b_shape is None else B.reshape(b_shape)
    return DinvResult(inverse=A, x=x, determinant=float(DETERM), pivots=PIVOT)

"""Factor algebra of square-root information and covariance (NumPy and LAPACK only).

A symmetric positive semi-definite M (n x n) is carried as a factor K (m x n) with M = KᵀK.
Two factors of the same M differ by an orthogonal matrix on the left, so stacking factors adds
their matrices, and a Householder QR of the stack gives back an n x n upper-triangular factor:

.. math::

    \\begin{bmatrix} K_1 \\\\ K_2 \\end{bmatrix} = Q \\begin{bmatrix} R \\\\ 0 \\end{bmatrix}
    \\;\\Rightarrow\\; R^T R = K_1^T K_1 + K_2^T K_2

(Bierman 1977, ch. IV; Golub & Van Loan, *Matrix Computations*, 4th ed., §5.2). Householder
QR is column-wise backward stable: the R computed is the exact factor of the stack with each
column perturbed by a few ε of its own norm, whatever the scaling of the columns (parameters
in km, km/s and rad side by side), so the sum keeps the digits the factors had. The normal
matrix M itself is never formed.

Products with a factor are formed as factors too: X M Yᵀ = (K Xᵀ)ᵀ (K Yᵀ), and X M Xᵀ is then
a Gram matrix, positive semi-definite with a non-negative diagonal by construction.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
from scipy import linalg

from tapp.errors import SingularMatrixError

__all__ = ["accurate_inverse", "accurate_map", "accurate_matmul", "accurate_stacked",
           "ar1_whitened",
           "digits_held", "gram", "map_growth", "product_unit", "psd_factor",
           "scaled_min_eigenvalue", "triangularize", "upper_from_packed"]


def triangularize(*blocks: np.ndarray, n: int | None = None) -> np.ndarray:
    """Return the (n, n) upper-triangular R, diagonal >= 0, with RᵀR = Σ KᵢᵀKᵢ.

    Householder QR (LAPACK ``dgeqrf``) of the blocks stacked by rows. With fewer rows than
    columns, the rows of R below them are zero.

    Parameters
    ----------
    *blocks : (m_i, n) factors; (0, n) blocks are allowed.
    n : number of columns, needed when no block is given.

    Examples
    --------
    >>> k = np.array([[3.0, 4.0]])
    >>> r = triangularize(k, np.array([[0.0, 5.0]]))
    >>> np.allclose(r.T @ r, k.T @ k + [[0, 0], [0, 25]])
    True
    """
    if not blocks:
        if n is None:
            raise ValueError("triangularize: give at least one block or n")
        return np.zeros((n, n))
    n = blocks[0].shape[-1] if n is None else n
    stack = blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=0)
    stack = np.asarray(stack, dtype=float)
    out = np.zeros((n, n))
    if stack.shape[0] == 0 or n == 0:
        return out
    r = linalg.qr(stack, mode="r", overwrite_a=len(blocks) > 1, check_finite=False)[0]
    m = min(r.shape[0], n)
    out[:m] = np.triu(r[:m])
    sign = np.where(np.diagonal(out) < 0, -1.0, 1.0)
    return out * sign[:, None]


def gram(k: np.ndarray, x: np.ndarray | None = None, y: np.ndarray | None = None) -> np.ndarray:
    """Return X (KᵀK) Yᵀ as (K Xᵀ)ᵀ (K Yᵀ); X = Y = I by default, Y = X when only X is given.

    With Y = X the result is a Gram matrix: exactly symmetric, diagonal >= 0.

    Parameters
    ----------
    k : (m, n) factor.
    x, y : (r, n), (c, n) maps applied on each side.
    """
    kx = k if x is None else k @ x.T
    if y is None or y is x:
        return kx.T @ kx
    return kx.T @ (k @ y.T)


def psd_factor(m: np.ndarray) -> np.ndarray:
    """Return an upper-triangular K (n, n) with KᵀK = M for a symmetric PSD M (given, exact).

    For matrices a user gives (a priori normal matrices and covariances). M is scaled to a
    unit diagonal first (its rows carry different units); a positive definite M gets its
    Cholesky factor, a semi-definite one (zero σ, or exactly correlated parameters) the
    triangularised square root of its eigen-decomposition with negative rounding set to zero.
    Rows and columns of zero variance are zero.
    """
    m = np.asarray(m, dtype=float)
    n = m.shape[0]
    d = np.sqrt(np.abs(np.diagonal(m)))
    live = d > 0
    out = np.zeros((n, n))
    if not np.any(live):
        return out
    idx = np.flatnonzero(live)
    scaled = m[np.ix_(idx, idx)] / np.outer(d[idx], d[idx])
    scaled = 0.5 * (scaled + scaled.T)
    try:
        k = linalg.cholesky(scaled, lower=False, check_finite=False)
    except linalg.LinAlgError:
        w, v = np.linalg.eigh(scaled)
        k = np.sqrt(np.maximum(w, 0.0))[:, None] * v.T
    full = np.zeros((idx.size, n))
    full[:, idx] = k * d[idx][None, :]
    return triangularize(full)


def scaled_min_eigenvalue(m: np.ndarray) -> float:
    """Return the smallest eigenvalue of a symmetric M scaled to a unit diagonal.

    .. math:: \\lambda_{min}(D^{-1/2} M D^{-1/2}), \\qquad D = \\operatorname{diag}(M)

    over the rows with M_ii > 0: the measure of semi-definiteness that does not depend on the
    units of the rows (a covariance's correlation matrix), each entry on its own scale
    √(M_ii M_jj). A PSD M gives >= 0 to rounding (a few ε n). −inf for a negative diagonal
    entry, or a non-zero entry in a row whose diagonal is zero (no PSD matrix has either);
    0 for an M with no positive diagonal entry.

    >>> scaled_min_eigenvalue(np.array([[4.0, 1.0], [1.0, 1.0]]))  # ρ = 0.5
    0.5
    >>> round(scaled_min_eigenvalue(np.array([[4.0, 2.0], [2.0, 1e-6]])), 6)  # ρ = 1000
    -999.0
    """
    m = np.asarray(m, dtype=float)
    d = np.diagonal(m)
    live = d > 0
    if np.any(d < 0) or np.any(m[~live] != 0) or np.any(m[:, ~live] != 0):
        return -math.inf
    if not np.any(live):
        return 0.0
    root = np.sqrt(d[live])
    scaled = m[np.ix_(live, live)] / np.outer(root, root)
    return float(np.linalg.eigvalsh(0.5 * (scaled + scaled.T))[0])


def upper_from_packed(packed: np.ndarray, rows: np.ndarray, cols: np.ndarray, n: int
                      ) -> np.ndarray:
    """Return the (..., n, n) upper-triangular matrices of upper triangles packed by rows.

    ``rows``, ``cols`` are ``np.triu_indices(n)`` (the packing order).
    """
    out = np.zeros(packed.shape[:-1] + (n, n))
    out[..., rows, cols] = packed
    return out


def ar1_whitened(b: np.ndarray, t_s: np.ndarray, tau_s: float) -> np.ndarray:
    """Return Cᵀ B, (n, p), with C Cᵀ = K, K_ab = exp(−|t_a − t_b|/τ): so (CᵀB)ᵀ(CᵀB) = BᵀKB.

    C is the Cholesky factor of the unit-variance first-order Gauss-Markov process at the
    times t (non-decreasing): x_1 = e_1, x_a = ρ_a x_{a−1} + √(1 − ρ_a²) e_a with
    ρ_a = exp(−(t_a − t_{a−1})/τ), so C_ab = c_b ρ_{b+1} ⋯ ρ_a (b <= a), c_1 = 1,
    c_b = √(1 − ρ_b²). Row b of CᵀB is c_b y_b with the backward recursion

    .. math:: y_n = B_n,\\qquad y_b = B_b + \\rho_{b+1}\\,y_{b+1},

    O(n p), no n x n matrix (the Markov property; Maybeck, *Stochastic Models, Estimation and
    Control* vol. 1, 1979, §4.11; Bierman 1977, ch. VIII for the same recursion in a filter).

    Parameters
    ----------
    b : (n, p) rows at the times t_s.
    t_s : (n,) non-decreasing times, s.
    tau_s : time constant, s, > 0.
    """
    b = np.asarray(b, dtype=float)
    t = np.asarray(t_s, dtype=float)
    n = b.shape[0]
    out = np.empty_like(b)
    if n == 0:
        return out
    dt = np.diff(t)
    rho = np.exp(-dt / tau_s)
    c = np.ones(n)
    c[1:] = np.sqrt(-np.expm1(-2.0 * dt / tau_s))
    y = b[-1].copy()
    out[-1] = c[-1] * y
    for a in range(n - 2, -1, -1):
        y = b[a] + rho[a] * y
        out[a] = c[a] * y
    return out


def digits_held(relative_error: float) -> float:
    """Return the significant digits −log₁₀(error) of a relative error (at most those of ε)."""
    eps = float(np.finfo(float).eps)
    return -math.log10(min(max(relative_error, eps), 1.0))


def map_growth(k_norms: np.ndarray, x: np.ndarray, m_norms: np.ndarray) -> float:
    """Return the largest growth of a map M = K Xᵀ over the columns of M, ≥ 0.

    .. math:: a = \\max_j \\frac{\\sum_i \\lVert K_{:i}\\rVert\\,|X_{ji}|}{\\lVert M_{:j}\\rVert}

    A perturbation of each column of K by η of its norm (the column-wise backward error a
    Householder QR leaves, or the rounding of a product's terms) moves column j of M by at
    most η a of its norm: a is the condition of the map as the factor K sees it (1 for an
    orthogonal X; on the deep-space tape, whose periapsis transition has cond 4.5e13, 2.7e4
    for the information mapped to the periapsis epoch and 3.2e6 for the real-world
    information read since the last recycle). For a stack of factors mapped block by block,
    the norms are the root sum of squares of the blocks' column norms. Columns of M whose
    terms are zero do not count; a zero column whose terms are not gives a = inf.

    Parameters
    ----------
    k_norms : (n,) column norms of K.
    x : (r, n) the map.
    m_norms : (r,) column norms of M.
    """
    terms = np.abs(np.asarray(x, dtype=float)) @ np.asarray(k_norms, dtype=float)
    live = terms > 0
    if not np.any(live):
        return 0.0
    with np.errstate(divide="ignore"):
        return float(np.max(terms[live] / np.asarray(m_norms, dtype=float)[live]))


def product_unit(n: int, accurate: bool) -> float:
    """Return the relative error bound per term of a product of n-term sums: γ_n for a
    floating-point product, γ_n² for :func:`accurate_matmul` (whose result carries u of
    itself besides), with γ_n = n u / (1 − n u), u = ε/2 the unit roundoff.

    .. math:: |\\hat M - M| \\le \\gamma_n |K|\\,|X|^T
        \\quad\\text{or}\\quad u |M| + \\gamma_n^2 |K|\\,|X|^T

    (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., 2002, §3.5; Ogita,
    Rump & Oishi 2005, Proposition 5.5 for Dot2.)
    """
    eps = float(np.finfo(float).eps) / 2.0  # the unit roundoff u of binary64
    gamma = n * eps / (1.0 - n * eps)
    return gamma * gamma if accurate else gamma


def _split(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Dekker's split a = hi + lo, each with at most 26 significant bits."""
    c = 134217729.0 * a  # 2**27 + 1
    hi = c - (c - a)
    return hi, a - hi


def accurate_matmul(a: np.ndarray, b: np.ndarray, c: np.ndarray | None = None, *,
                    split: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Return C + A B as if computed in twice the working precision and rounded once.

    Ogita, Rump & Oishi's Dot2 (*Accurate sum and dot product*, SIAM J. Sci. Comput. 26,
    2005, Algorithm 5.3) vectorised over the entries: every product split exactly into its
    rounded value and error (Dekker's TwoProduct), the sum accumulated with TwoSum. For
    products whose terms cancel (a factor mapped through an ill-conditioned transition),
    where the plain product keeps only ε times the cancellation factor; elementwise NumPy
    only, so the result does not depend on the BLAS. Shapes (r, m), (m, c), (r, c).

    With ``split``, return (hi, lo): the rounded result and the remainder, hi + lo the
    product to about ε² relative (a double-double), for a matrix whose own rounding matters
    (:func:`accurate_map` takes the remainder as ``x_lo``).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    out_shape = (a.shape[0], b.shape[1])
    p = np.zeros(out_shape) if c is None else np.array(c, dtype=float)
    s = np.zeros(out_shape)
    for i in range(a.shape[1]):
        x, y = a[:, i][:, None], b[i][None, :]
        h = x * y
        xh, xl = _split(np.broadcast_to(x, out_shape))
        yh, yl = _split(np.broadcast_to(y, out_shape))
        r = ((xh * yh - h) + xh * yl + xl * yh) + xl * yl       # TwoProduct: x y = h + r
        t = p + h                                                # TwoSum: p + h = t + q
        z = t - p
        q = (p - (t - z)) + (h - z)
        p = t
        s = s + (q + r)
    hi = p + s
    if split:
        return hi, (p - hi) + s
    return hi


def accurate_stacked(phi: np.ndarray, m: np.ndarray, c: np.ndarray | None = None
                     ) -> np.ndarray:
    """Return C_i + Φ_i M for stacked Φ (N, n, n), one M (n, p) and C (N, n, p) or None, each
    entry by :func:`accurate_matmul` (as if in twice the working precision, BLAS-free): the
    composition of transitions along a trajectory, Φ(t_i, t_0) = Φ(t_i, b) Φ(b, t_0) and
    S(t_i) = Φ(t_i, b) S(b) + S_b(t_i), whose terms cancel after a close approach."""
    n, k, p = phi.shape[0], phi.shape[1], m.shape[1]
    flat = accurate_matmul(phi.reshape(n * k, phi.shape[2]), m,
                           None if c is None else c.reshape(n * k, p))
    return flat.reshape(n, k, p)


def accurate_map(k: np.ndarray, x: np.ndarray, x_lo: np.ndarray | None = None) -> np.ndarray:
    """Return K (X + X_lo)ᵀ (m, r) by :func:`accurate_matmul`, exploiting unit rows and
    columns of X.

    A transformation of TAPP III is mostly identity: a row of X that is a unit row e_c
    copies column c of K, and a unit column e_i of X adds column i of K to column i of the
    result exactly, so only the other terms go through Dot2. ``x_lo`` (the remainder of a
    double-double X, zero on its unit rows and columns) adds its terms to the same sum.
    K (m, n), X (r, n).
    """
    k = np.asarray(k, dtype=float)
    x = np.asarray(x, dtype=float)
    r, n = x.shape
    out = np.zeros((k.shape[0], r))
    if k.shape[0] == 0:
        return out
    unit_cols = np.zeros(n, dtype=bool)
    if r == n:
        eye = np.eye(n, dtype=bool)
        unit_cols = np.all((x != 0) == eye, axis=0) & (np.diagonal(x) == 1.0)
        unit_rows = np.all((x != 0) == eye, axis=1) & (np.diagonal(x) == 1.0)
    else:
        unit_rows = np.zeros(r, dtype=bool)
    if np.any(unit_rows):
        out[:, unit_rows] = k[:, unit_rows]
    dense = ~unit_rows
    if not np.any(dense):
        return out
    addend = np.zeros((k.shape[0], r))
    if np.any(unit_cols):
        addend[:, unit_cols] = k[:, unit_cols]
    inner = ~unit_cols & np.any(x[dense] != 0, axis=0)
    a, b = k[:, inner], x[dense][:, inner].T
    if x_lo is not None:
        lo = np.asarray(x_lo, dtype=float)[dense]
        used = np.any(lo != 0, axis=0)
        a = np.hstack([a, k[:, used]])
        b = np.vstack([b, lo[:, used].T])
    out[:, dense] = accurate_matmul(a, b, addend[:, dense])
    return out


def accurate_inverse(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return A⁻¹ of a small square float64 matrix as a double-double (hi, lo), (n, n) each.

    The inverse is computed exactly, in rational arithmetic, and rounded twice: hi is A⁻¹
    correctly rounded, lo the remainder A⁻¹ − hi correctly rounded, so hi + lo is A⁻¹ to
    about ε² relative, entry by entry, whatever the condition number of A. The entries of A are
    integers times a common power of two, A = M 2^s; fraction-free Gauss-Jordan elimination
    on the integer matrix [M | I] (Bareiss, *Math. Comp.* 22, 1968; every division exact by
    Sylvester's identity) ends with [d I | d M⁻¹], d = ±det M, in Python's unbounded
    integers, and int / int rounds correctly.

    For the orbit block P of a transition taken from a tape (an STM computed in floating
    point), whose inverse must be consistent with P itself: after the deep-space lunar
    swing-by P has a condition number of 4.5e13 and is symplectic only to its rounding
    (|PᵀΓP − Γ| = 1.0e-4), so Γ P Γᵀ is not its inverse, and even the correctly rounded
    inverse alone (hi) leaves |P hi − I| of ε cond ≈ 1e-2 of the terms. O(n³) operations
    on integers of O(n) times the bits of A's entries: about 1 ms for a 6 x 6 block.

    Raises
    ------
    SingularMatrixError
        If A is exactly singular (or has an entry that is not finite).

    Examples
    --------
    >>> hi, lo = accurate_inverse(np.array([[3.0, 0.0], [0.0, 1.0]]))
    >>> float(hi[0, 0]), bool(lo[0, 0] == float(Fraction(1, 3) - Fraction(hi[0, 0])))
    (0.3333333333333333, True)
    """
    a = np.asarray(a, dtype=float)
    n = a.shape[0]
    if not np.all(np.isfinite(a)):
        raise SingularMatrixError("accurate_inverse: a matrix entry is not finite")
    mant, expo = np.frexp(a)  # a = mant 2^expo, 0.5 <= |mant| < 1 (both 0 for a = 0)
    live = mant != 0
    if not np.any(live):
        raise SingularMatrixError("accurate_inverse: the matrix is zero")
    low = int(expo[live].min()) - 53  # A = M 2^low with M integer
    m = [[int(mant[i, j] * 2.0 ** 53) << int(expo[i, j] - 53 - low) if live[i, j] else 0
          for j in range(n)] + [int(i == j) for j in range(n)] for i in range(n)]
    previous = 1
    for c in range(n):
        pivot = next((r for r in range(c, n) if m[r][c] != 0), None)
        if pivot is None:
            raise SingularMatrixError("accurate_inverse: the matrix is singular")
        m[c], m[pivot] = m[pivot], m[c]
        top = m[c]
        for r in range(n):
            if r != c:
                f = m[r][c]
                m[r] = [(top[c] * x - f * y) // previous for x, y in zip(m[r], top, strict=True)]
        previous = top[c]
    # every diagonal entry is now d = ±det M, the right half d M⁻¹; A⁻¹ = M⁻¹ 2^-low
    d = previous << max(low, 0)
    exact = [[Fraction(m[i][n + j] << max(-low, 0), d) for j in range(n)] for i in range(n)]
    hi = np.array([[float(x) for x in row] for row in exact])
    lo = np.array([[float(x - Fraction(h)) for x, h in zip(row, hi_row, strict=True)]
                   for row, hi_row in zip(exact, hi, strict=True)])
    return hi, lo

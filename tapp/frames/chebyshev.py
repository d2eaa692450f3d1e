"""Piecewise Chebyshev series of smooth functions of scenario time.

One table type serves the third-body ephemeris and the slowly varying Earth-orientation
quantities: both are fitted here, evaluated in NumPy (:meth:`ChebyshevTable.evaluate`) and in
the compiled DOP853 driver (``tapp/dynamics/dop853_driver.c``, ``eph_eval``), which reads the
same array layout. Segment k covers [t0_s + k h_s, t0_s + (k + 1) h_s] s from the scenario
epoch; on it each coordinate is Σ_j a_j T_j(τ), τ = 2 (t - t_k) / h_s - 1, interpolating the
function at the n_coef Chebyshev points of the first kind (near-minimax: the error is at most
about 1 + (2/π) ln n times the best polynomial's). The coefficients come from the discrete
Chebyshev transform at those points (Mason & Handscomb, *Chebyshev Polynomials*, 2003, §6.3),
elementwise NumPy rather than a least-squares fit through LAPACK, whose rounding depended on
the BLAS kernel: a 1e-16 difference in the Moon's table became 0.7 mm on the deep-space
trajectory after the swing-by, 3e-7 of its STMs and 1e-5 of the covariances processed from
its tape.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class ChebyshevTable:
    """Piecewise Chebyshev series of ``n_series`` 3-vectors of time.

    ``coeffs`` has shape (n_series, n_segments, 3, n_coef), in the units of the fitted
    function; segment k covers [t0_s + k h_s, t0_s + (k+1) h_s], s from the epoch.
    """

    coeffs: np.ndarray
    t0_s: float
    h_s: float

    @property
    def n_series(self) -> int:
        return int(self.coeffs.shape[0])

    @property
    def n_segments(self) -> int:
        return int(self.coeffs.shape[1])

    @property
    def n_coef(self) -> int:
        return int(self.coeffs.shape[3])

    @property
    def t_end_s(self) -> float:
        """End of the last segment, s from the epoch."""
        return self.t0_s + self.n_segments * self.h_s

    @staticmethod
    def empty() -> ChebyshevTable:
        """A table with no series (the driver never reads it)."""
        return ChebyshevTable(np.zeros((0, 1, 3, 1)), 0.0, 1.0)

    def stacked(self, other: ChebyshevTable) -> ChebyshevTable:
        """Return this table's series followed by ``other``'s (same segments required)."""
        if self.n_series == 0:
            return other
        if other.n_series == 0:
            return self
        if (self.t0_s, self.h_s, self.coeffs.shape[1:]) != (other.t0_s, other.h_s,
                                                            other.coeffs.shape[1:]):
            raise ValueError("stacked tables must share their segments and degree")
        return ChebyshevTable(np.ascontiguousarray(np.concatenate([self.coeffs, other.coeffs])),
                              self.t0_s, self.h_s)

    def evaluate(self, t_s) -> np.ndarray:
        """Return the series at times t_s (N,), shape (n_series, N, 3) (Clenshaw recurrence).

        Raises
        ------
        ValueError
            For a time outside [t0_s, t_end_s] (beyond 1e-9 of a segment of rounding).
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        u = (t - self.t0_s) / self.h_s
        if np.any(u < -1e-9) or np.any(u > self.n_segments + 1e-9):
            raise ValueError("time outside the Chebyshev table")
        seg = np.clip(np.floor(u).astype(int), 0, self.n_segments - 1)
        tau = 2.0 * (u - seg) - 1.0
        shape = (self.n_series, t.size, 3)
        b1, b2 = np.zeros(shape), np.zeros(shape)
        two_tau = (2.0 * tau)[None, :, None]
        for j in range(self.n_coef - 1, 0, -1):  # one (n_series, N, 3) gather per degree
            b1, b2 = two_tau * b1 - b2 + self.coeffs[..., j][:, seg], b1
        return tau[None, :, None] * b1 - b2 + self.coeffs[..., 0][:, seg]


def segment_starts(t_start_s: float, t_end_s: float, segment_s: float,
                   origin_s: float | None = None) -> np.ndarray:
    """Start times (n_seg,) of the segments covering [min, max] of the two times: from the
    first time, or, with ``origin_s``, on the grid origin_s + k segment_s."""
    lo, hi = min(t_start_s, t_end_s), max(t_start_s, t_end_s)
    if origin_s is not None:
        lo = origin_s + segment_s * np.floor((lo - origin_s) / segment_s + 1e-12)
    n_seg = max(1, int(np.ceil((hi - lo) / segment_s - 1e-12)))
    return lo + segment_s * np.arange(n_seg)


def fit_chebyshev(fn: Callable[[np.ndarray], np.ndarray], t_start_s: float, t_end_s: float,
                  segment_s: float, n_coef: int, origin_s: float | None = None
                  ) -> ChebyshevTable:
    """Fit ``fn`` on [min, max] of the two times in segments of ``segment_s``.

    Segments start at the first time, or, with ``origin_s``, on the grid origin_s + k
    segment_s (so that a kink of ``fn`` on that grid, e.g. daily EOP values interpolated
    linearly, falls on a segment boundary). ``fn(t)`` takes times (M,) in s from the epoch
    and returns (n_series, M, 3).
    """
    seg_start = segment_starts(t_start_s, t_end_s, segment_s, origin_s)
    n_seg = seg_start.size
    tau = np.cos(np.pi * (np.arange(n_coef) + 0.5) / n_coef)  # first-kind nodes in (-1, 1)
    t_nodes = seg_start[:, None] + 0.5 * (tau[None, :] + 1.0) * segment_s  # (n_seg, n_coef)
    values = np.asarray(fn(t_nodes.ravel()), dtype=float)
    n_series = values.shape[0]
    values = values.reshape(n_series, n_seg, n_coef, 3)
    # interpolation at the first-kind nodes: the discrete Chebyshev transform,
    # c_j = (2 - δ_j0)/n Σ_i f(τ_i) T_j(τ_i) (no least squares, no BLAS)
    theta = np.pi * (np.arange(n_coef) + 0.5) / n_coef
    t_mat = np.cos(np.outer(theta, np.arange(n_coef)))        # T_j(τ_i) = cos(j θ_i)
    weight = np.full(n_coef, 2.0 / n_coef)
    weight[0] = 1.0 / n_coef
    coeffs = np.einsum("bkic,ij->bkcj", values, t_mat) * weight
    return ChebyshevTable(np.ascontiguousarray(coeffs), float(seg_start[0]), float(segment_s))

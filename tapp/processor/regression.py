"""The regression algorithm of TAPP III (seed TAPP III §2.5): fit world versus real world.

Notation of the seed (§2): x⁰ the n_o TAPP I parameters; the fit world fits the n_1 parameters
x¹ and holds the rest fixed, δx⁰ = E¹₀ δx¹ (2-17), with the FW constraint matrix E (n_o x n_1)
and an extended a priori normal matrix S₀₀ (any matrix with S₁₁ = Eᵀ S₀₀ E, 2-18); the data
give J₀₀ = AᵀWA (2-20). The real world has the a priori covariance Λ̄⁰⁰ of δx⁰ and the real
covariance of the normalised noise, J̃₀₀ = AᵀWMWA (2-45). The algorithm's outputs a)–f):

.. math::

    {}^1S_{00} &= S_{00} + J_{00}                                   && \\text{(2-34)}\\\\
    {}^1S_{11} &= E^T\\,{}^1S_{00}\\,E                               && \\text{(2-35)}\\\\
    {}^1\\Lambda^{11} &= ({}^1S_{11})^{-1}                           && \\text{(2-28)}\\\\
    {}^1\\Lambda^{00} &= E\\,{}^1\\Lambda^{11} E^T                    && \\text{(2-31)}\\\\
    L &= I - {}^1\\Lambda^{00} J_{00}                                 && \\text{(2-37)}\\\\
    {}^1\\bar\\Lambda^{00} &= L\\,\\bar\\Lambda^{00} L^T
        + {}^1\\Lambda^{00}\\,\\tilde J_{00}\\,{}^1\\Lambda^{00}     && \\text{(2-46)}

The fit-world estimate error after the regression is δ'x = L δx − ¹Λ⁰⁰ AᵀW δm (2-39); the
real-world covariance f) follows from it whatever the real statistics are. f) is the consider
covariance of Tapley, Schutz & Born, *Statistical Orbit Determination* (2004) §6.3, when the
fit world holds constants fixed that the real world lets vary.

Numerics: ¹S₁₁ is factored once by Cholesky after scaling by its diagonal (the parameters'
units span many decades); ¹Λ¹¹ is the one inverse the algorithm wants as a result, and L is
formed from solves with that factor, not from the inverse. Symmetric outputs are symmetrised
so that they are exactly symmetric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg

from tapp.errors import SingularMatrixError

#: Reciprocal condition number of the diagonally scaled ¹S₁₁ below which it is refused:
#: beyond ~1e13 the solve loses more than 13 of 16 digits.
MIN_RCOND = 1e-13


class SingularFitError(SingularMatrixError):
    """The fit world's a posteriori normal matrix ¹S₁₁ cannot be inverted.

    Attributes
    ----------
    rcond : reciprocal condition number of the diagonally scaled matrix.
    direction : (n_1,) unit vector (in scaled fit parameters) of the near-null direction.
    """

    def __init__(self, rcond: float, direction: np.ndarray):
        self.rcond = rcond
        self.direction = direction
        super().__init__(f"the fit-world normal matrix is singular (reciprocal condition "
                         f"number {rcond:.3g} < {MIN_RCOND:g})")


@dataclass(frozen=True, slots=True, eq=False)
class Regression:
    """Outputs a)–f) of the regression algorithm (seed §2.5.2), float64 arrays.

    Attributes
    ----------
    S1_00 : (n_o, n_o) extended FW a posteriori normal matrix ¹S₀₀.
    S1_11 : (n_1, n_1) FW a posteriori normal matrix of the fit parameters ¹S₁₁.
    Lambda1_11 : (n_1, n_1) FW a posteriori covariance of the fit parameters ¹Λ¹¹.
    Lambda1_00 : (n_o, n_o) FW a posteriori covariance of the TAPP I parameters ¹Λ⁰⁰.
    L : (n_o, n_o) ∂(a posteriori error)/∂(a priori error), I − ¹Λ⁰⁰ J₀₀.
    Lambda_real : (n_o, n_o) RW a posteriori covariance ¹Λ̄⁰⁰.
    """

    S1_00: np.ndarray
    S1_11: np.ndarray
    Lambda1_11: np.ndarray
    Lambda1_00: np.ndarray
    L: np.ndarray
    Lambda_real: np.ndarray


def symmetric(m: np.ndarray) -> np.ndarray:
    """Return (M + Mᵀ)/2: exactly symmetric in floating point."""
    return 0.5 * (m + m.T)


class FitFactor:
    """Cholesky factor of a symmetric positive definite ¹S₁₁, diagonally scaled.

    ¹S₁₁ = D Ŝ D with D = diag(√s_ii); Ŝ = RᵀR. Raises :class:`SingularFitError` when Ŝ is not
    positive definite or its reciprocal condition number is below :data:`MIN_RCOND`.
    """

    def __init__(self, s11: np.ndarray):
        diag = np.diagonal(s11)
        if np.any(~np.isfinite(diag)) or np.any(diag <= 0):
            bad = int(np.argmax(~(np.isfinite(diag) & (diag > 0))))
            direction = np.zeros(diag.size)
            direction[bad] = 1.0
            raise SingularFitError(0.0, direction)
        self.d = np.sqrt(diag)
        scaled = s11 / np.outer(self.d, self.d)
        try:
            self.factor = linalg.cho_factor(scaled, lower=False, check_finite=False)
        except linalg.LinAlgError:
            self._refuse(scaled)
        rcond = self._rcond()
        if rcond < MIN_RCOND:
            self._refuse(scaled)

    def _rcond(self) -> float:
        r = np.triu(self.factor[0])
        d = np.abs(np.diagonal(r))
        return float((d.min() / d.max()) ** 2) if d.size else 1.0

    @staticmethod
    def _refuse(scaled: np.ndarray) -> None:
        w, v = np.linalg.eigh(symmetric(scaled))
        rcond = float(max(w[0], 0.0) / w[-1]) if w[-1] > 0 else 0.0
        raise SingularFitError(rcond, v[:, 0])

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Return ¹S₁₁⁻¹ b for b of shape (n_1,) or (n_1, m)."""
        d = self.d if b.ndim == 1 else self.d[:, None]
        return linalg.cho_solve(self.factor, b / d, check_finite=False) / d

    def inverse(self) -> np.ndarray:
        """Return ¹S₁₁⁻¹, exactly symmetric."""
        return symmetric(self.solve(np.eye(self.d.size)))


def regression(E1, S00, J00, Lambda_bar00, Jt00) -> Regression:
    """Run the regression algorithm (seed §2.5): return outputs a)–f).

    Parameters
    ----------
    E1 : array_like, (n_o, n_1)
        FW constraint matrix E¹₀ = ∂x⁰/∂x¹ (the fit parameters' columns).
    S00 : array_like, (n_o, n_o)
        Extended FW a priori normal matrix (S₁₁ = Eᵀ S₀₀ E).
    J00 : array_like, (n_o, n_o)
        AᵀWA of the data.
    Lambda_bar00 : array_like, (n_o, n_o)
        RW a priori covariance of δx⁰.
    Jt00 : array_like, (n_o, n_o)
        AᵀWMWA of the data.

    Raises
    ------
    SingularFitError
        If ¹S₁₁ is not positive definite to working precision.

    Examples
    --------
    One parameter, a priori σ = 2 in both worlds, one measurement of σ = 1 (fit) and
    σ = 2 (real): fit variance 1/(1/4 + 1) = 0.8, real 0.2²·4 + 0.8²·4 = 2.72.

    >>> r = regression([[1.0]], [[0.25]], [[1.0]], [[4.0]], [[4.0]])
    >>> round(float(r.Lambda1_11[0, 0]), 12), round(float(r.Lambda_real[0, 0]), 12)
    (0.8, 2.72)
    """
    E1, S00, J00, Lambda_bar00, Jt00 = (np.asarray(a, dtype=float)
                                       for a in (E1, S00, J00, Lambda_bar00, Jt00))
    n_o = S00.shape[0]
    S1_00 = symmetric(S00 + J00)                                   # a) (2-34)
    S1_11 = symmetric(E1.T @ S1_00 @ E1)                           # b) (2-35)
    fac = FitFactor(S1_11)
    Lambda1_11 = fac.inverse()                                     # c) (2-28)
    Lambda1_00 = symmetric(E1 @ Lambda1_11 @ E1.T)                 # d) (2-31)
    L = np.eye(n_o) - E1 @ fac.solve(E1.T @ J00)                   # e) (2-37)
    Lambda_real = symmetric(L @ Lambda_bar00 @ L.T                 # f) (2-46)
                            + Lambda1_00 @ Jt00 @ Lambda1_00)
    return Regression(S1_00, S1_11, Lambda1_11, Lambda1_00, L, Lambda_real)

"""The regression to a constrained parameter set (seed TAPP III §2.5) on factors.

Notation of the seed (§2): x⁰ the n_o TAPP I parameters; the fit world fits the n_1 parameters
x¹ and holds x² fixed, through the FW transformation matrices D = ∂[x¹; x²]/∂x⁰ (rows D₁, D₂)
and E = D⁻¹ (columns E₁, E₂): δx⁰ = E₁ δx¹ in the fit world (2-17). Its a priori normal
matrix is any valid extension S₀₀ (S₁₁ = E₁ᵀ S₀₀ E₁, 2-18); the data give J₀₀ = AᵀWA (2-20).
The real world has the a priori covariance Λ̄⁰⁰ of δx⁰ and the real covariance of the
normalised noise J̃₀₀ = AᵀWMWA (2-45). The outputs a)–f) of §2.5.2 are

.. math::

    {}^1S_{00} = S_{00} + J_{00},\\quad {}^1S_{11} = E_1^T\\,{}^1S_{00}E_1,\\quad
    {}^1\\Lambda^{00} = E_1\\,{}^1S_{11}^{-1}E_1^T,\\quad L = I - {}^1\\Lambda^{00} J_{00},\\quad
    {}^1\\bar\\Lambda^{00} = L\\bar\\Lambda^{00}L^T + {}^1\\Lambda^{00}\\tilde J_{00}\\,
    {}^1\\Lambda^{00}.

Here every symmetric input and output is a factor (:mod:`tapp.estimation.factors`):
S₀₀ = R_SᵀR_S, J₀₀ = R_JᵀR_J, Λ̄⁰⁰ = UᵀU, J̃₀₀ = R̃ᵀR̃, and no normal matrix, inverse or
difference of covariances is formed. The fit world is the least-squares problem of the
stacked information array (Bierman 1977, ch. V): one Householder QR

.. math::

    Q^T \\begin{bmatrix} R_S E_1 & I & 0 \\\\ R_J E_1 & 0 & R_J E_2 \\end{bmatrix}
    = \\begin{bmatrix} R_{11} & X & Y \\\\ 0 & * & * \\end{bmatrix}

gives ¹S₁₁ = R₁₁ᵀR₁₁ (b), ¹Λ⁰⁰ = F Fᵀ with F = E₁R₁₁⁻¹ (c, d: a triangular solve), and the
estimator's map as a sum of products,

.. math::

    L = E_1 R_{11}^{-1} (X R_S E_1 D_1 - Y D_2) + E_2 D_2,

because the estimate error is δx − E₁R₁₁⁻¹Q₁ᵀ[0; R_J δx + ν] and Q₁ᵀ[R_S E₁; R_J E₁] = R₁₁
(X R_S E₁ is what is left of the a priori error in the fitted directions, Y D₂ what the fit
makes of the held parameters: the consider sensitivity of Tapley, Schutz & Born, *Statistical
Orbit Determination*, 2004, §6.3). The real world's covariance f) is the Gram matrix of the
stack [U Lᵀ; R̃ F Fᵀ]; Σ = ¹Λ⁰⁰J̃¹Λ⁰⁰ (the tracking noise's share) has the
factor R̃ F Fᵀ. Both are positive semi-definite by construction. Every R₁₁⁻¹ is a triangular
solve with its right-hand side as given, backward stable, never a product with a formed F
or L: L is applied right to left (:meth:`Regression.apply_L`), because L U ᵀ is far smaller
than |L||U| (the fit removes all but 1e-3..1e-6 of the a priori error) and a formed L's
rounding, times that ratio, held the deep-space covariances to 1e-9 after the periapsis;
R̃ F cancels likewise (the data weigh what the fit has just determined).

The stacked factors a) and f) are returned as stacks: the caller triangularises them when
their rows grow (:func:`tapp.estimation.factors.triangularize`), preferably in the
representation in which they will be used. A Householder QR is backward stable column by
column in the representation it runs in; a factor triangularised and then mapped through an
ill-conditioned transition (an epoch change after a swing-by, cond 1e13) carries that rounding
times the condition, where one mapped first and triangularised after does not.

Accuracy: the QR and the triangular solves are backward stable column by column, so the
outputs hold about −log₁₀(ε κ) digits, κ the condition number of R₁₁ with its columns scaled
to unit norm (√ of that of the scaled ¹S₁₁, where the normal-matrix form held only
−log₁₀(ε κ²)); :attr:`Regression.kappa` carries it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import linalg

from tapp.errors import SingularMatrixError
from tapp.estimation.factors import gram, triangularize

#: Reciprocal condition number of R₁₁ (columns scaled to unit norm) below which the fit is
#: refused: the covariance would hold fewer than ~3 digits (ε / MIN_RCOND ≈ 2e-4).
MIN_RCOND = 1e-12


class SingularFitError(SingularMatrixError):
    """The fit world's a posteriori normal matrix ¹S₁₁ cannot be inverted.

    Attributes
    ----------
    rcond : reciprocal condition number of R₁₁ with unit-norm columns (the square root of
        that of the diagonally scaled ¹S₁₁).
    direction : (n_1,) unit vector (in scaled fit parameters) of the near-null direction.
    """

    def __init__(self, rcond: float, direction: np.ndarray):
        self.rcond = rcond
        self.direction = direction
        super().__init__(f"the fit-world normal matrix is singular (reciprocal condition "
                         f"number of its factor {rcond:.3g} < {MIN_RCOND:g})")


@dataclass(frozen=True, slots=True, eq=False)
class FitSystem:
    """The fit world's parametrisation: D = ∂[x¹; x²]/∂x⁰ (n_o, n_o), E = D⁻¹, n_1 fitted.

    TAPP III takes D and E from its transformation accumulator (the fit system's chain and
    its adjoint), so E is exact and no inverse is formed here.
    """

    D: np.ndarray
    E: np.ndarray
    n_1: int

    @classmethod
    def from_columns(cls, E1) -> FitSystem:
        """The fit system of a constraint matrix E₁ (n_o, n_1) of full column rank, completed
        by an orthonormal basis E₂ of the complement of its range (L does not depend on
        the completion)."""
        E1 = np.asarray(E1, dtype=float)
        n_o, n_1 = E1.shape
        q = linalg.qr(E1, mode="full")[0]
        E = np.hstack([E1, q[:, n_1:]])
        return cls(np.linalg.solve(E, np.eye(n_o)), E, n_1)


@dataclass(frozen=True, slots=True, eq=False)
class Regression:
    """Outputs a)–f) of the regression algorithm (seed §2.5.2) as factors, float64 arrays.

    Attributes
    ----------
    fit : the fit system.
    R_S1 : (m_s + m_j, n_o) factor of ¹S₀₀ = S₀₀ + J₀₀ (a): [R_S; R_J] stacked.
    R11 : (n_1, n_1) upper-triangular factor of ¹S₁₁ (b), diagonal > 0.
    F : (n_o, n_1) E₁R₁₁⁻¹: ¹Λ⁰⁰ = F Fᵀ (d).
    A, Y : (n_1, n_1), (n_1, n_2) X R_S E₁ and Y of the QR (module docstring): the estimator
        map (e) is L = E₁R₁₁⁻¹(A D₁ − Y D₂) + E₂D₂, applied by :meth:`apply_L`.
    U_real : (m_u + m, n_o) factor of ¹Λ̄⁰⁰ (f): [U Lᵀ; K_sigma] stacked; None without U
        and R̃.
    K_sigma : (m, n_o) factor of Σ = ¹Λ⁰⁰J̃₀₀¹Λ⁰⁰; None without R̃.
    kappa : condition number of R₁₁ with unit-norm columns (module docstring).
    """

    fit: FitSystem
    R_S1: np.ndarray
    R11: np.ndarray
    F: np.ndarray
    A: np.ndarray
    Y: np.ndarray
    U_real: np.ndarray | None
    K_sigma: np.ndarray | None
    kappa: float

    def _solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        return linalg.solve_triangular(self.R11, b, trans=trans, check_finite=False)

    def apply_L(self, M: np.ndarray) -> np.ndarray:
        """Return L M (n_o, c) for M (n_o, c), right to left.

        .. math:: L M = E_1 R_{11}^{-1}\\big(A\\,(D_1 M) - Y\\,(D_2 M)\\big) + E_2 (D_2 M)

        The estimator removes all but 1e-3 to 1e-6 of an a priori error, so L M is far
        smaller than |L| |M|: formed right to left, the triangular solve acts on what is left
        and keeps its relative accuracy, where the product of a formed L with M would carry
        L's rounding times that ratio.
        """
        n_1 = self.fit.n_1
        D1, D2 = self.fit.D[:n_1], self.fit.D[n_1:]
        d2m = D2 @ M
        return self.fit.E[:, :n_1] @ self._solve(self.A @ (D1 @ M) - self.Y @ d2m) \
            + self.fit.E[:, n_1:] @ d2m

    def noise_factor(self, Rt: np.ndarray) -> np.ndarray:
        """Return a factor of ¹Λ⁰⁰ (R̃ᵀR̃) ¹Λ⁰⁰ for a data factor R̃ (m, n_o): R̃ F Fᵀ as
        (R̃E₁) R₁₁⁻¹ R₁₁⁻ᵀ E₁ᵀ by two solves on R̃E₁ (R̃ F cancels: the data weigh what the
        fit has just determined), with at most n_o rows."""
        E1 = self.fit.E[:, :self.fit.n_1]
        k = (E1 @ self._solve(self._solve((np.atleast_2d(Rt) @ E1).T, "T"))).T
        return triangularize(k) if k.shape[0] > k.shape[1] else k

    @property
    def L(self) -> np.ndarray:
        """L = ∂(a posteriori error)/∂(a priori error) (n_o, n_o) (e)."""
        return self.apply_L(np.eye(self.fit.D.shape[0]))

    @property
    def S1_00(self) -> np.ndarray:
        """¹S₀₀ (n_o, n_o), 1/(u_a u_b)."""
        return gram(self.R_S1)

    @property
    def S1_11(self) -> np.ndarray:
        """¹S₁₁ (n_1, n_1)."""
        return gram(self.R11)

    @property
    def Lambda1_11(self) -> np.ndarray:
        """¹Λ¹¹ = R₁₁⁻¹R₁₁⁻ᵀ (n_1, n_1) (c)."""
        return gram(self._solve(np.eye(self.R11.shape[0])).T)

    @property
    def Lambda1_00(self) -> np.ndarray:
        """¹Λ⁰⁰ = F Fᵀ (n_o, n_o) (d), u_a u_b."""
        return gram(self.F.T)

    @property
    def Lambda_real(self) -> np.ndarray:
        """¹Λ̄⁰⁰ (n_o, n_o) (f), u_a u_b."""
        return gram(self.U_real)

    @property
    def Sigma(self) -> np.ndarray:
        """Σ = ¹Λ⁰⁰J̃₀₀¹Λ⁰⁰ (n_o, n_o), u_a u_b."""
        return gram(self.K_sigma)


def _fit_factor(r11: np.ndarray) -> float:
    """Return κ of R₁₁ (unit-norm columns); raise SingularFitError below MIN_RCOND."""
    norms = np.sqrt(np.einsum("ij,ij->j", r11, r11))
    if r11.size == 0:
        return 1.0
    if np.any(~np.isfinite(norms)) or np.any(norms == 0):
        bad = int(np.argmax(~(np.isfinite(norms) & (norms > 0))))
        direction = np.zeros(norms.size)
        direction[bad] = 1.0
        raise SingularFitError(0.0, direction)
    _, s, vt = np.linalg.svd(r11 / norms, full_matrices=False)
    rcond = float(s[-1] / s[0])
    if not rcond >= MIN_RCOND:
        raise SingularFitError(rcond, vt[-1])
    return 1.0 / rcond


def regression(fit: FitSystem, R_S, R_J, U=None, Rt=None) -> Regression:
    """Run the regression algorithm (seed §2.5) on factors: return outputs a)–f).

    Parameters
    ----------
    fit : the fit system (D, E, n_1).
    R_S : (m_s, n_o) factor of the extended FW a priori normal matrix S₀₀.
    R_J : (m_j, n_o) factor of AᵀWA of the data (m_j = 0: no data).
    U : (m_u, n_o) factor of the RW a priori covariance Λ̄⁰⁰, or None (no f).
    Rt : (m_t, n_o) factor of AᵀWMWA of the data, or None (no f, no Σ).

    Raises
    ------
    SingularFitError
        If R₁₁ is singular to working precision (:data:`MIN_RCOND`).

    Examples
    --------
    One parameter, a priori σ = 2 in both worlds, one measurement of σ = 1 (fit) and
    σ = 2 (real): fit variance 1/(1/4 + 1) = 0.8, real 0.2²·4 + 0.8²·4 = 2.72.

    >>> r = regression(FitSystem.from_columns([[1.0]]), [[0.5]], [[1.0]], [[2.0]], [[2.0]])
    >>> round(float(r.Lambda1_11[0, 0]), 12), round(float(r.Lambda_real[0, 0]), 12)
    (0.8, 2.72)
    """
    R_S, R_J = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (R_S, R_J))
    n_1 = fit.n_1
    E1, E2 = fit.E[:, :n_1], fit.E[:, n_1:]
    m_s, m_j, n_2 = R_S.shape[0], R_J.shape[0], E2.shape[1]
    rse1 = R_S @ E1
    array = np.zeros((m_s + m_j, n_1 + m_s + n_2))
    array[:m_s, :n_1] = rse1
    array[:m_s, n_1:n_1 + m_s] = np.eye(m_s)
    array[m_s:, :n_1] = R_J @ E1
    array[m_s:, n_1 + m_s:] = R_J @ E2
    top = linalg.qr(array, mode="r", overwrite_a=True, check_finite=False)[0][:n_1]
    if top.shape[0] < n_1:
        top = np.vstack([top, np.zeros((n_1 - top.shape[0], top.shape[1]))])
    top *= np.where(np.diagonal(top[:, :n_1]) < 0, -1.0, 1.0)[:, None]
    r11 = np.triu(top[:, :n_1])
    kappa = _fit_factor(r11)
    X, Y = top[:, n_1:n_1 + m_s], top[:, n_1 + m_s:]
    F = linalg.solve_triangular(r11, E1.T, trans="T", check_finite=False).T  # E₁R₁₁⁻¹
    reg = Regression(fit, np.vstack([R_S, R_J]), r11, F, X @ rse1, Y, None, None, kappa)
    if Rt is None:
        return reg
    K_sigma = reg.noise_factor(np.asarray(Rt, dtype=float))
    U_real = None
    if U is not None:
        U = np.atleast_2d(np.asarray(U, dtype=float))
        U_real = np.vstack([reg.apply_L(U.T).T, K_sigma])
    return dataclasses.replace(reg, U_real=U_real, K_sigma=K_sigma)


__all__ = ["MIN_RCOND", "FitSystem", "Regression", "SingularFitError", "regression"]

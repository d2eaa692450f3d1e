"""Estimation kernels in square-root information form (NumPy and SciPy only).

:mod:`.factors` holds the factor algebra (triangularising stacked factors by Householder QR,
products of factors, factors of given matrices, the whitening of exponentially correlated
noise); :mod:`.regression` the regression to a constrained parameter set of TAPP III (seed
§2.5) on factors: the fit world's a posteriori information and covariance, the estimator's
map L and the real world's covariance, each positive semi-definite by construction.

A symmetric positive semi-definite matrix M is carried as a factor K (m x n, any m) with
M = KᵀK: a square-root information matrix R for a normal matrix (AᵀWA = RᵀR), a
square-root covariance for a covariance. Forming M squares the condition number of the data;
the factor keeps it (Bierman, *Factorization Methods for Discrete Sequential Estimation*,
1977, ch. V).
"""

from tapp.estimation.factors import (
    gram,
    psd_factor,
    triangularize,
)
from tapp.estimation.regression import FitSystem, Regression, SingularFitError, regression

__all__ = ["FitSystem", "Regression", "SingularFitError", "gram", "psd_factor", "regression",
           "triangularize"]

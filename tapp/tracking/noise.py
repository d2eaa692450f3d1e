"""Fit-world and real-world measurement noise, and the per-pass normal matrices AᵀWA, AᵀWMWA.

TAPP I hands TAPP III two normal matrices per (record, station): the fit world's

.. math:: \\Delta J = A^T W A,\\qquad W = \\mathrm{diag}(1/\\sigma_i^2)

(seed TAPP III eq. 2-20, W = J_rr: the weights the orbit fit assumes, white noise of stated σ),
and the real world's

.. math:: \\Delta\\tilde J = A^T W M W A

(eq. 2-45, M = Σ^rr: the covariance the noise truly has). The real world here is white noise of
its own σ_w, plus a constant bias per pass of σ_b, plus an exponentially correlated (first-order
Gauss-Markov) noise of σ_c and time constant τ, independent of each other, between observable
kinds and between stations. Within one pass of one kind at times t_1 < ... < t_n:

.. math::

    M_{ab} = \\sigma_w^2\\,\\delta_{ab} + \\sigma_b^2
             + \\sigma_c^2\\,e^{-|t_a - t_b|/\\tau}.

With B = W A (rows scaled by the weights) and s = Bᵀ1,

.. math::

    A^T W M W A = \\sigma_w^2 B^T B + \\sigma_b^2\\, s s^T + \\sigma_c^2\\,(B^T F + F^T B - B^T B),
    \\qquad F = L B,\\ L_{ab} = e^{-(t_a - t_b)/\\tau}\\ (b \\le a),

because the exponential kernel is K = L + Lᵀ - I. F follows from the recursion
F_1 = B_1, F_a = B_a + e^{-(t_a - t_{a-1})/τ} F_{a-1}: O(n) per pass, no n x n matrix (the
Markov property of the process; e.g. Maybeck, *Stochastic Models, Estimation and Control*
vol. 1, 1979, §4.11). The result is exact, not a diagonal approximation, and exactly
symmetric as written.

Units: σ of each kind in the unit of ``tapp.measurements.OBSERVABLE_UNITS`` (km, km/s, rad),
τ in s. At the edges (scenario files) σ are in m, mm/s and deg (:data:`EDGE_UNITS`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tapp.errors import InputError
from tapp.measurements import OBSERVABLE_UNITS, Observable

#: The parts of the real-world AᵀWMWA (:func:`normal_matrix_parts`), in their order.
PARTS = ("white", "bias", "correlated")

#: Edge unit of each observable kind's noise in scenario files, and the factor to the internal
#: unit: σ_internal = σ_edge * factor (m -> km, mm/s -> km/s, deg -> rad).
EDGE_UNITS: dict[str, tuple[str, float]] = {
    "range": ("m", 1e-3),
    "range_rate": ("mm_s", 1e-6),
    "azimuth": ("deg", math.pi / 180.0),
    "elevation": ("deg", math.pi / 180.0),
}


def _check_kind(kind: str, where: str) -> str:
    if kind not in EDGE_UNITS:
        raise InputError(where, "kind", f"one of {', '.join(EDGE_UNITS)}", kind)
    return kind


def _check_sigma(value: float, where: str, field: str, *, positive: bool) -> None:
    ok = math.isfinite(value) and (value > 0 if positive else value >= 0)
    if not ok:
        raise InputError(where, field, "a finite number " + ("> 0" if positive else ">= 0"),
                         value)


@dataclass(frozen=True, slots=True)
class FitNoise:
    """Fit-world noise of one observable kind at one station: white, standard deviation σ.

    Attributes
    ----------
    kind : str
        Observable kind ("range", "range_rate", "azimuth", "elevation").
    sigma : float
        Standard deviation, > 0, in the kind's unit (:attr:`unit`).
    """

    kind: str
    sigma: float

    def __post_init__(self) -> None:
        _check_kind(self.kind, "FitNoise")
        _check_sigma(self.sigma, "FitNoise", f"sigma ({self.kind})", positive=True)

    @property
    def unit(self) -> str:
        """Unit of σ (km, km/s or rad)."""
        return OBSERVABLE_UNITS[Observable(self.kind)]

    @property
    def weight(self) -> float:
        """Weight 1/σ², in 1/unit²."""
        return 1.0 / self.sigma**2


@dataclass(frozen=True, slots=True)
class RealNoise:
    """Real-world noise of one observable kind at one station (module docstring for M).

    Attributes
    ----------
    kind : str
        Observable kind.
    sigma_white : float
        White-noise standard deviation σ_w >= 0, in the kind's unit.
    sigma_pass_bias : float
        Standard deviation σ_b >= 0 of a bias constant over each pass, in the kind's unit.
    sigma_correlated : float
        Standard deviation σ_c >= 0 of the exponentially correlated noise, in the kind's unit.
    tau_s : float
        Its time constant τ, s (> 0 when σ_c > 0; ignored otherwise).
    """

    kind: str
    sigma_white: float
    sigma_pass_bias: float = 0.0
    sigma_correlated: float = 0.0
    tau_s: float = math.inf

    def __post_init__(self) -> None:
        _check_kind(self.kind, "RealNoise")
        for name in ("sigma_white", "sigma_pass_bias", "sigma_correlated"):
            _check_sigma(getattr(self, name), "RealNoise", f"{name} ({self.kind})",
                         positive=False)
        if self.sigma_correlated > 0 and not (self.tau_s > 0 and not math.isnan(self.tau_s)):
            raise InputError("RealNoise", f"tau_s ({self.kind})",
                             "a time constant > 0 with correlated noise", self.tau_s)

    @classmethod
    def like(cls, fit: FitNoise, factor: float = 1.0) -> RealNoise:
        """Return white real-world noise of ``factor`` times the fit world's σ."""
        return cls(fit.kind, factor * fit.sigma)


def exponential_kernel_lower(b, t_s, tau_s: float) -> np.ndarray:
    """Return F = L B with L_ab = exp(-(t_a - t_b)/τ) for b <= a, shape (n, p); O(n p).

    .. math:: F_1 = B_1,\\qquad F_a = B_a + e^{-(t_a - t_{a-1})/\\tau} F_{a-1}

    Parameters
    ----------
    b : array_like, shape (n, p)
        Rows at the times ``t_s``.
    t_s : array_like, shape (n,)
        Non-decreasing times, s.
    tau_s : float
        Time constant, s, > 0 (``inf`` gives the running sum).
    """
    b = np.asarray(b, dtype=float)
    t = np.asarray(t_s, dtype=float)
    decay = np.exp(-np.diff(t) / tau_s)
    out = np.empty_like(b)
    if b.shape[0] == 0:
        return out
    out[0] = b[0]
    for a in range(1, b.shape[0]):
        out[a] = b[a] + decay[a - 1] * out[a - 1]
    return out


def covariance_block(t_s, real: RealNoise) -> np.ndarray:
    """Return the dense real-world covariance M of one pass of one kind, shape (n, n).

    For checks and small arcs only: :func:`normal_matrices` never forms it.

    Parameters
    ----------
    t_s : array_like, shape (n,)
        Observation times of the pass, s.
    real : RealNoise
        The real-world model.
    """
    t = np.asarray(t_s, dtype=float)
    m = np.full((t.size, t.size), real.sigma_pass_bias**2)
    m[np.diag_indices(t.size)] += real.sigma_white**2
    if real.sigma_correlated > 0:
        m += real.sigma_correlated**2 * np.exp(-np.abs(t[:, None] - t[None, :]) / real.tau_s)
    return m


def normal_matrix_parts(a, t_s, weights, real: RealNoise) -> tuple[np.ndarray, np.ndarray]:
    r"""Return AᵀWA (n_o, n_o) and AᵀWMWA split into its :data:`PARTS`, (3, n_o, n_o).

    The three terms of the module docstring's formula, for one pass of one observable kind:

    .. math::

        \tilde J_{white} = \sigma_w^2 B^T B,\quad
        \tilde J_{bias} = \sigma_b^2\, s s^T,\quad
        \tilde J_{corr} = \sigma_c^2\,(B^T F + F^T B - B^T B),

    each exactly symmetric as written, summing to AᵀWMWA (:func:`normal_matrices`). A term
    whose σ is zero is a zero matrix.

    Parameters
    ----------
    a : array_like, shape (n, n_o)
        Partials of the n observations w.r.t. the n_o parameters (one kind, one station).
    t_s : array_like, shape (n,)
        Their times, s, non-decreasing.
    weights : array_like, shape (n,)
        Fit-world weights 1/σ², 1/unit².
    real : RealNoise
        Real-world noise of the kind at the station.

    Returns
    -------
    j_fit : (n_o, n_o) AᵀWA, 1/(u_a u_b).
    parts : (3, n_o, n_o) white, per-pass bias and exponentially correlated parts of
        AᵀWMWA, 1/(u_a u_b).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(weights, dtype=float)[:, None] * a
    j_fit = a.T @ b
    btb = b.T @ b
    parts = np.zeros((len(PARTS), a.shape[1], a.shape[1]))
    parts[0] = real.sigma_white**2 * btb
    if real.sigma_pass_bias > 0:
        s = b.sum(axis=0)
        parts[1] = real.sigma_pass_bias**2 * np.outer(s, s)
    if real.sigma_correlated > 0:
        btf = b.T @ exponential_kernel_lower(b, t_s, real.tau_s)
        parts[2] = real.sigma_correlated**2 * (btf + btf.T - btb)
    return 0.5 * (j_fit + j_fit.T), parts


def normal_matrices(a, t_s, weights, real: RealNoise) -> tuple[np.ndarray, np.ndarray]:
    """Return (AᵀWA, AᵀWMWA), each (n_o, n_o), of one pass of one observable kind.

    Equations in the module docstring; M is block-diagonal over passes and kinds, so the
    normal matrices of an arc are the sums of these. AᵀWMWA is the sum of the parts of
    :func:`normal_matrix_parts`.

    Parameters
    ----------
    a : array_like, shape (n, n_o)
        Partials of the n observations w.r.t. the n_o parameters (one kind, one station).
    t_s : array_like, shape (n,)
        Their times, s, non-decreasing.
    weights : array_like, shape (n,)
        Fit-world weights 1/σ², 1/unit².
    real : RealNoise
        Real-world noise of the kind at the station.
    """
    j_fit, parts = normal_matrix_parts(a, t_s, weights, real)
    return j_fit, parts.sum(axis=0)

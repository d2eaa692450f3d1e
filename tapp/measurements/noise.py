"""Fit-world and real-world measurement noise, and the per-pass square-root information.

TAPP I hands TAPP III the data of each (record, station) in two worlds. The fit world's
normal matrix

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

Neither matrix is formed: each is given by rows whose Gram matrix it is (square-root
information, :mod:`tapp.estimation.factors`). With B = W A (rows scaled by the weights),

.. math::

    \\Delta J = (W^{1/2}A)^T (W^{1/2}A),\\qquad
    \\Delta\\tilde J = \\underbrace{(\\sigma_w B)^T(\\sigma_w B)}_{white}
      + \\underbrace{(\\sigma_b\\,1^T B)^T(\\sigma_b\\,1^T B)}_{bias}
      + \\underbrace{(\\sigma_c\\,C^T B)^T(\\sigma_c\\,C^T B)}_{correlated},

C the Cholesky factor of the unit exponential kernel, whose rows CᵀB follow from a backward
recursion, O(n) per pass (:func:`tapp.estimation.factors.ar1_whitened`; the Markov property
of the process). The result is exact, not a diagonal approximation. TAPP I triangularises the
rows of each (record, station) by Householder QR (T13 version 3).

Units: σ of each kind in the unit of ``tapp.measurements.OBSERVABLE_UNITS`` (km, km/s, rad),
τ in s. At the edges (scenario files) σ are in m, mm/s and deg (:data:`EDGE_UNITS`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tapp.errors import InputError
from tapp.estimation.factors import ar1_whitened, gram
from tapp.estimation.gauss_markov import gauss_markov_covariance
from tapp.measurements import OBSERVABLE_UNITS, Observable
from tapp.measurements.ddor import DDOR_KIND, DDOR_UNIT

#: Names of the parts of the real-world information AᵀWMWA, in the order of
#: :attr:`PassRows.parts`: white noise, per-pass bias, exponentially correlated noise. The T13
#: tape stores the parts' factors in this order (``pairs/Rt_parts``, attribute ``parts``) and
#: TAPP III names the noise sources of its error budget by them.
PARTS: tuple[str, str, str] = ("white", "bias", "correlated")
WHITE, BIAS, CORRELATED = PARTS

#: Edge unit of each observable kind's noise in scenario files, and the factor to the internal
#: unit: σ_internal = σ_edge * factor (m -> km, mm/s -> km/s, deg -> rad).
EDGE_UNITS: dict[str, tuple[str, float]] = {
    "range": ("m", 1e-3),
    "range_rate": ("mm_s", 1e-6),
    "azimuth": ("deg", math.pi / 180.0),
    "elevation": ("deg", math.pi / 180.0),
    "doppler": ("mm_s", 1e-6),
}


def _check_kind(kind: str, where: str) -> str:
    # ΔDOR is a baseline's kind: its noise is in [ddor], not [noise] (tapp.tracking.ddor).
    if kind not in EDGE_UNITS and kind != DDOR_KIND:
        raise InputError(where, "kind", f"one of {', '.join((*EDGE_UNITS, DDOR_KIND))}", kind)
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
        """Unit of σ (km, km/s or rad; ΔDOR: km, or rad when given as an angle)."""
        if self.kind == DDOR_KIND:
            return DDOR_UNIT
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
        m += gauss_markov_covariance(t, real.sigma_correlated, real.tau_s)
    return m


@dataclass(frozen=True, slots=True, eq=False)
class PassRows:
    """Rows whose Gram matrices are a pass's normal matrices (module docstring).

    Attributes
    ----------
    fit : (n, n_o) W^{1/2} A: fitᵀfit = AᵀWA, 1/(u_a u_b).
    parts : the :data:`~tapp.io.tape.t13.PARTS` of AᵀWMWA: white (n, n_o), bias (1, n_o) and
        correlated (n, n_o) rows ((0, n_o) where that σ is zero); their Grams sum to AᵀWMWA.
    """

    fit: np.ndarray
    parts: tuple[np.ndarray, np.ndarray, np.ndarray]


def pass_rows(a, t_s, weights, real: RealNoise) -> PassRows:
    """Return the fit-world and real-world rows of one pass of one observable kind.

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
    a = np.asarray(a, dtype=float)
    w = np.asarray(weights, dtype=float)
    b = w[:, None] * a
    empty = np.zeros((0, a.shape[1]))
    white = real.sigma_white * b if real.sigma_white > 0 else empty
    bias = real.sigma_pass_bias * b.sum(axis=0)[None] if real.sigma_pass_bias > 0 else empty
    corr = (real.sigma_correlated * ar1_whitened(b, t_s, real.tau_s)
            if real.sigma_correlated > 0 else empty)
    return PassRows(np.sqrt(w)[:, None] * a, (white, bias, corr))


def normal_matrices(a, t_s, weights, real: RealNoise) -> tuple[np.ndarray, np.ndarray]:
    """Return (AᵀWA, AᵀWMWA), each (n_o, n_o), of one pass of one observable kind.

    The Gram matrices of :func:`pass_rows` (for readers and checks: the tape carries the
    factors). M is block-diagonal over passes and kinds, so the normal matrices of an arc
    are the sums of these.
    """
    rows = pass_rows(a, t_s, weights, real)
    return gram(rows.fit), sum(gram(p) for p in rows.parts)

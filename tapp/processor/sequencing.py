"""The sequence of operations of TAPP III (seed §4.3, Figure C-4): T13 records in, outputs out.

Each cycle k = 0, 1, ..., n_IT runs four phases in order:

1. **Update** (PH = 1): when record k+1 is referred to a new epoch (j_T ≠ j), the stored
   quantities are re-referred to x^k = [p^k; q] by the standard update commands (UPC, Table
   B-5) through the executive: V, W, B ← ·∂x/∂x^k; J, J̃, S ← (∂x/∂x^k)ᵀ · (∂x/∂x^k);
   Λ̄ ← (∂x^k/∂x) Λ̄ (∂x^k/∂x)ᵀ; then U ← I and j ← k.
2. **Print output** (PH = 2) at the print times: the current statistics (k = 0: the Statistical
   Input Program, S' = |0,0,f1) S₀ (0,0,f1|, Λ̄' = |1,0,r1) Λ₀ (1,0,r1|; otherwise the
   Statistical Output Program = the regression algorithm of §2.5 with E = |1,0,f1)), then the
   print commands (POC) through the executive.
3. **Recycle** (PH = 3) at k = 0 (the initialisation, which puts the a priori in place) and at
   the recycle times: the statistics, the recycle commands (ROC) printed (δ_P) and written to
   the T32 tape (δ_T), then l ← k, V ← U, S ← S', Λ̄ ← Λ̄', J, J̃ ← 0.
4. **Tape read-in** (PH = 4): k, INFO and U of record k+1; J += ΔJ and J̃ += ΔJ̃ for every
   station whose time-station flag Δ_TS(k+1, s) is 1.

**Square-root information.** Every symmetric matrix of the machine is held as a factor
(:mod:`tapp.estimation`): J = R_JᵀR_J, J̃ = R̃ᵀR̃ and S = R_SᵀR_S as square-root
information, Λ̄ = UᵀU as a square-root covariance. Reading in a pair stacks its factors
(T13 carries them from version 3) under the running ones and triangularises the stack by
Householder QR; an update command maps a factor, K ← K Xᵀ (in twice the working precision:
:func:`tapp.estimation.factors.accurate_map`); the statistics are the
regression on factors (:func:`tapp.estimation.regression`), and an output entity
X₁ M X₂ᵀ is (K X₁ᵀ)ᵀ (K X₂ᵀ). No normal matrix is summed, no inverse formed and no
covariance subtracted, so the results keep the digits of the data rather than losing twice
the logarithm of their condition number; each printed covariance states the digits it holds
(:attr:`tapp.processor.executive.Entity.digits`).

A QR is backward stable column by column in the representation it runs in, and an epoch
change after a swing-by is ill-conditioned (cond 1e13): a factor triangularised at the old
epoch and then mapped carries that rounding times the condition. So the factors are mapped
first and triangularised in the new epoch: the records read since the last statistics time
are stacked only after the map, and the results of a regression stay stacked (up to
:data:`COMPACT_ROWS` n_o rows) until the next epoch change maps them. This held the
deep-space covariances after the periapsis epoch to 1e-10 of their scale, where
triangularising first left 1e-9.

Records are read lazily in blocks (the factors stay packed until they are stacked), so
memory does not grow with the tape. Departures from the seed, each an addition: with δ_PM = 0
(no print output) the statistics are still formed and updated at recycles, since the T32 tape
carries them; Λ' at k = 0 is formed from the a priori when it can be.

**Error budget.** The estimate error is linear in its sources: δ'x = G δx₀ + Σ_s (noise of
source s), with δx₀ the a priori error at injection (covariance E₃Λ₀E₃ᵀ) and s = (station,
part) for the white, per-pass bias and correlated parts of J̃ (the tape's ``pairs/Rt_parts``;
one "total" part per station when a tape has none). The a priori part is split into groups g
of uncertain parameters: the sequencer carries the map G_g = G E₃[:, g] K_gᵀ of each group's
whitened error (K_gᵀK_g = Λ₀[g, g]; G_g ← L G_g at every regression, applied right to left,
and ← T G_g on an epoch change) and a factor K_s of each noise source's covariance
(C_s ← L C_s Lᵀ + Λ' J̃_s Λ', K_s ← QR of [K_s Lᵀ; R̃_s Λ']), so
Λ̄' = Σ_g G_g G_gᵀ + Σ_s K_sᵀK_s when Λ₀ does not correlate groups; when it does, the whole
map G E₃ K₀ᵀ is carried too and the cross-correlations between groups are one more source,
its share beyond the groups, so the variances add up to the printed diagonal.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from threadpoolctl import threadpool_limits

from tapp.errors import InputError
from tapp.estimation.factors import (
    accurate_map,
    digits_held,
    gram,
    map_growth,
    product_unit,
    psd_factor,
    triangularize,
)
from tapp.estimation.regression import FitSystem, SingularFitError, regression
from tapp.frames.ric import RIC_NAMES, ric_state_rotation, rotate_covariance, rotate_rows
from tapp.io.tape.packing import tr_nonzero_rows, upper_from_tr
from tapp.io.tape.t13 import T13Header
from tapp.io.tape.t32 import T32Entity, T32Recycle
from tapp.measurements.noise import PARTS, WHITE
from tapp.processor.commands import UPC, Command
from tapp.processor.executive import Budget, Entity, evaluate, transform
from tapp.processor.plan import Plan
from tapp.processor.representations import (
    ISOLATED_SETS,
    ORBIT_SETS,
    SYSTEM_PARTITIONS,
    SYSTEMS,
    Accumulator,
    Stored,
    orbit_link,
)

#: Pairs read from the tape at a time (bounds the memory of a block of packed factors).
PAIRS_PER_BLOCK = 2048
#: Condition number of a transition's orbit block up to which factors are mapped to a new
#: epoch by a plain product (losing at most cond ε ≈ 2e-12 of their columns); beyond it the
#: product is formed in twice the working precision (the deep-space periapsis: 4.5e13).
PLAIN_MAP_COND = 1e4
#: Rows (times n_o) beyond which a running factor is triangularised at once; below, it stays
#: stacked until the next epoch change maps it and it is triangularised in the new epoch.
COMPACT_ROWS = 4
#: The budget source of the a priori correlations between groups of parameters.
CROSS = "correlations between a priori groups"
#: The error estimate of a covariance is ERROR_PER_KAPPA κ (ε + η) on its scale √(C_ii C_jj),
#: κ the largest condition number of a scaled fit factor R₁₁ it came from (every regression
#: since the injection, through the recycles) and η what the epoch changes added to the
#: column-wise backward error ε a Householder QR leaves (:meth:`Processor._digits`): the QR
#: and triangular-solve bounds grow like a small multiple of ε κ. Checked against exact
#: arithmetic with forward maps only on the deep-space study, whose largest ratio of error
#: to ε κ is 2.0 (1.7 with its stochastic accelerations; tests/tapp/processor/
#: test_reference.py).
ERROR_PER_KAPPA = 16.0
EPS = float(np.finfo(float).eps)


def _plain_map(k: np.ndarray, x: np.ndarray, x_lo: np.ndarray | None = None) -> np.ndarray:
    """K Xᵀ as a plain product (X_lo, below X's rounding, is immaterial here)."""
    return k @ x.T


class _Growth:
    """The growth (:func:`tapp.estimation.factors.map_growth`) of each stack of factors an
    epoch change maps block by block: the squared column norms of its blocks before and after
    the map, summed (a QR keeps column norms, so the stack's are the root of the sums).

    An information stack (S, J, J̃) enters the statistics only through its fitted columns,
    K E₁ (:mod:`tapp.estimation.regression`: R_S E₁, R_J E₁, R̃ E₁; the rest reaches the
    outputs multiplied by those), so its growth is that of the map K → K Xᵀ E₁; a covariance
    stack's is that of all its columns.
    """

    def __init__(self, e1: np.ndarray) -> None:
        self.e1 = e1
        self._stacks: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def mapper(self, stack: str, mapper: Callable[..., np.ndarray], *, information: bool
               ) -> Callable[..., np.ndarray]:
        """``mapper`` that also adds the blocks it maps to ``stack``."""
        def mapped(k: np.ndarray, x: np.ndarray, x_lo: np.ndarray | None = None) -> np.ndarray:
            out = mapper(k, x, x_lo)
            seen, terms = (out @ self.e1, np.abs(self.e1.T) @ np.abs(x)) if information else \
                (out, np.abs(x))
            before, after, _ = self._stacks.get(stack, (0.0, 0.0, terms))
            self._stacks[stack] = (before + np.einsum("ij,ij->j", k, k),
                                   after + np.einsum("ij,ij->j", seen, seen), terms)
            return out
        return mapped

    def largest(self) -> float:
        """The largest growth of any stack (0 when none was mapped)."""
        return max((map_growth(np.sqrt(before), terms, np.sqrt(after))
                    for before, after, terms in self._stacks.values()), default=0.0)


class TrackingData(Protocol):
    """What the processor reads: a T13 header and its pair factors by record range
    (a T13 file opened by :func:`tapp.io.tape.t13_hdf5.open_t13`, or
    :func:`tapp.io.tape.t13.memory_pairs`)."""

    header: T13Header

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True): ...


@dataclass(frozen=True, slots=True, eq=False)
class Block:
    """One output block of the O3 printout: heading i, j, l, k, INFO and the entities."""

    kind: str
    number: int
    j: int
    l: int
    k: int
    t_s: float
    info: np.ndarray
    entities: tuple[Entity, ...]


@dataclass(frozen=True, slots=True, eq=False)
class HistoryRow:
    """σ's at a statistics time: of the history partition and of the miss set, fit and real.

    ``miss_fit``/``miss_real`` are the (n_m, n_m) covariances of the miss set (None when the
    fit covariance is not defined, e.g. k = 0 without a full a priori); ``digits`` the
    significant digits these covariances hold (:attr:`Entity.digits`). ``ric_fit`` and
    ``ric_real`` (when the deck asks for RIC axes) are the σ of the orbit at t_k along the
    radial, in-track and cross-track axes of the nominal state, (6,) km and km/s in the order
    of :data:`tapp.frames.ric.RIC_NAMES`.
    """

    kind: str
    k: int
    t_s: float
    sigma_fit: np.ndarray | None
    sigma_real: np.ndarray
    miss_fit: np.ndarray | None
    miss_real: np.ndarray
    digits: float
    ric_fit: np.ndarray | None = None
    ric_real: np.ndarray | None = None


@dataclass(frozen=True, slots=True, eq=False)
class Run:
    """A processed tape: the O3 blocks, the σ history, the a priori, and the recycles as the
    T32 tape carries them (every n_o x n_o matrix in the representation x^k of its time).

    ``S0_fit_factor`` and ``Lambda0_real_factor`` are upper-triangular factors (n_o, n_o) of
    the a priori at injection: S⁰ = KᵀK (fit-world normal matrix), Λ̄⁰ = KᵀK (real-world
    covariance).
    """

    blocks: tuple[Block, ...]
    history: tuple[HistoryRow, ...]
    history_labels: tuple[str, ...]
    recycles: tuple[T32Recycle, ...]
    S0_fit_factor: np.ndarray
    Lambda0_real_factor: np.ndarray
    budget_sources: tuple[str, ...] = ()


@dataclass(slots=True)
class _Current:
    """Statistics at the current time (seed "current statistics", δ_CS = 1), as factors:
    S' = SᵀS, Λ̄' = LbᵀLb, Λ' = fitᵀfit, Σ = Sigmaᵀ Sigma, noise source s: K[s]ᵀK[s], a priori
    source g: apriori[g] apriori[g]ᵀ."""

    k: int
    S: np.ndarray
    Lb: np.ndarray
    L: np.ndarray
    fit: np.ndarray | None
    fit_error: InputError | None
    Sigma: np.ndarray
    apriori: list[np.ndarray]
    K: list[np.ndarray]
    kappa: float


class Processor:
    """The TAPP III machine on one tape (module docstring); run it with :meth:`run`."""

    def __init__(self, data: TrackingData, plan: Plan, source: str = "deck",
                 progress: Callable[[int, int], None] | None = None):
        self.data, self.plan, self.source, self.progress = data, plan, source, progress
        h = data.header
        self.h = h
        sy = plan.systems
        self.n_o, self.n_p = sy.n_o, sy.n_p
        self.n_it = int(h.records.k.size)
        self.miss_names = tuple(h.miss.name)
        eye = np.eye(self.n_p, self.n_o)
        self.stored = Stored(eye.copy(), eye.copy(), eye.copy(), eye.copy(),
                             np.array(h.miss.B, dtype=float))
        self.acc = Accumulator(sy, self.stored)
        self.RJ, self.RJt, self.RS, self.U = (self._empty() for _ in range(4))
        self.j, self.l, self.k = -1, 0, 0
        self.info = np.array(h.parameters.nominal[:self.n_p], dtype=float)
        self.current: _Current | None = None
        self.pending: list[int] = []
        self.station_ids = np.asarray(h.stations.id, dtype=np.int64)
        self.has_parts = True
        self.sources = [f"noise: {name} {part}" for name in h.stations.name
                        for part in PARTS]
        self.Rt_src = [self._empty() for _ in self.sources]
        self.apriori: list[np.ndarray] = []
        self.apriori_names: list[str] = []
        self.K = [self._empty() for _ in self.sources]
        self.kappa = 1.0
        self.map_error = 0.0
        self.blocks: list[Block] = []
        self.history: list[HistoryRow] = []
        self.recycles: list[T32Recycle] = []

    def _empty(self) -> np.ndarray:
        return np.zeros((0, self.n_o))

    # -----------------------------------------------------------------------------------------
    # Phase 4: tape read-in
    # -----------------------------------------------------------------------------------------

    def _keep(self, k: np.ndarray, station: np.ndarray) -> np.ndarray:
        keep = np.ones(k.size, dtype=bool)
        for off in self.plan.stations_off:
            keep &= ~((station == off.station) & (k >= off.k_first) & (k <= off.k_last))
        return keep

    def _rows(self, packed: np.ndarray, to: tuple | None = None,
              mapper: Callable[..., np.ndarray] = accurate_map) -> np.ndarray:
        """The stacked rows (m n_o, n_o) of m packed upper-triangular factors, mapped by
        ``to`` = (X, X_lo) (rows (X + X_lo)ᵀ by ``mapper``) when given; zero rows left
        out."""
        live = tr_nonzero_rows(packed, self.n_o).reshape(-1)
        stack = upper_from_tr(packed, self.n_o).reshape(-1, self.n_o)[live]
        return stack if to is None else mapper(stack, *to)

    def _flush(self, to: tuple[np.ndarray, np.ndarray | None] | None = None,
               mapper: Callable[..., np.ndarray] = accurate_map,
               growth: _Growth | None = None) -> None:
        """Stack the pending records' factors (flagged stations left out) under R_J, R̃;
        ``to`` (the update's adjoint and its remainder) maps their rows to a new epoch
        first, by ``mapper``, adding them to the stacks of ``growth``."""
        if not self.pending:
            return
        first, last = self.pending[0], self.pending[-1]
        self.pending.clear()
        n_ts = self.station_ids.size
        step = max(1, PAIRS_PER_BLOCK // max(1, n_ts))
        for a in range(first, last + 1, step):
            blk = self.data.pair_block(a, min(a + step - 1, last), parts=self.plan.budget)
            keep = self._keep(np.asarray(blk.k), np.asarray(blk.station))
            if not np.any(keep):
                continue
            info, noise = ((mapper, mapper) if growth is None else
                           (growth.mapper("information", mapper, information=True),
                            growth.mapper("real-world information", mapper, information=True)))
            self.RJ = triangularize(self.RJ, self._rows(blk.R[keep], to, info))
            self.RJt = triangularize(self.RJt, self._rows(blk.Rt[keep], to, noise))
            if self.plan.budget:
                self._budget_read(blk, keep, to, mapper)

    def _budget_read(self, blk, keep: np.ndarray, to: tuple | None = None,
                     mapper: Callable[..., np.ndarray] = accurate_map) -> None:
        station = np.asarray(blk.station)[keep]
        parts = None if blk.Rt_parts is None else blk.Rt_parts[keep]
        if parts is None:
            self.has_parts = False
        for pos, sid in enumerate(self.station_ids):
            mine = station == sid
            if not np.any(mine):
                continue
            for p in range(len(PARTS)):
                if parts is None and p > 0:
                    continue
                packed = blk.Rt[keep][mine] if parts is None else parts[mine, p]
                i = pos * len(PARTS) + p
                self.Rt_src[i] = triangularize(self.Rt_src[i], self._rows(packed, to, mapper))

    def _read(self, k: int) -> None:
        rec = self.h.records
        self.stored.U = np.array(rec.U[k - 1], dtype=float)
        self.info = np.array(rec.info[k - 1], dtype=float)
        self.acc.invalidate()
        self.pending.append(k)
        if len(self.pending) * max(1, self.station_ids.size) >= 8 * PAIRS_PER_BLOCK:
            self._flush()

    # -----------------------------------------------------------------------------------------
    # Phase 1: update
    # -----------------------------------------------------------------------------------------

    def _mapper(self) -> tuple[Callable[..., np.ndarray], float]:
        """How the factors are mapped to the new epoch, and the relative error per term of
        that product (:func:`tapp.estimation.factors.product_unit`): in twice the working
        precision (:func:`accurate_map`) when the orbit block of the transition is
        ill-conditioned (cond > :data:`PLAIN_MAP_COND`), else by a plain product, which then
        loses at most cond ε of the factors' columns."""
        if np.linalg.cond(self.stored.U[:, :self.n_p]) > PLAIN_MAP_COND:
            return accurate_map, product_unit(2 * self.n_o, accurate=True)
        return _plain_map, product_unit(self.n_o, accurate=False)

    def _digits(self, kappa: float) -> float:
        """Significant digits of a covariance from fits of condition numbers up to κ, after
        the epoch changes so far.

        .. math:: e = 16\\,\\kappa\\,(\\varepsilon + \\eta),\\qquad
            \\eta = \\sum_{\\text{epoch changes}} \\gamma \\max a

        A factor carries column-wise backward errors (ε of each column's norm from a
        Householder QR), and the fit turns them into covariance errors of about ε κ on the
        scale √(C_ii C_jj) (:mod:`tapp.estimation.regression`), in whatever representation
        the factors are then mapped to by an exact transition (a factor stays a factor). An
        epoch change adds what its products could not keep: the growth a of each stack of
        factors it maps (the information S, J and the records read; J̃ and its records; Λ̄:
        :func:`tapp.estimation.factors.map_growth`, the transition's conditioning as the
        factors see it) times the relative error γ per term of the product
        (:func:`tapp.estimation.factors.product_unit`). The stored partials (V, W, B) and the
        budget's factors are mapped alike but not counted: the printed entities are compared
        with exact arithmetic instead (tests/tapp/processor/test_reference.py).

        On the deep-space tape (n_o = 24, cond 4.5e13 at the periapsis epoch change) the
        growths reach 3.2e6: mapped in double length (γ ≈ 1e-28) that costs nothing, and the
        covariances after the periapsis claim 9.3 digits and hold 11.3 of the exact answer;
        mapped by plain products (γ = n_o u) they claim 1.7 digits and hold 7.7 (a bound:
        the growth takes every term at its largest). The old adjoint Γ P Γᵀ, inconsistent
        with P by ε cond P, held 5.1-5.6 digits while claiming 9.3.
        """
        return digits_held(ERROR_PER_KAPPA * kappa * (EPS + self.map_error))

    def _update(self, k: int) -> None:
        if k != 0:
            st = self.stored
            mapper, unit = self._mapper()
            growth = _Growth(self._fit_system().E[:, :self.plan.systems.n_f1])
            info = growth.mapper("information", mapper, information=True)
            mappers = (mapper, mapper, mapper, info,
                       growth.mapper("real-world information", mapper, information=True), info,
                       growth.mapper("real-world covariance", mapper, information=False))
            st.V, st.W, st.B, self.RJ, self.RJt, self.RS, self.U = (
                transform(cmd, self.acc, f, m)
                for cmd, f, m in zip(UPC, (st.V, st.W, st.B, self.RJ, self.RJt, self.RS, self.U),
                                     mappers, strict=True))
            t = self.acc.transformation(0, 1, 1)
            adj = (self.acc.transformation(1, 1, 1), self.acc.remainder(1, 1, "o"))
            self.apriori = [mapper(m.T, t).T for m in self.apriori]
            self.K = [mapper(f, t) for f in self.K]
            self.Rt_src = [mapper(f, *adj) for f in self.Rt_src]
            self._flush(adj, mapper, growth)  # pending records: mapped, then stacked
            self.RS, self.U, self.RJ, self.RJt = (triangularize(f, n=self.n_o) for f in
                                                  (self.RS, self.U, self.RJ, self.RJt))
            self.K = [triangularize(f, n=self.n_o) for f in self.K]
            self.Rt_src = [triangularize(f, n=self.n_o) for f in self.Rt_src]
            self.map_error += unit * growth.largest()
        self.stored.U = np.eye(self.n_p, self.n_o)
        self.j = k
        self.acc.invalidate()
        self.current = None

    # -----------------------------------------------------------------------------------------
    # Statistics (SIP, SOP)
    # -----------------------------------------------------------------------------------------

    def _t(self, k: int) -> float:
        return float(self.h.records.times_s[k])

    def _singular(self, k: int, exc: SingularFitError) -> InputError:
        names = self.acc.labels(0, "f1", self.miss_names)
        v = exc.direction
        order = np.argsort(-np.abs(v))
        terms = [f"{v[i]:+.2f} {names[i]}" for i in order[:6] if abs(v[i]) >= 0.05]
        return InputError(self.source, f"fit world at k = {k} (t = {self._t(k):.1f} s)",
                          "an invertible fit normal matrix ¹S₁₁ (give these parameters an a "
                          "priori σ, hold them fixed, or add data)",
                          f"reciprocal condition {exc.rcond:.2g}; near-null direction "
                          + " ".join(terms))

    def _fit_system(self) -> FitSystem:
        return FitSystem(self.acc.transformation(0, 0, 4),
                         self.acc.transformation(1, 0, 4).T, self.plan.systems.n_f1)

    def _statistics(self, k: int) -> _Current:
        if self.current is not None and self.current.k == k:
            return self.current
        self._flush()
        if k == 0:
            return self._apriori()
        try:
            reg = regression(self._fit_system(), self.RS, self.RJ, self.U, self.RJt)
        except SingularFitError as exc:
            raise self._singular(k, exc) from None
        K, apriori = self.K, self.apriori
        if self.plan.budget:
            K = [self._compact(np.vstack([reg.apply_L(k_s.T).T, reg.noise_factor(rt)]))
                 for k_s, rt in zip(self.K, self.Rt_src, strict=True)]
            apriori = [reg.apply_L(m) for m in self.apriori]
        self.current = _Current(k, self._compact(reg.R_S1), self._compact(reg.U_real), reg.L,
                                reg.F.T, None, reg.K_sigma, apriori, K,
                                max(self.kappa, reg.kappa))
        return self.current

    def _compact(self, f: np.ndarray) -> np.ndarray:
        """A factor with at most :data:`COMPACT_ROWS` n_o rows: triangularised beyond that,
        else left stacked until the next epoch change maps it (module docstring)."""
        return triangularize(f, n=self.n_o) if f.shape[0] > COMPACT_ROWS * self.n_o else f

    def _apriori(self) -> _Current:
        """Statistics at k = 0: the a priori (the Statistical Input Program)."""
        d1 = self.acc.partials(0, 0, "f1")
        e3 = self.acc.partials(1, 0, "r1").T
        self._apriori_sources(e3)
        self.RS = psd_factor(self.plan.S0) @ d1
        self.U = psd_factor(self.plan.Lambda0) @ e3.T
        self.S0_fit_factor = triangularize(self.RS, n=self.n_o)
        self.Lambda0_real_factor = triangularize(self.U, n=self.n_o)
        fit, error = None, None
        try:
            fit = regression(self._fit_system(), self.RS, self._empty()).F.T
        except SingularFitError as exc:
            error = self._singular(0, exc)
        self.current = _Current(0, self.RS, self.U, np.eye(self.n_o), fit, error,
                                self._empty(), self.apriori,
                                [self._empty() for _ in self.sources], 1.0)
        return self.current

    def _apriori_sources(self, e3: np.ndarray) -> None:
        """The a priori error sources of the budget: per group g of uncertain parameters the
        map E₃[:, g] K_gᵀ (K_gᵀK_g = Λ₀[g, g]) of its whitened error, and, when Λ₀ correlates
        groups, the whole E₃ K₀ᵀ last (its share beyond the groups is theirs together)."""
        n_p, n_r1 = self.n_p, self.plan.systems.n_r1
        lam0 = self.plan.Lambda0
        named = {i for _, idx in self.plan.budget_groups for i in idx}
        r1_names = self.plan.systems.system_names(6)
        groups = [("orbit (a priori)", tuple(range(n_p)))]
        groups += [(f"{name} (a priori)", idx) for name, idx in self.plan.budget_groups]
        groups += [(f"{r1_names[i]} (a priori)", (i,)) for i in range(n_p, n_r1)
                   if i not in named]
        block = np.zeros_like(lam0)
        self.apriori, self.apriori_names = [], []
        for name, idx in groups:
            ix = np.ix_(idx, idx)
            block[ix] = lam0[ix]
            self.apriori.append(e3[:, list(idx)] @ psd_factor(lam0[ix]).T)
            self.apriori_names.append(name)
        if np.any(lam0 != block):
            self.apriori.append(e3 @ psd_factor(lam0).T)
            self.apriori_names.append(CROSS)

    def _factor(self, cur: _Current) -> Callable[[str], np.ndarray]:
        def get(code: str) -> np.ndarray:
            if code == "L'":
                if cur.fit is None:
                    raise cur.fit_error
                return cur.fit
            return {"J": self.RJ, "Jt": self.RJt, "S": self.RS, "Lb": self.U, "S'": cur.S,
                    "Lb'": cur.Lb, "Sigma": cur.Sigma}[code]
        return get

    # -----------------------------------------------------------------------------------------
    # Error budget and accuracy
    # -----------------------------------------------------------------------------------------

    def _budget(self, x: np.ndarray, apriori: list[np.ndarray], k_src: list[np.ndarray],
                total: np.ndarray) -> Budget:
        """Per-source variances of the rows of X (Λ̄ or Λ̄') (module docstring)."""
        rows = [np.einsum("ij,ij->i", xm, xm) for xm in (x @ m for m in apriori)]
        if self.apriori_names[-1] == CROSS:
            rows[-1] = rows[-1] - np.sum(rows[:-1], axis=0)  # the whole minus the groups
        sources = list(self.apriori_names)
        for i, src in enumerate(self.sources):
            station, part = src.rsplit(" ", 1)
            if not self.has_parts:
                if part != WHITE:
                    continue
                src = f"{station} total"
            sources.append(src)
            rows.append(np.diagonal(gram(k_src[i], x)).copy())
        return Budget(tuple(sources), np.array(rows), total)

    def _entities(self, commands: tuple[Command, ...], cur: _Current) -> tuple[Entity, ...]:
        out = []
        factor = self._factor(cur)
        for omega, cmd in enumerate(commands, start=1):
            ent = evaluate(omega, cmd, self.acc, factor, self.miss_names)
            digits = None
            if cmd.is_covariance:
                kappa = self.kappa if cmd.sigma == "Lb" else cur.kappa
                digits = self._digits(kappa)
            ent = Entity(ent.omega, cmd, ent.rows, ent.cols, ent.matrix,
                         self._entity_budget(cmd, cur, ent.matrix), digits)
            rotation = self._ric_rotation(cmd, cur.k)
            if rotation is not None:
                matrix = rotate_covariance(rotation, ent.matrix)
                labels = (*(f"{n}@{ORBIT_SETS[self._orbit_time(cmd)]}" for n in RIC_NAMES),
                          *ent.rows[self.n_p:])
                ric = Entity(omega, cmd, labels, labels, matrix,
                             self._entity_budget(cmd, cur, matrix, rotation), digits)
                ent = Entity(ent.omega, cmd, ent.rows, ent.cols, ent.matrix, ent.budget, digits,
                             ric)
            out.append(ent)
        return tuple(out)

    def _entity_budget(self, cmd: Command, cur: _Current, matrix: np.ndarray,
                       rotation: np.ndarray | None = None) -> Budget | None:
        """The error budget of a real-world covariance entity (on one set of rows), its orbit
        rows rotated by ``rotation`` when given (the budget in RIC axes)."""
        if not (self.plan.budget and cmd.sigma in ("Lb", "Lb'") and cmd.rows == cmd.cols):
            return None
        x = self.acc.partials(cmd.rows.mu, cmd.rows.tau, cmd.rows.rho)
        if rotation is not None:
            x = rotate_rows(rotation, x)
        maps, k_src = (self.apriori, self.K) if cmd.sigma == "Lb" else (cur.apriori, cur.K)
        return self._budget(x, maps, k_src, np.diagonal(matrix).copy())

    # -----------------------------------------------------------------------------------------
    # RIC axes
    # -----------------------------------------------------------------------------------------

    def _orbit_time(self, cmd: Command) -> int | None:
        return self.plan.systems.orbit_time(cmd.rows.tau, cmd.rows.rho)

    def _state_at(self, k: int) -> np.ndarray:
        """The nominal state (6,) at T13 time index k, km and km/s (the tape's INFO; k = 0:
        the nominal orbit parameters at injection)."""
        if k == 0:
            return np.asarray(self.h.parameters.nominal[:self.n_p], dtype=float)
        return np.asarray(self.h.records.info[k - 1], dtype=float)

    def _ric_rotation(self, cmd: Command, k: int) -> np.ndarray | None:
        """blockdiag(T, T) of the nominal state at the time of a covariance entity's orbit
        rows, when the deck asks for RIC axes and the entity is a covariance (on one set of
        rows) that begins with a Cartesian orbit at one time; else None."""
        tau = self._orbit_time(cmd)
        if ("ric" not in self.plan.frames or not cmd.is_covariance or cmd.rows != cmd.cols
                or tau is None or self.n_p != len(RIC_NAMES)):
            return None
        return ric_state_rotation(self._state_at({0: self.j, 1: k, 2: self.l, 3: 0}[tau]))

    def _record_history(self, kind: str, k: int, cur: _Current) -> None:
        side = self.plan.history
        x = self.acc.partials(side.mu, side.tau, side.rho)
        real = np.sqrt(np.diagonal(gram(cur.Lb, x)))
        fit = None if cur.fit is None else np.sqrt(np.diagonal(gram(cur.fit, x)))
        b = self.stored.B
        miss_fit = None if cur.fit is None else gram(cur.fit, b)
        ric_fit = ric_real = None
        if "ric" in self.plan.frames and self.n_p == len(RIC_NAMES):
            x_ric = ric_state_rotation(self._state_at(k)) @ self.acc.partials(0, 1, "p")
            ric_real = np.sqrt(np.diagonal(gram(cur.Lb, x_ric)))
            ric_fit = None if cur.fit is None else np.sqrt(np.diagonal(gram(cur.fit, x_ric)))
        self.history.append(HistoryRow(kind, k, self._t(k), fit, real, miss_fit,
                                       gram(cur.Lb, b), self._digits(cur.kappa), ric_fit,
                                       ric_real))

    # -----------------------------------------------------------------------------------------
    # Phases 2 and 3
    # -----------------------------------------------------------------------------------------

    def _print(self, k: int, number: int) -> None:
        cur = self._statistics(k)
        self._record_history("print", k, cur)
        self.blocks.append(Block("print", number, self.j, self.l, k, self._t(k),
                                 self.info.copy(), self._entities(self.plan.print_commands,
                                                                  cur)))

    def _recycle(self, k: int, number: int) -> None:
        cur = self._statistics(k)
        if k != 0 and (self.plan.recycle_print or self.plan.recycle_tape):
            ents = self._entities(self.plan.recycle_commands, cur)
            if self.plan.recycle_print:
                self.blocks.append(Block("recycle", number, self.j, self.l, k, self._t(k),
                                         self.info.copy(), ents))
            if self.plan.recycle_tape:
                self._record_history("recycle", k, cur)
                self.recycles.append(self._t32_recycle(k, number, cur, ents))
        self.l = k
        self.stored.V = self.stored.U.copy()
        self.RS, self.U, self.apriori, self.K = cur.S, cur.Lb, cur.apriori, cur.K
        self.kappa = cur.kappa
        self.RJ, self.RJt = self._empty(), self._empty()
        self.Rt_src = [self._empty() for _ in self.sources]
        self.acc.invalidate()
        self.current = None

    def _t32_recycle(self, k: int, number: int, cur: _Current, ents) -> T32Recycle:
        t = self.acc.transformation(0, 1, 1)
        ta = self.acc.transformation(1, 1, 1)
        transition = accurate_map(t, self.acc.transformation(1, 2, 1),
                                  self.acc.remainder(1, 2, "o"))
        # The adjoint of the transition itself ([[P, Q], [0, I]] -> [[P*, 0], [-QᵀP*, I]]),
        # not of its two factors: a column of Q that is exactly 0 (a stochastic acceleration
        # whose interval ended before the last recycle) is the cancellation of sensitivities
        # of 1e10 km per km/s², and the two routes left different remainders of it (|TᵀA − I|
        # of 0.86 of the terms); from T's own blocks they cancel to rounding.
        adjoint = orbit_link(transition[:self.n_p], self.n_o, adjoint=True)
        fit = self._factor(cur)("L'")
        entities = tuple(T32Entity(e.omega, e.command.seed(), e.command.alias(), e.rows, e.cols,
                                   e.matrix) for e in ents)

        def mapped(f: np.ndarray, m: np.ndarray) -> np.ndarray:
            return triangularize(f @ m.T, n=self.n_o)

        return T32Recycle(
            number, k, self.l, self.j, self._t(k), self._t(self.l), self.info.copy(),
            S_fit_factor=mapped(cur.S, ta), Lambda_fit_factor=mapped(fit, t),
            Lambda_real_factor=mapped(cur.Lb, t), L=t @ cur.L @ ta.T,
            Sigma_factor=mapped(cur.Sigma, t), J_factor=mapped(self.RJ, ta),
            Jt_factor=mapped(self.RJt, ta), B=self.stored.B @ ta.T, transition=transition,
            transition_adjoint=adjoint, entities=entities)

    # -----------------------------------------------------------------------------------------

    def run(self) -> Run:
        """Process the whole tape (seed Figure C-4) and return the outputs.

        BLAS runs on one thread meanwhile (``threadpoolctl``): the factors are n_o x n_o,
        where threads cost more than they gain (a QR merge of two 50 x 50 triangles takes
        30 µs on one thread and up to 16 ms on two), and the rounding then does not depend on
        the number of threads either.
        """
        with threadpool_limits(limits=1, user_api="blas"):
            return self._run()

    def _run(self) -> Run:
        plan = self.plan
        prints = set(plan.print_k) if plan.print_statistics else set()
        recycles = {0, *plan.recycle_k}
        j_rec = np.asarray(self.h.records.j)
        i_print = i_recycle = 0
        for k in range(self.n_it + 1):
            if k < self.n_it and int(j_rec[k]) != self.j:
                self._update(k)
            if k in prints:
                i_print += 1
                self._print(k, i_print)
            if k in recycles:
                self._recycle(k, i_recycle)
                i_recycle += 1
            if k < self.n_it:
                self._read(k + 1)
            if self.progress is not None:
                self.progress(k, self.n_it)
        self._flush()  # read the tail too: every record's factors are checked once
        return Run(tuple(self.blocks), tuple(self.history),
                   tuple(self.acc.labels(plan.history.tau, plan.history.rho, self.miss_names)),
                   tuple(self.recycles), self.S0_fit_factor, self.Lambda0_real_factor,
                   tuple(self.sources))


def process(data: TrackingData, plan: Plan, *, source: str = "deck",
            progress: Callable[[int, int], None] | None = None) -> Run:
    """Run TAPP III on a tape (module docstring).

    Parameters
    ----------
    data : the tape's header and pair blocks.
    plan : the bound deck (:func:`tapp.processor.deck_bind.bind`).
    source : named in errors (the deck file).
    progress : called with (k, n_IT) after each cycle.

    Raises
    ------
    InputError
        A fit normal matrix that cannot be inverted (naming the time and the near-null
        direction), a print command asking Λ' where it is not defined.
    """
    return Processor(data, plan, source, progress).run()


__all__ = ["ISOLATED_SETS", "SYSTEMS", "SYSTEM_PARTITIONS", "Block", "HistoryRow", "Processor",
           "Run", "TrackingData", "process"]

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

Records are read lazily in blocks (the normal matrices stay packed until they are summed), so
memory does not grow with the tape. Departures from the seed, each an addition: with δ_PM = 0
(no print output) the statistics are still formed and updated at recycles, since the T32 tape
carries them; Λ' at k = 0 is formed from the a priori when it can be.

**Error budget.** The estimate error is linear in its sources: δ'x = G δx₀ + Σ_s (noise of
source s), with δx₀ the a priori error at injection (covariance E₃Λ₀E₃ᵀ) and s = (station,
part) for the white, per-pass bias and correlated parts of J̃ (the tape's ``pairs/dJt_parts``;
one "total" part per station when a tape has none). The sequencer carries G (G ← L G at every
regression, G ← T G on an epoch change) and each noise source's covariance
(C_s ← L C_s Lᵀ + Λ' J̃_s Λ'), so Λ̄' = G E₃Λ₀E₃ᵀ Gᵀ + Σ_s C_s; the a priori part is split
into groups of uncertain parameters, with the cross-correlations between groups as one more
source, so the variances add up exactly to the printed diagonal.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from tapp.errors import InputError
from tapp.processor.commands import UPC, Command
from tapp.processor.executive import Budget, Entity, evaluate
from tapp.processor.plan import Plan
from tapp.processor.regression import SingularFitError, regression, symmetric
from tapp.processor.representations import (
    ISOLATED_SETS,
    SYSTEM_PARTITIONS,
    SYSTEMS,
    Accumulator,
    Stored,
)
from tapp.tape.packing import unpack_tr
from tapp.tape.t32 import T32Entity, T32Recycle

#: Pairs read from the tape at a time (bounds the memory of a block of packed matrices).
PAIRS_PER_BLOCK = 2048
NOISE_PARTS = ("white", "bias", "correlated")


class TrackingData(Protocol):
    """What the processor reads: a T13 header and its pair matrices by record range
    (:func:`tapp.tape.t13_hdf5.open_t13` or :func:`tapp.tape.t13.memory_pairs`)."""

    header: object

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
    fit covariance is not defined, e.g. k = 0 without a full a priori).
    """

    kind: str
    k: int
    t_s: float
    sigma_fit: np.ndarray | None
    sigma_real: np.ndarray
    miss_fit: np.ndarray | None
    miss_real: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class Run:
    """A processed tape: the O3 blocks, the σ history, the a priori, and the recycles as the
    T32 tape carries them (every n_o x n_o matrix in the representation x^k of its time)."""

    blocks: tuple[Block, ...]
    history: tuple[HistoryRow, ...]
    history_labels: tuple[str, ...]
    recycles: tuple[T32Recycle, ...]
    S0_fit: np.ndarray
    Lambda0_real: np.ndarray
    budget_sources: tuple[str, ...] = ()


@dataclass(slots=True)
class _Current:
    """Statistics at the current time (seed "current statistics", δ_CS = 1)."""

    k: int
    S: np.ndarray
    Lb: np.ndarray
    L: np.ndarray
    fit: np.ndarray | None
    fit_error: InputError | None
    Sigma: np.ndarray
    G: np.ndarray
    C: np.ndarray


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
        zeros = np.zeros((self.n_o, self.n_o))
        self.J, self.Jt, self.S, self.Lb = zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy()
        self.j, self.l, self.k = -1, 0, 0
        self.info = np.array(h.parameters.nominal[:self.n_p], dtype=float)
        self.current: _Current | None = None
        self.pending: list[int] = []
        self.station_ids = np.asarray(h.stations.id, dtype=np.int64)
        self.has_parts = True
        self.sources = [f"noise: {name} {part}" for name in h.stations.name
                        for part in NOISE_PARTS]
        self.Jt_src = np.zeros((len(self.sources), self.n_o, self.n_o))
        self.G = np.eye(self.n_o)
        self.C = np.zeros_like(self.Jt_src)
        self.blocks: list[Block] = []
        self.history: list[HistoryRow] = []
        self.recycles: list[T32Recycle] = []

    # -----------------------------------------------------------------------------------------
    # Phase 4: tape read-in
    # -----------------------------------------------------------------------------------------

    def _keep(self, k: np.ndarray, station: np.ndarray) -> np.ndarray:
        keep = np.ones(k.size, dtype=bool)
        for off in self.plan.stations_off:
            keep &= ~((station == off.station) & (k >= off.k_first) & (k <= off.k_last))
        return keep

    def _flush(self) -> None:
        """Sum the pending records' ΔJ, ΔJ̃ (flagged stations left out) into J, J̃."""
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
            self.J += unpack_tr(blk.dJ[keep].sum(axis=0), self.n_o)
            self.Jt += unpack_tr(blk.dJt[keep].sum(axis=0), self.n_o)
            if self.plan.budget:
                self._budget_read(blk, keep)

    def _budget_read(self, blk, keep: np.ndarray) -> None:
        pos = np.searchsorted(self.station_ids, np.asarray(blk.station)[keep])
        onehot = np.zeros((self.station_ids.size, pos.size))
        onehot[pos, np.arange(pos.size)] = 1.0
        if blk.dJt_parts is None:
            self.has_parts = False
            parts = blk.dJt[keep][:, None, :] * np.array([1.0, 0.0, 0.0])[None, :, None]
        else:
            parts = blk.dJt_parts[keep]
        sums = (onehot @ parts.reshape(pos.size, -1)).reshape(-1, parts.shape[-1])
        self.Jt_src += unpack_tr(sums, self.n_o)

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

    def _update(self, k: int) -> None:
        if k != 0:
            self._flush()
            matrices = {"J": self.J, "Jt": self.Jt, "S": self.S, "Lb": self.Lb}
            out = {}
            for omega, cmd in enumerate(UPC, start=1):
                out[omega] = evaluate(omega, cmd, self.acc, matrices.__getitem__,
                                      self.miss_names).matrix
            t = self.acc.transformation(0, 1, 1)
            t_adj = self.acc.transformation(1, 1, 1)
            self.stored.V, self.stored.W, self.stored.B = out[1], out[2], out[3]
            self.J, self.Jt, self.S, self.Lb = out[4], out[5], out[6], out[7]
            self.G = t @ self.G
            self.C = t @ self.C @ t.T
            self.Jt_src = t_adj @ self.Jt_src @ t_adj.T
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

    def _statistics(self, k: int) -> _Current:
        if self.current is not None and self.current.k == k:
            return self.current
        self._flush()
        n = len(self.sources)
        if k == 0:
            d1 = self.acc.partials(0, 0, "f1")
            e3 = self.acc.partials(1, 0, "r1").T
            self.S0_fit = symmetric(d1.T @ self.plan.S0 @ d1)
            self.E3 = e3
            self.Lambda0_real = symmetric(e3 @ self.plan.Lambda0 @ e3.T)
            self.S, self.Lb = self.S0_fit, self.Lambda0_real
            fit, error = None, None
            try:
                fit = regression(self.acc.partials(1, 0, "f1").T, self.S0_fit,
                                 np.zeros_like(self.J), self.Lambda0_real,
                                 np.zeros_like(self.J)).Lambda1_00
            except SingularFitError as exc:
                error = self._singular(k, exc)
            self.current = _Current(k, self.S0_fit, self.Lambda0_real, np.eye(self.n_o), fit,
                                    error, np.zeros_like(self.J), np.eye(self.n_o),
                                    np.zeros((n, self.n_o, self.n_o)))
            return self.current
        e1 = self.acc.partials(1, 0, "f1").T
        try:
            reg = regression(e1, self.S, self.J, self.Lb, self.Jt)
        except SingularFitError as exc:
            raise self._singular(k, exc) from None
        lam = reg.Lambda1_00
        sigma = symmetric(lam @ self.Jt @ lam)
        c = reg.L @ self.C @ reg.L.T + lam @ self.Jt_src @ lam if self.plan.budget else self.C
        self.current = _Current(k, reg.S1_00, reg.Lambda_real, reg.L, lam, None, sigma,
                                reg.L @ self.G, c)
        return self.current

    def _matrix(self, cur: _Current) -> Callable[[str], np.ndarray]:
        def get(code: str) -> np.ndarray:
            if code == "L'":
                if cur.fit is None:
                    raise cur.fit_error
                return cur.fit
            return {"J": self.J, "Jt": self.Jt, "S": self.S, "Lb": self.Lb, "S'": cur.S,
                    "Lb'": cur.Lb, "Sigma": cur.Sigma}[code]
        return get

    # -----------------------------------------------------------------------------------------
    # Error budget
    # -----------------------------------------------------------------------------------------

    def _budget(self, x: np.ndarray, g: np.ndarray, c: np.ndarray, total: np.ndarray) -> Budget:
        """Per-source variances of the rows of X (Λ̄ or Λ̄') (module docstring)."""
        n_p = self.n_p
        n_r1 = self.plan.systems.n_r1
        xg = x @ g @ self.E3
        lam0 = self.plan.Lambda0
        named = {i for _, idx in self.plan.budget_groups for i in idx}
        groups = [("orbit (a priori)", tuple(range(n_p)))]
        groups += [(f"{name} (a priori)", idx) for name, idx in self.plan.budget_groups]
        r1_names = self.plan.systems.system_names(6)
        groups += [(f"{r1_names[i]} (a priori)", (i,)) for i in range(n_p, n_r1)
                   if i not in named]
        sources, rows = [], []
        block = np.zeros_like(lam0)
        for name, idx in groups:
            ix = np.ix_(idx, idx)
            block[ix] = lam0[ix]
            part = xg[:, idx]
            sources.append(name)
            rows.append(np.einsum("ij,jk,ik->i", part, lam0[ix], part))
        cross = lam0 - block
        if np.any(cross != 0):
            sources.append("correlations between a priori groups")
            rows.append(np.einsum("ij,jk,ik->i", xg, cross, xg))
        for i, src in enumerate(self.sources):
            station, part = src.rsplit(" ", 1)
            if not self.has_parts:
                if part != "white":
                    continue
                src = f"{station} total"
            sources.append(src)
            rows.append(np.einsum("ij,jk,ik->i", x, c[i], x))
        return Budget(tuple(sources), np.array(rows), total)

    def _entities(self, commands: tuple[Command, ...], cur: _Current) -> tuple[Entity, ...]:
        out = []
        for omega, cmd in enumerate(commands, start=1):
            ent = evaluate(omega, cmd, self.acc, self._matrix(cur), self.miss_names)
            if self.plan.budget and cmd.sigma in ("Lb", "Lb'") and cmd.rows == cmd.cols:
                x = self.acc.partials(cmd.rows.mu, cmd.rows.tau, cmd.rows.rho)
                g, c = (self.G, self.C) if cmd.sigma == "Lb" else (cur.G, cur.C)
                ent = Entity(ent.omega, ent.command, ent.rows, ent.cols, ent.matrix,
                             self._budget(x, g, c, np.diagonal(ent.matrix).copy()))
            out.append(ent)
        return tuple(out)

    def _record_history(self, kind: str, k: int, cur: _Current) -> None:
        side = self.plan.history
        x = self.acc.partials(side.mu, side.tau, side.rho)
        real = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", x, cur.Lb, x), 0.0))
        fit = None if cur.fit is None else np.sqrt(np.maximum(
            np.einsum("ij,jk,ik->i", x, cur.fit, x), 0.0))
        b = self.stored.B
        miss_real = symmetric(b @ cur.Lb @ b.T)
        miss_fit = None if cur.fit is None else symmetric(b @ cur.fit @ b.T)
        self.history.append(HistoryRow(kind, k, self._t(k), fit, real, miss_fit, miss_real))

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
        self.S, self.Lb, self.G, self.C = cur.S, cur.Lb, cur.G, cur.C
        self.J = np.zeros_like(self.J)
        self.Jt = np.zeros_like(self.Jt)
        self.Jt_src = np.zeros_like(self.Jt_src)
        self.acc.invalidate()
        self.current = None

    def _t32_recycle(self, k: int, number: int, cur: _Current, ents) -> T32Recycle:
        t = self.acc.transformation(0, 1, 1)
        ta = self.acc.transformation(1, 1, 1)
        transition = t @ self.acc.transformation(1, 2, 1).T
        fit = self._matrix(cur)("L'")
        entities = tuple(T32Entity(e.omega, e.command.seed(), e.command.alias(), e.rows, e.cols,
                                   e.matrix) for e in ents)
        return T32Recycle(
            number, k, self.l, self.j, self._t(k), self._t(self.l), self.info.copy(),
            symmetric(ta @ cur.S @ ta.T), symmetric(t @ fit @ t.T), symmetric(t @ cur.Lb @ t.T),
            t @ cur.L @ ta.T, symmetric(t @ cur.Sigma @ t.T), symmetric(ta @ self.J @ ta.T),
            symmetric(ta @ self.Jt @ ta.T), self.stored.B @ ta.T, transition, entities)

    # -----------------------------------------------------------------------------------------

    def run(self) -> Run:
        """Process the whole tape (seed Figure C-4) and return the outputs."""
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
        self._flush()  # read the tail too: every record's matrices are checked once
        return Run(tuple(self.blocks), tuple(self.history),
                   tuple(self.acc.labels(plan.history.tau, plan.history.rho, self.miss_names)),
                   tuple(self.recycles), self.S0_fit, self.Lambda0_real, tuple(self.sources))


def process(data: TrackingData, plan: Plan, *, source: str = "deck",
            progress: Callable[[int, int], None] | None = None) -> Run:
    """Run TAPP III on a tape (module docstring).

    Parameters
    ----------
    data : the tape's header and pair blocks.
    plan : the bound deck (:func:`tapp.processor.deck.bind`).
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

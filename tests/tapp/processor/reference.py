"""TAPP III in 40-digit arithmetic: the reference the square-root processor is checked against.

The seed's sequence (§4.3) and regression (§2.5) in their textbook normal-matrix form, every
operation in mpmath at :data:`DPS` significant digits, from a T13 tape whose factors are taken
as exact: J = Σ RᵀR and J̃ = Σ R̃ᵀR̃ by exact-product dot sums, the orbit link on an epoch
change adjointed by the seed's (3-13), P* = Γ P Γᵀ (exact arithmetic on the tape's U: the
inverse of the symplectic transition it represents; the exact inverse of the rounded U itself
would carry that rounding times cond P, 4.5e13 at the periapsis of the deep-space tape), and
¹S₁₁⁻¹ by Gaussian elimination. Forming normal matrices squares the condition number
(up to ~1e12 after scaling on the deep-space tape), which costs at most ~24 of the 40
digits; :func:`reference` is also run at a higher precision in the test to show that the
digits it keeps are right.

Scope: the print entities of covariances (Λ̄, Λ', Λ̄', Σ) on system partitions at the epoch
or current orbit set (τ = 0, 1) and on the isolated sets pk and m, and the recycle
covariances that go on the T32 tape, in the representation x^k of the recycle; the deck's
system chains are taken as given (exact permutations and constraint coefficients).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

from tapp.processor.commands import Command, Side
from tapp.processor.plan import Plan
from tapp.processor.representations import ISOLATED_SETS

#: Working precision, significant decimal digits.
DPS = 40


def _mp(a: np.ndarray) -> mpmath.matrix:
    return mpmath.matrix(np.asarray(a, dtype=float).tolist())


def _zeros(n: int, m: int | None = None) -> mpmath.matrix:
    return mpmath.zeros(n, n if m is None else m)


def _gram(rows: np.ndarray) -> mpmath.matrix:
    """Σ_r rows[r, a] rows[r, b] with exact products (mpmath.fdot), (n, n)."""
    n = rows.shape[1]
    cols = [[mpmath.mpf(float(v)) for v in rows[:, j]] for j in range(n)]
    out = _zeros(n)
    for a in range(n):
        for b in range(a, n):
            out[a, b] = out[b, a] = mpmath.fdot(cols[a], cols[b])
    return out


def to_float(m: mpmath.matrix) -> np.ndarray:
    """An mpmath matrix as float64 (rounded once)."""
    return np.array([[float(m[i, j]) for j in range(m.cols)] for i in range(m.rows)])


@dataclass(frozen=True)
class ReferenceRun:
    """Reference outputs: print entities by (k, command) and T32 recycle covariances by k
    (``Lambda_fit``, ``Lambda_real``, ``Sigma`` in x^k), float64 arrays."""

    prints: dict[tuple[int, Command], np.ndarray]
    recycles: dict[int, dict[str, np.ndarray]]


class _Machine:
    def __init__(self, tape, plan: Plan):
        self.tape, self.plan = tape, plan
        sy = plan.systems
        self.n_o, self.n_p, self.n_f1, self.n_r1 = sy.n_o, sy.n_p, sy.n_f1, sy.n_r1
        self.chain = {chi: _mp(sy.chain_matrix(chi)) for chi in (1, 4, 6)}
        d_fit = self.chain[4]
        self.E1 = (mpmath.inverse(d_fit))[:, :self.n_f1]
        self.D1 = d_fit[:self.n_f1, :]
        self.E3 = (mpmath.inverse(self.chain[6]))[:, :self.n_r1]
        self.J, self.Jt = _zeros(self.n_o), _zeros(self.n_o)
        self.S = self.Lb = None
        self.B = _mp(tape.miss.B)
        self.U = self._identity_rows()
        self.pending: list[np.ndarray] = []
        self.pending_t: list[np.ndarray] = []

    def _identity_rows(self) -> mpmath.matrix:
        out = _zeros(self.n_p, self.n_o)
        for i in range(self.n_p):
            out[i, i] = 1
        return out

    def orbit_link(self) -> mpmath.matrix:
        """∂x^k/∂x^j = [[U]; [0 I]] (n_o, n_o) of the current partials U."""
        out = mpmath.eye(self.n_o)
        for i in range(self.n_p):
            for j in range(self.n_o):
                out[i, j] = self.U[i, j]
        return out

    def read(self, k: int) -> None:
        """Record k: its partials U, and the factors of its pairs whose station is on."""
        self.U = _mp(self.tape.records.U[k - 1])
        pairs = self.tape.pairs
        for i in np.flatnonzero(pairs.k == k):
            station = int(pairs.station[i])
            if any(off.station == station and off.k_first <= k <= off.k_last
                   for off in self.plan.stations_off):
                continue
            self.pending.append(pairs.R[i])
            self.pending_t.append(pairs.Rt[i])

    def flush(self) -> None:
        if self.pending:
            self.J += _gram(np.concatenate(self.pending))
            self.Jt += _gram(np.concatenate(self.pending_t))
        self.pending, self.pending_t = [], []

    def adjoint_link(self) -> mpmath.matrix:
        """(∂x/∂x^k)ᵀ = T⁻ᵀ of the orbit link: [[P*, 0], [−Qᵀ P*, I]] with P* = Γ P Γᵀ, the
        seed's (3-13) (exact for a symplectic P: a signed permutation of its entries)."""
        n_p, h = self.n_p, self.n_p // 2
        out = mpmath.eye(self.n_o)
        for i in range(n_p):
            for j in range(n_p):
                # (Γ P Γᵀ)_ij with Γ = [[0, I], [−I, 0]]
                si, pi = (1, i + h) if i < h else (-1, i - h)
                sj, pj = (1, j + h) if j < h else (-1, j - h)
                out[i, j] = si * sj * self.U[pi, pj]
        p_star = out[:n_p, :n_p]
        q = self.U[:, n_p:]
        lower = -(q.T * p_star)
        for i in range(self.n_o - n_p):
            for j in range(n_p):
                out[n_p + i, j] = lower[i, j]
        return out

    def update(self) -> None:
        """Re-refer everything to the current time (the UPC commands)."""
        self.flush()
        t = self.orbit_link()
        t_inv = self.adjoint_link().T
        self.J = t_inv.T * self.J * t_inv
        self.Jt = t_inv.T * self.Jt * t_inv
        self.S = t_inv.T * self.S * t_inv
        self.Lb = t * self.Lb * t.T
        self.B = self.B * t_inv
        self.U = self._identity_rows()

    def statistics(self, k: int) -> dict[str, mpmath.matrix | None]:
        self.flush()
        if k == 0:
            self.S = self.D1.T * _mp(self.plan.S0) * self.D1
            self.Lb = self.E3 * _mp(self.plan.Lambda0) * self.E3.T
            s11 = self.E1.T * self.S * self.E1
            fit = self.E1 * mpmath.inverse(s11) * self.E1.T if mpmath.det(s11) != 0 else None
            return {"S'": self.S, "L'": fit, "Lb'": self.Lb, "Sigma": _zeros(self.n_o)}
        s1 = self.S + self.J
        lam = self.E1 * mpmath.inverse(self.E1.T * s1 * self.E1) * self.E1.T
        big_l = mpmath.eye(self.n_o) - lam * self.J
        sigma = lam * self.Jt * lam
        return {"S'": s1, "L'": lam, "Lb'": big_l * self.Lb * big_l.T + sigma, "Sigma": sigma}

    def side(self, side: Side) -> mpmath.matrix:
        """(0, τ, ρ| for τ = 0, 1 and the isolated sets pk, m."""
        if side.mu != 0:
            raise NotImplementedError("the reference evaluates covariances (parity 0) only")
        chi, t, h = self.plan.systems.bounds(side.rho)
        if chi == 0:
            stored = {"U": self.U, "B": self.B}[ISOLATED_SETS[side.rho]]
            return stored[t:h, :]
        if side.tau not in (0, 1):
            raise NotImplementedError("the reference has the orbit sets τ = 0, 1 only")
        link = mpmath.eye(self.n_o) if side.tau == 0 else self.orbit_link()
        return (self.chain[chi] * link)[t:h, :]


def reference(tape, plan: Plan, dps: int = DPS) -> ReferenceRun:
    """Run TAPP III on ``tape`` (a T13 in memory, with its pair factors) in ``dps``-digit
    arithmetic: the covariance print entities and the T32 recycle covariances."""
    with mpmath.workdps(dps):
        m = _Machine(tape, plan)
        prints, recycles = {}, {}
        j_rec = tape.records.j
        n_it = tape.n_it
        j = -1
        for k in range(n_it + 1):
            if k < n_it and int(j_rec[k]) != j:
                if k != 0:
                    m.update()
                j = k
            if k in plan.print_k or k in plan.recycle_k or k == 0:
                stats = m.statistics(k)
                if k in plan.print_k and plan.print_statistics:
                    for cmd in plan.print_commands:
                        if not cmd.is_covariance or stats.get(cmd.sigma, 0) is None:
                            continue
                        matrix = {"Lb": m.Lb, "L'": stats["L'"], "Lb'": stats["Lb'"],
                                  "Sigma": stats["Sigma"]}[cmd.sigma]
                        x1, x2 = m.side(cmd.rows), m.side(cmd.cols)
                        prints[(k, cmd)] = to_float(x1 * matrix * x2.T)
                if k == 0 or k in plan.recycle_k:
                    if k != 0:
                        t = m.orbit_link()
                        recycles[k] = {name: to_float(t * stats[key] * t.T) for name, key in
                                       (("Lambda_fit", "L'"), ("Lambda_real", "Lb'"),
                                        ("Sigma", "Sigma"))}
                    m.S, m.Lb = stats["S'"], stats["Lb'"]
                    m.J, m.Jt = _zeros(m.n_o), _zeros(m.n_o)
            if k < n_it:
                m.read(k + 1)
        return ReferenceRun(prints, recycles)

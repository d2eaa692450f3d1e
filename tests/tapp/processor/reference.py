"""TAPP III in extended-precision arithmetic: the reference the square-root processor is
checked against, by two exact routes.

The seed's sequence (§4.3) and regression (§2.5) in their textbook normal-matrix form, every
operation in mpmath at ``dps`` significant digits, from a T13 tape whose factors and partials
are taken as exact: J = Σ RᵀR and J̃ = Σ R̃ᵀR̃ by exact-product dot sums, ¹S₁₁⁻¹ by Gaussian
elimination. The two routes differ in where they keep the statistics:

* **forward** (:attr:`References.forward`, the answer): every matrix is referred to the
  injection epoch, as a batch does, and only forward maps are formed: the transition
  G = ∂x^j/∂x⁰ is the product of the tape's orbit links, the information of the records of
  epoch j enters as Gᵀ J G, and an entity X is X G. No transition is inverted, so the answer
  is that of the tape's own transitions, whatever their rounding.
* **adjoint** (:attr:`References.adjoint`, the processor's sequence): on an epoch change the
  information is mapped by the adjoint of the orbit link, the covariance by the link, the
  miss partials by its inverse (the update commands). The adjoint is the exact inverse of the
  tape's link, transposed, to the working precision: the seed's (3-13), P* = Γ P Γᵀ, is the
  inverse of a symplectic P, and the tape's P (cond 4.5e13 after the deep-space periapsis) is
  symplectic only to its rounding, |PᵀΓP − Γ| = 1.0e-4: with Γ P Γᵀ this route was 2.7e-7
  (periapsis) to 7.9e-6 (day 30) off the forward one. Both routes agree to the precision of
  the arithmetic: a cross-check of the sequencing, which only this route mirrors.

Forming normal matrices squares the condition number (up to ~1e12 after scaling on the
deep-space tape, more at the injection epoch of the forward route), which costs a share of
the digits; the tests also run the reference at a higher precision to show that the digits
it keeps are right.

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

#: Working precision, significant decimal digits: the forward route's normal matrices at the
#: injection epoch hold the information of the periapsis through G (cond 4.5e13).
DPS = 60


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


@dataclass(frozen=True)
class References:
    """The two exact routes of one run (module docstring)."""

    forward: ReferenceRun
    adjoint: ReferenceRun


class _Route:
    """The statistics of one route, in its representation: x^j (adjoint) or x⁰ (forward,
    with G = ∂x^j/∂x⁰)."""

    def __init__(self, n_o: int, miss_b: mpmath.matrix, forward: bool):
        self.forward = forward
        self.J, self.Jt = _zeros(n_o), _zeros(n_o)
        self.S = self.Lb = None
        self.B = miss_b
        self.G = mpmath.eye(n_o)
        self.prints: dict[tuple[int, Command], np.ndarray] = {}
        self.recycles: dict[int, dict[str, np.ndarray]] = {}

    def add(self, j: mpmath.matrix, jt: mpmath.matrix) -> None:
        """Add information of the current epoch."""
        self.J += self.G.T * j * self.G
        self.Jt += self.G.T * jt * self.G

    def update(self, link: mpmath.matrix) -> None:
        """Re-refer to the current time: the forward route composes G, the adjoint maps by
        the inverse of the link (the update commands)."""
        if self.forward:
            self.G = link * self.G
            return
        inv = mpmath.inverse(link)
        self.J = inv.T * self.J * inv
        self.Jt = inv.T * self.Jt * inv
        self.S = inv.T * self.S * inv
        self.Lb = link * self.Lb * link.T
        self.B = self.B * inv

    def run(self) -> ReferenceRun:
        return ReferenceRun(self.prints, self.recycles)


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
        self.routes = (_Route(self.n_o, _mp(tape.miss.B), forward=True),
                       _Route(self.n_o, _mp(tape.miss.B), forward=False))
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
            j, jt = _gram(np.concatenate(self.pending)), _gram(np.concatenate(self.pending_t))
            for route in self.routes:
                route.add(j, jt)
        self.pending, self.pending_t = [], []

    def update(self) -> None:
        """Re-refer everything to the current time (the UPC commands)."""
        self.flush()
        link = self.orbit_link()
        for route in self.routes:
            route.update(link)
        self.U = self._identity_rows()

    def statistics(self, route: _Route, k: int) -> dict[str, mpmath.matrix | None]:
        if k == 0:
            route.S = self.D1.T * _mp(self.plan.S0) * self.D1
            route.Lb = self.E3 * _mp(self.plan.Lambda0) * self.E3.T
            s11 = self.E1.T * route.S * self.E1
            fit = self.E1 * mpmath.inverse(s11) * self.E1.T if mpmath.det(s11) != 0 else None
            return {"S'": route.S, "L'": fit, "Lb'": route.Lb, "Sigma": _zeros(self.n_o)}
        s1 = route.S + route.J
        lam = self.E1 * mpmath.inverse(self.E1.T * s1 * self.E1) * self.E1.T
        big_l = mpmath.eye(self.n_o) - lam * route.J
        sigma = lam * route.Jt * lam
        return {"S'": s1, "L'": lam, "Lb'": big_l * route.Lb * big_l.T + sigma, "Sigma": sigma}

    def side(self, route: _Route, side: Side) -> mpmath.matrix:
        """(0, τ, ρ| for τ = 0, 1 and the isolated sets pk, m, in the route's representation."""
        if side.mu != 0:
            raise NotImplementedError("the reference evaluates covariances (parity 0) only")
        chi, t, h = self.plan.systems.bounds(side.rho)
        if chi == 0:
            if ISOLATED_SETS[side.rho] == "B":
                return route.B[t:h, :]
            return (self.U * route.G)[t:h, :]
        if side.tau not in (0, 1):
            raise NotImplementedError("the reference has the orbit sets τ = 0, 1 only")
        link = mpmath.eye(self.n_o) if side.tau == 0 else self.orbit_link()
        return (self.chain[chi] * link * route.G)[t:h, :]

    def outputs(self, route: _Route, k: int) -> None:
        """Statistics at k on one route: the print entities, the recycle's T32 covariances
        and the recycle itself."""
        plan = self.plan
        stats = self.statistics(route, k)
        if k in plan.print_k and plan.print_statistics:
            for cmd in plan.print_commands:
                if not cmd.is_covariance or stats.get(cmd.sigma, 0) is None:
                    continue
                matrix = {"Lb": route.Lb, "L'": stats["L'"], "Lb'": stats["Lb'"],
                          "Sigma": stats["Sigma"]}[cmd.sigma]
                x1, x2 = self.side(route, cmd.rows), self.side(route, cmd.cols)
                route.prints[(k, cmd)] = to_float(x1 * matrix * x2.T)
        if k == 0 or k in plan.recycle_k:
            if k != 0:
                t = self.orbit_link() * route.G
                route.recycles[k] = {name: to_float(t * stats[key] * t.T) for name, key in
                                     (("Lambda_fit", "L'"), ("Lambda_real", "Lb'"),
                                      ("Sigma", "Sigma"))}
            route.S, route.Lb = stats["S'"], stats["Lb'"]
            route.J, route.Jt = _zeros(self.n_o), _zeros(self.n_o)


def reference(tape, plan: Plan, dps: int = DPS) -> References:
    """Run TAPP III on ``tape`` (a T13 in memory, with its pair factors) in ``dps``-digit
    arithmetic by both routes: the covariance print entities and the T32 recycle
    covariances."""
    with mpmath.workdps(dps):
        m = _Machine(tape, plan)
        j_rec = tape.records.j
        n_it = tape.n_it
        j = -1
        for k in range(n_it + 1):
            if k < n_it and int(j_rec[k]) != j:
                if k != 0:
                    m.update()
                j = k
            if k in plan.print_k or k in plan.recycle_k or k == 0:
                m.flush()
                for route in m.routes:
                    m.outputs(route, k)
            if k < n_it:
                m.read(k + 1)
        forward, adjoint = (route.run() for route in m.routes)
        return References(forward, adjoint)

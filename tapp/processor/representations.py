"""Representations of TAPP III (seed §3.2–3.3, Tables B-2, B-3, B-4): the partials accumulator.

A representation x^{τ,χ} = [p^τ; q^χ] (3-7) pairs an orbit set option τ with a system set χ.
The program keeps every matrix in the standard representation x = x^{0,1} = [p^j; q] (the
orbit at the program epoch t_j and the TAPP I constants). The transformation accumulator

.. math::

    \\langle \\mu, \\tau, \\chi\\rangle = \\begin{cases}
        \\partial x^{\\tau,\\chi}/\\partial x & \\mu = 0\\\\
        [\\partial x/\\partial x^{\\tau,\\chi}]^T & \\mu = 1 \\end{cases}\\qquad (3\\text{-}9)

is the system chain (links, :mod:`tapp.processor.links`, Table B-3) times the orbit link
∂x^{τ,1}/∂x = [[∂p^τ/∂p, ∂p^τ/∂q], [0, I]] (3-14); for μ = 1 every factor is adjointed in
place, (AB)* = A* B*. The orbit link's adjoint (3-15) is [[P*, 0], [−Qᵀ P*, I]] with
P* = P⁻ᵀ, the exact inverse of the tape's P rounded to a double-double
(:func:`tapp.estimation.factors.accurate_inverse`), not the seed's Γ P Γᵀ (3-13): that is the
inverse of the symplectic transition of a Hamiltonian flow, and the tape's P, an STM computed
in floating point, is symplectic only to its rounding. After the deep-space lunar swing-by
(cond P = 4.5e13, |PᵀΓP − Γ| = 1.0e-4) the information mapped by Γ P Γᵀ and the real-world
covariance mapped by P itself (the forward map, 3-9 with μ = 0) were two different
transitions: the printed covariances after the periapsis epoch were 2.7e-7 (periapsis) to
2.8e-6 (day 30, the real-world miss) off the exact answer computed with forward maps only,
of their scale √(C_ii C_jj); with P⁻ᵀ as a double-double they are within 9e-12 of it, and
with P⁻ᵀ correctly rounded but without its remainder within 6.7e-7 only (ε cond P of the
terms). The alternative that needs no inverse, every factor referred to the injection epoch
by forward maps (as a batch does), held 1.0e-8 at day 30: the covariances at the current time
are then maps of the injection's through that ill-conditioned transition.

The partials accumulator (μ, τ, ρ| (3-30) is rows t..h of ⟨μ, τ, χ⟩ for a system partition
ρ of system χ, and rows t..h of a stored matrix (I, U, V, W, B: the orbit at epoch, current
time, last recycle, injection, and the miss set) for an isolated set (χ = 0, μ = 0, τ unused).

Orbit set options τ (Table B-2): 0 epoch t_j, 1 current time t_k, 2 last recycle time t_l,
3 injection t_0, 4 and 5 the 2nd and 3rd sets of n_p miss parameters (rows n_p..3n_p of B,
available only when the tape's miss set has them and they are canonical, as the seed's UDC and
DCA sets were).

System sets χ (Table B-3; links listed left to right as in the product (3-26)):
1 standard (none), 2 intermediate common (P_c), 3 common (K_c P_c), 4 fit (K_f P_f K_c P_c),
5 intermediate real (P_r K_c P_c), 6 real (K_r P_r K_c P_c). The fit permutation P_f is an
extension: the seed orders the fitted parameters through the common permutation alone; an
empty P_f (the default) gives exactly the seed's chain.

Set partitions ρ (Table B-4), rows [t, h) of their system: o (0, n_o), p (0, n_p), q (n_p, n_o)
of the standard system; c (0, n_o), c1 (0, n_c1), cp (0, n_p), cq (n_p, n_c1), c2 (n_c1, n_o)
of the common system; f (0, n_o), f0 (0, n_c1), f1 (0, n_f1), fp (0, n_p), fq (n_p, n_f1),
fz (n_f1, n_c1) of the fit system; r (0, n_o), r0 (0, n_c1), r1 (0, n_r1), rp (0, n_p),
rq (n_p, n_r1), r2 (n_r1, n_c1) of the real system; isolated: pj, pk, pl, pi (the orbit at
epoch, current, last recycle, injection), m (the miss set), m1..m9 (rows t_mi..h_mi of B).
Reconstructed: the scan gives c the bounds of c1; its description "complete set (cp: cq: c2)"
says (0, n_o), used here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tapp.errors import InputError
from tapp.estimation.factors import accurate_inverse, accurate_matmul
from tapp.processor.links import Constraint, Link, Permutation

ORBIT_SETS = {0: "epoch", 1: "current", 2: "recycle", 3: "injection", 4: "miss2", 5: "miss3"}
SYSTEMS = {1: "standard", 2: "common-intermediate", 3: "common", 4: "fit",
           5: "real-intermediate", 6: "real"}
#: ρ -> (system χ, tail, head), bounds named by the dimension they take.
SYSTEM_PARTITIONS: dict[str, tuple[int, str, str]] = {
    "o": (1, "0", "n_o"), "p": (1, "0", "n_p"), "q": (1, "n_p", "n_o"),
    "c": (3, "0", "n_o"), "c1": (3, "0", "n_c1"), "cp": (3, "0", "n_p"),
    "cq": (3, "n_p", "n_c1"), "c2": (3, "n_c1", "n_o"),
    "f": (4, "0", "n_o"), "f0": (4, "0", "n_c1"), "f1": (4, "0", "n_f1"),
    "fp": (4, "0", "n_p"), "fq": (4, "n_p", "n_f1"), "fz": (4, "n_f1", "n_c1"),
    "r": (6, "0", "n_o"), "r0": (6, "0", "n_c1"), "r1": (6, "0", "n_r1"),
    "rp": (6, "0", "n_p"), "rq": (6, "n_p", "n_r1"), "r2": (6, "n_r1", "n_c1"),
}
#: Isolated sets ρ -> stored matrix (I, U, V, W, B).
ISOLATED_SETS = {"pj": "I", "pk": "U", "pl": "V", "pi": "W", "m": "B",
                 **{f"m{i}": "B" for i in range(1, 10)}}
PARTITIONS = (*SYSTEM_PARTITIONS, *ISOLATED_SETS)
#: Time tag of the orbit rows of each stored orbit set.
_ORBIT_TAG = {"I": "epoch", "U": "current", "V": "recycle", "W": "injection"}
#: Orbit set option τ (Table B-2) of the isolated orbit sets.
_ISOLATED_TAU = {"pj": 0, "pk": 1, "pl": 2, "pi": 3}


@dataclass(frozen=True, slots=True)
class Systems:
    """The coded systems of a run: links and the partition sizes (seed Appendix A.1).

    Attributes
    ----------
    n_o, n_p : numbers of TAPP I and orbit parameters.
    n_c1 : common parameters (n_p <= n_c1 <= n_o); rows n_c1.. of the common system are
        eliminated (held fixed in both worlds).
    n_f1 : fitted parameters (n_p <= n_f1 <= n_c1).
    n_r1 : real-world uncertain parameters (n_p <= n_r1 <= n_c1).
    P_c, K_c, P_f, K_f, P_r, K_r : the links (None: identity).
    names : (n_o,) names of the standard parameters (as on the tape).
    miss_partitions : m1..m9 -> (tail, head) rows of the miss set.
    """

    n_o: int
    n_p: int
    n_c1: int
    n_f1: int
    n_r1: int
    names: tuple[str, ...]
    n_m: int = 0
    P_c: Permutation | None = None
    K_c: Constraint | None = None
    P_f: Permutation | None = None
    K_f: Constraint | None = None
    P_r: Permutation | None = None
    K_r: Constraint | None = None
    miss_partitions: dict[str, tuple[int, int]] = field(default_factory=dict)

    def chain(self, chi: int) -> tuple[Link, ...]:
        """Links of system χ, left to right as in (3-26): ∂x^χ/∂x = L_1 L_2 ... L_n."""
        links = {1: (), 2: (self.P_c,), 3: (self.K_c, self.P_c),
                 4: (self.K_f, self.P_f, self.K_c, self.P_c),
                 5: (self.P_r, self.K_c, self.P_c),
                 6: (self.K_r, self.P_r, self.K_c, self.P_c)}[chi]
        return tuple(link for link in links if link is not None)

    def chain_matrix(self, chi: int) -> np.ndarray:
        """The system chain ∂x^{τ,χ}/∂x^{τ,1} as a dense (n_o, n_o) matrix."""
        return apply_chain(self.chain(chi), np.eye(self.n_o), adjoint=False)

    def dim(self, name: str) -> int:
        """Value of a bound name of :data:`SYSTEM_PARTITIONS`."""
        return {"0": 0, "n_o": self.n_o, "n_p": self.n_p, "n_c1": self.n_c1,
                "n_f1": self.n_f1, "n_r1": self.n_r1}[name]

    def bounds(self, rho: str) -> tuple[int, int, int]:
        """Return (χ, t, h) of partition ρ (χ = 0 for isolated sets)."""
        if rho in SYSTEM_PARTITIONS:
            chi, t, h = SYSTEM_PARTITIONS[rho]
            return chi, self.dim(t), self.dim(h)
        if rho in ("pj", "pk", "pl", "pi"):
            return 0, 0, self.n_p
        if rho == "m":
            return 0, 0, self.n_m
        if rho in self.miss_partitions:
            return 0, *self.miss_partitions[rho]
        raise InputError("partition", rho, f"one of {', '.join(PARTITIONS)}"
                         + ("" if rho not in ISOLATED_SETS else
                            f" ({rho} is not defined: give it in the deck's [miss] table)"))

    def orbit_time(self, tau: int | None, rho: str) -> int | None:
        """Return the orbit set option τ (0..3: epoch, current, recycle, injection) when the
        rows of the set (τ, ρ) begin with the n_p orbit components at one time (the links
        never touch the orbit rows, :mod:`tapp.processor.links`); None otherwise (constants
        only, a miss set, the miss orbit sets τ = 4, 5)."""
        if rho in _ISOLATED_TAU:
            return _ISOLATED_TAU[rho]
        if rho not in SYSTEM_PARTITIONS or tau not in (0, 1, 2, 3):
            return None
        _, t, h = self.bounds(rho)
        return tau if t == 0 and h >= self.n_p else None

    def system_names(self, chi: int) -> list[str]:
        """Names of the rows of system χ: permuted, and primed where a constraint acts."""
        order = list(self.names)
        for link in reversed(self.chain(chi)):
            if isinstance(link, Permutation):
                order = link.move(order)
            else:
                for a in link.a:
                    if not order[a].endswith("'"):
                        order[a] = order[a] + "'"
        return order


def apply_chain(links: tuple[Link, ...], m: np.ndarray, adjoint: bool) -> np.ndarray:
    """Return L_1 ... L_n M (or L_1* ... L_n* M), applying the links right to left."""
    for link in reversed(links):
        m = link.apply(m, adjoint)
    return m


def orbit_link(partials: np.ndarray, n_o: int, adjoint: bool) -> np.ndarray:
    """Return the orbit link ∂x^{τ,1}/∂x (3-14) or its adjoint (3-15), (n_o, n_o).

    The adjoint is the double-double :func:`orbit_link_adjoint` rounded (its ``hi``).

    Parameters
    ----------
    partials : (n_p, n_o) ∂p^τ/∂x = [P, Q].
    """
    if adjoint:
        return orbit_link_adjoint(partials, n_o)[0]
    out = np.eye(n_o)
    out[:partials.shape[0]] = partials
    return out


def orbit_link_adjoint(partials: np.ndarray, n_o: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the orbit link's adjoint (3-15) [[P*, 0], [−Qᵀ P*, I]] as a double-double
    (hi, lo), (n_o, n_o) each: hi rounded, lo its remainder (zero on the unit rows).

    P* = P⁻ᵀ from :func:`tapp.estimation.factors.accurate_inverse` (module docstring), and
    −Qᵀ P* by :func:`tapp.estimation.factors.accurate_matmul` from both parts of P*: after a
    lunar swing-by P* has entries of 1e6 and a condition number of 1e13, its products with
    the sensitivities Q cancel, and the plain product's rounding moved the covariances after
    an epoch change by 1e-7. A factor mapped through hi + lo
    (:func:`tapp.estimation.factors.accurate_map`) is mapped through the inverse of the tape's
    own transition to about ε² of the terms: after the deep-space periapsis the rounding of
    −Qᵀ P* alone moved the information of the last record by 2e-11 of its scale and the
    covariances by 1e-9.

    Parameters
    ----------
    partials : (n_p, n_o) ∂p^τ/∂x = [P, Q].

    Raises
    ------
    SingularMatrixError
        If P is singular.
    """
    n_p = partials.shape[0]
    hi, lo = np.eye(n_o), np.zeros((n_o, n_o))
    p, q = partials[:, :n_p], partials[:, n_p:]
    inv_hi, inv_lo = accurate_inverse(p)
    hi[:n_p, :n_p], lo[:n_p, :n_p] = inv_hi.T, inv_lo.T
    hi[n_p:, :n_p], lo[n_p:, :n_p] = accurate_matmul(np.hstack([-q.T, -q.T]),
                                                     np.vstack([inv_hi.T, inv_lo.T]),
                                                     split=True)
    return hi, lo


@dataclass(slots=True)
class Stored:
    """The stored partials w.r.t. the program representation x (seed §4.2, Appendix A.3).

    I (n_p, n_o) orbit at epoch ([I 0]), U at the current time, V at the last recycle time,
    W at injection, B (n_m, n_o) the miss set. Mutable: the sequencer replaces them.
    """

    I: np.ndarray
    U: np.ndarray
    V: np.ndarray
    W: np.ndarray
    B: np.ndarray

    def orbit_set(self, tau: int) -> np.ndarray:
        """Return ∂p^τ/∂x (n_p, n_o) of orbit set option τ (Table B-2)."""
        n_p = self.I.shape[0]
        if tau in (0, 1, 2, 3):
            return (self.I, self.U, self.V, self.W)[tau]
        first = (tau - 3) * n_p
        if tau not in (4, 5) or self.B.shape[0] < first + n_p:
            raise InputError("orbit set", str(tau), "0..3, or 4/5 when the tape's miss set has "
                             f"{first + n_p} or more parameters (it has {self.B.shape[0]})")
        return self.B[first:first + n_p]


class Accumulator:
    """The partials accumulator (μ, τ, ρ| and transformation accumulator ⟨μ, τ, χ⟩.

    Transformations are cached until :meth:`invalidate` (the stored partials changed).
    """

    def __init__(self, systems: Systems, stored: Stored):
        self.systems = systems
        self.stored = stored
        self._cache: dict[tuple, np.ndarray] = {}

    def invalidate(self) -> None:
        """Forget cached transformations (after U, V, W or B changed)."""
        self._cache.clear()

    def _adjoint(self, tau: int) -> tuple[np.ndarray, np.ndarray]:
        """The orbit link's adjoint of orbit set τ as a double-double (one exact inverse of
        its P per τ until :meth:`invalidate`)."""
        key = ("adjoint", tau)
        if key not in self._cache:
            self._cache[key] = orbit_link_adjoint(self.stored.orbit_set(tau), self.systems.n_o)
        return self._cache[key]

    def transformation(self, mu: int, tau: int, chi: int) -> np.ndarray:
        """Return ⟨μ, τ, χ⟩ (3-9), (n_o, n_o)."""
        key = (mu, tau, chi)
        if key not in self._cache:
            if mu == 1:
                link = self._adjoint(tau)[0]
            else:
                link = orbit_link(self.stored.orbit_set(tau), self.systems.n_o, adjoint=False)
            self._cache[key] = apply_chain(self.systems.chain(chi), link, adjoint=mu == 1)
        return self._cache[key]

    def remainder(self, mu: int, tau: int | None, rho: str) -> np.ndarray | None:
        """Return the rounding remainder of (μ, τ, ρ| for μ = 1 and a system partition (the
        ``lo`` of :func:`orbit_link_adjoint`, through the system chain), rows t..h; None
        where there is none (μ = 0, isolated sets)."""
        chi, t, h = self.systems.bounds(rho)
        if mu != 1 or chi == 0:
            return None
        key = ("remainder", tau, chi)
        if key not in self._cache:
            self._cache[key] = apply_chain(self.systems.chain(chi), self._adjoint(tau)[1],
                                           adjoint=True)
        return self._cache[key][t:h]

    def partials(self, mu: int, tau: int | None, rho: str) -> np.ndarray:
        """Return (μ, τ, ρ| (3-30): (h − t, n_o)."""
        chi, t, h = self.systems.bounds(rho)
        if chi == 0:
            stored = getattr(self.stored, ISOLATED_SETS[rho])
            if h > stored.shape[0]:
                raise InputError("partition", rho, f"rows within the {stored.shape[0]} rows of "
                                 f"{ISOLATED_SETS[rho]}", (t, h))
            return stored[t:h]
        return self.transformation(mu, tau, chi)[t:h]

    def labels(self, tau: int | None, rho: str, miss_names: tuple[str, ...]) -> list[str]:
        """Row labels of (μ, τ, ρ|: parameter names, orbit rows tagged with their time."""
        chi, t, h = self.systems.bounds(rho)
        n_p = self.systems.n_p
        if chi == 0:
            which = ISOLATED_SETS[rho]
            if which == "B":
                return list(miss_names[t:h])
            return [f"{n}@{_ORBIT_TAG[which]}" for n in self.systems.names[:n_p]][t:h]
        names = self.systems.system_names(chi)
        if tau in (4, 5):
            orbit = list(miss_names[(tau - 3) * n_p:(tau - 2) * n_p])
        else:
            orbit = [f"{n}@{ORBIT_SETS[tau]}" for n in self.systems.names[:n_p]]
        return (orbit + names[n_p:])[t:h]

"""System links of TAPP III (seed §3.1 formats IP and IK, §3.2.3): permutations and constraints.

A link maps one system representation to the next, q^χ = f^χ(q^χ') (3-19); it touches only the
constants q (rows n_p.. of x), never the orbit set (3-17). Two kinds, both adjointed without a
general inverse (the adjoint of a matrix M is M* = (M⁻¹)ᵀ, 3-9):

* **Permutation** P (format IP): a list of pairs (a, b) meaning u(a) = v(b) for u = P v (3-4);
  rows not named are unchanged. P is orthogonal, so P* = P (3-21).
* **Constraint** K = I − E (format IK): a list of (a, b, e) meaning v(a) ← v(a) − e v(b) (3-5),
  i.e. ∂v(a)/∂v(b) = e (3-6); the rows a and the columns b must be disjoint, so E² = 0,
  K⁻¹ = I + E and K* = I + Eᵀ.

Reconstructed: the scanned (3-23) reads "K* = I + E", which is K⁻¹; with the seed's own
definition of the adjoint (3-9, "inverse-transposed") it is I + Eᵀ, as implemented here. The
identity every link satisfies, and that the tests check, is (L*)ᵀ L = I.

Positions here are 0-based rows of the n_o-vector; the deck's 1-based indices are converted on
reading. Links are applied to the rows of a matrix, M ← L M (or L* M), in O(pairs · columns).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.errors import InputError


@dataclass(frozen=True, slots=True, eq=False)
class Permutation:
    """A permutation link (IP): ``target[i]`` ← ``source[i]`` (0-based rows), u(a) = v(b)."""

    target: np.ndarray
    source: np.ndarray

    @classmethod
    def from_pairs(cls, pairs, n_o: int, n_p: int, where: str) -> Permutation:
        """Build from (a, b) pairs (0-based), checking it permutes rows n_p..n_o-1 only.

        Raises
        ------
        InputError
            Rows outside the constants, a row named twice, or a list that is not a
            permutation (naming ``where``).
        """
        pairs = [(int(a), int(b)) for a, b in pairs]
        target = np.array([a for a, _ in pairs], dtype=np.int64)
        source = np.array([b for _, b in pairs], dtype=np.int64)
        for name, rows in (("a", target), ("b", source)):
            if np.any((rows < n_p) | (rows >= n_o)):
                raise InputError(where, "permutation", f"positions {n_p + 1}..{n_o} (the "
                                 f"constants q; the orbit set is never permuted)",
                                 sorted(int(r) + 1 for r in rows[(rows < n_p) | (rows >= n_o)]))
            if np.unique(rows).size != rows.size:
                raise InputError(where, "permutation", f"each position at most once as {name}",
                                 [p_ for p_ in (int(r) + 1 for r in rows)])
        if set(target.tolist()) != set(source.tolist()):
            raise InputError(where, "permutation", "a permutation: the positions a and b name "
                             "the same set (u(a) = v(b), every v used once)",
                             {"a only": sorted(set(target.tolist()) - set(source.tolist())),
                              "b only": sorted(set(source.tolist()) - set(target.tolist()))})
        return cls(target, source)

    def apply(self, m: np.ndarray, adjoint: bool = False) -> np.ndarray:
        """Return P M (P* M = P M: permutations are self-adjoint, 3-21)."""
        out = m.copy()
        out[self.target] = m[self.source]
        return out

    def matrix(self, n_o: int) -> np.ndarray:
        """Return P as a dense (n_o, n_o) matrix."""
        return self.apply(np.eye(n_o))

    def move(self, order: list) -> list:
        """Return the labels of the rows after the link: u(a) = v(b)."""
        out = list(order)
        for a, b in zip(self.target, self.source, strict=True):
            out[a] = order[b]
        return out


@dataclass(frozen=True, slots=True, eq=False)
class Constraint:
    """A constraint link (IK): v(a) ← v(a) − e v(b) for each (a, b, e) (0-based rows)."""

    a: np.ndarray
    b: np.ndarray
    e: np.ndarray

    @classmethod
    def from_triples(cls, triples, n_o: int, n_p: int, where: str) -> Constraint:
        """Build from (a, b, e) (0-based rows a, b), checking the IK rules.

        Raises
        ------
        InputError
            Rows outside the constants, a non-finite e, or a row that is both an a and a b
            (then E² ≠ 0 and K is no constraint link), naming ``where``.
        """
        a = np.array([int(t[0]) for t in triples], dtype=np.int64)
        b = np.array([int(t[1]) for t in triples], dtype=np.int64)
        e = np.array([float(t[2]) for t in triples], dtype=float)
        rows = np.concatenate([a, b])
        if np.any((rows < n_p) | (rows >= n_o)):
            raise InputError(where, "constraints", f"positions {n_p + 1}..{n_o} (the constants "
                             "q: system sets do not depend on the orbit set, 3-17)",
                             sorted(int(r) + 1 for r in rows[(rows < n_p) | (rows >= n_o)]))
        if not np.all(np.isfinite(e)):
            raise InputError(where, "constraints", "finite coefficients e", e.tolist())
        both = sorted(set(a.tolist()) & set(b.tolist()))
        if both:
            raise InputError(where, "constraints", "rows a and columns b with no position in "
                             "common (E² = 0, seed §3.1 format IK)", [i + 1 for i in both])
        if np.unique(a * n_o + b).size != a.size:
            raise InputError(where, "constraints", "each (a, b) pair once")
        return cls(a, b, e)

    def apply(self, m: np.ndarray, adjoint: bool = False) -> np.ndarray:
        """Return K M = (I − E) M, or K* M = (I + Eᵀ) M when ``adjoint``."""
        out = m.copy()
        if adjoint:
            np.add.at(out, self.b, self.e[:, None] * m[self.a])
        else:
            np.add.at(out, self.a, -self.e[:, None] * m[self.b])
        return out

    def matrix(self, n_o: int) -> np.ndarray:
        """Return K as a dense (n_o, n_o) matrix."""
        return self.apply(np.eye(n_o))


Link = Permutation | Constraint

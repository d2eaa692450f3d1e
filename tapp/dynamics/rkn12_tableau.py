"""The RKN12(10) tableau of Dormand, El-Mikkawy & Prince (1987), as exact rationals.

Source: J. R. Dormand, M. E. A. El-Mikkawy and P. J. Prince, "High-order embedded
Runge-Kutta-Nystrom formulae", IMA Journal of Numerical Analysis 7(4), 423-430 (1987), the
17-stage pair of order 12 with an embedded order-10 solution for y'' = f(t, y). The rationals
were transcribed from the published tableau (as reproduced in the SciML OrdinaryDiffEq.jl
RKN tableaus, DPRKN12); the tests check them against the order conditions and against the
observed order of convergence on the Kepler problem. Stage i (1-based, as in the paper):

.. math::
    Y_i = y_n + c_i h y'_n + h^2 \\sum_j a_{ij} f(t_n + c_j h, Y_j),\\quad
    y_{n+1} = y_n + h y'_n + h^2 \\sum_i b_i f_i,\\quad
    y'_{n+1} = y'_n + h \\sum_i b'_i f_i,

with the embedded order-10 weights ``bh`` and ``bph`` in place of b and b'. Zero entries
are left out. Rows of ``rkn12_tableau.txt`` (beside this module): ``c i value``,
``a i j value``, ``b i value``, ``bp i value``, ``bh i value``, ``bph i value``.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cache
from importlib.resources import files

STAGES = 17


@dataclass(frozen=True, slots=True)
class RknTableau:
    """Exact coefficients, 0-based lists: c (s,), a (s, s), b, bp, bh, bph (s,)."""

    c: tuple[Fraction, ...]
    a: tuple[tuple[Fraction, ...], ...]
    b: tuple[Fraction, ...]
    bp: tuple[Fraction, ...]
    bh: tuple[Fraction, ...]
    bph: tuple[Fraction, ...]


@cache
def rkn12() -> RknTableau:
    """Parse the table into exact fractions (stage indices shifted to 0-based)."""
    c = [Fraction(0)] * STAGES
    a = [[Fraction(0)] * STAGES for _ in range(STAGES)]
    weights = {name: [Fraction(0)] * STAGES for name in ("b", "bp", "bh", "bph")}
    for row in files("tapp.dynamics").joinpath("rkn12_tableau.txt").read_text().splitlines():
        kind, *idx, value = row.split()
        if kind == "c":
            c[int(idx[0]) - 1] = Fraction(value)
        elif kind == "a":
            a[int(idx[0]) - 1][int(idx[1]) - 1] = Fraction(value)
        else:
            weights[kind][int(idx[0]) - 1] = Fraction(value)
    return RknTableau(tuple(c), tuple(map(tuple, a)), *(tuple(weights[k]) for k in
                                                        ("b", "bp", "bh", "bph")))

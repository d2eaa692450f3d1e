"""SEARCH: a generic n-by-n Newton-Raphson targeter and DINV (JPL TM 33-203, 1965).

``search`` drives any callable ``f(x) -> y``, as the original drove any program sequence under
JPTRAJ; it knows nothing of orbits and imports nothing from ``tapp``.

>>> import numpy as np
>>> from search import solve
>>> r = solve(lambda x: np.array([x[0] ** 2]), [1.0], [4.0], tolerances=[1e-9], increments=[1e-6])
>>> r.status, round(float(r.x[0]), 6)
('converged', 2.0)
"""

from search.dinv import DEFAULT_PIVOT_RTOL, DinvResult, dinv
from search.errors import SearchError, SearchInputError, SingularMatrixError
from search.report import format_report
from search.solver import (
    EXIT_FLAG,
    MAX_STEP_HALVINGS,
    Case,
    History,
    PartialSet,
    SearchInputs,
    SearchResult,
    Step,
    solve,
)

__all__ = [
    "DEFAULT_PIVOT_RTOL",
    "EXIT_FLAG",
    "MAX_STEP_HALVINGS",
    "Case",
    "DinvResult",
    "History",
    "PartialSet",
    "SearchError",
    "SearchInputError",
    "SearchInputs",
    "SearchResult",
    "SingularMatrixError",
    "Step",
    "dinv",
    "format_report",
    "solve",
]

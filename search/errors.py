"""The typed failures of ``search``; every message states the numbers behind it.

``search`` is a generic engine and must not import ``tapp`` (an import-linter contract forbids
it), so it keeps its own small hierarchy. ``SearchInputError`` derives from ``ValueError`` so
that callers which only know the standard library still catch bad input.
"""

from __future__ import annotations


class SearchError(Exception):
    """Base class of every error ``search`` raises on purpose."""


class SearchInputError(SearchError, ValueError):
    """Bad input to ``search``: names the argument, what was expected and what was received.

    Parameters
    ----------
    argument : str
        Name of the offending argument (e.g. ``"increments"``, or ``"f"`` for a bad output of
        the driven function, in which case ``got`` names the case).
    expected : str
        What a valid value looks like.
    got : object, optional
        The value (or a description of it) that was received.
    """

    def __init__(self, argument: str, expected: str, got: object = None):
        self.argument = argument
        self.expected = expected
        self.got = got
        detail = "" if got is None else f" (got {got})"
        super().__init__(f"{argument}: expected {expected}{detail}")


class SingularMatrixError(SearchError):
    """DINV met a pivot at or below its relative threshold: the matrix is singular to working
    precision.

    Parameters
    ----------
    step : int
        1-based elimination step (pivot number) at which the small pivot was met.
    order : int
        Order n of the matrix.
    pivot : float
        The largest remaining element, i.e. the pivot that was rejected.
    threshold : float
        ``pivot_rtol * max|a_ij|``, the absolute threshold it was compared with.
    """

    def __init__(self, step: int, order: int, pivot: float, threshold: float):
        self.step = step
        self.order = order
        self.pivot = pivot
        self.threshold = threshold
        super().__init__(
            f"matrix of order {order} is singular: pivot {step} of {order} is {pivot:.3e}, "
            f"at or below the threshold {threshold:.3e}"
        )

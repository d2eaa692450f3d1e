"""Checks of tape values, shared by the tapes in memory and their HDF5 readers (NumPy only).

:class:`Checker` checks shapes, finiteness, symmetry and UTF-8 text and turns every failure
into a :class:`~tapp.errors.TapeError` ``"{file}: {dataset}: expected ... (got ...)"``;
:meth:`Checker.rows` checks the shapes of the rows of a layout table
(:mod:`tapp.io.tape.layout`); :func:`frozen` returns read-only copies of arrays;
:data:`PACKINGS` names the storages of symmetric matrices. :func:`tapp.io.tape.t13.validate`
and :func:`tapp.io.tape.t32.validate` use them on a tape in memory, the reader of
:mod:`tapp.io.tape.hdf5io` on the values it reads.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from tapp.errors import TapeError
from tapp.io.tape.layout import Field, resolve
from tapp.io.tape.packing import symmetry_defect

#: Storage of symmetric matrices: "TR" (upper triangle by rows) or "full" (n² entries).
PACKINGS = ("TR", "full")
#: Relative asymmetry max |M_ij - M_ji| / sqrt(M_ii M_jj) above which a symmetric matrix is
#: rejected (:func:`tapp.io.tape.packing.symmetry_defect`).
SYMMETRY_TOL = 1e-12
#: Largest magnitude of a number on a tape (partials, factors, states, times; a matrix that
#: is a product of two, such as a covariance, its square). The programs square these and
#: multiply them with one another: a factor times a partial, squared, stays within 1e240,
#: below the 1.8e308 of a double. What the shipped tapes hold is far smaller (3e5 for the
#: deep-space transitions, 1e11 for its information factors), and a TAPP III deck at the top
#: of its σ range writes ~1e31 (tapp.processor.deck.SIGMA_RANGE).
MAX_MAGNITUDE = 1e60


def frozen(a, dtype=float) -> np.ndarray:
    """Return a read-only copy of ``a`` as ``dtype``."""
    out = np.array(a, dtype=dtype)
    out.setflags(write=False)
    return out


class Checker:
    """Checks of values; every failure raises TapeError naming the file and the dataset."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, dataset: str, expected: str, got: object = None):
        """Raise ``TapeError("{source}: {dataset}: expected {expected} (got {got})")``."""
        detail = "" if got is None else f" (got {got})"
        raise TapeError(f"{self.source}: {dataset}: expected {expected}{detail}")

    def shape(self, dataset: str, a: np.ndarray | None, shape: tuple[int, ...]) -> None:
        """Check that ``a`` is an array of ``shape``."""
        if not isinstance(a, np.ndarray):
            self.fail(dataset, f"an array of shape {shape}",
                      "None" if a is None else type(a).__name__)
        if a.shape != shape:
            self.fail(dataset, f"shape {shape}", a.shape)

    def finite(self, dataset: str, a: np.ndarray, limit: float = MAX_MAGNITUDE) -> None:
        """Check that every value is finite and at most ``limit`` in magnitude
        (:data:`MAX_MAGNITUDE`)."""
        if a.dtype.kind not in "fc" or a.size == 0:
            return
        if a.dtype.kind == "f" and a.max() <= limit and a.min() >= -limit:
            return  # real: two reductions without a temporary, 3x faster (NaN fails both)
        if not np.all(np.abs(a) <= limit):
            bad = tuple(int(i) for i in np.argwhere(~(np.abs(a) <= limit))[0])
            self.fail(dataset, f"finite values of magnitude <= {limit:g}",
                      f"{a[bad]} at index {bad}")

    def symmetric(self, dataset: str, m: np.ndarray, *, what: str = "normal matrices",
                  label: str | None = "pair", offset: int = 0, tol: float = SYMMETRY_TOL,
                  floor: np.ndarray | None = None) -> None:
        """Check symmetric matrices (..., n, n) with a non-negative diagonal.

        ``label`` names the leading index in the message ("pair 3"), with ``offset`` added
        (a slice of a larger stack); None for a single matrix. ``floor`` (n,), >= 0, accepts
        diagonal entries down to −floor (the rounding of a variance that cancels to ~0).
        """
        stack = m.reshape(-1, *m.shape[-2:])

        def where(i: int) -> str:
            return "" if label is None else f" in {label} {i + offset}"

        defect = symmetry_defect(stack) if stack.size else np.zeros(0)
        if np.any(defect > tol):
            first = int(np.argmax(defect > tol))
            self.fail(dataset, f"symmetric {what} (relative asymmetry <= {tol:g})",
                      f"{defect[first]:.3g}{where(first)}")
        diag = np.diagonal(stack, axis1=-2, axis2=-1)
        low = diag < (0.0 if floor is None else -floor)
        if np.any(low):
            i, col = (int(v) for v in np.argwhere(low)[0])
            self.fail(dataset, f"a non-negative diagonal ({what})",
                      f"{diag[i, col]:.3g}{where(i)}, row {col}")

    def rows(self, fields: Iterable[Field], value_of: Callable[[Field], object],
             dims: dict[str, int], *, finite: bool = True) -> None:
        """Check the values of layout rows (:mod:`tapp.io.tape.layout`) against their shapes,
        the symbols resolved by ``dims`` (rows whose shape has another symbol, attributes and
        packed matrices are checked elsewhere): text by its count ("expected N entries"),
        arrays by :meth:`shape`, numbers by :meth:`finite` unless the row allows
        non-finite values or ``finite`` is False (shapes only: a reader indexing rows it
        leaves the validation of values to)."""
        for field in fields:
            shape = resolve(field.shape, dims)
            if field.is_attr or field.dtype in ("factor", "symmetric") or shape is None:
                continue
            value = value_of(field)
            if field.dtype == "str":
                if len(value) != shape[0]:
                    self.fail(field.path, f"{shape[0]} entries", len(value))
                continue
            self.shape(field.path, value, shape)
            if finite and field.dtype == "float" and field.finite:
                self.finite(field.path, value)

    def text(self, where: str, value: object) -> str:
        """Return ``value`` (bytes or str) as text; fail unless it is valid UTF-8."""
        if isinstance(value, bytes | np.bytes_):
            try:
                return bytes(value).decode("utf-8")
            except UnicodeDecodeError:
                self.fail(where, "UTF-8 text", repr(bytes(value)[:40]))
        text = str(value)
        try:  # h5py hands undecodable bytes of a UTF-8 attribute back as lone surrogates
            text.encode("utf-8")
        except UnicodeEncodeError:
            self.fail(where, "UTF-8 text", repr(text.encode("utf-8", "surrogateescape")[:40]))
        return text

"""Tapes in the layouts of earlier versions, and the algebra the tape tests check factors with.

The library writes T13 version 4 and T32 version 2 (square-root information). Its readers
still read T13 versions 1 and 2 and T32 version 1, which carried the normal matrices and
covariances themselves, and T13 version 3 (version 4 gzip-compressed):
:func:`write_t13_version` writes those T13 layouts (the library keeps
``_write(..., version=)`` for it), :func:`write_t32_version_1` the T32 one (the library no
longer writes it: the layout of ``tapp/io/tape/t32_hdf5.py`` before version 2).

Factors and Gram matrices are formed here with plain NumPy (einsum, explicit index lists), not
with the library's helpers, so that the tests compare against values the code under test did
not produce.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.io.tape import hdf5io, t13_hdf5
from tapp.io.tape.t13 import NORMAL_MATRIX_VERSIONS, T13
from tapp.io.tape.t32 import SYMMETRIC, T32
from tapp.io.tape.t32_hdf5 import write_t32

EPS = float(np.finfo(float).eps)

#: The warning of reading a T32 version-1 tape.
T32_V1_WARNING = ("T32 version 1 carries the covariances, not their factors: they hold only "
                  "the digits their products kept")


def refactored_tol(n: int) -> float:
    """Tolerance of a matrix M (n x n) of an old tape against the Gram KᵀK of the factor its
    reader forms, on the scale sqrt(M_aa M_bb): n² ε.

    A bound on the backward error of the Cholesky factor (or, for a semi-definite M, the
    symmetric eigen-decomposition) of M scaled to a unit diagonal, whose 2-norm is at most n,
    and of the QR and the Gram that follow (Higham, *Accuracy and Stability of Numerical
    Algorithms*, 2nd ed., §10.1: |ΔM| <= γ_{n+1} |Rᵀ||R| for Cholesky).
    """
    return n**2 * EPS


def gram(k: np.ndarray) -> np.ndarray:
    """KᵀK of factors (..., m, n), summed row by row with einsum."""
    return np.einsum("...ki,...kj->...ij", k, k)


def upper_by_rows(m: np.ndarray) -> np.ndarray:
    """The upper triangles of (..., n, n) row by row (what "TR" packing stores), (..., L)."""
    n = m.shape[-1]
    return np.stack([m[..., i, j] for i in range(n) for j in range(i, n)], axis=-1)


def upper_from_rows(packed: np.ndarray, n: int) -> np.ndarray:
    """The upper-triangular (..., n, n) of upper triangles by rows (..., L), zero below."""
    rows, cols = np.triu_indices(n)
    out = np.zeros((*packed.shape[:-1], n, n))
    out[..., rows, cols] = packed
    return out


def symmetric_from_rows(packed: np.ndarray, n: int) -> np.ndarray:
    """The symmetric (..., n, n) of upper triangles by rows (..., L), mirrored."""
    rows, cols = np.triu_indices(n)
    out = np.zeros((*packed.shape[:-1], n, n))
    out[..., rows, cols] = packed
    out[..., cols, rows] = packed
    return out


def bits(a: np.ndarray) -> np.ndarray:
    """The bit patterns of float64 values (-0.0 and 0.0 differ)."""
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


# ---------------------------------------------------------------------------------------------
# T13
# ---------------------------------------------------------------------------------------------


def write_t13_version(path: Path, tape: T13, version: int, packing: str = "TR") -> Path:
    """Write ``tape`` in the layout of ``version`` (1 and 2: the normal matrices RᵀR of the
    factors, ``pairs/dJ``, ``pairs/dJt`` and, version 2, ``pairs/dJt_parts``; 3: the factors,
    gzip-compressed)."""
    with h5py.File(path, "w") as f:
        t13_hdf5._write(f, tape, packing, version=version)
    return path


@contextmanager
def t13_read_warnings(version: int) -> Iterator[None]:
    """Expect exactly the warnings of reading a T13 tape of ``version`` (none for 3): the
    precision of normal matrices (1, 2), no checksums (1)."""
    with ExitStack() as stack:
        if version in NORMAL_MATRIX_VERSIONS:
            stack.enter_context(pytest.warns(UserWarning, match=(
                rf"T13 version {version} carries normal matrices, not square-root information: "
                r"its factors are formed from them and hold only the digits they kept")))
        if version == 1:
            stack.enter_context(pytest.warns(UserWarning, match=(
                "T13 version 1 carries no checksums: corruption cannot be detected")))
        yield


# ---------------------------------------------------------------------------------------------
# T32
# ---------------------------------------------------------------------------------------------


def t32_matrices(tape: T32) -> dict[str, tuple[np.ndarray, str]]:
    """The factors of a T32 tape's symmetric matrices by their version-1 dataset names, with
    the units of the matrices."""
    out = {"apriori/S0_fit": (tape.S0_fit_factor, "1/(u_a u_b)"),
           "apriori/Lambda0_real": (tape.Lambda0_real_factor, "u_a u_b")}
    for rc in tape.recycles:
        for name, _, units in SYMMETRIC:
            out[f"recycles/{rc.number}/{name}"] = (getattr(rc, f"{name}_factor"), units)
    return out


def write_t32_version_1(path: Path, tape: T32, matrices: dict[str, np.ndarray] | None = None
                        ) -> Path:
    """Write ``tape`` in the layout of T32 version 1 and return the path.

    Version 1 is version 2 but for the symmetric matrices, stored themselves (packed TR,
    attrs ``packing``, ``order`` and ``units``) under the names without ``_factor``, and no
    ``transition_adjoint``: the tape is written by the library, then those datasets replaced.
    The matrices are the Grams of the tape's factors, or those of ``matrices`` (by dataset
    name, e.g. ``"recycles/1/Sigma"``: a matrix no factor has, such as a Σ whose variance
    rounding made negative).
    """
    write_t32(path, tape)
    given = matrices or {}
    with h5py.File(path, "r+") as f:
        f.attrs["version"] = 1
        for name, (k, units) in t32_matrices(tape).items():
            m = given.get(name, gram(k))
            del f[f"{name}_factor"]
            parent, _, leaf = name.rpartition("/")
            ds = hdf5io.write_numbers(f[parent], leaf, upper_by_rows(m), units)
            hdf5io.write_attrs(ds, {"packing": "TR", "order": m.shape[-1]})
        for rc in tape.recycles:
            del f[f"recycles/{rc.number}/transition_adjoint"]
    return path

"""The T32 tape's HDF5 form (through h5py): layout, atomic writer, validating reader.

The tape in memory (its types, notation and validation) is :mod:`tapp.io.tape.t32`;
DESIGN.md ("Tapes") fixes this form.

HDF5 layout: the rows of :data:`tapp.io.tape.layout.T32_LAYOUT` (every dataset and
attribute, with its type, shape, units and versions; rendered as ``docs/reference/tapes.md``),
which :func:`_write` writes in order. Every dataset is chunked with a Fletcher-32 checksum and
has a ``units`` attribute; text is fixed-length UTF-8 (attributes too: h5py reads them as
bytes); every symmetric matrix M (normal matrix or covariance) is stored as its
upper-triangular factor K, M = KᵀK, diagonal >= 0 (``<name>_factor``), packed "TR" (upper
triangle by rows, L = n_o(n_o+1)/2 entries; attrs ``packing`` = "TR", ``order`` = n_o,
``form`` = "factor") as on the T13 tape (:mod:`tapp.io.tape.hdf5io`); units of a factor: 1/u_b
(normal) or u_b (covariance).

All n_o x n_o matrices of a recycle are in x^k, with k that recycle's record index.

Version 1 (still read, with a ``UserWarning`` that its precision is limited) stored the
symmetric matrices themselves under the names without ``_factor`` and no adjoint; the reader
checks them as that version did (symmetric, a non-negative diagonal, Σ_ii down to
−1e-6 Λ̄'_ii as rounding), factors them (:func:`tapp.estimation.factors.psd_factor`: negative
rounding set to zero) and inverts the transitions.

The writer validates, then writes to a temporary file beside the target and renames it: no
half-written tape. The reader rejects a wrong format or version, a missing dataset or
attribute, a wrong shape, a non-finite value or one beyond
:data:`tapp.io.tape.checks.MAX_MAGNITUDE` (a version-1 matrix: its square), a factor that is
not upper triangular or has a negative diagonal (version 1: a non-symmetric or
negative-diagonal matrix), a
partition outside its system (or whose names are not the system's), recycle numbers other
than 1..n_r, indices k not ascending, an entity matrix whose shape is not (rows, cols), a
dataset without a checksum and a checksum mismatch, with a :class:`~tapp.errors.TapeError`
``"{file}: {dataset}: expected ... (got ...)"``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

from tapp.estimation.factors import psd_factor
from tapp.frames.time import Epoch
from tapp.io.atomic import atomic_write
from tapp.io.tape import hdf5io
from tapp.io.tape.checks import MAX_MAGNITUDE
from tapp.io.tape.hdf5io import Reader
from tapp.io.tape.layout import STAMPED, T32_LAYOUT, Field, build, filled, rows, sourced
from tapp.io.tape.t13 import TapeParameters
from tapp.io.tape.t32 import (
    CHAINED,
    FORMAT,
    SIGMA_ROUNDING,
    SUPPORTED_VERSIONS,
    T32,
    UNITS_NOTE,
    V1_PSD_TOL,
    VERSION,
    T32Entity,
    T32Partition,
    T32Recycle,
    system_values,
    validate,
)

__all__ = ["read_t32", "t32_file_writer", "write_t32"]


# ---------------------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------------------


def _write(f: h5py.File, t32: T32) -> None:
    """Write ``t32`` into the open file ``f``: the rows of :data:`T32_LAYOUT` of
    :data:`VERSION`, the systems', recycles' and entities' once per system, recycle and
    command, then the further provenance."""
    n_o, rcs, parts = t32.n_o, t32.recycles, t32.partitions
    extra = {k: v for k, v in t32.provenance.items() if k not in STAMPED}
    computed = {
        "attrs/format": FORMAT, "attrs/version": VERSION, "attrs/n_o": n_o,
        "attrs/n_p": t32.n_p, "attrs/n_m": t32.n_m, "attrs/n_recycles": len(rcs),
        "attrs/n_partitions": len(parts), "attrs/epoch": t32.epoch.iso(6),
        "attrs/epoch_jd_whole": t32.epoch.jd_whole,
        "attrs/epoch_jd_fraction": t32.epoch.jd_fraction, "attrs/time_scale": "UTC",
        "attrs/units": UNITS_NOTE, "attrs/provenance_keys": list(extra),
        **{f"attrs/{key}": value for key, value in hdf5io.provenance_attrs().items()},
        "partitions/name": [p.name for p in parts],
        "partitions/system": [p.system for p in parts],
        "partitions/tail": np.array([p.tail for p in parts], dtype=np.int64),
        "partitions/head": np.array([p.head for p in parts], dtype=np.int64),
        "partitions/names": [n for p in parts for n in p.names],
        "recycles/info": np.array([r.info for r in rcs], dtype=float).reshape(len(rcs), 6)}
    for field in rows(T32_LAYOUT, VERSION, "recycles/"):
        if "{" not in field.path and field.path not in computed:
            computed[field.path] = np.array([getattr(r, field.source) for r in rcs],
                                            dtype=np.int64 if field.dtype == "int" else float)

    def big(field: Field) -> bool:
        return field.big and n_o > 100

    def write(prefix: str, obj: object, values: dict[str, object], **names: object) -> None:
        """The rows under ``prefix`` (with {s}, {i}, {omega} filled in from ``names``)."""
        hdf5io.write_rows(f, filled(T32_LAYOUT, VERSION, prefix, **names),
                          lambda field: values[field.path] if field.path in values
                          else sourced(obj, field.source), big=big)

    write("", t32, computed)
    chains = system_values(t32)
    for name in CHAINED:
        write("systems/{s}/", None, chains, s=name)
    for rc in rcs:
        write("recycles/{i}/", rc, {}, i=rc.number)
        for e in rc.entities:
            write("recycles/{i}/entities/{omega}", e, {}, i=rc.number, omega=int(e.omega))
    hdf5io.write_attrs(f, extra)


def t32_file_writer(t32: T32, *, source: str = "T32") -> Callable[[Path], None]:
    """Validate ``t32`` now; return a function that writes it, complete, at a given path.

    For committing several outputs together (:func:`tapp.io.atomic.atomic_write` of each);
    :func:`write_t32` is ``atomic_write(path, t32_file_writer(t32))``.

    Raises
    ------
    TapeError
        If the tape fails :func:`tapp.io.tape.t32.validate` (``source`` names it in the message).
    """
    validate(t32, source)

    def write(path: Path) -> None:
        with hdf5io.create(Path(path)) as f:
            _write(f, t32)

    return write


def write_t32(path: Path | str, t32: T32) -> Path:
    """Validate ``t32`` and write it to ``path`` atomically (temporary file, then rename).

    Parameters
    ----------
    path : path of the tape (conventionally ``*.t32.h5``).
    t32 : T32

    Raises
    ------
    TapeError
        If the tape fails :func:`tapp.io.tape.t32.validate` (nothing is written).
    """
    path = Path(path)
    return atomic_write(path, t32_file_writer(t32, source=str(path)))


# ---------------------------------------------------------------------------------------------
# Reader
# ---------------------------------------------------------------------------------------------


def _entities(r: Reader, version: int, i: int) -> tuple[T32Entity, ...]:
    """The command outputs of recycle ``i``: the rows under ``recycles/{i}/entities/{omega}``
    of each command number ω found, ascending."""
    where = f"recycles/{i}/entities"
    group = r.dataset_or_group(where)
    if not isinstance(group, h5py.Group):
        r.check.fail(where, "a group of command outputs", "a dataset")
    with r.guard(where, "a readable group"):
        keys = list(group.keys())
    if not all(key.isdigit() and int(key) >= 1 for key in keys):
        r.check.fail(where, "command numbers ω >= 1 as group names", keys)
    out = []
    for omega in sorted(int(key) for key in keys):
        values = {field.source: r.row(field) if r.present(field) else ""
                  for field in filled(T32_LAYOUT, version, "recycles/{i}/entities/{omega}",
                                      i=i, omega=omega)}
        out.append(T32Entity(omega=omega, **values))
    return tuple(out)


def _v1_factor(r: Reader, name: str, n: int, floor: np.ndarray | None = None,
               scale: np.ndarray | None = None) -> np.ndarray:
    """Version 1: a symmetric matrix checked as that version did, returned as its factor
    (refused when that factor's Gram matrix departs from it by more than :data:`V1_PSD_TOL`
    of its scale, √(s_i s_j) with s its diagonal or the given ``scale``: indefinite beyond
    the rounding of its products)."""
    m = r.symmetric(name, (), n)
    r.check.finite(name, m, MAX_MAGNITUDE**2)  # a covariance: its factor within the bound
    r.check.symmetric(name, m, what="matrix", label=None, floor=floor)
    k = psd_factor(m)
    d = np.sqrt(np.abs(np.diagonal(m)) if scale is None else scale)
    both = np.outer(d, d)
    gap = np.abs(k.T @ k - m)
    defect = float(np.max(np.divide(gap, both, out=np.where(gap > 0, np.inf, 0.0),
                                    where=both > 0)))
    if defect > V1_PSD_TOL:
        r.check.fail(name, f"a positive semi-definite matrix (to {V1_PSD_TOL:g} of its "
                           "scale)", f"{defect:.3g}")
    return k


def _v1_adjoint(r: Reader, name: str, transition: np.ndarray) -> np.ndarray:
    """Version 1 has no adjoint: (T⁻¹)ᵀ by an LU solve."""
    r.check.finite(name, transition)
    try:
        return np.linalg.solve(transition, np.eye(transition.shape[0])).T
    except np.linalg.LinAlgError:
        r.check.fail(name, "an invertible transition")


def _matrices(r: Reader, fields: tuple[Field, ...], n_o: int, real: np.ndarray | None = None
              ) -> dict[str, object]:
    """The values of ``fields`` (placeholders filled in) by source: factors unpacked, the
    symmetric matrices of version 1 as their factors (:func:`_v1_factor`; Σ <= Λ̄' in exact
    arithmetic: ``real``, the diagonal of Λ̄', sets Σ's rounding floor and its scale), the
    others by their types."""
    out: dict[str, object] = {}
    for field in fields:
        if field.dtype == "factor":
            out[field.source] = r.triangular(field.path, (), n_o)
        elif field.dtype == "symmetric":
            sigma = field.name == "Sigma"
            out[field.source] = _v1_factor(r, field.path, n_o,
                                           SIGMA_ROUNDING * real if sigma else None,
                                           real if sigma else None)
        else:
            out[field.source] = r.row(field)
    return out


def _recycle(r: Reader, version: int, i: int, table: dict[str, np.ndarray], n_o: int
             ) -> T32Recycle:
    """Recycle ``i`` (1-based): its entries of the ``recycles/`` rows read (``table``, by
    source, shapes checked) and its rows under ``recycles/{i}/``."""
    base = f"recycles/{i}"
    real = None
    if version == 1:  # Λ̄' first: its diagonal bounds Σ's
        real = np.clip(np.diagonal(r.symmetric(f"{base}/Lambda_real", (), n_o)), 0.0, None)
    values = _matrices(r, filled(T32_LAYOUT, version, "recycles/{i}/", i=i), n_o, real)
    if version == 1:
        values["transition_adjoint"] = _v1_adjoint(r, f"{base}/transition",
                                                   values["transition"])
    entries = {source: column[i - 1] for source, column in table.items()}
    return T32Recycle(**{source: entry.item() if entry.ndim == 0 else entry
                         for source, entry in entries.items()}, **values,
                      entities=_entities(r, version, i))


def _read(r: Reader) -> T32:
    """Return the tape: the rows of :data:`T32_LAYOUT` of its version read by their types
    (by source; the attributes the writer computes as the dimensions), those under
    ``systems/{s}``, ``recycles/{i}`` and their entities once per system, recycle and
    command, after the dimensions are checked against the datasets."""
    version = r.format_version(FORMAT, SUPPORTED_VERSIONS)
    if version == 1:
        warnings.warn(f"{r.check.source}: T32 version 1 carries the covariances, not their "
                      "factors: they hold only the digits their products kept (the real-world "
                      "covariances of an ill-conditioned fit, a few); process the T13 tape "
                      "again for version 2", UserWarning, stacklevel=4)
    dims = {name: r.attr(name, int) for name in ("n_o", "n_p", "n_m", "n_recycles",
                                                 "n_partitions")}
    n_o = dims["n_o"]
    dims["n_r"] = dims["n_recycles"]
    epoch = Epoch(r.attr("epoch_jd_whole", float), r.attr("epoch_jd_fraction", float))
    values: dict[str, object] = {}
    for field in rows(T32_LAYOUT, version):
        if "{" in field.path or field.dtype in ("factor", "symmetric") \
                or (field.is_attr and not field.source):
            continue  # a row of each system, recycle, command, a matrix (below), computed
        values[field.source or field.path] = r.row(field)
    parameters = build(TapeParameters, "parameters", values)
    for name, value in (("n_o", len(parameters.name)), ("n_m", len(values["miss_name"]))):
        if dims[name] != value:
            r.check.fail(f"attrs/{name}", f"{name} = {value} as the datasets have", dims[name])

    group = r.dataset_or_group("systems")
    if not isinstance(group, h5py.Group):
        r.check.fail("systems", "a group of system chains", "a dataset")
    with r.guard("systems", "a readable group"):
        keys = sorted(group.keys())
    if keys != sorted(CHAINED):
        r.check.fail("systems", f"the systems {', '.join(CHAINED)}", keys)
    chains = {name: {field.name: r.row(field)
                     for field in filled(T32_LAYOUT, version, "systems/{s}/", s=name)}
              for name in CHAINED}

    # the rows of partitions and recycles indexed below: their lengths first
    indexed = tuple(f for f in rows(T32_LAYOUT, version) if "{" not in f.path
                    and f.path.startswith(("partitions/", "recycles/")))
    r.check.rows(indexed, lambda field: values[field.source or field.path], dims,
                 finite=False)
    tail, head = values["partitions/tail"], values["partitions/head"]
    flat = values["partitions/names"]
    sizes = head - tail
    if np.any(sizes < 0) or int(sizes.sum()) != len(flat):
        r.check.fail("partitions/names", "head - tail names for each partition, "
                                         f"{int(np.clip(sizes, 0, None).sum())} in all",
                     len(flat))
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
    partitions = tuple(
        T32Partition(values["partitions/name"][i], values["partitions/system"][i],
                     int(tail[i]), int(head[i]), flat[offsets[i]:offsets[i + 1]])
        for i in range(dims["n_partitions"]))

    apriori = _matrices(r, filled(T32_LAYOUT, version, "apriori/"), n_o)
    n_r = dims["n_r"]
    if not np.array_equal(values["number"], np.arange(1, n_r + 1)):
        r.check.fail("recycles/number", f"recycle numbers 1..{n_r} in order",
                     values["number"].tolist())
    table = {f.source: values[f.source] for f in indexed if f.path.startswith("recycles/")}
    recycles = tuple(_recycle(r, version, i, table, n_o) for i in range(1, n_r + 1))

    keys = r.attr("provenance_keys", list, default=())
    provenance = {key: r.attr(key, str) for key in (*STAMPED, *keys) if r.has_attr(key)}
    return T32(values["iden"], epoch, dims["n_p"], parameters, values["miss_name"],
               values["miss_unit"], {name: chains[name]["chain"] for name in CHAINED},
               {name: chains[name]["names"] for name in CHAINED}, partitions, **apriori,
               recycles=recycles, provenance=provenance)


def read_t32(path: Path | str) -> T32:
    """Read and validate a T32 tape.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        If it is not a readable HDF5 file (truncated, corrupt: a checksum mismatch), or not
        a valid T32 tape (:func:`tapp.io.tape.t32.validate`); the message names the file and the
        dataset (or attribute) at fault.
    """
    path = Path(path)
    with hdf5io.open_tape(path, "T32 tape") as f:
        t32 = _read(Reader(f, str(path), checksums=True))
    validate(t32, str(path))
    return t32

"""The T32 tape's HDF5 form (through h5py): layout, atomic writer, validating reader.

The tape in memory (its types, notation and validation) is :mod:`tapp.io.tape.t32`;
DESIGN.md ("Tapes") fixes this form.

HDF5 layout, version 2. Every dataset is chunked with a Fletcher-32 checksum and has a
``units`` attribute; text is fixed-length UTF-8 (attributes too: h5py reads them as bytes);
every symmetric matrix M (normal matrix or covariance) is stored as its upper-triangular
factor K, M = KᵀK, diagonal >= 0 (``<name>_factor``), packed "TR" (upper triangle by rows,
L = n_o(n_o+1)/2 entries; attrs ``packing`` = "TR", ``order`` = n_o, ``form`` = "factor") as
on the T13 tape (:mod:`tapp.io.tape.hdf5io`); units of a factor: 1/u_b (normal) or u_b
(covariance):

===============================  ===============  =============================================
path                             shape            content
===============================  ===============  =============================================
attrs                                             format="T32", version, iden, n_o, n_p, n_m,
                                                  n_recycles, n_partitions, epoch (ISO UTC),
                                                  epoch_jd_whole, epoch_jd_fraction,
                                                  time_scale, units; provenance: tapp_version,
                                                  git_commit, created_utc, provenance_keys
                                                  (the names of the further provenance attrs:
                                                  e.g. deck (JSON), deck_source, t13_source,
                                                  t13_iden)
parameters/name, unit, kind      (n_o,) str       the standard parameters, from the T13 tape
parameters/station               (n_o,) int       station number of a station parameter, 0
parameters/nominal               (n_o,) float     values at t_0, units ``unit``
miss/name, unit                  (n_m,) str       miss parameters
systems/<s>/chain                (n_o, n_o)       ∂x^s/∂x, s = common, fit, real: the system
                                                  chain of the deck (permutations and
                                                  constraints of q), (row unit)/(column unit)
systems/<s>/names                (n_o,) str       row names of the system vector x^s
partitions/name, system          (n_p',) str      the n_p' = n_partitions set partitions of
                                                  Table B-4; system one of standard, common,
                                                  fit, real, miss
partitions/tail, head            (n_p',) int      rows tail..head-1 (0-based, head exclusive)
                                                  of that system's vector
partitions/names                 (Σ (head-tail),) the row names of every partition, joined in
                                 str              partition order: partition i owns the
                                                  head_i - tail_i entries after those of
                                                  partitions 0..i-1; they equal the system's
                                                  names tail..head-1
apriori/S0_fit_factor            (L,)             S⁰ fit-world a priori normal matrix at
                                                  injection, in x^0
apriori/Lambda0_real_factor      (L,)             Λ̄⁰ real-world a priori covariance at
                                                  injection, in x^0
recycles/number                  (n_r,) int       recycle number i' = 1..n_r
recycles/k, l, j                 (n_r,) int       current, last recycle and program epoch
                                                  T13 indices (k ascending, l_1 < k_1,
                                                  l_i = k_{i-1})
recycles/t_s, t_l_s              (n_r,) float     t_k and t_l, s from the tape epoch
recycles/info                    (n_r, 6) float   state at t_k, km, km/s, EME2000
recycles/<i'>/S_fit_factor       (L,)             S' fit-world normal matrix (extended)
recycles/<i'>/Lambda_fit_factor  (L,)             Λ' fit-world covariance
recycles/<i'>/Lambda_real_factor (L,)             Λ̄' real-world covariance
recycles/<i'>/Sigma_factor       (L,)             Λ' J̃ Λ', this interval's tracking-noise
                                                  covariance
recycles/<i'>/J_factor,          (L,)             AᵀWA, AᵀWMWA from t_l to t_k
Jt_factor
recycles/<i'>/L                  (n_o, n_o)       ∂(a posteriori error)/∂(a priori error at
                                                  t_l), both in x^k, u_a/u_b
recycles/<i'>/B                  (n_m, n_o)       ∂m/∂x^k, (miss unit)/u_b
recycles/<i'>/transition         (n_o, n_o)       ∂x^k/∂x^{k_prev}, from the previous
                                                  recycle's representation (x^0 for the
                                                  first), u_a/u_b
recycles/<i'>/transition_adjoint (n_o, n_o)       its inverse transposed, u_b/u_a
recycles/<i'>/entities/<ω>/      (r, c)           output of recycle command ω (1-based) of
matrix                                            Table B-5; attrs command (seed notation,
                                                  e.g. "I; 0,-,pk; 1,2,fp"), alias (readable)
recycles/<i'>/entities/<ω>/      (r,), (c,) str   row and column labels (parameter names
rows, cols                                        with units)
===============================  ===============  =============================================

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
from tapp.io.tape.t13 import TapeParameters
from tapp.io.tape.t32 import (
    CHAINED,
    FACTOR_UNITS,
    FORMAT,
    INFO_UNITS,
    SIGMA_ROUNDING,
    STAMPED,
    SUPPORTED_VERSIONS,
    SYMMETRIC,
    T32,
    UNITS_NOTE,
    V1_PSD_TOL,
    VERSION,
    T32Entity,
    T32Partition,
    T32Recycle,
    validate,
)

__all__ = ["read_t32", "t32_file_writer", "write_t32"]


# ---------------------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------------------


def _write(f: h5py.File, t32: T32) -> None:
    n_o = t32.n_o
    extra = {k: v for k, v in t32.provenance.items() if k not in STAMPED}
    hdf5io.write_attrs(f, dict(
        format=FORMAT, version=VERSION, iden=t32.iden, n_o=n_o, n_p=t32.n_p, n_m=t32.n_m,
        n_recycles=len(t32.recycles), n_partitions=len(t32.partitions),
        epoch=t32.epoch.iso(6), epoch_jd_whole=t32.epoch.jd_whole,
        epoch_jd_fraction=t32.epoch.jd_fraction, time_scale="UTC", units=UNITS_NOTE,
        provenance_keys=list(extra), **hdf5io.provenance_attrs()))
    hdf5io.write_attrs(f, extra)
    strings, numbers = hdf5io.write_strings, hdf5io.write_numbers

    par = t32.parameters
    g = f.create_group("parameters")
    strings(g, "name", par.name)
    strings(g, "unit", par.unit)
    strings(g, "kind", par.kind)
    numbers(g, "station", par.station, "")
    numbers(g, "nominal", par.nominal, "see unit")
    g = f.create_group("miss")
    strings(g, "name", t32.miss_name)
    strings(g, "unit", t32.miss_unit)

    g = f.create_group("systems")
    for name in CHAINED:
        s = g.create_group(name)
        numbers(s, "chain", t32.systems[name], "(row unit)/(column unit)")
        strings(s, "names", t32.system_names[name])

    g = f.create_group("partitions")
    parts = t32.partitions
    strings(g, "name", [p.name for p in parts])
    strings(g, "system", [p.system for p in parts])
    numbers(g, "tail", np.array([p.tail for p in parts], dtype=np.int64), "row (0-based)")
    numbers(g, "head", np.array([p.head for p in parts], dtype=np.int64),
            "row (0-based, exclusive)")
    strings(g, "names", [n for p in parts for n in p.names])

    g = f.create_group("apriori")
    hdf5io.write_packed(g, "S0_fit_factor", t32.S0_fit_factor, FACTOR_UNITS["normal"],
                        form="factor")
    hdf5io.write_packed(g, "Lambda0_real_factor", t32.Lambda0_real_factor,
                        FACTOR_UNITS["covariance"], form="factor")

    g = f.create_group("recycles")
    rcs = t32.recycles
    for name in ("number", "k", "l", "j"):
        numbers(g, name, np.array([getattr(r, name) for r in rcs], dtype=np.int64), "")
    numbers(g, "t_s", np.array([r.t_s for r in rcs], dtype=float), "s")
    numbers(g, "t_l_s", np.array([r.t_l_s for r in rcs], dtype=float), "s")
    numbers(g, "info", np.array([r.info for r in rcs], dtype=float).reshape(len(rcs), 6),
            INFO_UNITS)
    for rc in rcs:
        rg = g.create_group(str(rc.number))
        for name, what, _ in SYMMETRIC:
            hdf5io.write_packed(rg, f"{name}_factor", getattr(rc, f"{name}_factor"),
                                FACTOR_UNITS[what], form="factor", big=n_o > 100)
        numbers(rg, "L", rc.L, "u_a/u_b", big=n_o > 100)
        numbers(rg, "transition", rc.transition, "u_a/u_b", big=n_o > 100)
        numbers(rg, "transition_adjoint", rc.transition_adjoint, "u_b/u_a", big=n_o > 100)
        numbers(rg, "B", rc.B, "miss/unit per parameters/unit")
        eg = rg.create_group("entities")
        for e in rc.entities:
            ent = eg.create_group(str(int(e.omega)))
            hdf5io.write_attrs(ent, {"command": e.command, "alias": e.alias})
            numbers(ent, "matrix", np.asarray(e.matrix, dtype=float),
                    "(row unit)/(column unit), or their product for normal and covariance "
                    "blocks: see rows, cols")
            strings(ent, "rows", e.rows)
            strings(ent, "cols", e.cols)


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


def _entities(r: Reader, base: str) -> tuple[T32Entity, ...]:
    group = r.dataset_or_group(f"{base}/entities")
    if not isinstance(group, h5py.Group):
        r.check.fail(f"{base}/entities", "a group of command outputs", "a dataset")
    with r.guard(f"{base}/entities", "a readable group"):
        keys = list(group.keys())
    if not all(key.isdigit() and int(key) >= 1 for key in keys):
        r.check.fail(f"{base}/entities", "command numbers ω >= 1 as group names", keys)
    out = []
    for omega in sorted(int(key) for key in keys):
        where = f"{base}/entities/{omega}"
        out.append(T32Entity(omega, r.attr("command", str, owner=where),
                             r.attr("alias", str, owner=where, default=""),
                             r.strings(f"{where}/rows"), r.strings(f"{where}/cols"),
                             r.read(f"{where}/matrix")))
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


def _v1_recycle_factors(r: Reader, base: str, n: int) -> dict[str, np.ndarray]:
    real = np.clip(np.diagonal(r.symmetric(f"{base}/Lambda_real", (), n)), 0.0, None)
    out = {}
    for name, _, _ in SYMMETRIC:
        # Σ <= Λ̄' in exact arithmetic: Λ̄' sets its rounding floor and its scale
        sigma = name == "Sigma"
        out[name] = _v1_factor(r, f"{base}/{name}", n, SIGMA_ROUNDING * real if sigma else None,
                               real if sigma else None)
    return out


def _v1_adjoint(r: Reader, name: str, transition: np.ndarray) -> np.ndarray:
    """Version 1 has no adjoint: (T⁻¹)ᵀ by an LU solve."""
    r.check.finite(name, transition)
    try:
        return np.linalg.solve(transition, np.eye(transition.shape[0])).T
    except np.linalg.LinAlgError:
        r.check.fail(name, "an invertible transition")


def _read(r: Reader) -> T32:
    version = r.format_version(FORMAT, SUPPORTED_VERSIONS)
    if version == 1:
        warnings.warn(f"{r.check.source}: T32 version 1 carries the covariances, not their "
                      "factors: they hold only the digits their products kept (the real-world "
                      "covariances of an ill-conditioned fit, a few); process the T13 tape "
                      "again for version 2", UserWarning, stacklevel=4)
    dims = {name: r.attr(name, int) for name in ("n_o", "n_p", "n_m", "n_recycles",
                                                 "n_partitions")}
    n_o = dims["n_o"]
    epoch = Epoch(r.attr("epoch_jd_whole", float), r.attr("epoch_jd_fraction", float))
    parameters = TapeParameters(r.strings("parameters/name"), r.strings("parameters/unit"),
                                r.strings("parameters/kind"), r.read("parameters/station", "i"),
                                r.read("parameters/nominal"))
    miss_name, miss_unit = r.strings("miss/name"), r.strings("miss/unit")
    for name, value in (("n_o", len(parameters.name)), ("n_m", len(miss_name))):
        if dims[name] != value:
            r.check.fail(f"attrs/{name}", f"{name} = {value} as the datasets have", dims[name])

    group = r.dataset_or_group("systems")
    if not isinstance(group, h5py.Group):
        r.check.fail("systems", "a group of system chains", "a dataset")
    with r.guard("systems", "a readable group"):
        keys = sorted(group.keys())
    if keys != sorted(CHAINED):
        r.check.fail("systems", f"the systems {', '.join(CHAINED)}", keys)
    systems = {name: r.read(f"systems/{name}/chain") for name in CHAINED}
    system_names = {name: r.strings(f"systems/{name}/names") for name in CHAINED}

    n_part = dims["n_partitions"]
    p_name, p_system = r.strings("partitions/name"), r.strings("partitions/system")
    tail, head = r.read("partitions/tail", "i"), r.read("partitions/head", "i")
    for name, values in (("name", p_name), ("system", p_system), ("tail", tail),
                         ("head", head)):
        if len(values) != n_part:
            r.check.fail(f"partitions/{name}", f"n_partitions = {n_part} entries", len(values))
    flat = r.strings("partitions/names")
    sizes = head - tail
    if np.any(sizes < 0) or int(sizes.sum()) != len(flat):
        r.check.fail("partitions/names", "head - tail names for each partition, "
                                         f"{int(np.clip(sizes, 0, None).sum())} in all",
                     len(flat))
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
    partitions = tuple(
        T32Partition(p_name[i], p_system[i], int(tail[i]), int(head[i]),
                     flat[offsets[i]:offsets[i + 1]]) for i in range(n_part))

    if version == 1:
        s0 = _v1_factor(r, "apriori/S0_fit", n_o)
        lam0 = _v1_factor(r, "apriori/Lambda0_real", n_o)
    else:
        s0 = r.triangular("apriori/S0_fit_factor", (), n_o)
        lam0 = r.triangular("apriori/Lambda0_real_factor", (), n_o)

    n_r = dims["n_recycles"]
    table = {name: r.read(f"recycles/{name}", "i") for name in ("number", "k", "l", "j")}
    table.update({name: r.read(f"recycles/{name}") for name in ("t_s", "t_l_s")})
    for name, values in table.items():
        r.check.shape(f"recycles/{name}", values, (n_r,))
    info = r.read("recycles/info")
    r.check.shape("recycles/info", info, (n_r, 6))
    if not np.array_equal(table["number"], np.arange(1, n_r + 1)):
        r.check.fail("recycles/number", f"recycle numbers 1..{n_r} in order",
                     table["number"].tolist())
    recycles = []
    for i in range(n_r):
        base = f"recycles/{i + 1}"
        transition = r.read(f"{base}/transition")
        if version == 1:
            fac = _v1_recycle_factors(r, base, n_o)
            adjoint = _v1_adjoint(r, f"{base}/transition", transition)
        else:
            fac = {name: r.triangular(f"{base}/{name}_factor", (), n_o)
                   for name, _, _ in SYMMETRIC}
            adjoint = r.read(f"{base}/transition_adjoint")
        recycles.append(T32Recycle(
            i + 1, int(table["k"][i]), int(table["l"][i]), int(table["j"][i]),
            float(table["t_s"][i]), float(table["t_l_s"][i]), info[i], fac["S_fit"],
            fac["Lambda_fit"], fac["Lambda_real"], r.read(f"{base}/L"), fac["Sigma"],
            fac["J"], fac["Jt"], r.read(f"{base}/B"), transition, adjoint,
            _entities(r, base)))

    keys = r.attr("provenance_keys", list, default=())
    provenance = {key: r.attr(key, str) for key in (*STAMPED, *keys) if r.has_attr(key)}
    return T32(r.attr("iden", str), epoch, dims["n_p"], parameters, miss_name, miss_unit,
               systems, system_names, partitions, s0, lam0, tuple(recycles), provenance)


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

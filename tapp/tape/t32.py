"""The T32 tape (TAPP III -> TAPP II): schema, atomic HDF5 writer, validating reader.

Seed TAPP III §4.3.3 (the recycle phase) fixes the content: at each recycle (midcourse
correction) time t_k the processor writes a heading (i', j, l, k, INFO) and the outputs of the
recycle output commands ω = 1..n_RO (ROC, seed Table B-5), on sets of the partitions of seed
Table B-4 (fp, fq, fz, r1, m1, ...). DESIGN.md ("Tapes") fixes the HDF5 form. Besides the
command outputs the tape carries, per recycle, every matrix TAPP II needs in one
representation, x^k = [orbit at t_k; q] (the standard system of the seed with the orbit
parameters at the recycle time), so TAPP II needs no command output to run.

Notation: n_o parameters x = [p; q] as on the T13 tape (n_p orbit parameters p), n_m miss
parameters, recycles i' = 1..n_r at the T13 record indices k; l the index of the last
recycle time (0 for the first: injection), j the program epoch index; u_a the unit of
parameter a (``parameters/unit``; the orbit at t_k has the units of p).

HDF5 layout, version 1. Every dataset is chunked with a Fletcher-32 checksum and has a
``units`` attribute; text is fixed-length UTF-8 (attributes too: h5py reads them as bytes);
symmetric matrices are packed "TR" (upper triangle by rows, L = n_o(n_o+1)/2 entries; attrs
``packing`` = "TR", ``order`` = n_o) as on the T13 tape (:mod:`tapp.tape.hdf5io`):

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
apriori/S0_fit                   (L,)             S⁰ fit-world a priori normal matrix at
                                                  injection, in x^0, 1/(u_a u_b)
apriori/Lambda0_real             (L,)             Λ̄⁰ real-world a priori covariance at
                                                  injection, in x^0, u_a u_b
recycles/number                  (n_r,) int       recycle number i' = 1..n_r
recycles/k, l, j                 (n_r,) int       current, last recycle and program epoch
                                                  T13 indices (k ascending, l_1 < k_1,
                                                  l_i = k_{i-1})
recycles/t_s, t_l_s              (n_r,) float     t_k and t_l, s from the tape epoch
recycles/info                    (n_r, 6) float   state at t_k, km, km/s, EME2000
recycles/<i'>/S_fit              (L,)             S' fit-world normal matrix (extended),
                                                  1/(u_a u_b)
recycles/<i'>/Lambda_fit         (L,)             Λ' fit-world covariance, u_a u_b
recycles/<i'>/Lambda_real        (L,)             Λ̄' real-world covariance, u_a u_b
recycles/<i'>/Sigma              (L,)             Λ' J̃ Λ', this interval's tracking-noise
                                                  covariance, u_a u_b
recycles/<i'>/J, Jt              (L,)             AᵀWA, AᵀWMWA from t_l to t_k, 1/(u_a u_b)
recycles/<i'>/L                  (n_o, n_o)       ∂(a posteriori error)/∂(a priori error at
                                                  t_l), both in x^k, u_a/u_b
recycles/<i'>/B                  (n_m, n_o)       ∂m/∂x^k, (miss unit)/u_b
recycles/<i'>/transition         (n_o, n_o)       ∂x^k/∂x^{k_prev}, from the previous
                                                  recycle's representation (x^0 for the
                                                  first), u_a/u_b
recycles/<i'>/entities/<ω>/      (r, c)           output of recycle command ω (1-based) of
matrix                                            Table B-5; attrs command (seed notation,
                                                  e.g. "I; 0,-,pk; 1,2,fp"), alias (readable)
recycles/<i'>/entities/<ω>/      (r,), (c,) str   row and column labels (parameter names
rows, cols                                        with units)
===============================  ===============  =============================================

All n_o x n_o matrices of a recycle are in x^k, with k that recycle's record index. The writer
validates, then writes to a temporary file beside the target and renames it: no half-written
tape. The reader rejects a wrong format or version, a missing dataset or attribute, a wrong
shape, a non-finite value, a non-symmetric or negative-diagonal normal or covariance matrix, a
partition outside its system (or whose names are not the system's), recycle numbers other
than 1..n_r, indices k not ascending, an entity matrix whose shape is not (rows, cols), a
dataset without a checksum and a checksum mismatch, with a :class:`~tapp.errors.TapeError`
``"{file}: {dataset}: expected ... (got ...)"``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from tapp.atomic import atomic_write
from tapp.frames.time import Epoch
from tapp.tape import hdf5io
from tapp.tape.hdf5io import Checker, Reader
from tapp.tape.t13 import TapeParameters, check_parameters, utc_at

FORMAT = "T32"
VERSION = 1
SUPPORTED_VERSIONS = (1,)
#: Systems a partition may belong to; the systems with a chain on the tape.
SYSTEMS = ("standard", "common", "fit", "real", "miss")
CHAINED = ("common", "fit", "real")
#: Symmetric matrices of a recycle: (name, "normal" or "covariance", units).
SYMMETRIC = (("S_fit", "normal", "1/(u_a u_b)"), ("Lambda_fit", "covariance", "u_a u_b"),
             ("Lambda_real", "covariance", "u_a u_b"), ("Sigma", "covariance", "u_a u_b"),
             ("J", "normal", "1/(u_a u_b)"), ("Jt", "normal", "1/(u_a u_b)"))
#: Σ = Λ' J̃ Λ' is a covariance, but the variance of a parameter the data barely reach
#: cancels to ~0 and its rounding can come out negative (−1.5e-9 Λ̄'_ii seen when a station
#: is switched off); since Σ <= Λ̄' in exact arithmetic, Σ_ii down to −1e-6 Λ̄'_ii is rounding.
SIGMA_ROUNDING = 1e-6
#: Provenance the writer stamps itself (a value given for these is replaced).
STAMPED = ("tapp_version", "git_commit", "created_utc")
#: Root attributes of the schema: not available as provenance names.
SCHEMA_ATTRS = ("format", "version", "iden", "n_o", "n_p", "n_m", "n_recycles",
                "n_partitions", "epoch", "epoch_jd_whole", "epoch_jd_fraction", "time_scale",
                "units", "provenance_keys")
UNITS_NOTE = ("km, km/s, s, rad; with u the units of parameters/unit (the orbit at t_k in "
              "the units of p): normal matrices 1/(u_a u_b), covariances u_a u_b, partials "
              "(row unit)/(column unit)")
#: Unit note of the state in ``recycles/info``.
INFO_UNITS = "km, km/s (x, y, z, vx, vy, vz), EME2000"
_ORBIT_UNITS = ("km", "km", "km", "km/s", "km/s", "km/s")

__all__ = ["FORMAT", "SUPPORTED_VERSIONS", "SYSTEMS", "T32", "VERSION", "T32Entity",
           "T32Partition", "T32Recycle", "format_t32_summary", "read_t32", "summary",
           "t32_file_writer", "validate", "write_t32"]


# ---------------------------------------------------------------------------------------------
# The tape in memory
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, eq=False)
class T32Entity:
    """One output entity of a recycle command (seed TAPP III Table B-5, ROC).

    Attributes
    ----------
    omega : command number ω, 1-based.
    command : the command in seed notation ``σ0; μ1,τ1,ρ1; μ2,τ2,ρ2``, e.g.
        ``"I; 0,-,pk; 1,2,fp"``.
    alias : its readable form, e.g. ``"partials pk wrt fp@recycle"``.
    rows, cols : labels of the rows and columns (parameter names with units).
    matrix : (len(rows), len(cols)) the output, (row unit)/(column unit) for partials, the
        product of the units for normal and covariance blocks.
    """

    omega: int
    command: str
    alias: str
    rows: tuple[str, ...]
    cols: tuple[str, ...]
    matrix: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class T32Partition:
    """A set partition of seed Table B-4 (e.g. fp, fq, fz, r1, m1).

    Attributes
    ----------
    name : partition name.
    system : "standard", "common", "fit", "real" or "miss".
    tail, head : rows tail..head-1 (0-based, head exclusive) of that system's vector.
    names : (head - tail) names of those rows.
    """

    name: str
    system: str
    tail: int
    head: int
    names: tuple[str, ...]


@dataclass(frozen=True, slots=True, eq=False)
class T32Recycle:
    """One recycle (midcourse correction) time.

    Every n_o x n_o matrix is in the representation x^k = [orbit at t_k; q] (standard
    system), k the record index.

    Attributes
    ----------
    number : recycle number i', 1-based.
    k, l, j : current, last recycle and program epoch T13 indices.
    t_s, t_l_s : t_k and t_l, s from the tape epoch.
    info : (6,) state at t_k, km, km/s.
    S_fit : (n_o, n_o) S' fit-world normal matrix (extended), symmetric, 1/(u_a u_b).
    Lambda_fit : (n_o, n_o) Λ' fit-world covariance, symmetric PSD, u_a u_b.
    Lambda_real : (n_o, n_o) Λ̄' real-world covariance, symmetric PSD, u_a u_b.
    L : (n_o, n_o) ∂(a posteriori error)/∂(a priori error at t_l), both in x^k.
    Sigma : (n_o, n_o) Λ' J̃ Λ', this interval's tracking-noise covariance, symmetric.
    J, Jt : (n_o, n_o) AᵀWA, AᵀWMWA from t_l to t_k in x^k, symmetric, 1/(u_a u_b).
    B : (n_m, n_o) ∂m/∂x^k.
    transition : (n_o, n_o) ∂x^k/∂x^{k_prev}, from the previous recycle's representation
        (the injection representation x^0 for the first).
    entities : the recycle command outputs, ω ascending.
    """

    number: int
    k: int
    l: int  # noqa: E741  (the seed's name of the last recycle index)
    j: int
    t_s: float
    t_l_s: float
    info: np.ndarray
    S_fit: np.ndarray
    Lambda_fit: np.ndarray
    Lambda_real: np.ndarray
    L: np.ndarray
    Sigma: np.ndarray
    J: np.ndarray
    Jt: np.ndarray
    B: np.ndarray
    transition: np.ndarray
    entities: tuple[T32Entity, ...]


@dataclass(frozen=True, slots=True, eq=False)
class T32:
    """A T32 tape in memory: what TAPP III writes and TAPP II reads.

    Attributes
    ----------
    iden : identification (of the T13 tape's run).
    epoch : the tape epoch (t = 0, injection), as on the T13 tape.
    n_p : number of orbit parameters.
    parameters : the n_o standard parameters, from the T13 tape.
    miss_name, miss_unit : the n_m miss parameters.
    systems : "common", "fit", "real" -> (n_o, n_o) system chain ∂x^s/∂x (q links only).
    system_names : "common", "fit", "real" -> (n_o) row names of each system vector.
    partitions : the set partitions (Table B-4).
    S0_fit : (n_o, n_o) fit-world a priori normal matrix at injection in x^0.
    Lambda0_real : (n_o, n_o) real-world a priori covariance at injection in x^0.
    recycles : the recycles, numbers 1..n_r.
    provenance : text describing how the tape was made (e.g. deck (JSON), deck_source,
        t13_source, t13_iden; plus tapp_version, git_commit, created_utc on reading).
    """

    iden: str
    epoch: Epoch
    n_p: int
    parameters: TapeParameters
    miss_name: tuple[str, ...]
    miss_unit: tuple[str, ...]
    systems: dict[str, np.ndarray]
    system_names: dict[str, tuple[str, ...]]
    partitions: tuple[T32Partition, ...]
    S0_fit: np.ndarray
    Lambda0_real: np.ndarray
    recycles: tuple[T32Recycle, ...]
    provenance: dict[str, str] = field(default_factory=dict)

    @property
    def n_o(self) -> int:
        """Number of parameters."""
        return len(self.parameters.name)

    @property
    def n_m(self) -> int:
        """Number of miss parameters."""
        return len(self.miss_name)

    def system_size(self, system: str) -> int:
        """Length of a system's vector: n_m for "miss", n_o otherwise."""
        return self.n_m if system == "miss" else self.n_o

    def names_of(self, system: str) -> tuple[str, ...]:
        """Row names of a system's vector."""
        if system == "standard":
            return self.parameters.name
        if system == "miss":
            return self.miss_name
        return self.system_names[system]

    def partition(self, name: str) -> T32Partition:
        """Return the partition called ``name`` (KeyError if there is none)."""
        for p in self.partitions:
            if p.name == name:
                return p
        raise KeyError(name)


# ---------------------------------------------------------------------------------------------
# Validation
# ---------------------------------------------------------------------------------------------


def _matrix(c: Checker, name: str, m: np.ndarray, shape: tuple[int, ...]) -> None:
    if not isinstance(m, np.ndarray):
        c.fail(name, f"an array of shape {shape}", type(m).__name__)
    c.shape(name, m, shape)
    c.finite(name, m)


def _symmetric(c: Checker, name: str, m: np.ndarray, n: int, what: str,
               floor: np.ndarray | None = None) -> None:
    _matrix(c, name, m, (n, n))
    c.symmetric(name, m, what=f"{what} matrix", label=None, floor=floor)


def validate(t32: T32, source: str = "T32") -> None:
    """Check the dimensions and invariants of a T32 tape; raise TapeError naming the dataset.

    Checks: n_p in 1..n_o, parameter and miss lists of matching lengths; the three system
    chains (n_o, n_o) finite with n_o row names; partitions uniquely named, in a known
    system, 0 <= tail <= head <= the system's length, their names those of the system's
    rows; the a priori and every recycle's symmetric matrices (n_o, n_o), finite, symmetric
    (relative asymmetry <= 1e-12) with a non-negative diagonal; recycle numbers 1..n_r, k
    strictly ascending, 0 <= l < k with l_i = k_{i-1}, 0 <= j < k, 0 <= t_l < t_k with
    t_l of a recycle the t_k of the one before; the other matrices of the right shapes and
    finite; entity numbers ω >= 1 ascending, matrices (len(rows), len(cols)) and finite;
    provenance text under names that are not schema attributes.
    """
    c = Checker(source)
    n_o, n_p, n_m = t32.n_o, t32.n_p, t32.n_m
    check_parameters(c, t32.parameters, n_p)
    if len(t32.miss_unit) != n_m:
        c.fail("miss/unit", f"{n_m} entries", len(t32.miss_unit))

    for what, mapping in (("systems", t32.systems), ("system_names", t32.system_names)):
        if sorted(mapping) != sorted(CHAINED):
            c.fail("systems", f"the systems {', '.join(CHAINED)} ({what})",
                   ", ".join(sorted(mapping)) or "none")
    for name in CHAINED:
        _matrix(c, f"systems/{name}/chain", t32.systems[name], (n_o, n_o))
        if len(t32.system_names[name]) != n_o:
            c.fail(f"systems/{name}/names", f"{n_o} names", len(t32.system_names[name]))

    seen: set[str] = set()
    for i, p in enumerate(t32.partitions):
        where = f"partitions/name[{i}]"
        if not p.name or p.name in seen:
            c.fail(where, "a unique, non-empty partition name", repr(p.name))
        seen.add(p.name)
        if p.system not in SYSTEMS:
            c.fail(f"partitions/system[{i}]", f"one of {', '.join(SYSTEMS)}", repr(p.system))
        size = t32.system_size(p.system)
        if not (0 <= p.tail <= p.head <= size):
            c.fail(f"partitions/tail[{i}]", f"0 <= tail <= head <= {size} (rows of the "
                                            f"{p.system} system) for {p.name}",
                   f"tail = {p.tail}, head = {p.head}")
        expected = t32.names_of(p.system)[p.tail:p.head]
        if tuple(p.names) != tuple(expected):
            c.fail(f"partitions/names[{i}]", f"the names of rows {p.tail}..{p.head - 1} of the "
                                             f"{p.system} system for {p.name}: "
                                             f"{', '.join(expected)}", ", ".join(p.names))

    _symmetric(c, "apriori/S0_fit", t32.S0_fit, n_o, "normal")
    _symmetric(c, "apriori/Lambda0_real", t32.Lambda0_real, n_o, "covariance")

    prev: T32Recycle | None = None
    for i, rc in enumerate(t32.recycles):
        base = f"recycles/{rc.number}"
        if rc.number != i + 1:
            c.fail("recycles/number", f"recycle numbers 1..{len(t32.recycles)} in order",
                   [r.number for r in t32.recycles])
        if prev is not None and rc.k <= prev.k:
            c.fail("recycles/k", "strictly ascending record indices k",
                   [r.k for r in t32.recycles])
        if rc.k < 1:
            c.fail("recycles/k", "record indices k >= 1", rc.k)
        expected_l = 0 if prev is None else prev.k
        if not (0 <= rc.l < rc.k) or (prev is not None and rc.l != expected_l):
            c.fail("recycles/l", "the last recycle index: 0 <= l < k, and l = k of the recycle "
                                 "before", f"l = {rc.l} in recycle {rc.number} (k = {rc.k})")
        if not 0 <= rc.j <= rc.k:  # j = k at an epoch time: the update phase comes first
            c.fail("recycles/j", "a program epoch index 0 <= j <= k",
                   f"j = {rc.j} in recycle {rc.number} (k = {rc.k})")
        if not (math.isfinite(rc.t_s) and math.isfinite(rc.t_l_s) and 0 <= rc.t_l_s < rc.t_s
                and (prev is None or rc.t_l_s == prev.t_s)):
            c.fail("recycles/t_l_s", "finite times 0 <= t_l < t_k, t_l = t_k of the recycle "
                                     "before", f"t_l = {rc.t_l_s}, t_k = {rc.t_s} in recycle "
                                               f"{rc.number}")
        _matrix(c, "recycles/info", rc.info, (6,))
        for name, what, _ in SYMMETRIC:
            floor = None
            if name == "Sigma" and np.shape(rc.Lambda_real) == (n_o, n_o):
                floor = SIGMA_ROUNDING * np.clip(np.diagonal(rc.Lambda_real), 0.0, None)
            _symmetric(c, f"{base}/{name}", getattr(rc, name), n_o, what, floor)
        for name in ("L", "transition"):
            _matrix(c, f"{base}/{name}", getattr(rc, name), (n_o, n_o))
        _matrix(c, f"{base}/B", rc.B, (n_m, n_o))
        omega = 0
        for e in rc.entities:
            where = f"{base}/entities/{e.omega}"
            if not (isinstance(e.omega, int | np.integer) and e.omega > omega):
                c.fail(f"{base}/entities", "command numbers ω >= 1, ascending, each once",
                       [x.omega for x in rc.entities])
            omega = e.omega
            if not e.command.strip():
                c.fail(f"{where}.attrs/command", "the command in seed notation", repr(e.command))
            _matrix(c, f"{where}/matrix", e.matrix, (len(e.rows), len(e.cols)))
        prev = rc

    for key, value in t32.provenance.items():
        if (not isinstance(key, str) or not key or "/" in key or key in SCHEMA_ATTRS
                or not isinstance(value, str)):
            c.fail(f"attrs/{key}", "provenance text under a name that is not a schema "
                                   f"attribute ({', '.join(SCHEMA_ATTRS)})",
                   f"{key!r} = {type(value).__name__}")


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
    hdf5io.write_symmetric(g, "S0_fit", t32.S0_fit, "1/(u_a u_b)")
    hdf5io.write_symmetric(g, "Lambda0_real", t32.Lambda0_real, "u_a u_b")

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
        for name, _, units in SYMMETRIC:
            hdf5io.write_symmetric(rg, name, getattr(rc, name), units, big=n_o > 100)
        numbers(rg, "L", rc.L, "u_a/u_b", big=n_o > 100)
        numbers(rg, "transition", rc.transition, "u_a/u_b", big=n_o > 100)
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

    For committing several outputs together (:func:`tapp.atomic.atomic_write` of each);
    :func:`write_t32` is ``atomic_write(path, t32_file_writer(t32))``.

    Raises
    ------
    TapeError
        If the tape fails :func:`validate` (``source`` names it in the message).
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
        If the tape fails :func:`validate` (nothing is written).
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


def _read(r: Reader) -> T32:
    fmt = r.attr("format", str)
    if fmt != FORMAT:
        r.check.fail("attrs/format", f"format = {FORMAT!r}", repr(fmt))
    version = r.attr("version", int)
    if version not in SUPPORTED_VERSIONS:
        r.check.fail("attrs/version", f"a supported version {SUPPORTED_VERSIONS}", version)
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

    s0 = r.symmetric("apriori/S0_fit", (), n_o)
    lam0 = r.symmetric("apriori/Lambda0_real", (), n_o)

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
        sym = {name: r.symmetric(f"{base}/{name}", (), n_o) for name, _, _ in SYMMETRIC}
        recycles.append(T32Recycle(
            i + 1, int(table["k"][i]), int(table["l"][i]), int(table["j"][i]),
            float(table["t_s"][i]), float(table["t_l_s"][i]), info[i], sym["S_fit"],
            sym["Lambda_fit"], sym["Lambda_real"], r.read(f"{base}/L"), sym["Sigma"], sym["J"],
            sym["Jt"], r.read(f"{base}/B"), r.read(f"{base}/transition"),
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
        a valid T32 tape (:func:`validate`); the message names the file and the dataset (or
        attribute) at fault.
    """
    path = Path(path)
    with hdf5io.open_tape(path, "T32 tape") as f:
        t32 = _read(Reader(f, str(path), checksums=True))
    validate(t32, str(path))
    return t32


# ---------------------------------------------------------------------------------------------
# Summary
# ---------------------------------------------------------------------------------------------


def _sigmas(t32: T32, cov: np.ndarray) -> tuple[float | None, float | None]:
    """RSS σ of the position (km) and velocity (km/s) at t_k, when x^k starts with them."""
    if t32.n_p < 6 or tuple(t32.parameters.unit[:6]) != _ORBIT_UNITS:
        return None, None
    d = np.clip(np.diag(cov)[:6], 0.0, None)
    return float(np.sqrt(d[:3].sum())), float(np.sqrt(d[3:].sum()))


def summary(t32: T32, *, version: int = VERSION) -> dict:
    """Return a JSON-ready summary: dimensions, partitions with their names, systems, and per
    recycle its indices, time, position and velocity σ (fit vs real world) and entities."""
    recycles = []
    for rc in t32.recycles:
        pos_fit, vel_fit = _sigmas(t32, rc.Lambda_fit)
        pos_real, vel_real = _sigmas(t32, rc.Lambda_real)
        recycles.append({
            "number": rc.number, "k": rc.k, "l": rc.l, "j": rc.j, "t_s": rc.t_s,
            "t_l_s": rc.t_l_s, "utc": utc_at(t32.epoch, rc.t_s),
            "sigma_position_km": {"fit": pos_fit, "real": pos_real},
            "sigma_velocity_km_s": {"fit": vel_fit, "real": vel_real},
            "entities": [{"omega": e.omega, "command": e.command, "alias": e.alias,
                          "shape": list(e.matrix.shape)} for e in rc.entities]})
    return {
        "format": FORMAT, "version": version, "iden": t32.iden,
        "epoch_utc": t32.epoch.iso(3),
        "dimensions": {"n_o": t32.n_o, "n_p": t32.n_p, "n_m": t32.n_m,
                       "n_recycles": len(t32.recycles), "n_partitions": len(t32.partitions)},
        "parameters": [{"name": n, "unit": u} for n, u in zip(t32.parameters.name,
                                                              t32.parameters.unit, strict=True)],
        "miss": [{"name": n, "unit": u} for n, u in zip(t32.miss_name, t32.miss_unit,
                                                        strict=True)],
        "systems": {name: list(t32.system_names[name]) for name in CHAINED},
        "partitions": [{"name": p.name, "system": p.system, "tail": p.tail, "head": p.head,
                        "names": list(p.names)} for p in t32.partitions],
        "recycles": recycles,
        "provenance": {k: v for k, v in t32.provenance.items() if k != "deck"},
    }


def _number(value: float | None, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def format_t32_summary(info: dict) -> str:
    """Render :func:`summary`'s dict (as ``tapp tape info`` prints it) as plain text."""
    dims = info["dimensions"]
    lines = [f"T32 v{info['version']}  iden {info['iden']}  epoch {info['epoch_utc']} UTC",
             "  ".join(f"{k} = {v}" for k, v in dims.items()), "", "Partitions"]
    width = max([4, *(len(p["name"]) for p in info["partitions"])])
    for p in info["partitions"]:
        rows = f"{p['tail']}..{p['head'] - 1}" if p["head"] > p["tail"] else "(empty)"
        lines.append(f"  {p['name']:<{width}}  {p['system']:<8}  rows {rows:<8}  "
                     + ", ".join(p["names"]))
    lines += ["", "Recycles (sigma: RSS of position km / velocity km/s, fit vs real world)",
              f"  {'#':>3} {'k':>5} {'l':>5} {'j':>5} {'t (s)':>14}  {'UTC':<23}  "
              f"{'pos fit':>10} {'pos real':>10} {'vel fit':>10} {'vel real':>10}"]
    for rc in info["recycles"]:
        pos, vel = rc["sigma_position_km"], rc["sigma_velocity_km_s"]
        lines.append(f"  {rc['number']:>3} {rc['k']:>5} {rc['l']:>5} {rc['j']:>5} "
                     f"{rc['t_s']:>14.3f}  {rc['utc']:<23}  {_number(pos['fit'], '10.4g')} "
                     f"{_number(pos['real'], '10.4g')} {_number(vel['fit'], '10.4g')} "
                     f"{_number(vel['real'], '10.4g')}")
        for e in rc["entities"]:
            alias = f"  ({e['alias']})" if e["alias"] else ""
            lines.append(f"      ω {e['omega']:>2}: {e['command']}{alias}  "
                         f"{e['shape'][0]} x {e['shape'][1]}")
    prov = info["provenance"]
    lines += ["", f"written by tapp {prov.get('tapp_version', '?')} on "
                  f"{prov.get('created_utc', '?')} from {prov.get('deck_source', '?')} and "
                  f"{prov.get('t13_source', '?')}; Earth orientation "
                  f"{prov.get('t13_earth_orientation', 'gmst (not recorded)')}"]
    return "\n".join(line.rstrip() for line in lines)

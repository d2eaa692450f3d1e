"""The T32 tape (TAPP III -> TAPP II) in memory: types, validation, summary.

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

A tape (:class:`T32`) holds the n_o standard parameters and the n_m miss parameters, the
system chains of the deck, the set partitions (:class:`T32Partition`), the a priori at
injection and the recycles (:class:`T32Recycle`), each with its matrices and the outputs of
the recycle commands (:class:`T32Entity`). All n_o x n_o matrices of a recycle are in x^k,
with k that recycle's record index.

Version 2 carries every symmetric matrix (normal matrix or covariance) as its upper-triangular
factor K, M = KᵀK (square-root information or covariance, as TAPP III computes them), so that
TAPP II forms Σ, draws its samples and re-runs the regression without subtraction and without
factoring a matrix that rounding has made indefinite; the matrices themselves are the
properties of the same names (:attr:`T32Recycle.Sigma`). It also carries each transition's
adjoint (inverse transpose), the orbit block's from its exact inverse (TAPP III rounds it to a
double-double, :func:`tapp.estimation.factors.accurate_inverse`). Version 1 carried the
matrices; its reader factors them (:mod:`tapp.io.tape.t32_hdf5`).

:func:`validate` checks the dimensions and invariants of a tape; :func:`summary` and
:func:`format_t32_summary` summarise it. NumPy only: the HDF5 layout, the writer and the
reader are in :mod:`tapp.io.tape.t32_hdf5`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tapp.estimation.factors import gram
from tapp.frames.time import Epoch
from tapp.io.tape.checks import MAX_MAGNITUDE, Checker
from tapp.io.tape.layout import T32_LAYOUT, T32_SYMMETRIC, Field, filled, sourced
from tapp.io.tape.t13 import TapeParameters, check_parameters

FORMAT = "T32"
VERSION = 2
SUPPORTED_VERSIONS = (1, 2)
#: Systems a partition may belong to; the systems with a chain on the tape.
SYSTEMS = ("standard", "common", "fit", "real", "miss")
CHAINED = ("common", "fit", "real")
#: Symmetric matrices of a recycle: (name, "normal" or "covariance", units of the matrix),
#: from the layout (:data:`tapp.io.tape.layout.T32_SYMMETRIC`). Version 2 stores the factor of
#: each (``<name>_factor``, units the square roots).
SYMMETRIC = tuple((name, what, units) for name, what, units, _ in T32_SYMMETRIC)
#: Version 1 only (it carried Σ = Λ' J̃ Λ' formed as a product): the variance of a parameter
#: the data barely reach cancels to ~0 and its rounding can come out negative (−1.5e-9 Λ̄'_ii
#: seen when a station is switched off); since Σ <= Λ̄' in exact arithmetic, Σ_ii down to
#: −1e-6 Λ̄'_ii is read as rounding.
SIGMA_ROUNDING = 1e-6
#: Version 1 only: largest scaled difference between a stored covariance or normal matrix and
#: the Gram matrix of its factor (its positive part). Those products were PSD only to the
#: rounding of their terms: Σ_k's scaled eigenvalues reached −2e-4 on the deep-space tape.
V1_PSD_TOL = 1e-3
#: Largest |Tᵀ A − I|, relative to the terms |T|ᵀ|A|, for a transition T and its adjoint A:
#: TAPP III inverts the tape's STMs exactly and rounds the result, so the product is I to
#: ~1e-12 of the terms; anything beyond this is not the adjoint of that transition.
ADJOINT_TOL = 1e-6
#: Root attributes of the schema: not available as provenance names.
SCHEMA_ATTRS = ("format", "version", "iden", "n_o", "n_p", "n_m", "n_recycles",
                "n_partitions", "epoch", "epoch_jd_whole", "epoch_jd_fraction", "time_scale",
                "units", "provenance_keys")
UNITS_NOTE = ("km, km/s, s, rad; with u the units of parameters/unit (the orbit at t_k in "
              "the units of p): normal matrices 1/(u_a u_b), covariances u_a u_b, partials "
              "(row unit)/(column unit)")
_ORBIT_UNITS = ("km", "km", "km", "km/s", "km/s", "km/s")

__all__ = ["FORMAT", "SUPPORTED_VERSIONS", "SYSTEMS", "T32", "VERSION", "T32Entity",
           "T32Partition", "T32Recycle", "format_t32_summary", "summary", "validate"]


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
    S_fit_factor : (n_o, n_o) upper-triangular factor of S', the fit-world normal matrix
        (extended), 1/u_b.
    Lambda_fit_factor : (n_o, n_o) factor of Λ', the fit-world covariance, u_b.
    Lambda_real_factor : (n_o, n_o) factor of Λ̄', the real-world covariance, u_b.
    L : (n_o, n_o) ∂(a posteriori error)/∂(a priori error at t_l), both in x^k.
    Sigma_factor : (n_o, n_o) factor of Σ = Λ' J̃ Λ', this interval's tracking-noise
        covariance, u_b.
    J_factor, Jt_factor : (n_o, n_o) factors of AᵀWA, AᵀWMWA from t_l to t_k in x^k, 1/u_b.
    B : (n_m, n_o) ∂m/∂x^k.
    transition : (n_o, n_o) ∂x^k/∂x^{k_prev}, from the previous recycle's representation
        (the injection representation x^0 for the first).
    transition_adjoint : (n_o, n_o) its inverse transposed, (∂x^{k_prev}/∂x^k)ᵀ: an
        information factor R of x^{k_prev} maps to R T⁻¹ = R (adjoint)ᵀ.
    entities : the recycle command outputs, ω ascending.

    The factors K (KᵀK = M, upper triangular, diagonal >= 0) are what the tape carries; the
    matrices are the properties ``S_fit``, ``Lambda_fit``, ``Lambda_real``, ``Sigma``,
    ``J``, ``Jt``.
    """

    number: int
    k: int
    l: int  # noqa: E741  (the seed's name of the last recycle index)
    j: int
    t_s: float
    t_l_s: float
    info: np.ndarray
    S_fit_factor: np.ndarray
    Lambda_fit_factor: np.ndarray
    Lambda_real_factor: np.ndarray
    L: np.ndarray
    Sigma_factor: np.ndarray
    J_factor: np.ndarray
    Jt_factor: np.ndarray
    B: np.ndarray
    transition: np.ndarray
    transition_adjoint: np.ndarray
    entities: tuple[T32Entity, ...]

    @property
    def S_fit(self) -> np.ndarray:
        """S' (n_o, n_o), 1/(u_a u_b)."""
        return gram(self.S_fit_factor)

    @property
    def Lambda_fit(self) -> np.ndarray:
        """Λ' (n_o, n_o), u_a u_b."""
        return gram(self.Lambda_fit_factor)

    @property
    def Lambda_real(self) -> np.ndarray:
        """Λ̄' (n_o, n_o), u_a u_b."""
        return gram(self.Lambda_real_factor)

    @property
    def Sigma(self) -> np.ndarray:
        """Σ = Λ'J̃Λ' (n_o, n_o), u_a u_b."""
        return gram(self.Sigma_factor)

    @property
    def J(self) -> np.ndarray:
        """AᵀWA of the interval (n_o, n_o), 1/(u_a u_b)."""
        return gram(self.J_factor)

    @property
    def Jt(self) -> np.ndarray:
        """AᵀWMWA of the interval (n_o, n_o), 1/(u_a u_b)."""
        return gram(self.Jt_factor)


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
    S0_fit_factor : (n_o, n_o) upper-triangular factor of S⁰, the fit-world a priori normal
        matrix at injection in x^0 (property ``S0_fit``).
    Lambda0_real_factor : (n_o, n_o) factor of Λ̄⁰, the real-world a priori covariance at
        injection in x^0 (property ``Lambda0_real``).
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
    S0_fit_factor: np.ndarray
    Lambda0_real_factor: np.ndarray
    recycles: tuple[T32Recycle, ...]
    provenance: dict[str, str] = field(default_factory=dict)

    @property
    def S0_fit(self) -> np.ndarray:
        """S⁰ (n_o, n_o), 1/(u_a u_b)."""
        return gram(self.S0_fit_factor)

    @property
    def Lambda0_real(self) -> np.ndarray:
        """Λ̄⁰ (n_o, n_o), u_a u_b."""
        return gram(self.Lambda0_real_factor)

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


def system_values(t32: T32) -> dict[str, object]:
    """The values of the layout rows ``systems/{s}/chain`` and ``systems/{s}/names`` of each
    chained system, by path."""
    return {f"systems/{name}/{leaf}": value for name in CHAINED
            for leaf, value in (("chain", t32.systems[name]),
                                ("names", t32.system_names[name]))}


def _factor(c: Checker, name: str, m: np.ndarray, n: int) -> None:
    """An (n, n) upper-triangular factor, finite, with a non-negative diagonal."""
    c.shape(name, m, (n, n))
    c.finite(name, m)
    if np.any(np.tril(m, -1) != 0):
        c.fail(name, "an upper-triangular factor (zero below the diagonal)")
    diag = np.diagonal(m)
    if np.any(diag < 0):
        row = int(np.argmax(diag < 0))
        c.fail(name, "a factor with a non-negative diagonal", f"{diag[row]:.3g} in row {row}")


def _check_rows(c: Checker, table: tuple[Field, ...], obj: object, dims: dict[str, int],
                n_o: int) -> None:
    """The layout rows ``table`` (placeholders filled in) of ``obj`` (the tape, a recycle,
    an entity), their values by source: factors by :func:`_factor`, the others by
    :meth:`Checker.rows` (shapes, finite numbers)."""
    for row in table:
        if row.dtype == "factor":
            _factor(c, row.path, sourced(obj, row.source), n_o)
    c.rows(table, lambda row: sourced(obj, row.source), dims)


def validate(t32: T32, source: str = "T32") -> None:
    """Check the dimensions and invariants of a T32 tape; raise TapeError naming the dataset.

    Checks (every number finite and within :data:`tapp.io.tape.checks.MAX_MAGNITUDE`, an entity
    matrix within its square): n_p in 1..n_o, parameter and miss lists of matching lengths;
    the three system chains (n_o, n_o) finite with n_o row names; partitions uniquely named,
    in a known system, 0 <= tail <= head <= the system's length, their names those of the
    system's rows; the factors of the a priori and of every recycle's symmetric matrices (n_o, n_o),
    finite, upper triangular with a non-negative diagonal; each transition's adjoint its
    inverse transpose (:data:`ADJOINT_TOL`); recycle numbers 1..n_r, k
    strictly ascending, 0 <= l < k with l_i = k_{i-1}, 0 <= j < k, 0 <= t_l < t_k with
    t_l of a recycle the t_k of the one before; the other matrices of the right shapes and
    finite; entity numbers ω >= 1 ascending, matrices (len(rows), len(cols)) and finite;
    provenance text under names that are not schema attributes. The shapes are those of the
    rows of :data:`tapp.io.tape.layout.T32_LAYOUT` (:meth:`Checker.rows`).
    """
    c = Checker(source)
    n_o, n_p, n_m = t32.n_o, t32.n_p, t32.n_m
    dims = {"n_o": n_o, "n_p": n_p, "n_m": n_m, "n_r": len(t32.recycles),
            "n_partitions": len(t32.partitions)}
    check_parameters(c, t32.parameters, n_p)
    _check_rows(c, filled(T32_LAYOUT, VERSION, "miss/"), t32, dims, n_o)

    for what, mapping in (("systems", t32.systems), ("system_names", t32.system_names)):
        if sorted(mapping) != sorted(CHAINED):
            c.fail("systems", f"the systems {', '.join(CHAINED)} ({what})",
                   ", ".join(sorted(mapping)) or "none")
    chains = system_values(t32)
    c.rows(tuple(f for name in CHAINED for f in filled(T32_LAYOUT, VERSION, "systems/{s}/",
                                                         s=name)),
           lambda field: chains[field.path], dims)

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

    _check_rows(c, filled(T32_LAYOUT, VERSION, "apriori/"), t32, dims, n_o)

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
        # this recycle's row of recycles/info (n_r, 6)
        c.shape("recycles/info", rc.info, (6,))
        c.finite("recycles/info", rc.info)
        _check_rows(c, filled(T32_LAYOUT, VERSION, "recycles/{i}/", i=rc.number), rc, dims,
                    n_o)
        terms = np.abs(rc.transition.T) @ np.abs(rc.transition_adjoint)
        defect = np.abs(rc.transition.T @ rc.transition_adjoint - np.eye(n_o))
        if np.any(defect > ADJOINT_TOL * np.maximum(terms, 1.0)):
            c.fail(f"{base}/transition_adjoint", "the inverse transpose of the transition "
                   f"(|Tᵀ A − I| <= {ADJOINT_TOL:g} of the terms)",
                   f"{float(np.max(defect / np.maximum(terms, 1.0))):.3g}")
        omega = 0
        for e in rc.entities:
            where = f"{base}/entities/{e.omega}"
            if not (isinstance(e.omega, int | np.integer) and e.omega > omega):
                c.fail(f"{base}/entities", "command numbers ω >= 1, ascending, each once",
                       [x.omega for x in rc.entities])
            omega = e.omega
            if not e.command.strip():
                c.fail(f"{where}.attrs/command", "the command in seed notation", repr(e.command))
            _check_rows(c, filled(T32_LAYOUT, VERSION, "recycles/{i}/entities/{omega}",
                                  i=rc.number, omega=e.omega), e,
                        {"rows": len(e.rows), "cols": len(e.cols)}, n_o)
            # an output entity may be a covariance: a product of two tape values
            c.finite(f"{where}/matrix", e.matrix, MAX_MAGNITUDE**2)
        prev = rc

    for key, value in t32.provenance.items():
        if (not isinstance(key, str) or not key or "/" in key or key in SCHEMA_ATTRS
                or not isinstance(value, str)):
            c.fail(f"attrs/{key}", "provenance text under a name that is not a schema "
                                   f"attribute ({', '.join(SCHEMA_ATTRS)})",
                   f"{key!r} = {type(value).__name__}")


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
            "t_l_s": rc.t_l_s, "utc": t32.epoch.iso_after(rc.t_s, 3),
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

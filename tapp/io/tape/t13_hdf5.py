"""The T13 tape's HDF5 form (through h5py): layout, atomic writer, validating readers.

The tape in memory (its types, notation and validation) is :mod:`tapp.io.tape.t13`;
DESIGN.md ("Tapes") fixes this form.

HDF5 layout: the rows of :data:`tapp.io.tape.layout.T13_LAYOUT` (every dataset and
attribute, with its type, shape, units and versions; rendered as ``docs/reference/tapes.md``),
which :func:`_write` writes in order and :func:`_read` reads by their types. Every dataset has
a ``units`` attribute and a Fletcher-32 checksum (:mod:`tapp.io.tape.hdf5io`); the large
datasets are compressed by :data:`COMPRESSION_OF_VERSION`.

Units of the factors: entry (r, b) in 1/u_b with u the parameters' units (of the normal
matrices RᵀR: 1/(u_a u_b)); U and B entries in (unit of row)/(unit of column). Every dataset is
chunked (whole rows) with a Fletcher-32 checksum, text (of datasets and attributes: h5py reads
text attributes as bytes) is fixed-length UTF-8, and the large datasets (``records/U``, the
pair factors and ``raw/``) are LZ4-compressed (HDF5 filter 32004: plain h5py reads them after
``import hdf5plugin``; the others need no filter).

Version 3 is version 4 with its large datasets gzip-compressed (after a byte shuffle), which
any HDF5 library reads, at a tenth of the speed.

Versions 1 and 2 (still read, with a ``UserWarning`` that says their precision is limited)
carry the normal matrices themselves, ``pairs/dJ`` = AᵀWA and ``pairs/dJt`` = AᵀWMWA (packed
the same way, symmetric), and version 2 ``pairs/dJt_parts``; the readers turn each into a
factor (:func:`tapp.io.tape.t13.factor_normal_matrices`). Version 1 has no checksums and no parts,
and variable-length text.

The writer writes to a temporary file beside the target and renames it: no half-written tape.
The readers reject a wrong format or version, a missing dataset, a wrong shape, a non-finite
value or one beyond :data:`tapp.io.tape.checks.MAX_MAGNITUDE`, a factor with a negative diagonal
(or, "full", non-zero below it; a normal matrix of version 1 or 2 that is not symmetric or
has a negative diagonal), parts whose Gram matrices do not sum to R̃ᵀR̃, an inconsistent epoch
index and a checksum mismatch, with a :class:`~tapp.errors.TapeError` naming the file and the
dataset. :func:`read_t13` loads the
whole tape; :func:`open_t13` loads everything but the pair factors and reads those record
range by record range (:meth:`T13File.pair_block`), for tapes too large to unpack at once;
:func:`tapp.io.tape.t13.memory_pairs` offers the same interface over a tape in memory.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

import h5py
import numpy as np

from tapp.dynamics.gates import GatesErrors, GatesRangeError
from tapp.dynamics.manoeuvres import AXES, BURN_KINDS, Burn, FiniteBurn, ImpulsiveBurn
from tapp.errors import InputError, TapeError
from tapp.estimation.gauss_markov import StochasticAccelerations
from tapp.frames.time import Epoch
from tapp.io.atomic import atomic_write
from tapp.io.tape import hdf5io
from tapp.io.tape.checks import PACKINGS, Checker, frozen
from tapp.io.tape.hdf5io import Reader
from tapp.io.tape.layout import T13_LAYOUT, Field, build, rows, sourced
from tapp.io.tape.packing import pack_tr, scaled_difference, unpack_tr
from tapp.io.tape.t13 import (
    FORMAT,
    INFO_COLUMNS,
    NORMAL_MATRIX_VERSIONS,
    PARTS_TOL,
    SCENARIO_PROVENANCE,
    SUPPORTED_VERSIONS,
    T13,
    UNITS_NOTE,
    VERSION,
    PairBlock,
    T13Header,
    TapeEditing,
    TapeMiss,
    TapePairs,
    TapeParameters,
    TapePasses,
    TapeRaw,
    TapeRecords,
    TapeStations,
    _PairSource,
    _record_range,
    _validate_header,
    check_factors,
    check_parts_sum,
    factor_normal_matrices,
    frame_of,
    packed_column_norms2,
    packed_column_sums,
    validate,
)
from tapp.measurements.noise import PARTS

__all__ = ["COMPRESSION_OF_VERSION", "T13File", "open_t13", "read_t13", "t13_file_writer",
           "write_t13"]

#: The compression of the large datasets (a key of :data:`tapp.io.tape.hdf5io.COMPRESSION`)
#: by the version whose layout is written.
COMPRESSION_OF_VERSION = {1: "gzip", 2: "gzip", 3: "gzip", 4: "lz4"}


# ---------------------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------------------


def _write(f: h5py.File, tape: T13, packing: str, version: int = VERSION) -> None:
    """Write ``tape`` into the open file ``f``: the rows of :data:`T13_LAYOUT` ``version``
    carries, in order.

    ``version`` 1, 2 or 3 writes the layout of that version (1 and 2: the normal matrices
    RᵀR of the factors, version 1 without checksums and parts; 3: gzip for LZ4): kept so
    that the readers of those versions stay tested.
    """
    cs = version >= 2
    parts = None if tape.pairs.Rt_parts is None or not cs else list(PARTS)
    computed = {
        "attrs/format": FORMAT, "attrs/version": version, "attrs/n_o": tape.n_o,
        "attrs/n_p": tape.n_p, "attrs/n_m": tape.n_m, "attrs/n_ts": tape.n_ts,
        "attrs/n_it": tape.n_it, "attrs/epoch": tape.epoch.iso(6),
        "attrs/epoch_jd_whole": tape.epoch.jd_whole,
        "attrs/epoch_jd_fraction": tape.epoch.jd_fraction, "attrs/time_scale": "UTC",
        "attrs/frame": frame_of(tape.provenance), "attrs/center": "earth",
        "attrs/units": UNITS_NOTE, "attrs/packing": packing,
        **{f"attrs/{key}": value for key, value in hdf5io.provenance_attrs().items()},
        **{f"attrs/{key}": tape.provenance.get(key, "") for key in SCENARIO_PROVENANCE},
        "records/info.attrs/columns": list(INFO_COLUMNS),
        "pairs/Rt_parts.attrs/parts": parts, "pairs/dJt_parts.attrs/parts": parts,
        **_manoeuvre_values(tape.manoeuvres)}

    def value_of(field: Field) -> object:
        if field.path in computed:
            return computed[field.path]
        if field.path in ("pairs/dJt_parts", "pairs/Rt_parts") and not cs:
            return None
        return sourced(tape, field.source)

    hdf5io.write_rows(f, rows(T13_LAYOUT, version), value_of, checksums=cs,
                      compression=COMPRESSION_OF_VERSION[version], packing=packing)


def t13_file_writer(tape: T13, packing: str = "TR", *, source: str = "T13"
                    ) -> Callable[[Path], None]:
    """Validate ``tape`` now; return a function that writes it, complete, at a given path.

    For committing several outputs together (:func:`tapp.io.atomic.atomic_write` of each);
    :func:`write_t13` is ``atomic_write(path, t13_file_writer(tape, packing))``.

    Parameters
    ----------
    tape : T13
    packing : "TR" (upper triangle by rows, the default) or "full" (n_o² per matrix).
    source : name of the tape in the messages of :func:`tapp.io.tape.t13.validate`.

    Raises
    ------
    TapeError
        If the tape fails :func:`tapp.io.tape.t13.validate`.
    InputError
        For an unknown packing.
    """
    if packing not in PACKINGS:
        raise InputError("write_t13", "packing", f"one of {', '.join(PACKINGS)}", packing)
    validate(tape, source)

    def write(path: Path) -> None:
        with hdf5io.create(Path(path)) as f:
            _write(f, tape, packing)

    return write


def write_t13(path: Path | str, tape: T13, *, packing: str = "TR") -> Path:
    """Validate ``tape`` and write it to ``path`` atomically (temporary file, then rename).

    Parameters
    ----------
    path : path of the tape (conventionally ``*.t13.h5``).
    tape : T13
    packing : "TR" (upper triangle by rows, the default) or "full" (n_o² per matrix).

    Raises
    ------
    TapeError
        If the tape fails :func:`tapp.io.tape.t13.validate`.
    InputError
        For an unknown packing.
    """
    path = Path(path)
    return atomic_write(path, t13_file_writer(tape, packing, source=str(path)))


# ---------------------------------------------------------------------------------------------
# Readers
# ---------------------------------------------------------------------------------------------


def _pair_datasets(version: int) -> tuple[str, str, str]:
    """The pair datasets of a version: (AᵀWA, AᵀWMWA, its parts) as factors or, before
    version 3, matrices (the packed rows of :data:`T13_LAYOUT`; the parts' also of version
    1, which has none: the reader finds them absent)."""
    packed = [f.path for f in T13_LAYOUT if f.dtype in ("factor", "symmetric")
              and f.path.startswith("pairs/") and f.in_version(max(version, 2))]
    return packed[0], packed[1], packed[2]


def _reader(f: h5py.File, source: str) -> tuple[Reader, int]:
    """Check format and version; return the reader (checksums required from version 2)."""
    r = Reader(f, source, checksums=False)
    version = r.format_version(FORMAT, SUPPORTED_VERSIONS)
    if version == 1:
        warnings.warn(f"{source}: T13 version 1 carries no checksums: corruption cannot be "
                      "detected", UserWarning, stacklevel=3)
    if version in NORMAL_MATRIX_VERSIONS:
        warnings.warn(f"{source}: T13 version {version} carries normal matrices, not "
                      "square-root information: its factors are formed from them and hold "
                      "only the digits they kept (about 16 - 2 log10 of the condition number "
                      f"of the data); simulate it again for version {VERSION}", UserWarning,
                      stacklevel=3)
    r.checksums = version >= 2
    return r, version


def _parts_attr(r: Reader, name: str) -> None:
    parts = r.attr("parts", list, owner=name, default=())
    if parts != PARTS:
        r.check.fail(f"{name}.attrs/parts", f"the parts {', '.join(PARTS)}",
                     ", ".join(parts) or "none")


def _factors_of_matrices(c, names: tuple[str, str, str], dj, djt, parts):
    """Version 1, 2: check the normal matrices as the tape had them, then factor them."""
    for name, m in zip(names[:2], (dj, djt), strict=True):
        c.symmetric(name, m)
    if parts is not None:
        _check_legacy_parts(c, names[2], parts, djt, 0)
    return tuple(None if m is None else factor_normal_matrices(m, c, name)
                 for name, m in zip(names, (dj, djt, parts), strict=True))


def _check_legacy_parts(c, name: str, parts: np.ndarray, total: np.ndarray, offset: int
                        ) -> None:
    """The parts of a version-2 tape summing to its AᵀWMWA, as that version was checked."""
    defect = scaled_difference(parts.sum(axis=1), total)
    if np.any(defect > PARTS_TOL):
        first = int(np.argmax(defect > PARTS_TOL))
        c.fail(name, f"parts summing to pairs/dJt (relative difference <= {PARTS_TOL:g})",
               f"{defect[first]:.3g} in pair {first + offset}")


#: Values of optional attributes a tape lacks, by source.
_DEFAULTS = {"miss.kind": "", "miss.t_s": math.nan, "raw.kinds": ()}


def _read(r: Reader, version: int, *, raw: bool, matrices: bool
          ) -> tuple[T13Header, np.ndarray]:
    """Return the tape (a :class:`T13` with its factors if ``matrices``, else its
    :class:`T13Header`; the factors' stored shapes checked all the same) and records/t_s
    (checked against times/t_s once those are valid).

    The rows of :data:`T13_LAYOUT` are read by their types, the pair matrices last (after
    the dimensions are checked against the datasets).
    """
    dims = {name: r.attr(name, int) for name in ("n_o", "n_p", "n_m", "n_ts", "n_it")}
    epoch = Epoch(r.attr("epoch_jd_whole", float), r.attr("epoch_jd_fraction", float))
    values: dict[str, object] = {}
    provenance: dict[str, str] = {}
    for field in rows(T13_LAYOUT, version):
        computed = field.is_attr and not field.source and field.optional != field.path
        packed = field.dtype in ("factor", "symmetric")  # read below
        if computed or packed or (field.path.startswith("raw") and not raw) \
                or not r.present(field):
            continue
        value = r.row(field)
        if field.path.startswith("attrs/") and field.optional:
            provenance[field.name] = value
        values[field.source or field.path] = value
    values.update({key: value for key, value in _DEFAULTS.items() if key not in values})
    parameters = build(TapeParameters, "parameters", values)
    stations = build(TapeStations, "stations", values)
    miss = build(TapeMiss, "miss", values)
    records = build(TapeRecords, "records", values)
    for name, value in (("n_o", len(parameters.name)), ("n_m", len(miss.name)),
                        ("n_ts", len(stations.name)), ("n_it", records.k.size)):
        if dims[name] != value:
            r.check.fail(f"attrs/{name}", f"{name} = {value} as the datasets have", dims[name])
    n_pairs, n_o = values["pairs.k"].size, dims["n_o"]
    names = _pair_datasets(version)
    has_parts = r.has(names[2])
    if has_parts:
        _parts_attr(r, names[2])
    leads = ((n_pairs,), (n_pairs,), (n_pairs, len(PARTS)))
    factors = (None, None, None)
    if matrices and version in NORMAL_MATRIX_VERSIONS:
        stored = [r.symmetric(name, lead, n_o) if i < 2 or has_parts else None
                  for i, (name, lead) in enumerate(zip(names, leads, strict=True))]
        factors = _factors_of_matrices(r.check, names, *stored)
    elif matrices:
        factors = tuple(r.triangular(name, lead, n_o) if i < 2 or has_parts else None
                        for i, (name, lead) in enumerate(zip(names, leads, strict=True)))
    else:
        for i, (name, lead) in enumerate(zip(names, leads, strict=True)):
            if i < 2 or has_parts:
                r.stored_shape(name, lead, n_o)
    pairs = TapePairs(values["pairs.k"], values["pairs.station"], values["pairs.n_obs"],
                      *factors)
    editing = build(TapeEditing, "editing", values) if "editing.rule" in values else None
    stochastic = None
    if "stochastic.frame" in values:
        stochastic = StochasticAccelerations(
            values["stochastic.frame"], tuple(values["stochastic.components"]),
            tuple(float(t) for t in values["stochastic.boundaries_s"]),
            values["stochastic.sigma_km_s2"], values["stochastic.tau_s"])
    manoeuvres = _read_manoeuvres(r.check, values) if "manoeuvres/name" in values else ()
    header = T13Header(values["iden"], epoch, dims["n_p"], parameters, stations, miss,
                       records, pairs, build(TapePasses, "passes", values), provenance,
                       editing, stochastic, manoeuvres)
    if not matrices:
        return header, values["records.t_s"]
    tape_raw = build(TapeRaw, "raw", values) if "raw.t_s" in values else None
    return T13(**{f.name: getattr(header, f.name) for f in fields(T13Header)}, raw=tape_raw), \
        values["records.t_s"]


#: The numbers of a burn on the tape beside its name, kind, axes, vector and σ's (those an
#: impulsive burn has not are 0 on the tape).
_BURN_NUMBERS = ("t_start_s", "duration_s", "thrust_N", "mass_kg", "mass_flow_kg_s")


def _manoeuvre_values(burns: tuple[Burn, ...]) -> dict[str, object]:
    """The rows of the ``manoeuvres/`` group by path (none without burns)."""
    if not burns:
        return {}
    out: dict[str, object] = {f"manoeuvres/{name}": [getattr(b, name) for b in burns]
                              for name in ("name", "kind", "axes")}
    for name in _BURN_NUMBERS:
        out[f"manoeuvres/{name}"] = np.array([getattr(b, name, 0.0) for b in burns])
    out["manoeuvres/vector"] = np.array([b.dv_km_s if b.kind == "impulsive" else b.direction
                                         for b in burns])
    out["manoeuvres/sigma"] = np.array([b.errors.sources for b in burns])
    return out


def _read_manoeuvres(c: Checker, values: dict[str, object]) -> tuple[Burn, ...]:
    """The burns of the ``manoeuvres/`` rows read (by path), checked as the scenario's were."""
    names, kinds, axes = (values[f"manoeuvres/{n}"] for n in ("name", "kind", "axes"))
    n_b = len(names)
    numbers = {name: values[f"manoeuvres/{name}"] for name in _BURN_NUMBERS}
    vector, sigma = values["manoeuvres/vector"], values["manoeuvres/sigma"]
    for name, a, shape in (("kind", kinds, n_b), ("axes", axes, n_b)):
        if len(a) != shape:
            c.fail(f"manoeuvres/{name}", f"{n_b} entries", len(a))
    for name, a in numbers.items():
        c.shape(f"manoeuvres/{name}", a, (n_b,))
        c.finite(f"manoeuvres/{name}", a)
    c.shape("manoeuvres/vector", vector, (n_b, 3))
    c.finite("manoeuvres/vector", vector)
    c.shape("manoeuvres/sigma", sigma, (n_b, 4))
    out = []
    for i in range(n_b):
        if kinds[i] not in BURN_KINDS:
            c.fail("manoeuvres/kind", f"one of {', '.join(BURN_KINDS)}", kinds[i])
        if axes[i] not in AXES:
            c.fail("manoeuvres/axes", f"one of {', '.join(AXES)}", axes[i])
        try:
            errors = GatesErrors(*(float(x) for x in sigma[i]))
        except GatesRangeError as exc:
            c.fail("manoeuvres/sigma", exc.expected, exc.got)
        common = {"name": names[i], "axes": axes[i], "errors": errors}
        v = tuple(float(x) for x in vector[i])
        if kinds[i] == "impulsive":
            out.append(ImpulsiveBurn(**common, t_s=float(numbers["t_start_s"][i]), dv_km_s=v))
        else:
            if min(numbers[n][i] for n in ("duration_s", "thrust_N", "mass_kg",
                                           "mass_flow_kg_s")) <= 0 or \
                    numbers["mass_flow_kg_s"][i] * numbers["duration_s"][i] >= \
                    numbers["mass_kg"][i]:
                c.fail("manoeuvres/duration_s", "a finite burn's positive duration, thrust, "
                       "mass and mass flow, mass left at cut-off", names[i])
            out.append(FiniteBurn(**common, direction=v, **{
                name: float(numbers[name][i]) for name in _BURN_NUMBERS}))
    return tuple(out)


def _check_record_times(source: str, record_times: np.ndarray, tape: T13Header) -> None:
    if not np.array_equal(record_times, tape.records.t_s):
        raise TapeError(f"{source}: records/t_s: expected the record times t_k = "
                        "times/t_s[1:]")


def read_t13(path: Path | str, *, raw: bool = True) -> T13:
    """Read and validate a whole T13 tape (every pair factor unpacked in memory).

    For tapes too large for that, :func:`open_t13` reads the pair factors record range by
    record range.

    Parameters
    ----------
    path : the tape file.
    raw : also load the optional ``raw/`` group when present.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        If it is not a readable HDF5 file (truncated, corrupt), or not a valid T13 tape; the
        message names the file and the dataset (or attribute) at fault.

    Warns
    -----
    UserWarning
        For a version-1 or -2 tape (normal matrices, whose factors hold only the digits they
        kept; version 1 without checksums: corruption cannot be detected).
    """
    path = Path(path)
    with hdf5io.open_tape(path, "T13 tape") as f:
        r, version = _reader(f, str(path))
        tape, record_times = _read(r, version, raw=raw, matrices=True)
    validate(tape, str(path))
    _check_record_times(str(path), record_times, tape)
    return tape


class T13File(_PairSource):
    """A T13 tape open for lazy reading of its pair factors (from :func:`open_t13`).

    A context manager (``with open_t13(path) as tape:``); :meth:`close` closes the file.

    Attributes
    ----------
    header : T13Header
        Everything of the tape but the pair factors (``header.pairs.R``, ``Rt`` and
        ``Rt_parts`` are None) and the raw rows, validated.
    path : Path
    version : int
        Version of the tape.
    names : the pair datasets of its version (factors, or normal matrices before version 3).
    packing : str
        Storage of the pair datasets on the tape ("TR" or "full").
    has_parts : bool
        Whether the tape has the parts (``pairs/Rt_parts``, ``pairs/dJt_parts``).
    """

    __slots__ = ("_file", "_reader", "has_parts", "header", "names", "packing", "path",
                 "version")

    def __init__(self, path: Path | str):
        self.path = Path(path)
        self._file = hdf5io.open_tape(self.path, "T13 tape")
        try:
            self._reader, self.version = _reader(self._file, str(self.path))
            tape, record_times = _read(self._reader, self.version, raw=False, matrices=False)
            c = self._reader.check
            _validate_header(c, tape)
            _check_record_times(str(self.path), record_times, tape)
            self.names = _pair_datasets(self.version)
            self.packing = self._reader.packing(self.names[0])
            self.has_parts = self._reader.has(self.names[2])
            for name in self.names[1:] if self.has_parts else self.names[1:2]:
                if self._reader.packing(name) != self.packing:
                    c.fail(f"{name}.attrs/packing",
                           f"the packing of {self.names[0]} ({self.packing})")
        except BaseException:
            self._file.close()
            raise
        self.header = tape

    def __enter__(self) -> T13File:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the file (:meth:`pair_block` then fails)."""
        self._file.close()

    def _stored(self, name: str, lo: int, hi: int, lead: tuple[int, ...]) -> np.ndarray:
        """Rows lo..hi-1 of a pair dataset, finite, as full matrices (m, *lead, n_o, n_o) for
        "full" packing or packed TR (m, *lead, L)."""
        n_o = self.header.n_o
        stored = self._reader.read(name, selection=np.s_[lo:hi])
        self._reader.check.finite(name, stored)
        if self.packing == "full":
            return stored.reshape(hi - lo, *lead, n_o, n_o)
        return stored

    def _factors(self, name: str, lo: int, hi: int, lead: tuple[int, ...]) -> np.ndarray:
        """Version 3: read and check factors, packed TR (m, *lead, L)."""
        n_o = self.header.n_o
        stored = self._stored(name, lo, hi, lead)
        lower = None
        if self.packing == "full":
            lower = np.tril(stored, -1)
            stored = frozen(pack_tr(stored))
        check_factors(self._reader.check, name, stored, n_o, lower=lower, offset=lo)
        return stored

    def _legacy(self, lo: int, hi: int, parts: bool) -> tuple:
        """Versions 1, 2: read the normal matrices, check them as their version was checked,
        and return their factors packed TR."""
        n_o = self.header.n_o
        full = []
        for name, lead in zip(self.names, ((), (), (len(PARTS),)), strict=True):
            if lead and not parts:
                full.append(None)
                continue
            stored = self._stored(name, lo, hi, lead)
            full.append(stored if self.packing == "full" else unpack_tr(stored, n_o))
        c = self._reader.check
        for name, m in zip(self.names[:2], full[:2], strict=True):
            c.symmetric(name, m, offset=lo)
        if full[2] is not None:
            _check_legacy_parts(c, self.names[2], full[2], full[1], lo)
        return tuple(None if m is None else frozen(pack_tr(factor_normal_matrices(m, c, name,
                                                                                  lo)))
                     for name, m in zip(self.names, full, strict=True))

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True) -> PairBlock:
        """Return the pairs of records k_first..k_last (inclusive), read and checked now.

        ``parts=False`` skips ``pairs/Rt_parts`` (``Rt_parts`` is then None): TAPP III needs
        them only for its error budget, and they are 3/5 of the bytes.

        Only the rows of ``pairs/R``, ``pairs/Rt`` (and ``pairs/Rt_parts``) of those records
        are read (and their checksums checked); they are checked finite, upper triangular
        with a non-negative diagonal, and the parts' Gram matrices summing to R̃ᵀR̃ on the
        diagonal. A version-1 or -2 tape's normal matrices are checked as that version was,
        then factored (:func:`tapp.io.tape.t13.factor_normal_matrices`).

        Raises
        ------
        InputError
            Record indices outside 1 <= k_first <= k_last <= n_it.
        TapeError
            A check fails (naming the file and the dataset; pairs numbered from 0 over the
            whole tape).
        """
        if not self._file:
            raise InputError(str(self.path), "file", "an open T13 tape (pair_block after "
                                                     "close)")
        lo, hi = _record_range(self.header, k_first, k_last)
        pairs = self.header.pairs
        parts = parts and self.has_parts
        if self.version in NORMAL_MATRIX_VERSIONS:
            r, rt, split = self._legacy(lo, hi, parts)
        else:
            r, rt = (self._factors(name, lo, hi, ()) for name in self.names[:2])
            split = None
            if parts:
                split = self._factors(self.names[2], lo, hi, (len(PARTS),))
                n_o = self.header.n_o
                # the parts' squares summed first: one pass over the columns, not three
                parts2 = packed_column_sums(np.einsum("mpl,mpl->ml", split, split), n_o)
                check_parts_sum(self._reader.check, parts2, packed_column_norms2(rt, n_o), lo)
        return PairBlock(pairs.k[lo:hi], pairs.station[lo:hi], pairs.n_obs[lo:hi], r, rt,
                         split)


def open_t13(path: Path | str) -> T13File:
    """Open a T13 tape for reading its pair factors record range by record range.

    Everything but the pair factors (and the raw rows) is read and validated now, as by
    :func:`read_t13`; the pair factors are read and checked block by block
    (:meth:`T13File.pair_block`, :meth:`T13File.blocks`), so a tape of 20,000 pairs of
    n_o = 50 needs no more memory than one block.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        As :func:`read_t13`, for everything but the values of the pair factors (their
        stored shapes are checked).

    Warns
    -----
    UserWarning
        For a version-1 or -2 tape (normal matrices; version 1 without checksums).

    Examples
    --------
    >>> with open_t13("run.t13.h5") as tape:  # doctest: +SKIP
    ...     for block in tape.blocks():
    ...         ...
    """
    return T13File(path)

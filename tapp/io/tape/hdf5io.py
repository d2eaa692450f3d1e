"""How the tapes store and check their HDF5 datasets: one writer and one validating reader.

Shared by the T13 (:mod:`tapp.io.tape.t13_hdf5`) and T32 (:mod:`tapp.io.tape.t32_hdf5`) tapes.

Storage (tapes with checksums: T13 version >= 2, every T32):

- every dataset is chunked and carries HDF5's Fletcher-32 checksum filter, so a flipped byte
  in its data fails on read; chunks hold whole rows (axis 0) up to :data:`CHUNK_BYTES`, so a
  slice of rows reads (and checks) only the chunks it touches;
- large datasets are also compressed, before the checksum (so it covers the stored bytes),
  by one of :data:`COMPRESSION`: gzip (a byte shuffle, then deflate level 4: built into every
  HDF5 library) or LZ4 (HDF5's registered filter 32004, no shuffle: 10x faster to read;
  plain h5py reads it once ``import hdf5plugin`` has registered the filter, and any HDF5
  tool with ``HDF5_PLUGIN_PATH`` set to ``hdf5plugin.PLUGIN_PATH``);
- text is fixed-length UTF-8, in datasets and attributes alike, null-padded to the longest
  entry: variable-length strings live in HDF5's global heap, which no filter and no checksum
  covers (and a corrupt global heap can make the HDF5 library loop forever on reading);
- files are written with the HDF5 1.8 object formats (``libver="v108"``), whose object
  headers and B-trees carry their own checksums: a flipped byte in the metadata fails too.

Reading: :class:`Reader` reads a dataset or an attribute and checks its kind, and turns every
failure into a :class:`~tapp.errors.TapeError` ``"{file}: {dataset}: expected ... (got ...)"``:
a checksum mismatch, an unreadable (truncated) chunk, text that is not UTF-8, a dataset
without a checksum in a tape whose version promises one. The checks of values (shape,
finite, symmetric) are those of :class:`tapp.io.tape.checks.Checker`;
:func:`tapp.io.tape.files.verify` reads every dataset and attribute of any tape, chunk by chunk.
"""

from __future__ import annotations

import math
import subprocess
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path

import h5py
import hdf5plugin
import numpy as np

from iter.inputfile import regular_file
from tapp import __version__
from tapp.errors import InputError, TapeError
from tapp.io.tape.checks import PACKINGS, Checker, frozen
from tapp.io.tape.layout import Field
from tapp.io.tape.packing import pack_tr, tr_size, unpack_tr, upper_from_tr

#: Target size of a chunk (bytes): whole rows of axis 0 up to this size.
CHUNK_BYTES = 1 << 18
#: Compressions of large datasets, by name (h5py's dataset options). Read whole with their
#: checksums, in one run on the shared 2-core machine: the packed factors of the benchmark's
#: n_o = 50 tape (tests/bench/processor.py, 306 MB) in 1.6 s gzip (12.9 MB stored), 0.13 s
#: LZ4 (11.5 MB), 0.33 s LZ4 after a shuffle (15.5 MB: the shuffle spreads a factor's runs of
#: zeros over its bytes), 0.31 s unfiltered (the Fletcher-32 of 306 MB); those of a simulated
#: deep-space tape (n_o = 69, denser), 352 MB, in 3.1 s gzip (94 MB), 0.31 s LZ4 (88 MB).
COMPRESSION = {"gzip": {"compression": "gzip", "compression_opts": 4, "shuffle": True},
               "lz4": dict(hdf5plugin.LZ4())}
#: Lowest HDF5 object-format version written: 1.8 (object headers with checksums).
LIBVER = "v108"
#: What h5py raises on corrupt metadata (a checksum mismatch in an object header, a B-tree, a
#: heap), depending on the call: each is turned into a TapeError naming the object.
HDF5_ERRORS = (OSError, KeyError, RuntimeError, ValueError, TypeError)


def git_commit() -> str:
    """Commit of the source checkout tapp runs from, or "unknown"."""
    try:
        proc = subprocess.run(["git", "rev-parse", "HEAD"], cwd=Path(__file__).parent,
                              capture_output=True, text=True, check=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return proc.stdout.strip()


def provenance_attrs() -> dict[str, str]:
    """Return the root attributes every tape gets: tapp_version, git_commit, created_utc."""
    return {"tapp_version": __version__, "git_commit": git_commit(),
            "created_utc": datetime.now(UTC).isoformat(timespec="seconds")}


@contextmanager
def create(path: Path) -> Iterator[h5py.File]:
    """Yield a new HDF5 file (object formats of :data:`LIBVER`) built in memory; on leaving the
    block, write it to ``path`` (truncating) in one plain write.

    The HDF5 library never writes to the disk itself: when one of its writes fails (a full
    disk) it crashes the process while closing the file (a segmentation fault after pages
    of tracebacks, in 24 of 24 tries writing a T13 tape onto a full tmpfs), where a plain
    write raises an OSError that the caller turns into one line (24 of 24). The whole file
    is held in memory while it is built (no more than the tape's own arrays: large
    datasets are compressed).

    Raises
    ------
    OSError
        ``path`` cannot be written (nothing is written if the block raises).
    """
    with h5py.File(path.name, "w", libver=LIBVER, driver="core", backing_store=False) as f:
        yield f
        f.flush()
        image = f.id.get_file_image()
    path.write_bytes(image)


# ---------------------------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------------------------


def _fixed_text(values: list[str]) -> np.ndarray:
    encoded = [v.encode("utf-8") for v in values]
    width = max([1, *(len(b) for b in encoded)])
    return np.array(encoded, dtype=h5py.string_dtype("utf-8", width))


def write_attrs(obj: h5py.HLObject, values: dict[str, object], *, checksums: bool = True
                ) -> None:
    """Set attributes; text (a str, or a list or tuple of str) as fixed-length UTF-8.

    Fixed-length text is stored in the object header (checksummed from HDF5 1.8 formats),
    never in the global heap. ``checksums=False`` stores them as h5py does by default
    (variable-length text: T13 version 1).
    """
    for name, value in values.items():
        if checksums and isinstance(value, str):
            obj.attrs.create(name, _fixed_text([value])[0])
        elif (checksums and isinstance(value, list | tuple) and value
              and all(isinstance(v, str) for v in value)):
            obj.attrs.create(name, _fixed_text(list(value)))
        else:
            obj.attrs[name] = value


def _layout(data: np.ndarray, *, compression: str | None) -> dict:
    """Chunked, Fletcher-32 storage options of ``data`` (whole rows per chunk), compressed by
    ``compression`` (a key of :data:`COMPRESSION`) unless None."""
    if data.ndim == 0:
        raise InputError("hdf5io", "data", "an array of at least one dimension (chunked)",
                         data.shape)
    if data.size == 0:  # HDF5 needs chunk dims >= 1 <= the maximum dims: let them grow
        return {"chunks": tuple(max(1, d) for d in data.shape),
                "maxshape": (None,) * data.ndim, "fletcher32": True}
    row_bytes = data.itemsize * math.prod(data.shape[1:])
    rows = max(1, min(data.shape[0], CHUNK_BYTES // max(1, row_bytes)))
    options = {"chunks": (rows, *data.shape[1:]), "fletcher32": True}
    if compression is not None:
        options.update(COMPRESSION[compression])
    return options


def write_strings(group: h5py.Group, name: str, values: Iterable[str], units: str = "", *,
                  checksums: bool = True) -> h5py.Dataset:
    """Write text as fixed-length UTF-8, chunked with Fletcher-32, attribute ``units``.

    ``checksums=False`` writes the unfiltered variable-length strings of T13 version 1.
    """
    texts = [str(v) for v in values]
    if not checksums:
        ds = group.create_dataset(name, data=np.array(texts, dtype=h5py.string_dtype()))
    else:
        data = _fixed_text(texts)
        ds = group.create_dataset(name, data=data, **_layout(data, compression=None))
    write_attrs(ds, {"units": units}, checksums=checksums)
    return ds


def write_numbers(group: h5py.Group, name: str, values, units: str, *, big: bool = False,
                  checksums: bool = True, compression: str = "gzip") -> h5py.Dataset:
    """Write numbers (or booleans), chunked with Fletcher-32, attribute ``units``.

    ``big`` also compresses, by ``compression`` (a key of :data:`COMPRESSION`).
    ``checksums=False`` writes the layout of T13 version 1 (contiguous, or chunked and
    compressed when ``big``, no checksum).
    """
    data = np.asarray(values)
    if checksums:
        options = _layout(data, compression=compression if big else None)
    elif big and data.size:
        chunk = list(data.shape)
        chunk[0] = max(1, min(data.shape[0], CHUNK_BYTES // max(1, data[0].nbytes)))
        options = {"chunks": tuple(chunk), **COMPRESSION[compression]}
    else:
        options = {}
    ds = group.create_dataset(name, data=data, **options)
    write_attrs(ds, {"units": units}, checksums=checksums)
    return ds


def write_packed(group: h5py.Group, name: str, matrices, units: str, packing: str = "TR",
                 form: str = "symmetric", *, big: bool = False, checksums: bool = True,
                 compression: str = "gzip") -> h5py.Dataset:
    """Write symmetric matrices or upper-triangular factors (..., n, n) packed ("TR": the
    upper triangle by rows, (..., n(n+1)/2); "full": (..., n²)).

    Attributes ``packing``, ``order`` (n) and ``form`` ("symmetric", or "factor": M = KᵀK
    with K upper triangular) say how to unpack.
    """
    m = np.asarray(matrices, dtype=float)
    n = m.shape[-1]
    if packing == "TR":
        stored = pack_tr(m)
    else:
        stored = m.reshape(*m.shape[:-2], n * n)
    ds = write_numbers(group, name, stored, units, big=big, checksums=checksums,
                       compression=compression)
    write_attrs(ds, {"packing": packing, "order": n, "form": form}, checksums=checksums)
    return ds


def write_rows(f: h5py.File | h5py.Group, fields: Iterable[Field],
               value_of: Callable[[Field], object], *, checksums: bool = True,
               compression: str = "gzip", packing: str = "TR",
               big: Callable[[Field], bool] = lambda field: field.big) -> None:
    """Write the rows of a layout table (:mod:`tapp.io.tape.layout`), in order, into ``f``.

    ``value_of(row)`` gives each row's value (None: absent, not written); groups are created
    as their first row needs them. Text datasets by :func:`write_strings`, packed matrices
    (types factor, symmetric) by :func:`write_packed` in ``packing``, other datasets by
    :func:`write_numbers` (compressed when ``big(row)``), attributes by :func:`write_attrs`;
    every dataset gets the row's unit as its ``units`` attribute.
    """
    for field in fields:
        value = value_of(field)
        if value is None:
            continue
        if field.is_attr:
            owner = f.require_group(field.owner) if field.owner and field.owner not in f \
                else f[field.owner] if field.owner else f
            write_attrs(owner, {field.name: value}, checksums=checksums)
            continue
        folder, _, name = field.path.rpartition("/")
        group = f.require_group(folder) if folder else f
        if field.dtype == "str":
            write_strings(group, name, value, field.unit, checksums=checksums)
        elif field.dtype in ("factor", "symmetric"):
            write_packed(group, name, value, field.unit, packing,
                         "factor" if field.dtype == "factor" else "symmetric", big=big(field),
                         checksums=checksums, compression=compression)
        else:
            write_numbers(group, name, value, field.unit, big=big(field), checksums=checksums,
                          compression=compression)


# ---------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------


def open_tape(path: Path | str, what: str = "tape") -> h5py.File:
    """Open an existing tape for reading.

    Raises
    ------
    InputError
        If the file does not exist ("expected an existing {what} file") or is not a regular
        file (a FIFO, a device: :func:`iter.inputfile.regular_file`).
    TapeError
        If it is not a readable HDF5 file (truncated, corrupt).
    """
    path = regular_file(path, f"{what} file", error=InputError)
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        raise TapeError(f"{path}: file: expected a readable HDF5 file (truncated or corrupt: "
                        f"{exc})") from None


#: How :meth:`Reader.row` reads a dataset and an attribute of each row type.
_ROW_KINDS = {"int": "i", "float": "f", "bool": "b"}
_ATTR_KINDS = {"str": str, "int": int, "float": float, "str[]": list}
_KINDS = {"f": ("fiu", "numbers", float), "i": ("iu", "integers", np.int64),
          "b": ("b", "booleans", bool), "s": ("OS", "strings", None)}


class Reader:
    """Reads datasets and attributes of an open file, naming the file and the dataset.

    Parameters
    ----------
    f : the open file (or a group: dataset names are then relative to it).
    source : file name for the messages.
    checksums : require the Fletcher-32 filter on every dataset read.
    """

    def __init__(self, f: h5py.File | h5py.Group, source: str, *, checksums: bool = True):
        self.f = f
        self.check = Checker(source)
        self.checksums = checksums

    @contextmanager
    def guard(self, where: str, expected: str) -> Iterator[None]:
        """Turn the errors h5py raises on corrupt metadata into a TapeError naming ``where``."""
        try:
            yield
        except HDF5_ERRORS as exc:
            self.check.fail(where, f"{expected} (corrupt file?)", exc)

    # -- attributes ----------------------------------------------------------------------

    def _attrs(self, owner: str):
        obj = self.f if owner == "" else self.dataset_or_group(owner)
        with self.guard(owner or "attrs", "readable attributes"):
            return obj.attrs

    def has_attr(self, name: str, owner: str = "") -> bool:
        attrs = self._attrs(owner)
        with self.guard(f"{owner}.attrs/{name}" if owner else f"attrs/{name}",
                        "readable attributes"):
            return name in attrs

    def attr(self, name: str, kind: type = str, owner: str = "", default: object = ...):
        """Return attribute ``name`` of the root (or of ``owner``) as int, float or str.

        Missing: ``default`` if given, else a TapeError.
        """
        where = f"{owner}.attrs/{name}" if owner else f"attrs/{name}"
        if not self.has_attr(name, owner):
            if default is not ...:
                return default
            self.check.fail(where, "this attribute present")
        attrs = self._attrs(owner)
        with self.guard(where, "a readable attribute"):
            value = attrs[name]
        if kind is int:
            if not (isinstance(value, int | np.integer) and not isinstance(value, bool)
                    and value >= 0):
                self.check.fail(where, "an integer >= 0", value)
            return int(value)
        if kind is float:
            if not (isinstance(value, float | np.floating | int | np.integer)
                    and np.isfinite(value)):
                self.check.fail(where, "a finite number", value)
            return float(value)
        if kind is list:
            values = np.atleast_1d(np.asarray(value, dtype=object))
            return tuple(self.check.text(where, v) for v in values)
        if isinstance(value, np.ndarray):
            self.check.fail(where, "a text", value.tolist())
        return self.check.text(where, value)

    # -- datasets ------------------------------------------------------------------------

    def format_version(self, fmt: str, supported: tuple[int, ...]) -> int:
        """Check ``attrs/format`` is ``fmt`` and ``attrs/version`` one of ``supported``;
        return the version."""
        found = self.attr("format", str)
        if found != fmt:
            self.check.fail("attrs/format", f"format = {fmt!r}", repr(found))
        version = self.attr("version", int)
        if version not in supported:
            self.check.fail("attrs/version", f"a supported version {supported}", version)
        return version

    def dataset_or_group(self, name: str) -> h5py.Dataset | h5py.Group:
        if not self.has(name):
            self.check.fail(name, "this dataset present")
        with self.guard(name, "a readable object"):
            return self.f[name]

    def has(self, name: str) -> bool:
        with self.guard(name, "a readable object"):
            return name in self.f

    def dataset(self, name: str) -> h5py.Dataset:
        ds = self.dataset_or_group(name)
        if not isinstance(ds, h5py.Dataset):
            self.check.fail(name, "this dataset present", "a group")
        with self.guard(name, "a readable dataset header"):
            checksummed = ds.fletcher32
        if self.checksums and not checksummed:
            self.check.fail(name, "a Fletcher-32 checksum filter on the dataset", "none")
        return ds

    def raw(self, name: str, selection=()) -> np.ndarray:
        """Return the stored data of ``name`` (or a selection of it), unconverted."""
        ds = self.dataset(name)
        try:
            return np.asarray(ds[()] if selection == () else ds[selection])
        except OSError as exc:
            if ds.fletcher32 and "filter" in str(exc):
                self.check.fail(name, "data matching its Fletcher-32 checksum",
                                "checksum mismatch (corrupt file)")
            self.check.fail(name, "readable data (truncated or corrupt file?)", exc)
        except HDF5_ERRORS as exc:
            self.check.fail(name, "readable data (truncated or corrupt file?)", exc)

    def read(self, name: str, kind: str = "f", selection=()) -> np.ndarray:
        """Read dataset ``name``; kind "f" float, "i" integer, "b" bool, "s" strings (UTF-8).

        Returns a read-only array (floats as float64, integers as int64); strings as an
        array of str.
        """
        data = self.raw(name, selection)
        ok, what, dtype = _KINDS[kind]
        if data.dtype.kind not in ok or (data.ndim == 0 and kind != "f"):
            self.check.fail(name, what, data.dtype)
        if kind == "s":
            out = np.array([self.check.text(name, v) for v in data.ravel()], dtype=object)
            return out.reshape(data.shape)
        if data.dtype != dtype:
            return frozen(data, dtype)
        data.setflags(write=False)  # h5py's own new array: frozen without a copy
        return data

    def strings(self, name: str) -> tuple[str, ...]:
        return tuple(self.read(name, "s"))

    def present(self, field: Field) -> bool:
        """Whether a row the tape may lack (:attr:`Field.optional`) is on the tape."""
        if not field.optional:
            return True
        if field.optional == field.path and field.is_attr:
            return (field.owner == "" or self.has(field.owner)) and \
                self.has_attr(field.name, field.owner)
        return self.has(field.optional)

    def row(self, field: Field, default: object = ...):
        """Read a row of a layout table by its type: a dataset as :meth:`read` (text as a
        tuple), an attribute as :meth:`attr`; packed matrices are read by
        :meth:`symmetric` and :meth:`triangular`, not here."""
        if field.is_attr:
            return self.attr(field.name, _ATTR_KINDS[field.dtype], owner=field.owner,
                             default=default)
        if field.dtype == "str":
            return self.strings(field.path)
        return self.read(field.path, _ROW_KINDS[field.dtype])

    def packing(self, name: str) -> str:
        packing = self.attr("packing", str, owner=name, default="TR")
        if packing not in PACKINGS:
            self.check.fail(f"{name}.attrs/packing", f"one of {', '.join(PACKINGS)}", packing)
        return packing

    def stored_shape(self, name: str, lead: tuple[int, ...], n: int) -> str:
        """Check the stored shape of packed symmetric matrices without reading; return the
        packing."""
        packing = self.packing(name)
        length = tr_size(n) if packing == "TR" else n * n
        got = self.dataset(name).shape
        if got != (*lead, length):
            self.check.fail(name, f"shape {(*lead, length)} ({packing} packing, order {n})",
                            got)
        return packing

    def symmetric(self, name: str, lead: tuple[int, ...], n: int) -> np.ndarray:
        """Read packed symmetric matrices and return them full, shape (*lead, n, n)."""
        packing = self.stored_shape(name, lead, n)
        stored = self.read(name)
        if packing == "TR":
            return frozen(unpack_tr(stored, n))
        return frozen(stored.reshape(*lead, n, n))

    def triangular(self, name: str, lead: tuple[int, ...], n: int) -> np.ndarray:
        """Read packed upper-triangular factors and return them full, shape (*lead, n, n)
        ("full" packing: checked zero below the diagonal)."""
        packing = self.stored_shape(name, lead, n)
        stored = self.read(name)
        if packing == "TR":
            return frozen(upper_from_tr(stored, n))
        out = stored.reshape(*lead, n, n)
        if np.any(np.tril(out, -1) != 0):
            self.check.fail(name, "upper-triangular factors (zero below the diagonal)")
        return frozen(out)


def attr_value(check: Checker, where: str, value: object) -> object:
    """Return an attribute as a JSON-ready value (text checked as UTF-8)."""
    if isinstance(value, bytes | np.bytes_ | str):
        return check.text(where, value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "OSU":
            return [check.text(where, v) for v in value.ravel()]
        return value.tolist()
    return value

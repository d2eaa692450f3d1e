"""Results files: the table as HDF5 and CSV. The only module of ``iter`` that imports h5py.

HDF5 layout (one row per case, sorted by case index)::

    /                 attrs: format = "iter-results", format_version = 2,
                             generator ("iter, tapp <version>"),
                             sweep_json (the sweep file contents as JSON),
                             definition_json (canonical loops + body; resuming checks it),
                             source (the sweep file), n_cases (cases in the sweep),
                             created_utc, updated_utc (ISO 8601, UTC)
    /case             (N,) int64
    /inputs/<name>    (N,) float64, one per varied parameter, outermost loop first
    /outputs/<name>   (N,) float64 (NaN where missing) or UTF-8 text ("" where missing)
    /status           (N,) int8, attrs codes = {"0": "ok", "1": "failed"}
    /error            (N,) UTF-8 text, "" for ok cases
    /elapsed_s        (N,) float64, wall time of the body

Every dataset has a ``units`` attribute, read from the name's suffix (``azimuth_deg`` ->
``deg``; see :data:`UNIT_SUFFIXES`), empty when the name carries no recognised unit, and a
``sha256`` attribute, the digest of its values (:func:`values_digest`), checked on read: a
flipped byte is a :class:`ResultFileError` naming the dataset, never data. Files of
format_version 1 (no digests) are still read, with a :class:`ResultFileWarning`. The
file may hold fewer rows than ``n_cases`` while a sweep runs: it is rewritten as cases
complete, each time to a hidden temporary ``.NAME.<random>.tmp`` beside it, renamed over the
old one, so it is never half written; temporaries left by a killed run are removed on the next
write (the same convention as ``tapp.io.outputs``, which ``iter`` may not import). Reading checks
the layout (every dataset present, one row per case, status codes, case numbers unique and
within the sweep), so a tampered or truncated file is a :class:`ResultFileError`, not a
traceback.

CSV: a header line with the table's columns (:attr:`iter.table.ResultTable.columns`), then
one line per case; ``status`` is written as its name (``ok``, ``failed``).
"""

from __future__ import annotations

import csv
import hashlib
import importlib.metadata
import json
import math
import os
import re
import secrets
import stat
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from .errors import ResultFileError, ResultWriteError
from .inputfile import regular_file
from .table import CaseResult, CaseStatus, OutputValue, ResultTable

FORMAT_NAME = "iter-results"
FORMAT_VERSION = 2
#: The first format version whose datasets carry a ``sha256`` digest.
DIGEST_VERSION = 2


class ResultFileWarning(UserWarning):
    """A results file is readable but unprotected (format_version 1: no checksums)."""


def values_digest(values: np.ndarray | list, text: bool) -> str:
    """Return the SHA-256 (hex) of a column's values: the JSON list of texts, or the
    little-endian bytes of numbers."""
    if text:
        data = json.dumps([str(v) for v in values]).encode("utf-8")
    else:
        array = np.asarray(values)
        data = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("<")).tobytes()
    return hashlib.sha256(data).hexdigest()

#: Name suffix -> units attribute, longest suffixes tried first.
UNIT_SUFFIXES = {
    "_km3_s2": "km^3/s^2", "_km_s": "km/s", "_m_s": "m/s", "_km": "km", "_m": "m",
    "_s": "s", "_day": "day", "_deg": "deg", "_rad": "rad", "_kg": "kg",
}

_TEXT = h5py.string_dtype(encoding="utf-8")


def units_of(name: str) -> str:
    """Return the unit carried by ``name``'s suffix, or ``""`` if it carries none.

    >>> units_of("v_inf_km_s"), units_of("azimuth_deg"), units_of("count")
    ('km/s', 'deg', '')
    """
    base = name.split("[", 1)[0]
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        if base.endswith(suffix):
            return UNIT_SUFFIXES[suffix]
    return ""


@dataclass(frozen=True, slots=True)
class StoredResults:
    """A results file read back.

    Parameters
    ----------
    table : ResultTable
        The rows stored so far.
    sweep_json, definition_json : str
        The sweep file contents, and the canonical definition, as JSON.
    created_utc : str
        When the file was first written, ISO 8601 UTC.
    n_cases : int
        Number of cases in the sweep.
    """

    table: ResultTable
    sweep_json: str
    definition_json: str
    created_utc: str
    n_cases: int


#: Random part of a temporary's name (``secrets.token_hex(8)``, or older styles).
_RANDOM = r"(?:[0-9a-f]{16}|[A-Za-z0-9_]{8}|tmp[0-9]+)"


def stale_temporaries(path: Path) -> list[Path]:
    """Return the temporaries of ``path`` left in its folder by a killed run."""
    folder = path.parent
    if not folder.is_dir():
        return []
    pattern = re.compile(rf"^\.{re.escape(path.name)}\.(?:{_RANDOM}\.tmp|tmp[0-9]+)$")
    return sorted(p for p in folder.iterdir() if pattern.match(p.name))


def _device(path: Path) -> bool:
    """Whether ``path`` is an existing device, pipe or socket (``/dev/null``, a FIFO): written
    into, never renamed over (a rename would replace the device with a regular file)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


@contextmanager
def _atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (parents created); rename it over ``path``. A
    device or a pipe (:func:`_device`) is yielded itself, and written in place."""
    if _device(path):
        try:
            yield path
        except OSError as exc:
            raise ResultWriteError(str(path), exc) from None
        return
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(8)}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        for stale in stale_temporaries(path):
            stale.unlink(missing_ok=True)
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        raise ResultWriteError(str(path), exc) from None
    finally:
        if tmp.exists():  # False, not an error, when the directory is unusable
            tmp.unlink()


def write_hdf5(path: str | Path, table: ResultTable, *, sweep_json: str,
               definition_json: str, source: str, n_cases: int, created_utc: str,
               updated_utc: str) -> None:
    """Write ``table`` to the HDF5 file ``path`` atomically (layout in the module docstring).

    Raises
    ------
    ResultFileError
        The file or its directory cannot be written.
    """
    path = Path(path)
    with _atomic_path(path) as tmp, _in_memory(tmp) as f:
        f.attrs.update({"format": FORMAT_NAME, "format_version": FORMAT_VERSION,
                        "generator": _generator(),
                        "sweep_json": sweep_json, "definition_json": definition_json,
                        "source": source, "n_cases": n_cases, "created_utc": created_utc,
                        "updated_utc": updated_utc})
        _dataset(f, "case", table.column("case"), "")
        inputs = f.create_group("inputs", track_order=True)
        for name in table.names:
            _dataset(inputs, name, table.column(name), units_of(name))
        outputs = f.create_group("outputs", track_order=True)
        for name in table.output_names:
            column = table.column(name)
            data = column if column.dtype == np.float64 else column.astype(_TEXT)
            _dataset(outputs, name, data, units_of(name))
        status = _dataset(f, "status", table.column("status").astype(np.int8), "")
        status.attrs["codes"] = json.dumps({str(int(s)): s.name.lower() for s in CaseStatus})
        _dataset(f, "error", table.column("error").astype(_TEXT), "")
        _dataset(f, "elapsed_s", table.column("elapsed_s"), "s")


@contextmanager
def _in_memory(path: Path) -> Iterator[h5py.File]:
    """Yield a new HDF5 file built in memory; write it to ``path`` in one plain write on
    leaving the block.

    The HDF5 library then never writes to the disk itself: on a full disk it can crash the
    process (a segmentation fault) where a plain write raises an OSError (the same reason
    as ``tapp.io.tape.hdf5io.create``, which ``iter`` may not import).
    """
    with h5py.File(path.name, "w", track_order=True, driver="core",
                   backing_store=False) as f:
        yield f
        f.flush()
        image = f.id.get_file_image()
    path.write_bytes(image)


def _generator() -> str:
    """Return ``"iter, tapp <version>"``, from the installed distribution's metadata."""
    try:
        return f"iter, tapp {importlib.metadata.version('tapp')}"
    except importlib.metadata.PackageNotFoundError:
        return "iter, tapp (version unknown: not installed)"


def _dataset(group: h5py.Group, name: str, data: np.ndarray, units: str) -> h5py.Dataset:
    dataset = group.create_dataset(name, data=data, dtype=data.dtype)
    dataset.attrs["units"] = units
    dataset.attrs["sha256"] = values_digest(data, text=data.dtype.kind not in "fiu")
    return dataset


def read_hdf5(path: str | Path) -> StoredResults:
    """Return the results stored in the HDF5 file ``path``, checking its layout.

    Raises
    ------
    ResultFileError
        The file cannot be opened, is not an ``iter`` results file, or its layout is broken
        (a dataset missing or of the wrong type or length, an unknown status code, case
        numbers repeated or outside the sweep); the message names the dataset.
    """
    source = str(path)
    regular_file(path, "HDF5 results file", error=ResultFileError)
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT_NAME:
                raise ResultFileError(source, "format", f"an {FORMAT_NAME} file (attribute "
                                      f"format = {FORMAT_NAME!r})", f.attrs.get("format"))
            attrs = {k: _text_attr(f, source, k) for k in ("sweep_json", "definition_json",
                                                            "created_utc")}
            version = _version(f, source)
            n_cases = _count_attr(f, source)
            indices = _column(f, source, "case", "i")
            n_rows = indices.size
            names = tuple(_group(f, source, "inputs"))
            inputs = [_column(f, source, f"inputs/{n}", "f", n_rows) for n in names]
            values = np.column_stack(inputs) if names else np.empty((n_rows, 0))
            outputs = {n: _read_column(f, source, f"outputs/{n}", n_rows)
                       for n in _group(f, source, "outputs")}
            status = _column(f, source, "status", "i", n_rows)
            errors = _text_column(f, source, "error", n_rows)
            elapsed_s = _column(f, source, "elapsed_s", "f", n_rows)
            if version >= DIGEST_VERSION:
                for name, column in (("case", indices), ("status", status), ("error", errors),
                                     ("elapsed_s", elapsed_s),
                                     *((f"inputs/{n}", c) for n, c in zip(names, inputs,
                                                                         strict=True)),
                                     *((f"outputs/{n}", c) for n, c in outputs.items())):
                    _verify(f, source, name, column)
    except OSError as exc:
        raise ResultFileError(source, "file", "a readable HDF5 results file (truncated or "
                              "corrupt?)", str(exc)) from None
    codes = {int(s) for s in CaseStatus}
    if not set(np.unique(status).tolist()) <= codes:
        raise ResultFileError(source, "status", f"codes {sorted(codes)}",
                              sorted(set(np.unique(status).tolist()) - codes))
    if np.unique(indices).size != n_rows or (n_rows and (indices.min() < 0
                                                          or indices.max() >= n_cases)):
        raise ResultFileError(source, "case", f"distinct case numbers 0 .. {n_cases - 1}")
    rows = []
    for k, index in enumerate(indices):
        case_status = CaseStatus(int(status[k]))
        row_outputs: dict[str, OutputValue] = {}
        if case_status is CaseStatus.OK:
            row_outputs = {n: column[k] for n, column in outputs.items()
                           if not _is_missing(column[k])}
        rows.append(CaseResult(index=int(index), values=tuple(float(v) for v in values[k]),
                               outputs=row_outputs, status=case_status, error=str(errors[k]),
                               elapsed_s=float(elapsed_s[k])))
    return StoredResults(table=ResultTable(names=names, rows=tuple(rows)),
                         sweep_json=attrs["sweep_json"],
                         definition_json=attrs["definition_json"],
                         created_utc=attrs["created_utc"], n_cases=n_cases)


def _version(f: h5py.File, source: str) -> int:
    version = f.attrs.get("format_version", 1)
    if (not isinstance(version, int | np.integer) or isinstance(version, bool)
            or not 1 <= version <= FORMAT_VERSION):
        raise ResultFileError(source, "format_version", f"1 to {FORMAT_VERSION}", version)
    if version < DIGEST_VERSION:
        warnings.warn(f"{source}: format_version {version} results carry no checksums; they "
                      "are checked again once rewritten", ResultFileWarning, stacklevel=3)
    return int(version)


def _verify(f: h5py.File, source: str, name: str, values: np.ndarray | list) -> None:
    dataset = f[name]
    stored = dataset.attrs.get("sha256")
    if isinstance(stored, bytes):
        stored = stored.decode("ascii", "replace")
    if stored != values_digest(values, text=h5py.check_string_dtype(dataset.dtype) is not None):
        raise ResultFileError(source, name, "values matching its sha256 attribute (the file "
                              "was altered or corrupted after it was written)")


def _text_attr(f: h5py.File, source: str, key: str) -> str:
    value = f.attrs.get(key)
    if isinstance(value, bytes):
        try:
            value = value.decode("utf-8")
        except UnicodeDecodeError:
            value = None
    if not isinstance(value, str):
        raise ResultFileError(source, key, "a text attribute", type(value).__name__)
    return value


def _count_attr(f: h5py.File, source: str) -> int:
    value = f.attrs.get("n_cases")
    if not isinstance(value, int | np.integer) or isinstance(value, bool) or value < 0:
        raise ResultFileError(source, "n_cases", "a whole number >= 0", value)
    return int(value)


def _group(f: h5py.File, source: str, name: str) -> h5py.Group:
    group = f.get(name)
    if not isinstance(group, h5py.Group):
        raise ResultFileError(source, name, "a group", "nothing" if group is None else
                              type(group).__name__)
    return group


def _checked_dataset(f: h5py.File, source: str, name: str,
                     n_rows: int | None) -> h5py.Dataset:
    dataset = f.get(name)
    if not isinstance(dataset, h5py.Dataset) or dataset.ndim != 1:
        raise ResultFileError(source, name, "a one-dimensional dataset",
                              "nothing" if dataset is None else getattr(dataset, "shape", None))
    if n_rows is not None and dataset.shape[0] != n_rows:
        raise ResultFileError(source, name, f"{n_rows} rows (as many as /case)",
                              dataset.shape[0])
    return dataset


def _column(f: h5py.File, source: str, name: str, kind: str,
            n_rows: int | None = None) -> np.ndarray:
    dataset = _checked_dataset(f, source, name, n_rows)
    if dataset.dtype.kind not in (kind, "u" if kind == "i" else kind):
        raise ResultFileError(source, name, "integers" if kind == "i" else "floats",
                              str(dataset.dtype))
    return dataset[()]


def _text_column(f: h5py.File, source: str, name: str, n_rows: int) -> list[str]:
    dataset = _checked_dataset(f, source, name, n_rows)
    if h5py.check_string_dtype(dataset.dtype) is None:
        raise ResultFileError(source, name, "UTF-8 text", str(dataset.dtype))
    try:
        return [str(v) for v in dataset.asstr()[()]]
    except UnicodeDecodeError:
        raise ResultFileError(source, name, "UTF-8 text", "undecodable bytes") from None


def _read_column(f: h5py.File, source: str, name: str, n_rows: int) -> list[OutputValue]:
    dataset = _checked_dataset(f, source, name, n_rows)
    if dataset.dtype.kind == "f":
        return [float(v) for v in dataset[()]]
    return list(_text_column(f, source, name, n_rows))


def _is_missing(value: OutputValue) -> bool:
    """A text cell "" was missing; a float NaN is kept (it may be the body's own NaN)."""
    return value == ""


def write_csv(path: str | Path, table: ResultTable) -> None:
    """Write ``table`` to the CSV file ``path`` atomically (columns: ``table.columns``).

    Raises
    ------
    ResultFileError
        The file or its directory cannot be written.
    """
    path = Path(path)
    columns = table.columns
    data = {name: table.column(name) for name in columns}
    data["status"] = np.array([CaseStatus(int(s)).name.lower() for s in data["status"]])
    with _atomic_path(path) as tmp, tmp.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(columns)
        for k in range(len(table.rows)):
            writer.writerow([_cell(data[name][k]) for name in columns])


def _cell(value: object) -> str:
    if isinstance(value, float | np.floating):
        return "" if math.isnan(value) else repr(float(value))
    return str(value)

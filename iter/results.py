"""Results files: the table as HDF5 and CSV. The only module of ``iter`` that imports h5py.

HDF5 layout (one row per case, sorted by case index)::

    /                 attrs: format = "iter-results", format_version = 1,
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
``deg``; see :data:`UNIT_SUFFIXES`), empty when the name carries no recognised unit. The
file may hold fewer rows than ``n_cases`` while a sweep runs: it is rewritten as cases
complete, each time to a temporary file renamed over the old one, so it is never half
written.

CSV: a header line with the table's columns (:attr:`iter.table.ResultTable.columns`), then
one line per case; ``status`` is written as its name (``ok``, ``failed``).
"""

from __future__ import annotations

import csv
import importlib.metadata
import json
import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from .errors import ResultFileError
from .table import CaseResult, CaseStatus, OutputValue, ResultTable

FORMAT_NAME = "iter-results"
FORMAT_VERSION = 1

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


@contextmanager
def _atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (parents created); rename it over ``path``."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        raise ResultFileError(str(path), f"cannot write: {exc}") from None
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
    with _atomic_path(path) as tmp, h5py.File(tmp, "w", track_order=True) as f:
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


def _generator() -> str:
    """Return ``"iter, tapp <version>"``, from the installed distribution's metadata."""
    try:
        return f"iter, tapp {importlib.metadata.version('tapp')}"
    except importlib.metadata.PackageNotFoundError:
        return "iter, tapp (version unknown: not installed)"


def _dataset(group: h5py.Group, name: str, data: np.ndarray, units: str) -> h5py.Dataset:
    dataset = group.create_dataset(name, data=data, dtype=data.dtype)
    dataset.attrs["units"] = units
    return dataset


def read_hdf5(path: str | Path) -> StoredResults:
    """Return the results stored in the HDF5 file ``path``.

    Raises
    ------
    ResultFileError
        The file cannot be opened or is not an ``iter`` results file.
    """
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT_NAME:
                raise ResultFileError(str(path), f"not an {FORMAT_NAME} file (no format "
                                      f"attribute {FORMAT_NAME!r})")
            names = tuple(f["inputs"])
            indices = f["case"][()]
            values = np.column_stack([f["inputs"][n][()] for n in names])
            outputs = {n: _read_column(f["outputs"][n]) for n in f["outputs"]}
            status = f["status"][()]
            errors = f["error"].asstr()[()]
            elapsed_s = f["elapsed_s"][()]
            attrs = {k: f.attrs[k] for k in ("sweep_json", "definition_json", "created_utc",
                                             "n_cases")}
    except (OSError, KeyError) as exc:
        raise ResultFileError(str(path), f"cannot read results: {exc}") from None
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
                         sweep_json=str(attrs["sweep_json"]),
                         definition_json=str(attrs["definition_json"]),
                         created_utc=str(attrs["created_utc"]), n_cases=int(attrs["n_cases"]))


def _read_column(dataset: h5py.Dataset) -> list[OutputValue]:
    if dataset.dtype.kind == "f":
        return [float(v) for v in dataset[()]]
    return [str(v) for v in dataset.asstr()[()]]


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

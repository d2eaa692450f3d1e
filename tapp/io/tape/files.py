"""Functions on whole tape files, whatever the tape: :func:`verify` and :func:`describe`.

:func:`verify` reads every dataset and attribute of any HDF5 file (checksums, UTF-8 text);
:func:`describe` verifies a file, then summarises it: a T13 tape through
:mod:`tapp.io.tape.t13_hdf5`, a T32 tape through :mod:`tapp.io.tape.t32_hdf5`, any other HDF5 file
by its attributes and datasets (``tapp tape info``).
"""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np

from tapp.io.tape import hdf5io
from tapp.io.tape.hdf5io import Reader, attr_value, open_tape
from tapp.io.tape.t13 import summary
from tapp.io.tape.t13_hdf5 import open_t13
from tapp.io.tape.t32 import summary as t32_summary
from tapp.io.tape.t32_hdf5 import read_t32

__all__ = ["describe", "verify"]


def _rows(ds: h5py.Dataset) -> int:
    """Rows of axis 0 read at once by :func:`verify` (whole chunks, about CHUNK_BYTES)."""
    if ds.chunks:
        chunk_bytes = ds.dtype.itemsize * math.prod(ds.chunks)
        return ds.chunks[0] * max(1, hdf5io.CHUNK_BYTES // max(1, chunk_bytes))
    row = ds.dtype.itemsize * math.prod(ds.shape[1:])
    return max(1, hdf5io.CHUNK_BYTES // max(1, row))


def verify(path: Path | str) -> list[str]:
    """Read every dataset and attribute of a tape (any HDF5 file); return the dataset names.

    Each dataset is read whole-chunk by whole-chunk, so its Fletcher-32 checksums are
    checked, and text (datasets and attributes) must be valid UTF-8. A dataset without a
    checksum is read all the same (a T13 version-1 tape, another HDF5 file): corruption of
    its data cannot be detected.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        On the first failure: an unreadable file or object, a checksum mismatch, text that
        is not UTF-8; the message names the file and the dataset (or attribute).
    """
    path = Path(path)
    with open_tape(path) as f:
        r = Reader(f, str(path), checksums=False)
        names: list[str] = []
        owners: list[str] = [""]

        def visit(name: str, obj) -> None:
            (names if isinstance(obj, h5py.Dataset) else owners).append(name)

        with r.guard("file", "a readable group structure"):
            f.visititems(visit)
        for owner in owners + names:
            attrs = r._attrs(owner)
            with r.guard(owner or "attrs", "readable attributes"):
                keys = list(attrs.keys())
            for key in keys:
                where = f"{owner}.attrs/{key}" if owner else f"attrs/{key}"
                with r.guard(where, "a readable attribute"):
                    value = attrs[key]
                attr_value(r.check, where, value)
        for name in names:
            ds = r.dataset(name)
            with r.guard(name, "a readable dataset header"):
                shape = ds.shape
            if shape is None:  # an empty (null) dataspace: nothing stored
                continue
            if len(shape) == 0:
                data = [r.raw(name)]
            else:
                step = _rows(ds)
                data = (r.raw(name, np.s_[a:a + step]) for a in range(0, ds.shape[0], step))
            for block in data:
                if block.dtype.kind in "OS":
                    for v in np.ravel(block):
                        r.check.text(name, v)
    return names


def describe(path: Path | str) -> dict:
    """Return a JSON-ready summary of a tape file, every dataset of it verified first.

    :func:`verify` reads every dataset (checksums, UTF-8 text); then a T13 tape is validated
    block by block through :func:`tapp.io.tape.t13_hdf5.open_t13` (the raw rows aside) and
    summarised by :func:`tapp.io.tape.t13.summary`, a T32 tape is read by
    :func:`tapp.io.tape.t32_hdf5.read_t32` and summarised by :func:`tapp.io.tape.t32.summary`
    (:func:`tapp.io.tape.t32.format_t32_summary` renders it as text); any other HDF5 file (an
    observation file) gets its root attributes and the shape and type of every dataset. Each
    summary has ``verified_datasets``, the number of datasets verified.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        If it is unreadable or corrupt, or a T13 or T32 tape that fails validation (naming
        the dataset).

    Warns
    -----
    UserWarning
        For a T13 version-1 tape (no checksums).
    """
    path = Path(path)
    verified = len(verify(path))
    with open_tape(path) as f:
        r = Reader(f, str(path), checksums=False)
        fmt = r.attr("format", str, default="")
        if fmt not in ("T13", "T32"):
            datasets: dict[str, dict] = {}

            def visit(name: str, obj: h5py.HLObject) -> None:
                if isinstance(obj, h5py.Dataset):
                    datasets[name] = {"shape": list(obj.shape or ()), "dtype": str(obj.dtype)}

            with r.guard("file", "a readable group structure"):
                f.visititems(visit)
                items = list(f.attrs.items())
            attrs = {k: attr_value(r.check, f"attrs/{k}", v) for k, v in items
                     if k != "scenario"}
            return {"format": fmt or "unknown", "attributes": attrs, "datasets": datasets,
                    "verified_datasets": verified}
    if fmt == "T32":
        t32 = read_t32(path)
        with open_tape(path) as f:
            version = Reader(f, str(path), checksums=False).attr("version", int)
        return {**t32_summary(t32, version=version), "verified_datasets": verified}
    with open_t13(path) as tape:
        for _ in tape.blocks():  # the pair matrices, checked block by block
            pass
        return {**summary(tape.header, version=tape.version), "verified_datasets": verified}

"""Tapes between the programs (HDF5 through h5py): T13 (TAPP I -> TAPP III), and later T32.

The only package of tapp, with the other I/O modules, that imports h5py. Schemas are contracts:
versioned, validated on read, written atomically. :func:`describe` summarises any tape.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from tapp.errors import InputError, TapeError
from tapp.tape.packing import pack_tr, symmetry_defect, tr_index, tr_order, tr_size, unpack_tr
from tapp.tape.t13 import T13, read_t13, summary, validate, write_t13

__all__ = ["T13", "describe", "pack_tr", "read_t13", "summary", "symmetry_defect", "tr_index",
           "tr_order", "tr_size", "unpack_tr", "validate", "write_t13"]


def _attr_text(value) -> object:
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def describe(path: Path | str) -> dict:
    """Return a JSON-ready summary of a tape file.

    A T13 tape is read and validated (:func:`tapp.tape.t13.read_t13`, without its raw rows)
    and summarised by :func:`tapp.tape.t13.summary`; any other HDF5 file (a T32 tape, an
    observation file) gets its root attributes and the shape and type of every dataset.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        If it is unreadable, or a T13 tape that fails validation (naming the dataset).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(str(path), "file", "an existing tape file")
    try:
        with h5py.File(path, "r") as f:
            fmt = _attr_text(f.attrs.get("format", ""))
            if fmt != "T13":
                datasets: dict[str, dict] = {}

                def visit(name: str, obj: h5py.HLObject) -> None:
                    if isinstance(obj, h5py.Dataset):
                        datasets[name] = {"shape": list(obj.shape), "dtype": str(obj.dtype)}

                f.visititems(visit)
                attrs = {k: _attr_text(v) for k, v in f.attrs.items() if k != "scenario"}
                return {"format": fmt or "unknown", "attributes": attrs, "datasets": datasets}
    except OSError as exc:
        raise TapeError(f"{path}: file: expected a readable HDF5 file (truncated or corrupt: "
                        f"{exc})") from None
    return summary(read_t13(path, raw=False))

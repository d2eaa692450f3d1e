"""Tapes between the programs (HDF5 through h5py): T13 (TAPP I -> TAPP III) and T32 (TAPP III
-> TAPP II).

The only package of tapp, with the other I/O modules, that imports h5py. Schemas are contracts:
versioned, validated on read, written atomically, every dataset checksummed
(:mod:`tapp.tape.hdf5io`). :func:`describe` summarises any tape, :func:`verify` reads every
dataset of one.
"""

from __future__ import annotations

from pathlib import Path

import h5py

from tapp.tape.hdf5io import Reader, attr_value, open_tape, verify
from tapp.tape.packing import pack_tr, symmetry_defect, tr_index, tr_order, tr_size, unpack_tr
from tapp.tape.t13 import (
    T13,
    MemoryPairs,
    PairBlock,
    T13File,
    memory_pairs,
    open_t13,
    read_t13,
    summary,
    t13_file_writer,
    validate,
    write_t13,
)
from tapp.tape.t32 import (
    T32,
    T32Entity,
    T32Partition,
    T32Recycle,
    format_t32_summary,
    read_t32,
    t32_file_writer,
    write_t32,
)
from tapp.tape.t32 import summary as t32_summary

__all__ = ["T13", "T32", "MemoryPairs", "PairBlock", "T13File", "T32Entity", "T32Partition",
           "T32Recycle", "describe", "format_t32_summary", "memory_pairs", "open_t13",
           "pack_tr", "read_t13", "read_t32", "summary", "symmetry_defect", "t13_file_writer",
           "t32_file_writer", "tr_index", "tr_order", "tr_size", "unpack_tr", "validate",
           "verify", "write_t13", "write_t32"]


def describe(path: Path | str) -> dict:
    """Return a JSON-ready summary of a tape file, every dataset of it verified first.

    :func:`verify` reads every dataset (checksums, UTF-8 text); then a T13 tape is validated
    block by block through :func:`open_t13` (the raw rows aside) and summarised by
    :func:`tapp.tape.t13.summary`, a T32 tape is read by :func:`read_t32` and summarised by
    :func:`tapp.tape.t32.summary` (:func:`format_t32_summary` renders it as text); any other
    HDF5 file (an observation file) gets its root attributes and the shape and type of every
    dataset. Each summary has ``verified_datasets``, the number of datasets verified.

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
        return {**t32_summary(t32), "verified_datasets": verified}
    with open_t13(path) as tape:
        for _ in tape.blocks():  # the pair matrices, checked block by block
            pass
        return {**summary(tape.header, version=tape.version), "verified_datasets": verified}

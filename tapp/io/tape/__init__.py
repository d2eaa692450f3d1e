"""Tapes between the programs: T13 (TAPP I -> TAPP III) and T32 (TAPP III -> TAPP II).

Importing :mod:`tapp.io.tape` loads NumPy only: the tapes in memory, their validation and
summaries (:mod:`tapp.io.tape.t13`, :mod:`tapp.io.tape.t32`, with the checks of
:mod:`tapp.io.tape.checks`) and the packing of symmetric matrices (:mod:`tapp.io.tape.packing`),
so the programs that compute on tapes (TAPP III, TAPP II) never load h5py.

The HDF5 form is kept apart, in the only modules of the package that import h5py:
:mod:`tapp.io.tape.t13_hdf5` (``write_t13``, ``t13_file_writer``, ``read_t13``, ``open_t13``,
``T13File``), :mod:`tapp.io.tape.t32_hdf5` (``write_t32``, ``t32_file_writer``, ``read_t32``),
:mod:`tapp.io.tape.hdf5io` (the storage and the validating reader both share) and
:mod:`tapp.io.tape.files` (``verify`` reads every dataset of any tape, ``describe`` summarises
one). Schemas are contracts: versioned, validated on read, written atomically, every dataset
checksummed.
"""

from __future__ import annotations

from tapp.io.tape.packing import pack_tr, symmetry_defect, tr_index, tr_order, tr_size, unpack_tr
from tapp.io.tape.t13 import T13, MemoryPairs, PairBlock, memory_pairs, summary, validate
from tapp.io.tape.t32 import T32, T32Entity, T32Partition, T32Recycle, format_t32_summary

__all__ = ["T13", "T32", "MemoryPairs", "PairBlock", "T32Entity", "T32Partition", "T32Recycle",
           "format_t32_summary", "memory_pairs", "pack_tr", "summary", "symmetry_defect",
           "tr_index", "tr_order", "tr_size", "unpack_tr", "validate"]

"""ITER: run a body over nested loops of cases, serially or on Dask (seed section VI).

A *loop* varies n named parameters over ``sets`` cases, either from a full table (type 1) or
from a first row plus increments (type 2); loops nest to any depth, inner loops restarting
for every outer case. The *body* is a Python callable (``"module:function"``) or a command-line
program; each case gives one row of a results table (varied values, outputs, status, error),
written to HDF5 and CSV. See :mod:`iter.sweepfile` for the sweep-file format, the rule for
the paths in it (taken from the sweep file's folder) and the checks made before any case runs.

This package knows nothing of ``tapp`` and never imports it. Inside it, use relative imports:
``import iter`` would shadow the builtin ``iter()``; from outside, ``from iter import ...`` or
``import iter as sweeps``. The names of the modules that read and write the results files
(:mod:`iter.results`, :mod:`iter.run`: the only ones that load h5py) are imported on first
use, so that a program using only part of the package (say :mod:`iter.schema` or the executors
of :mod:`iter.execute`) does not load h5py.

>>> from iter import Loop, generate_cases
>>> azimuths = Loop(type=2, names=("azimuth_deg",), sets=5, vary=(96.0,), delta=(3.0,))
>>> [case.values[0] for case in generate_cases([azimuths])]
[96.0, 99.0, 102.0, 105.0, 108.0]
"""

import importlib

from .body import CallableBody, ProgramBody, input_check, resolve_callable, run_case
from .errors import (
    AllCasesFailed,
    ClusterError,
    IterError,
    ResultFileError,
    ResultWriteError,
    SchedulerError,
    SweepInputError,
)
from .execute import Execution, probe_scheduler
from .loops import Case, Loop, case_count, generate_cases
from .sweep import Sweep
from .sweepfile import load_sweep, parse_sweep
from .table import CaseResult, CaseStatus, ResultTable

__all__ = [
    "AllCasesFailed", "CallableBody", "Case", "CaseResult", "CaseStatus", "ClusterError",
    "Execution", "IterError", "Loop", "ProgramBody", "ResultFileError", "ResultTable",
    "ResultWriteError", "SchedulerError", "Sweep", "SweepInputError", "SweepResult",
    "SweepSummary", "case_count", "generate_cases", "input_check", "load_sweep", "parse_sweep",
    "probe_scheduler", "read_hdf5", "resolve_callable", "run_case", "run_sweep", "write_csv",
    "write_hdf5",
]

#: Public names imported on first use, and their modules (which load h5py).
_ON_FIRST_USE = {"SweepResult": "run", "SweepSummary": "run", "run_sweep": "run",
                 "read_hdf5": "results", "write_csv": "results", "write_hdf5": "results"}


def __getattr__(name: str) -> object:
    if name in _ON_FIRST_USE:
        return getattr(importlib.import_module(f".{_ON_FIRST_USE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
